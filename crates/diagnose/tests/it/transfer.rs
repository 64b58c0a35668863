//! Transfer: effects named only where they hold on poses the fit never saw — on the real UR10 (series C
//! fitted, series B in other arm configurations scored), and on data made by the independent tracker of
//! `tracker.rs` (narrow joint coverage, two offsets of parallel joints).

use thermokin_chain::{ErrorParams, Robot};
use thermokin_diagnose::{Config, Extrapolation, FoldGrouping, Outliers, Shrinkage, Validation, diagnose};
use thermokin_identify::{FrameMode, ToolMode};
use thermokin_testdata::workspace;

use crate::tracker::measure;

fn ur10() -> thermokin_chain::Robot {
    let options = thermokin_io::RobotOptions { base: None, tip: Some("tool0".into()) };
    thermokin_io::read_robot_with(&thermokin_testdata::urdf("ur10.urdf"), &options).unwrap()
}

/// The real UR10's series C and B (one tracker frame), read for `robot`.
fn series_c_and_b(robot: &Robot) -> (thermokin_chain::Dataset, thermokin_chain::Dataset) {
    let kinds: Vec<_> = robot.chain().joints().iter().map(|j| j.kind).collect();
    let read = |file: &str| {
        thermokin_io::read_measurements(&workspace(&format!("fixtures/real/ur10-ipa/{file}")), &kinds).unwrap()
    };
    (read("series_C.csv"), read("series_B.csv"))
}

#[test]
fn ur10_series_c_transfers_to_series_b() {
    // All 2,773 poses of C diagnosed, nested, as a user runs it, and the chosen model scored on all
    // 1,495 poses of B (its registration and probe refitted there, the effects kept): the bound
    // is 0.65 mm mean (an independent full-geometry + compliance fit: 0.587; nominal 1.025). A seeded
    // 500-pose subsample of C does not meet it (0.754 mm: joint 2 then covers 8 % of its travel and the
    // compliance is not found) — recorded in docs/diagnosis.md; the claim is tested on the whole file.
    let robot = ur10();
    let (c, b) = series_c_and_b(&robot);
    assert_eq!((c.len(), b.len()), (2773, 1495));
    let train = c;
    let config = Config {
        frame: FrameMode::Tracker,
        tool: ToolMode::Unknown,
        noise_mm: Some(0.01),
        validation: Validation::Nested { outer: 5 },
        ..Config::default()
    };
    let report = diagnose(&robot, &train, Some(&b), &config).unwrap();
    crate::golden::export_reproduces_the_residuals(&robot, &report, &train);
    crate::golden::drift_check("ur10-c-holdout-b", &robot, &report);
    let labels: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    let h = report.holdout.as_ref().unwrap();
    let n = report.nested.as_ref().unwrap();
    eprintln!("{}\nchosen {labels:?}", report.validation);
    eprintln!("B: nominal {:.4} → chosen {:.4} mm mean", h.nominal.heldout_mean_mm, h.selected.heldout_mean_mm);
    for f in &n.folds {
        eprintln!(
            "outer {}: {:.4} → {:.4} mm RMS {:?}",
            f.fold, f.nominal.heldout_rms_mm, f.selected.heldout_rms_mm, f.effects
        );
    }
    for r in &report.identifiability.not_identifiable {
        eprintln!("not identifiable: {} — {}", r.effect, r.reason);
    }
    assert!((h.nominal.heldout_mean_mm - 1.025).abs() < 0.01, "nominal on B {:.4}", h.nominal.heldout_mean_mm);
    assert!(h.selected.heldout_mean_mm <= 0.65, "chosen model on B: {:.4} mm mean", h.selected.heldout_mean_mm);
    // Issue #36: registration and tool refitted on B, no worse than the 0.456 mm before it. In the
    // training frame (the export through `fk`, nothing refitted) at or below the independent full-DH +
    // compliance fit's 0.771 mm, the goal FIGAROH's 0.647: 0.773 while joint 3's gear ratio, which gains
    // 0.0009 mm among C's neighbouring poses, was exported — fitted on one half of joint 2's arc its sign
    // flips, and it is now refused for what it costs beyond the poses it was fitted on (0.511).
    assert!(h.selected.heldout_mean_mm <= 0.456, "chosen model on B, refitted: {:.4}", h.selected.heldout_mean_mm);
    let same_frame = h.same_frame.selected.heldout_mean_mm;
    eprintln!("B in the training frame: {same_frame:.4} mm mean");
    assert!(same_frame <= 0.771, "B in the training frame: {same_frame:.4} mm mean");
    assert!(same_frame < 0.647, "B in the training frame, the goal: {same_frame:.4} mm mean");
    // Joint 3's gear ratio is not exported: where the selection offers it, it is refused for what it
    // costs beyond the poses it was fitted on.
    assert!(!labels.contains(&"joint_scale[3]"), "{labels:?}");
    if let Some(scale3) = report.identifiability.not_identifiable.iter().find(|r| r.effect == "joint_scale[3]") {
        assert!(scale3.reason.ends_with("it does not hold beyond the poses it was fitted on"), "{}", scale3.reason);
        assert!(scale3.reason.contains("joint 2's poses"), "{}", scale3.reason);
    }
    assert!(n.worse_than_nominal.is_empty(), "outer folds worse than nominal: {:?}", n.worse_than_nominal);
    assert!(report.honest_end.is_none(), "{:?}", report.honest_end);
    // Every reported parameter is identified: one standard deviation under 1 mm or 1° (a final refit that
    // re-decided identifiability at its solution once reported link_deviation[3].dz_mm ± 585 mm — the
    // same fit, parameterised through a nearly dependent rotation).
    // The completion's rows too, fitted with the shrinkage the folds chose (without it the rows of joints 5
    // and 6 sat at 1.4 ± 30.7 and 4.2 ± 28.0 mm: a combination the poses barely see, spread over two
    // rows).
    assert!(report.shrinkage > 0.0);
    for e in report.effects.iter().chain(&report.completed) {
        for (name, p) in &e.parameters {
            assert!(p.std.is_none_or(|s| s < 1.0), "{name}: ± {:?}", p.std);
        }
    }
    // Joint 2 covers 13 % of its travel in C: its gear ratio is refused, with what to measure.
    let scale2 = report.identifiability.not_identifiable.iter().find(|r| r.effect == "joint_scale[2]").unwrap();
    assert!(scale2.remedy.contains("joint 2 over at least 180°"), "{}", scale2.remedy);
    assert!(!labels.contains(&"joint_scale[2]"));
    // The air temperature moves by less than 0.8 K: no per-kelvin drift is selectable.
    assert!(labels.iter().all(|l| !l.contains("temperature")));
    // The identified robot — what --export writes — carries every chosen effect: the model scored on B.
    let carried = report.identified.beyond_urdf();
    eprintln!("identified robot's corrections beyond geometry: {carried:?}");
    for e in labels.iter().filter(|l| l.starts_with("joint_compliance") || l.starts_with("joint_scale")) {
        let joint = e.split(['[', ']']).nth(1).unwrap();
        assert!(
            carried.iter().any(|c| c.starts_with(&format!("joint {joint} "))),
            "{e} not in the export: {carried:?}"
        );
    }
}

/// Series C has no time column: its rows have no order, and its diagnosis is the same whatever their
/// order (issue #59: shuffled with two seeds, the step at line 711 disappeared and the hold-out as
/// exported moved 0.5068 → 0.5805 / 0.6058 mm, the completion's prior 10 → 3 → 1 rows per parameter, the
/// nominal model's fold scores changed). The file's order and three seeded shuffles: the same effects,
/// completion rows, prior and every figure on B; no step of the frame (the lines are no order without
/// `--order file`).
#[test]
fn series_c_gives_one_answer_in_any_row_order() {
    use rand::SeedableRng;
    use rand::seq::SliceRandom;
    let robot = ur10();
    let (c, b) = series_c_and_b(&robot);
    let config = Config {
        frame: FrameMode::Tracker,
        tool: ToolMode::Unknown,
        noise_mm: Some(0.01),
        validation: Validation::SelectionOnly,
        ..Config::default()
    };
    let run = |data: &thermokin_chain::Dataset| {
        let report = diagnose(&robot, data, Some(&b), &config).unwrap();
        let h = report.holdout.as_ref().unwrap();
        let labels: Vec<String> = report.effects.iter().chain(&report.completed).map(|e| e.label.clone()).collect();
        let figures = [
            report.nominal.heldout_rms_mm,
            h.selected.heldout_mean_mm,
            h.same_frame.selected.heldout_mean_mm,
            report.shrinkage,
        ];
        // Listed in the order given: the same lines, in another order for shuffled rows.
        let mut outliers: Vec<Option<usize>> = report.outliers.iter().map(|o| o.line).collect();
        outliers.sort();
        (labels, figures, outliers)
    };
    let (labels, figures, outliers) = run(&c);
    eprintln!("file order: {labels:?} {figures:?} {outliers:?}");
    assert!(labels.iter().all(|l| !l.starts_with("frame_step")), "{labels:?}");
    for seed in [11, 12, 13] {
        let mut rows: Vec<usize> = (0..c.len()).collect();
        rows.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(seed));
        let (l, f, o) = run(&c.subset(&rows));
        assert_eq!(l, labels, "seed {seed}");
        assert_eq!(o, outliers, "seed {seed}");
        for (a, b) in f.iter().zip(&figures) {
            assert!((a - b).abs() <= 1e-9 * b.abs().max(1.0), "seed {seed}: {f:?} vs {figures:?}");
        }
    }
}

/// Sixty random poses of the real UR10's series C, diagnosed as a user runs it and scored on series B
/// (registration and probe refitted): three seeded draws that ended at or above the nominal robot's
/// 1.025 mm while the completion asked a compliance to lie three standard errors from zero (seed 111:
/// 1.003, 113: 1.008, 114: 1.056 — joint 2 over 49° only, its real sag imitated by rows that
/// extrapolate it wrong; `completion.rs`, `SEEN_STANDARD_ERRORS`). Measured now: 0.642, 0.590, 0.626.
/// Fails if any of the three transfers worse than 0.9 × nominal. Of our twenty draws (seeds 100–119)
/// the one nearest nominal is seed 112, at 1.020: a draw of 60 C poses may still not reach B
/// (docs/diagnosis.md, "Small sets").
#[test]
fn sixty_random_poses_of_the_ur10_transfer_better_than_the_nominal_robot() {
    use rand::SeedableRng;
    let robot = ur10();
    let (c, b) = series_c_and_b(&robot);
    let config = Config { frame: FrameMode::Tracker, tool: ToolMode::Unknown, ..Config::default() };
    for seed in [111, 113, 114] {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let rows = rand::seq::index::sample(&mut rng, c.len(), 60).into_vec();
        let report = diagnose(&robot, &c.subset(&rows), Some(&b), &config).unwrap();
        let holdout = report.holdout.as_ref().unwrap();
        let (nominal, selected) = (holdout.nominal.heldout_mean_mm, holdout.selected.heldout_mean_mm);
        eprintln!("UR10 60 poses of C, seed {seed}: {nominal:.4} -> {selected:.4} mm on B");
        assert!(selected < 0.9 * nominal, "seed {seed}: {selected} against the nominal {nominal}");
    }
}

#[test]
fn offsets_of_two_parallel_joints_come_out_as_two_offsets() {
    // Joints 2 and 3 of the IRB 140 turn about parallel axes: both offsets lie inside joint 3's link
    // row, which the forward steps may take first; parsimony over combinations must give them back.
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let data = measure(robot.chain(), 200, 211, |q| {
        let mut a = q.to_vec();
        a[1] += 0.05f64.to_radians();
        a[2] -= 0.04f64.to_radians();
        a
    });
    let config = Config { validation: Validation::SelectionOnly, ..Config::default() };
    let report = diagnose(&robot, &data, None, &config).unwrap();
    let mut labels: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    eprintln!("{labels:?}; {:?}", report.additive.iter().map(|r| &r.model).collect::<Vec<_>>());
    labels.sort_unstable();
    assert_eq!(labels, ["joint_offset[2]", "joint_offset[3]"]);
}

#[test]
fn an_effect_over_a_short_arc_is_refused_with_what_to_measure() {
    // Joint 2's gear ratio with joint 2 kept between 5° and 20° (of its 200° travel): over that arc the
    // scale trades against an offset, so it is not selectable; the report says to measure 50° of joint 2.
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let data = crate::tracker::measure_short_arc(robot.chain(), 150, 101, (1, 5.0, 20.0), |q| {
        let mut a = q.to_vec();
        a[1] *= 1.0 + 2e-3;
        a
    });
    let config = Config { validation: Validation::SelectionOnly, ..Config::default() };
    let report = diagnose(&robot, &data, None, &config).unwrap();
    let refused = report.identifiability.not_identifiable.iter().find(|r| r.effect == "joint_scale[2]").unwrap();
    eprintln!("{} — {}; {}", refused.effect, refused.reason, refused.remedy);
    assert!(refused.remedy.starts_with("measure joint 2 over at least 50°"), "{}", refused.remedy);
    assert!(report.effects.iter().all(|e| e.label != "joint_scale[2]"));
}

#[test]
fn an_effect_that_moves_with_the_probe_is_refused() {
    // Tracker frame and unknown probe; joint 6 turns over 2° only. Joint 5's zero offset then swings the
    // probe along the same direction in the flange's frame as a change of the probe's point does (their
    // estimates correlated beyond 0.99): not a property of the robot the data can tell apart, so not
    // selectable — while the hidden joint-3 offset is still found.
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let data = crate::tracker::measure_short_arc(robot.chain(), 150, 301, (5, 10.0, 12.0), |q| {
        let mut a = q.to_vec();
        a[2] += 0.05f64.to_radians();
        a
    });
    let config = Config {
        frame: FrameMode::Tracker,
        tool: ToolMode::Unknown,
        validation: Validation::SelectionOnly,
        ..Config::default()
    };
    let report = diagnose(&robot, &data, None, &config).unwrap();
    for r in &report.identifiability.not_identifiable {
        eprintln!("not identifiable: {} — {}", r.effect, r.reason);
    }
    let refused = report.identifiability.not_identifiable.iter().find(|r| r.effect == "joint_offset[5]").unwrap();
    assert!(refused.reason.contains("correlation") && refused.reason.contains("tool_point"), "{}", refused.reason);
    let labels: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    eprintln!("{labels:?}");
    assert!(!labels.contains(&"joint_offset[5]"));
    assert!(labels.iter().any(|l| l.starts_with("joint_offset[") || l.starts_with("link_deviation[")), "{labels:?}");
}

/// `robot` with every length (rows, centres of mass) multiplied by `size`, masses kept.
fn halved_or_whole(robot: Robot, size: f64) -> Robot {
    let c = robot.chain();
    let row =
        |r: &thermokin_chain::FixedRow| thermokin_chain::FixedRow { translation: r.translation * size, ..r.clone() };
    let joints = c.joints().iter().map(|j| thermokin_chain::Joint { offset: j.offset * size, ..j.clone() }).collect();
    let chain = thermokin_chain::Chain::new(row(c.base()), joints, row(c.tool())).unwrap();
    let masses =
        robot.masses().iter().map(|m| m.map(|m| thermokin_chain::LinkMass { com_mm: m.com_mm * size, ..m })).collect();
    Robot::new(robot.name(), chain).with_masses(masses).unwrap()
}

/// The IRB 140 with joint 3's row moved by `dx_mm`, scaled by `size` (every length of the robot and the
/// deviation alike), diagnosed; the refusal of `link_deviation[3]`, if any.
fn row_three_moved(dx_mm: f64, size: f64) -> (Option<String>, Vec<String>) {
    let robot = halved_or_whole(thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap(), size);
    let chain = robot.chain();
    let mut rows = vec![ErrorParams::ZERO; 6];
    rows[2] = thermokin_testdata::error_mm_deg([dx_mm * size, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let zeros = vec![0.0; 6];
    let truth = chain.with_errors_and_zeros(ErrorParams::ZERO, &rows, ErrorParams::ZERO, &zeros).unwrap();
    let data = measure(&truth, 120, 302, <[f64]>::to_vec);
    let config = Config { validation: Validation::SelectionOnly, ..Config::default() };
    let report = diagnose(&robot, &data, None, &config).unwrap();
    let refused = report.identifiability.not_identifiable.iter().find(|r| r.effect == "link_deviation[3]");
    let labels = report.effects.iter().map(|e| e.label.clone()).collect();
    (refused.map(|r| r.reason.clone()), labels)
}

#[test]
fn a_link_deviation_beyond_the_plausible_is_refused_with_its_value_in_the_robots_scale() {
    // Joint 3's row moved by 40 mm on an arm whose tool point reaches ~0.8 m from joint 1: beyond 2 % of
    // the extent (the bound in the robot's own scale), the fit's value is refused with the value measured
    // and where the bound comes from, instead of being taken as the robot's.
    let (refused, labels) = row_three_moved(40.0, 1.0);
    let reason = refused.expect("the 40 mm row is refused");
    eprintln!("{reason}");
    // The value quoted is a fit's run to its end (not where the plausibility bounds stopped it): the
    // simulated 40 mm, within a hundredth of a millimetre.
    let fitted: f64 = reason
        .split("its translation fitted at ")
        .nth(1)
        .and_then(|rest| rest.split(" mm").next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no fitted value in: {reason}"));
    assert!((fitted - 40.0).abs() <= 0.01, "{reason}");
    assert!(reason.contains("2% of the arm's") && reason.contains("mm extent"), "{reason}");
    assert!(!labels.contains(&"link_deviation[3]".to_string()));
    // 8 mm — a cable-driven arm's real wrist error, and 1 % of this arm's extent — is the robot's.
    let (refused, labels) = row_three_moved(8.0, 1.0);
    assert_eq!(refused, None);
    assert!(labels.contains(&"link_deviation[3]".to_string()), "{labels:?}");
}

#[test]
fn the_plausibility_bounds_scale_with_the_robot() {
    // The same robot at half its size with the deviation halved is the same robot: judged the same.
    // (Absolute millimetre and degree bounds refused the halved arm's rotation where they passed the
    // whole one's.)
    for dx in [8.0, 40.0] {
        let (whole, _) = row_three_moved(dx, 1.0);
        let (half, _) = row_three_moved(dx, 0.5);
        assert_eq!(whole.is_some(), half.is_some(), "{dx} mm: {whole:?} vs {half:?}");
    }
}

#[test]
fn outer_folds_worse_than_nominal_are_named_and_said_first() {
    // An error that exists on one wrist branch only (joint 2 off by 0.1° when joint 5 is positive): an
    // offset fitted on folds that hold that branch is applied to folds that do not, which it makes
    // worse. Leave-one-configuration-out nested validation must name those folds, and the report must
    // say first that the chosen model does not transfer.
    let report = nested_by_configuration(303, |q| q[4] > 0.0);
    let n = report.nested.as_ref().unwrap();
    eprintln!("{:?}", report.honest_end);
    assert!(!n.worse_than_nominal.is_empty());
    for &k in &n.worse_than_nominal {
        let f = &n.folds[k - 1];
        assert!(f.selected.heldout_rms_mm > f.nominal.heldout_rms_mm);
    }
    assert!(
        report.honest_end.as_deref().is_some_and(|s| s.contains("predicts worse than the nominal")),
        "{:?}",
        report.honest_end
    );
}

#[test]
fn an_outer_fold_holding_most_of_the_error_is_named_in_the_verdict() {
    // An error on one arm configuration of four only (joint 2 off by 0.1° where the elbow is above its
    // median and joint 5 positive): left out, that configuration keeps its error — more than half of all
    // the squared held-out error with a quarter of the poses. The nested figures name that fold and the
    // verdict says the RMS is mostly it. Without shrinkage: it tests the verdict's naming, on the
    // nested figures of a least-squares fit (with the prior chosen by cross-validation, the fold's
    // held-out RMS falls from 0.0129 to 0.0102 mm against 0.0087 of noise — the shrunk geometry carries
    // part of that configuration's error over — and no fold holds half of the squared error).
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let median = crate::tracker::elbow_median(robot.chain(), 304);
    let report = nested_by_configuration(304, |q| q[2] > median && q[4] > 0.0);
    let n = report.nested.as_ref().unwrap();
    eprintln!("{}", report.verdict);
    let k = n.dominated_by.expect("a dominating fold");
    // The dominating fold is the configuration with the error: its poses all carry it.
    let f = &n.folds[k - 1];
    let total: f64 = n.folds.iter().map(|f| f.selected.heldout_rms_mm.powi(2) * f.poses as f64).sum();
    assert!(f.selected.heldout_rms_mm.powi(2) * f.poses as f64 > 0.5 * total);
    assert!(
        report.verdict.contains(&format!("outer fold {k} holds more than half of the squared error")),
        "{}",
        report.verdict
    );
}

/// Joint 2 off by 0.1° on the poses where `on(commanded)` holds (200 poses of the independent tracker,
/// seeded), diagnosed with leave-one-configuration-out folds and without shrinkage; the outer folds
/// printed. The gross-error screen's flags are kept in the data (`Outliers::Keep`): the configuration's
/// millimetre is what these tests are about, and the screen's full geometry, which cannot bend to it,
/// flags every pose that carries it (51 of 200 for seed 304). Before they were kept, the verdict test
/// passed on a bug only — the completion's gate the wrong way round put six rows fitted to noise into
/// every outer fold, and the fold that held the most of that noise "dominated".
fn nested_by_configuration(seed: u64, on: impl Fn(&[f64]) -> bool) -> thermokin_diagnose::Report {
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let data = crate::tracker::joint_two_off_where(robot.chain(), seed, on);
    let config = Config {
        folds_by: FoldGrouping::JointConfiguration,
        shrinkage: Shrinkage::Off,
        outliers: Outliers::Keep,
        ..Config::default()
    };
    let report = diagnose(&robot, &data, None, &config).unwrap();
    for f in &report.nested.as_ref().unwrap().folds {
        eprintln!(
            "outer {} ({} poses): {:.4} → {:.4} mm RMS {:?}",
            f.fold, f.poses, f.nominal.heldout_rms_mm, f.selected.heldout_rms_mm, f.effects
        );
    }
    report
}

#[test]
fn a_shape_that_gains_more_among_the_poses_than_it_costs_beyond_them_stays() {
    // Joint 3 of the IRB 140 lags by c·q3·(q2 − q2₀), a coupling of two joints that no catalogue effect
    // describes; the poses cover 80 % of every joint's travel. Shapes of the joint angle stand in for part
    // of it (joint 3's and joint 5's gear ratios); fitted on one half of a joint's arc and scored on the
    // other they may lose, but among neighbouring poses they gain, and poses drawn anew over the same
    // travel (where this robot is used) confirm it: the phase weighs both, and they stay — the same
    // effects, the same fresh-pose error, with the check and without it. The seven poses at the end of
    // joint 3's range, where the coupling is largest, gather and are kept as a systematic block (before
    // they were called gross errors, `periodic[3]` was chosen and the fresh poses were missed by 0.0819 mm
    // mean; kept, 0.0804).
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let q20 = (-14.0f64).to_radians();
    let truth = |q: &[f64]| {
        let mut a = q.to_vec();
        a[2] += 2.8e-4 * q[2] * (q[1] - q20);
        a
    };
    let data = measure(robot.chain(), 300, 411, truth);
    let hold = measure(robot.chain(), 300, 412, truth);
    let run = |extrapolation| {
        let config = Config { validation: Validation::SelectionOnly, extrapolation, ..Config::default() };
        let report = diagnose(&robot, &data, Some(&hold), &config).unwrap();
        let labels: Vec<String> = report.effects.iter().map(|e| e.label.clone()).collect();
        (report.holdout.unwrap().same_frame.selected.heldout_mean_mm, labels)
    };
    let (judged, judged_labels) = run(Extrapolation::HalfArcs);
    let (off, off_labels) = run(Extrapolation::Off);
    eprintln!("judged {judged:.4} {judged_labels:?}; off {off:.4} {off_labels:?}");
    let shape = |labels: &[String]| labels.iter().any(|l| l == "periodic[3]" || l == "joint_scale[3]");
    assert!(shape(&off_labels), "{off_labels:?}");
    assert_eq!(judged_labels, off_labels);
    assert!(judged < 0.0819, "{judged}");
    // The same model, the same fit: the same hold-out error (1e-9 mm: arithmetic, not a tolerance).
    assert!((judged - off).abs() < 1e-9, "{judged} vs {off}");
}
