//! Another class of arm: a real cable-driven 7-joint Barrett WAM (`fixtures/real/jacobi-wam/`), fitted on
//! its 216-pose grid and scored on its 20 random poses, in the base frame its author registered.

use thermokin_chain::{Dataset, Robot};
use thermokin_diagnose::{Config, diagnose};
use thermokin_identify::{Effect, FrameMode, JointIndex, ToolMode};
use thermokin_testdata::workspace;

/// The WAM (URDF, `wam_base` → `wam_flange`) and its grid and random sets.
pub fn wam() -> (Robot, Dataset, Dataset) {
    let options = thermokin_io::RobotOptions::default();
    let robot = thermokin_io::read_robot_with(&workspace("fixtures/real/jacobi-wam/wam.urdf"), &options).unwrap();
    let kinds: Vec<_> = robot.chain().joints().iter().map(|j| j.kind).collect();
    let read = |f: &str| thermokin_io::read_measurements(&workspace(&format!("fixtures/real/jacobi-wam/{f}")), &kinds);
    (robot.clone(), read("wam-grid.csv").unwrap(), read("wam-random.csv").unwrap())
}

/// The grid diagnosed with its lines as the order it was measured in (`--order file`: the grid's poses
/// one after the other, which a backlash follows) and scored on the random poses. Without that word the
/// rows have no order and the diagnosis is that of the poses in their own order
/// ([`a_grid_without_an_order_gives_one_answer_in_any_row_order`]); the independent fits' bounds below
/// were met, before issue #59, by the grid's lines read as the order of its folds' shuffle — one
/// drawing, not the data's.
#[test]
fn wam_grid_to_random() {
    let (robot, grid, random) = wam();
    assert_eq!((grid.len(), random.len()), (216, 20));
    let config = Config {
        frame: FrameMode::Tracker,
        tool: ToolMode::Unknown,
        order: thermokin_chain::MeasuringOrder::File,
        ..Config::default()
    };
    let report = diagnose(&robot, &grid, Some(&random), &config).unwrap();
    let h = report.holdout.as_ref().unwrap();
    let labels: Vec<&str> = report.effects.iter().chain(&report.completed).map(|e| e.label.as_str()).collect();
    eprintln!(
        "WAM random: same frame {:.4} → {:.4}, refitted {:.4} → {:.4} mm mean; {labels:?}",
        h.same_frame.nominal.heldout_mean_mm,
        h.same_frame.selected.heldout_mean_mm,
        h.nominal.heldout_mean_mm,
        h.selected.heldout_mean_mm
    );
    for r in &report.identifiability.not_identifiable {
        eprintln!("refused: {} — {}", r.effect, r.reason);
    }
    // The nominal model scored as the data's README scores it, both protocols: the independent 4.046
    // (training registration and tool kept) and 3.573 (refitted on the 20 test poses).
    assert!((h.same_frame.nominal.heldout_mean_mm - 4.046).abs() < 0.01, "{}", h.same_frame.nominal.heldout_mean_mm);
    assert!((h.nominal.heldout_mean_mm - 3.573).abs() < 0.01, "{}", h.nominal.heldout_mean_mm);
    // At or below the independent DH + gravity compliance fit in both protocols (issue #36: 2.741 same
    // frame, 2.361 refitted; the diagnosis before the issue: 3.779 and 3.535; with the geometry and the
    // determined compliances completed: 2.928 and 2.533; with the compliance coupling of joints 5 and 6 —
    // the WAM's wrist differential — that the selection now finds: 2.671 and 2.255; with the pair's own
    // compliances beside it, its compliance matrix positive semidefinite: 2.688 and 2.292).
    assert!(h.same_frame.selected.heldout_mean_mm <= 2.741, "same frame {:.4}", h.same_frame.selected.heldout_mean_mm);
    assert!(h.selected.heldout_mean_mm <= 2.361, "refitted {:.4}", h.selected.heldout_mean_mm);
    assert!(labels.contains(&"compliance_coupling[5]"), "{labels:?}");
    // A cable-driven arm's real wrist millimetres are not refused as implausible (the absolute 5 mm bound
    // refused link_deviation[5] at 9 mm with advice about masses and units), and every row is in the model.
    assert!(
        report.identifiability.not_identifiable.iter().all(|r| !r.reason.contains("beyond the plausible")),
        "{:?}",
        report.identifiability.not_identifiable
    );
    // A cable-driven arm sags under its own weight: the completion carries the compliances the data
    // determine (√2 standard errors from zero), and none that rises under its load.
    assert!(labels.iter().any(|l| l.starts_with("joint_compliance[")), "{labels:?}");
    for j in 1..=7 {
        assert!(labels.contains(&format!("link_deviation[{j}]").as_str()), "{labels:?}");
    }
    // Joint 1 carries no gravity torque: its compliance is refused as such, not as a 0/0 span.
    let c1 = report.identifiability.not_identifiable.iter().find(|r| r.effect == "joint_compliance[1]").unwrap();
    assert!(c1.reason.contains("gravity never loads joint 1"), "{}", c1.reason);
    assert!(report.identifiability.not_identifiable.iter().all(|r| !r.reason.contains("±0.0 N·m")));
    let in_order = grid.clone().with_approach(thermokin_chain::MeasuringOrder::File);
    crate::golden::export_reproduces_the_residuals(&robot, &report, &in_order);
    crate::golden::drift_check("wam-grid-holdout-random", &robot, &report);
}

/// The grid without an order (no time column, no `--order file`): its rows in the file's order and
/// shuffled by three seeds give one diagnosis — the same effects, every figure the same. (Issue #59: the
/// answer depended on the order of the rows, three seeds giving three sets of effects; the figures of
/// this one drawing are in docs/real-data.md, above the bounds the file's order met — a finding.)
#[test]
fn a_grid_without_an_order_gives_one_answer_in_any_row_order() {
    use rand::SeedableRng;
    use rand::seq::SliceRandom;
    let (robot, grid, random) = wam();
    let config = Config { frame: FrameMode::Tracker, tool: ToolMode::Unknown, ..Config::default() };
    let run = |data: &Dataset| {
        let report = diagnose(&robot, data, Some(&random), &config).unwrap();
        let h = report.holdout.as_ref().unwrap();
        let n = report.nested.as_ref().unwrap();
        let labels: Vec<String> = report.effects.iter().chain(&report.completed).map(|e| e.label.clone()).collect();
        let figures = [
            n.nominal.heldout_mean_mm,
            n.selected.heldout_mean_mm,
            h.same_frame.selected.heldout_mean_mm,
            h.selected.heldout_mean_mm,
            report.nominal.heldout_rms_mm,
            report.shrinkage,
        ];
        let lines: Vec<Option<usize>> = report.poses.iter().map(|p| p.line).collect();
        (labels, figures, lines)
    };
    let (labels, figures, lines) = run(&grid);
    eprintln!("file order: {labels:?} {figures:?}");
    // The nominal robot as the data's README scores it, and the choice beats it in both protocols.
    assert!(figures[3] < 3.573 && figures[2] < 4.046, "{figures:?}");
    for seed in [1, 2, 3] {
        let mut rows: Vec<usize> = (0..grid.len()).collect();
        rows.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(seed));
        let (l, f, shuffled_lines) = run(&grid.subset(&rows));
        assert_eq!(l, labels, "seed {seed}");
        for (a, b) in f.iter().zip(&figures) {
            assert!((a - b).abs() <= 1e-9 * b.abs().max(1.0), "seed {seed}: {f:?} vs {figures:?}");
        }
        // The report's poses are listed in the order they were given, each with its own line.
        let mut given: Vec<Option<usize>> = rows.iter().map(|&i| grid.line_of(i)).collect();
        given.retain(|l| lines.contains(l));
        assert_eq!(shuffled_lines, given, "seed {seed}");
    }
}

/// Thirty poses of the grid, as a user with an hour of tracker time measures them (ten seeded draws),
/// diagnosed and scored on the 20 random poses in both protocols, against the complete geometry with the
/// gravity compliance of the loaded joints 2, 4, 6 fitted by plain least squares on the same thirty —
/// the class of the independent reference fit (issue #35: small sets of other robots at their full fit,
/// within 5 %). Measured on 2026-11-25 (medians of the ten, mm): the full fit 3.418 same frame and 2.952
/// refitted; the diagnosis 3.175 and 2.774 — 3.798 and 3.427 before the completion was judged in its
/// shrunk fit (the wrist rows' least-squares values, traded against each other and the probe on thirty
/// poses, refused the rows, and the partial models did not transfer), 3.438 and 2.891 before the gross-error
/// screen stopped taking the WAM's systematic millimetres, which the frame alone leaves, for gross errors.
#[test]
fn thirty_grid_poses_end_at_the_full_fit() {
    use rand::SeedableRng;
    let (robot, grid, random) = wam();
    let config = Config {
        frame: FrameMode::Tracker,
        tool: ToolMode::Unknown,
        validation: thermokin_diagnose::Validation::SelectionOnly,
        ..Config::default()
    };
    let full: Vec<Effect> = (0..7)
        .map(|j| Effect::LinkDeviation(JointIndex::of(&robot, j).unwrap()))
        .chain([1, 3, 5].map(|j| Effect::JointCompliance(JointIndex::of(&robot, j).unwrap())))
        .collect();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let (mut ours, mut theirs) = (Vec::new(), Vec::new());
    for _ in 0..10 {
        let rows = rand::seq::index::sample(&mut rng, grid.len(), 30).into_vec();
        let train = grid.subset(&rows);
        let report = diagnose(&robot, &train, Some(&random), &config).unwrap();
        let h = report.holdout.as_ref().unwrap();
        ours.push((h.same_frame.selected.heldout_mean_mm, h.selected.heldout_mean_mm));
        let f = thermokin_diagnose::evaluate(&robot, &train, &random, &full, &config).unwrap();
        theirs.push((f.same_frame.heldout_mean_mm, f.refitted.heldout_mean_mm));
    }
    let median = |v: &[(f64, f64)], pick: fn(&(f64, f64)) -> f64| {
        let mut x: Vec<f64> = v.iter().map(pick).collect();
        x.sort_by(f64::total_cmp);
        0.5 * (x[4] + x[5])
    };
    let (same, refit) = (median(&ours, |p| p.0), median(&ours, |p| p.1));
    let (full_same, full_refit) = (median(&theirs, |p| p.0), median(&theirs, |p| p.1));
    eprintln!("thirty grid poses, medians: ours {same:.3} / {refit:.3}, full fit {full_same:.3} / {full_refit:.3}");
    assert!(same <= 1.05 * full_same, "same frame {same:.3} vs full fit {full_same:.3}");
    assert!(refit <= 1.05 * full_refit, "refitted {refit:.3} vs full fit {full_refit:.3}");
}

/// The first seeded draw of thirty grid poses, which issue #35 found with one outer fold far off (4.8 →
/// 12.7 mm RMS, one pose at 20 mm; nested mean 4.00 against the nominal 3.47 mm, within the paired
/// difference's uncertainty — the case that taught the verdict to weigh outer folds with it, now a unit
/// test of `validation::worse_beyond_uncertainty`). Since the fits stop where they settle and the
/// completion's prior is chosen from the weakest one up where least squares walks away (issue #49), no
/// outer fold of it is far off: the procedure beats the nominal model on its outer folds beyond their
/// uncertainty, and the export beats it on the random poses, nothing said against either. (Over forty
/// seeded draws none ends above the nominal model on its outer folds now.)
#[test]
fn the_first_thirty_pose_draw_transfers() {
    use rand::SeedableRng;
    let (robot, grid, random) = wam();
    let config = Config { frame: FrameMode::Tracker, tool: ToolMode::Unknown, ..Config::default() };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let rows = rand::seq::index::sample(&mut rng, grid.len(), 30).into_vec();
    let report = diagnose(&robot, &grid.subset(&rows), Some(&random), &config).unwrap();
    let nested = report.nested.as_ref().unwrap();
    let h = report.holdout.as_ref().unwrap();
    eprintln!(
        "nested {:.4} vs nominal {:.4} ({:.4} ± {:.4}); hold-out same frame {:.4} vs {:.4}; {:?}; {:?}",
        nested.selected.heldout_mean_mm,
        nested.nominal.heldout_mean_mm,
        nested.mean_difference_mm,
        nested.mean_difference_se_mm,
        h.same_frame.selected.heldout_mean_mm,
        h.same_frame.nominal.heldout_mean_mm,
        report.honest_end,
        report.warnings.first()
    );
    for f in &nested.folds {
        eprintln!(
            "fold {} ({} poses): {:.4} -> {:.4} {:?}",
            f.fold, f.poses, f.nominal.heldout_rms_mm, f.selected.heldout_rms_mm, f.effects
        );
    }
    eprintln!("chosen {:?}", report.effects.iter().map(|e| e.label.clone()).collect::<Vec<_>>());
    assert!(nested.mean_difference_mm < -2.0 * nested.mean_difference_se_mm, "not better beyond its uncertainty");
    assert!(report.honest_end.is_none(), "{:?}", report.honest_end);
    assert!(!report.warnings.iter().any(|w| w.contains("cannot show")), "{:?}", report.warnings);
    assert!(h.same_frame.selected.heldout_mean_mm < h.same_frame.nominal.heldout_mean_mm);
    assert!(h.selected.heldout_mean_mm < h.nominal.heldout_mean_mm);
}
