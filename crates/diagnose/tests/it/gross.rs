//! Gross errors (a beam break, a probe knocked in its nest): found at their lines, kept out of every fit
//! and figure, never invented on clean data — on a simulated set written to a file and read back, and on
//! the real UR10 series C with 1 % of its poses displaced by 2–10 mm.

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use thermokin_chain::{Dataset, JointKind};
use thermokin_diagnose::{Config, HiddenEffect, Outliers, SimulationConfig, Validation, diagnose, simulate};
use thermokin_identify::{Effect, FrameMode, JointIndex, ToolMode};
use thermokin_testdata::workspace;

/// `count` distinct measurements of `data` (seeded) displaced by 2–10 mm in a random direction; their
/// 0-based indices, sorted.
fn displace(data: &mut Dataset, count: usize, seed: u64) -> Vec<usize> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut chosen = Vec::new();
    while chosen.len() < count {
        let i = rng.random_range(0..data.len());
        if chosen.contains(&i) {
            continue;
        }
        chosen.push(i);
        let d = Vector3::new(rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5);
        data.measurements[i].position_mm += d.normalize() * rng.random_range(2.0..10.0);
    }
    chosen.sort_unstable();
    chosen
}

/// A simulated IRB 140 set with a hidden offset, written as a measurements file and read back: the
/// lines a report names are the file's.
fn simulated_file(dir: &std::path::Path, displaced: usize) -> (thermokin_chain::Robot, Dataset, Vec<usize>) {
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let hidden = HiddenEffect { effect: Effect::JointOffset(JointIndex::of(&robot, 1).unwrap()), values: vec![3e-4] };
    let sim = SimulationConfig { poses: 150, minutes: 0.0, seed: 41, ..SimulationConfig::default() };
    let mut data = simulate(&robot, &[hidden], &sim).unwrap();
    let chosen = displace(&mut data, displaced, 5);
    let kinds = vec![JointKind::Revolute; 6];
    let path = dir.join("m.csv");
    let mut out = Vec::new();
    thermokin_io::write_measurements(&mut out, &data, &kinds).unwrap();
    std::fs::write(&path, out).unwrap();
    let read = thermokin_io::read_measurements(&path, &kinds).unwrap();
    (robot, read, chosen)
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("thermokin-gross-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn injected_gross_errors_are_found_at_their_lines_and_left_out() {
    let dir = scratch("lines");
    let (robot, data, chosen) = simulated_file(&dir, 4);
    let config = Config { validation: Validation::SelectionOnly, ..Config::default() };
    let report = diagnose(&robot, &data, None, &config).unwrap();
    // The header is line 1: measurement i (0-based) is on line i + 2.
    let expected: Vec<Option<usize>> = chosen.iter().map(|i| Some(i + 2)).collect();
    let lines: Vec<Option<usize>> = report.outliers.iter().map(|o| o.line).collect();
    eprintln!("{}", report.text().to_string().lines().take(6).collect::<Vec<_>>().join("\n"));
    assert_eq!(lines, expected);
    assert!(report.outliers.iter().all(|o| o.residual_mm > 1.9), "{:?}", report.outliers);
    // Four scattered gross errors are not mistaken for a systematic block.
    assert!(report.outlier_screen.clusters.is_empty(), "{:?}", report.outlier_screen.clusters);
    // Left out: the offset is found and the model ends at the noise (5 µm per axis), which 2–10 mm
    // residuals in the fit would forbid.
    assert_eq!(report.effects.first().map(|e| e.label.as_str()), Some("joint_offset[2]"));
    assert!(report.additive.last().unwrap().stats.heldout_rms_mm < 1.5 * 0.005 * 3f64.sqrt());
    let json = serde_json::to_value(&report).unwrap();
    assert_eq!(json["outliers"][0]["line"], serde_json::json!(chosen[0] + 2));
    // Kept when asked: still listed, and then in the fit (the model no longer reaches the noise).
    let kept = diagnose(&robot, &data, None, &Config { outliers: Outliers::Keep, ..config }).unwrap();
    assert_eq!(kept.outliers.len(), 4);
    assert!(kept.additive.last().unwrap().stats.heldout_rms_mm > 0.1);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn a_clean_simulated_set_flags_nothing() {
    let dir = scratch("clean");
    let (robot, data, _) = simulated_file(&dir, 0);
    let config = Config { validation: Validation::SelectionOnly, ..Config::default() };
    let report = diagnose(&robot, &data, None, &config).unwrap();
    assert!(report.outliers.is_empty(), "{:?}", report.outliers);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn ur10_series_c_with_one_percent_gross_errors() {
    // The real series C, 1 % of its 2,773 poses displaced by 2–10 mm (seeded): at least 90 % of them
    // flagged, at most 0.5 % of the clean poses, and B's error (registration and probe refitted) at
    // most 0.47 mm — the clean set's 0.453.
    let robot = thermokin_io::read_robot_with(
        &workspace("fixtures/urdf/ur10.urdf"),
        &thermokin_io::RobotOptions { base: None, tip: Some("tool0".into()) },
    )
    .unwrap();
    let kinds: Vec<_> = robot.chain().joints().iter().map(|j| j.kind).collect();
    let read = |f: &str| thermokin_io::read_measurements(&workspace(&format!("fixtures/real/ur10-ipa/{f}")), &kinds);
    let (mut c, b) = (read("series_C.csv").unwrap(), read("series_B.csv").unwrap());
    let count = c.len() / 100;
    let chosen = displace(&mut c, count, 2026);
    let config = Config {
        frame: FrameMode::Tracker,
        tool: ToolMode::Unknown,
        noise_mm: Some(0.01),
        validation: Validation::SelectionOnly,
        ..Config::default()
    };
    let report = diagnose(&robot, &c, Some(&b), &config).unwrap();
    let flagged: Vec<usize> = report.outliers.iter().map(|o| o.measurement - 1).collect();
    let found = chosen.iter().filter(|i| flagged.contains(i)).count();
    let false_flags = flagged.iter().filter(|i| !chosen.contains(i)).count();
    let h = report.holdout.as_ref().unwrap();
    eprintln!(
        "found {found} of {}, {false_flags} clean poses flagged; B {:.4} mm refitted, {:.4} same frame",
        chosen.len(),
        h.selected.heldout_mean_mm,
        h.same_frame.selected.heldout_mean_mm
    );
    assert!(found * 10 >= chosen.len() * 9, "{found} of {}", chosen.len());
    assert!(false_flags * 200 <= c.len() - chosen.len(), "{false_flags} clean poses flagged");
    assert!(h.selected.heldout_mean_mm <= 0.47, "{}", h.selected.heldout_mean_mm);
    // Displaced at random: gathered nowhere — not in lines, a joint's range or one neighbourhood.
    assert!(report.outlier_screen.clusters.is_empty(), "{:?}", report.outlier_screen.clusters);
}

#[test]
fn flags_gathered_in_one_configuration_are_kept_as_a_systematic_effect() {
    // Joint 2 off by 0.1° wherever the elbow is above its median and joint 5 positive (a quarter of the
    // poses of the independent tracker): no screening model bends to it, so the screen flags those poses
    // — and, since they gather (along the elbow's range, or in one neighbourhood of configurations), which
    // independent gross errors would not, keeps them as a systematic effect instead of leaving a quarter
    // of the data out as beam breaks.
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let median = crate::tracker::elbow_median(robot.chain(), 304);
    let data = crate::tracker::joint_two_off_where(robot.chain(), 304, |q| q[2] > median && q[4] > 0.0);
    let config = Config { validation: Validation::SelectionOnly, ..Config::default() };
    let report = diagnose(&robot, &data, None, &config).unwrap();
    let clusters = &report.outlier_screen.clusters;
    eprintln!("{} flagged; {clusters:?}", report.outliers.len());
    let kept: usize = clusters.iter().map(|c| c.kept).sum();
    assert!(kept > 20, "{clusters:?}");
    assert!(clusters.iter().all(|c| c.chance < thermokin_diagnose::FALSE_ALARM && c.joint_ranges.len() == 6));
    // Every pose of the block is still in the data: the isolated flags left are few.
    let affected = data.measurements.iter().filter(|m| m.q[2] > median && m.q[4] > 0.0).count();
    assert!(report.outliers.len() + 3 <= affected, "{} of {affected}", report.outliers.len());
    assert!(report.warnings.iter().any(|w| w.contains("kept as a systematic effect")), "{:?}", report.warnings);
    assert!(report.text().to_string().contains("not gross errors"));
}

/// A systematic block: the 25 poses at the top of joint 2's range (of 300) sag by 0.4–0.6 mm — a
/// compliance that grows there, which no catalogue effect's shape follows. At most 3 of them may be called
/// gross errors (issue #48); the block is said where it lies, along joint 2.
#[test]
fn a_block_at_the_top_of_a_joints_range_is_kept_and_said_where_it_lies() {
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let chain = robot.chain();
    let mut q2: Vec<f64> =
        crate::tracker::measure(chain, 300, 77, <[f64]>::to_vec).measurements.iter().map(|m| m.q[1]).collect();
    q2.sort_by(f64::total_cmp);
    let (threshold, top) = (q2[300 - 25], q2[299]);
    // The same draw (same seed): the robot sags at joint 2 beyond the threshold, 0.035°–0.05° growing with
    // the angle — 0.4–0.6 mm at the tool point of an IRB 140 reaching out there.
    let data = crate::tracker::measure(chain, 300, 77, |q| {
        let mut a = q.to_vec();
        if q[1] >= threshold {
            let grown = (q[1] - threshold) / (top - threshold).max(1e-9);
            a[1] += (0.035 + 0.015 * grown).to_radians();
        }
        a
    });
    let block: Vec<usize> = (0..300).filter(|&i| data.measurements[i].q[1] >= threshold).collect();
    assert_eq!(block.len(), 25);
    let config = Config { validation: Validation::SelectionOnly, ..Config::default() };
    let report = diagnose(&robot, &data, None, &config).unwrap();
    let called: Vec<usize> = report.outliers.iter().map(|o| o.measurement - 1).filter(|i| block.contains(i)).collect();
    eprintln!("{}", report.text().to_string().lines().take(8).collect::<Vec<_>>().join("\n"));
    eprintln!("{:?}", report.warnings);
    assert!(called.len() <= 3, "{} of the block's 25 called gross errors: {called:?}", called.len());
    let c = report.outlier_screen.clusters.first().expect("the block is said");
    assert!(
        matches!(c.along, thermokin_diagnose::Along::Joint { joint: 2, .. })
            || c.along == thermokin_diagnose::Along::Configurations,
        "{c:?}"
    );
}

/// Small clean real sets as users measure them — 60 poses of the WAM's grid, 30 and 60 of the UR10's
/// series C, ten seeded draws each — flag at most 0.5 % of their poses (issue #35: no false flags on clean
/// real data; the whole grid flags none, the whole series C two, neither drawn here). With the frame alone
/// screening every set too small for the unshrunk full geometry, the WAM's 60-pose draws flagged 59 of
/// their 600 poses: its millimetres of systematic error, which the frame leaves, were taken for gross
/// errors. Now the full geometry screens wherever its identifiable parameters, or, shrunk toward the
/// nominal robot, its effective ones, leave four rows each. (Thirty poses of the WAM still flag 7 of 300:
/// poses where its nominal error reaches 16 mm, beyond what a geometry shrunk to 22 effective
/// parameters bends to — docs/diagnosis.md.)
#[test]
fn small_clean_real_sets_flag_at_most_half_a_percent() {
    let (wam, grid, _) = crate::wam::wam();
    let ur10 = thermokin_io::read_robot_with(
        &workspace("fixtures/urdf/ur10.urdf"),
        &thermokin_io::RobotOptions { base: None, tip: Some("tool0".into()) },
    )
    .unwrap();
    let kinds: Vec<_> = ur10.chain().joints().iter().map(|j| j.kind).collect();
    let c = thermokin_io::read_measurements(&workspace("fixtures/real/ur10-ipa/series_C.csv"), &kinds).unwrap();
    let config = Config {
        frame: FrameMode::Tracker,
        tool: ToolMode::Unknown,
        validation: Validation::SelectionOnly,
        ..Config::default()
    };
    for (name, robot, data, n) in [("WAM", &wam, &grid, 60), ("UR10", &ur10, &c, 30), ("UR10", &ur10, &c, 60)] {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut flagged = Vec::new();
        for _ in 0..10 {
            let rows = rand::seq::index::sample(&mut rng, data.len(), n).into_vec();
            let report = diagnose(robot, &data.subset(&rows), None, &config).unwrap();
            flagged.extend(report.outliers.iter().map(|o| rows[o.measurement - 1] + 2));
        }
        eprintln!("{name}, ten draws of {n}: lines {flagged:?} flagged");
        assert!(flagged.len() * 200 <= 10 * n, "{name}, {n} poses: {} flagged", flagged.len());
    }
}
