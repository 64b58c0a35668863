//! Shrinkage on a small set, against a known truth: an arm with a small error in every joint row,
//! measured at few poses in the middle of its joint ranges with a tracker's noise, and scored on poses
//! over the whole ranges measured on the same arm — the case where a full geometry fitted by least
//! squares leans on what the few poses barely constrain (issue #35). The data come from the chain built
//! with the errors (`Chain::with_errors_and_zeros`), not from the diagnosis' model.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::{Chain, Dataset, ErrorParams, Robot};
use thermokin_diagnose::{Config, Shrinkage, Validation, diagnose};
use thermokin_testdata::{error_mm_deg, gauss, measured_point, workspace};

/// Noise per axis of the small set, mm (a tracker at ten metres, or a portable measuring arm): where the
/// noise of few poses, not the model, limits the fit.
const NOISE_MM: f64 = 0.1;

/// `n` poses of `truth` with joint values drawn in the central `fraction` of each joint's limits, with
/// `noise_mm` of Gaussian noise per axis.
fn measure(truth: &Chain, n: usize, seed: u64, fraction: f64, noise_mm: f64) -> Dataset {
    measure_with(truth, &<[f64]>::to_vec, n, seed, fraction, noise_mm)
}

/// As [`measure`], the robot standing at `actual(commanded)` (a deflection the chain computes).
fn measure_with(
    truth: &Chain,
    actual: &dyn Fn(&[f64]) -> Vec<f64>,
    n: usize,
    seed: u64,
    fraction: f64,
    noise_mm: f64,
) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let measurements = (0..n)
        .map(|_| {
            let q: Vec<f64> = truth
                .joints()
                .iter()
                .map(|j| {
                    let l = j.limits.unwrap();
                    let (mid, half) = (0.5 * (l.upper + l.lower), 0.5 * fraction * (l.upper - l.lower));
                    rng.random_range(mid - half..mid + half)
                })
                .collect();
            let p = truth.tool_pose(&actual(&q)).unwrap().translation.vector;
            measured_point(q, p, noise_mm, &mut rng)
        })
        .collect();
    Dataset { measurements, ..Dataset::default() }
}

/// `nominal` with every joint row off by a few tenths of a millimetre and a few hundredths of a degree
/// (Gaussian, 0.3 mm and 0.03° per component, seeded by `seed`).
fn every_row_off(nominal: &Chain, seed: u64) -> Chain {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut small = || 0.3 * gauss(&mut rng);
    let rows: Vec<ErrorParams> = (0..6)
        .map(|_| error_mm_deg([small(), small(), small(), 0.1 * small(), 0.1 * small(), 0.1 * small()]))
        .collect();
    nominal.with_errors_and_zeros(nominal.base().error, &rows, nominal.tool().error, &[0.0; 6]).unwrap()
}

#[test]
fn a_small_set_is_shrunk_toward_nominal_and_predicts_the_whole_workspace_better() {
    let robot: Robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let nominal = robot.chain().clone();
    // Every row off by a few tenths of a millimetre and a few hundredths of a degree (seeded); 20 poses in
    // the middle half of the ranges, scored on 400 over the central 80 %. Measured: least squares 0.252 mm,
    // shrunk (a prior worth 0.1 rows per parameter) 0.212, nominal 1.675; 0.207 since the completion takes a
    // compliance at √2 standard errors (joint 2's joins, which the truth lacks: the rows' errors over
    // the narrow arcs resemble its sag).
    let truth = every_row_off(&nominal, 35);
    let train = measure(&truth, 20, 1, 0.5, NOISE_MM);
    let test = measure(&truth, 400, 2, 0.8, 0.0);
    let run = |shrinkage| {
        let config = Config { validation: Validation::SelectionOnly, shrinkage, ..Config::default() };
        diagnose(&robot, &train, Some(&test), &config).unwrap()
    };
    let (shrunk, plain) = (run(Shrinkage::CrossValidated), run(Shrinkage::Off));
    let score = |r: &thermokin_diagnose::Report| r.holdout.as_ref().unwrap().selected.heldout_mean_mm;
    let labels = |r: &thermokin_diagnose::Report| {
        r.effects.iter().chain(&r.completed).map(|e| e.label.clone()).collect::<Vec<_>>()
    };
    eprintln!(
        "shrunk (prior {} rows) {:.4} mm {:?}; least squares {:.4} mm {:?}; nominal {:.4}",
        shrunk.shrinkage,
        score(&shrunk),
        labels(&shrunk),
        score(&plain),
        labels(&plain),
        plain.holdout.as_ref().unwrap().nominal.heldout_mean_mm
    );
    assert_eq!(plain.shrinkage, 0.0);
    assert!(shrunk.shrinkage > 0.0, "cross-validation chose no prior");
    assert!(score(&shrunk) < score(&plain), "{} vs {}", score(&shrunk), score(&plain));
}

/// A few poses of a light arm (the WAM's description) whose every joint row is off by millimetres: the
/// diagnosis ends at the plain least-squares fit of the complete geometry, or below it, on poses it never
/// saw (issue #35: small sets at their full fit, within 5 %), in the training frame. The data come from
/// the chain built with the errors.
#[test]
fn a_few_poses_of_an_arm_off_in_every_row_end_at_the_full_fit() {
    let options = thermokin_io::RobotOptions::default();
    let robot = thermokin_io::read_robot_with(&workspace("fixtures/real/jacobi-wam/wam.urdf"), &options).unwrap();
    let nominal = robot.chain().clone();
    let dof = nominal.dof();
    // Each row off by about 2 mm and 0.2° (seeded); 30 poses over 90 % of the ranges with 1 mm of noise
    // per axis (what a light arm's unmodelled millimetres look like to a geometric model), scored on 400
    // noise-free poses. Measured: the diagnosis 1.052 mm in the training frame, the plain full fit 1.200;
    // nominal 6.65.
    let (mm, deg) = (2.0, 0.2);
    let mut rng = ChaCha8Rng::seed_from_u64(36);
    let mut g = || gauss(&mut rng);
    let rows: Vec<ErrorParams> =
        (0..dof).map(|_| error_mm_deg([mm * g(), mm * g(), mm * g(), deg * g(), deg * g(), deg * g()])).collect();
    let truth =
        nominal.with_errors_and_zeros(nominal.base().error, &rows, nominal.tool().error, &vec![0.0; dof]).unwrap();
    let train = measure(&truth, 30, 1, 0.9, 1.0);
    let test = measure(&truth, 400, 2, 0.9, 0.0);
    let config = Config {
        frame: thermokin_identify::FrameMode::Tracker,
        tool: thermokin_identify::ToolMode::Unknown,
        validation: Validation::SelectionOnly,
        ..Config::default()
    };
    let report = diagnose(&robot, &train, Some(&test), &config).unwrap();
    let complete: Vec<thermokin_identify::Effect> = (0..dof)
        .map(|j| thermokin_identify::Effect::LinkDeviation(thermokin_identify::JointIndex::of(&robot, j).unwrap()))
        .collect();
    let full = thermokin_diagnose::evaluate(&robot, &train, &test, &complete, &config).unwrap();
    let h = report.holdout.as_ref().unwrap();
    let labels: Vec<&str> = report.effects.iter().chain(&report.completed).map(|e| e.label.as_str()).collect();
    eprintln!(
        "diagnosis same {:.4} refit {:.4} (prior {}) {:?}; full fit same {:.4} refit {:.4}; nominal {:.4}",
        h.same_frame.selected.heldout_mean_mm,
        h.selected.heldout_mean_mm,
        report.shrinkage,
        labels,
        full.same_frame.heldout_mean_mm,
        full.refitted.heldout_mean_mm,
        h.same_frame.nominal.heldout_mean_mm
    );
    for r in &report.identifiability.not_identifiable {
        eprintln!("  refused {} — {}", r.effect, r.reason);
    }
    assert!(h.same_frame.selected.heldout_mean_mm <= 1.05 * full.same_frame.heldout_mean_mm);
}

/// A sag the selection does not choose on a few poses: an IRB 140 whose joint 2 deflects 4e-4 °/N·m
/// under its masses (up to 0.03°, computed by the chain) beside small errors in every row, measured at 40
/// poses over the central 40 % of each joint's range (0.05 mm noise) and scored on 300 over 90 %. The
/// rows alone imitate the sag over the narrow arcs and extrapolate it wrong; the completion takes the
/// compliance where its fit puts it √2 standard errors from zero (`completion.rs`,
/// `SEEN_STANDARD_ERRORS`). Measured on ten such sessions (seeds 0–9): mean 0.129 mm refitted with the
/// rule at three standard errors, 0.107 at √2 — this one (seed 0) 0.288 → 0.092. The rule's cost, on
/// the same ten: a spurious compliance of joint 3 or 5 joins in two (0.059 → 0.070, 0.102 → 0.137), and
/// with a sag three times as strong (chosen by the selection) or none, the means go 0.103 → 0.109 and
/// 0.102 → 0.106. Fails if the compliance stays out, or the fresh poses are missed by more than 0.15 mm.
#[test]
fn a_sag_the_selection_leaves_joins_the_completed_geometry_of_a_few_poses() {
    use thermokin_chain::gravity_torques;
    let robot: Robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let nominal = robot.chain().clone();
    let truth = every_row_off(&nominal, 500);
    let sagging = |q: &[f64]| {
        let tau = gravity_torques(robot.chain(), robot.masses(), q, &-nalgebra::Vector3::z_axis()).unwrap();
        let mut actual = q.to_vec();
        actual[1] += 4e-4f64.to_radians() * tau[1];
        actual
    };
    let train = measure_with(&truth, &sagging, 40, 1000, 0.4, 0.05);
    let fresh = measure_with(&truth, &sagging, 300, 2000, 0.9, 0.0);
    let config = Config { frame: thermokin_identify::FrameMode::Tracker, ..Config::default() };
    let report = diagnose(&robot, &train, Some(&fresh), &config).unwrap();
    let labels: Vec<&str> = report.effects.iter().chain(&report.completed).map(|e| e.label.as_str()).collect();
    let holdout = report.holdout.as_ref().unwrap();
    eprintln!("{labels:?}: {:.4} -> {:.4} mm", holdout.nominal.heldout_mean_mm, holdout.selected.heldout_mean_mm);
    assert!(labels.contains(&"joint_compliance[2]"), "{labels:?}");
    assert!(holdout.selected.heldout_mean_mm < 0.15, "{}", holdout.selected.heldout_mean_mm);
}
