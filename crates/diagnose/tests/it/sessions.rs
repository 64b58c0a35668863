//! A tracker session as it runs (issue #48): poses measured one after the other over a warm-up, with a
//! truth the diagnosis does not share — the independent tracker of `tracker.rs` — and what only the
//! order tells, or must not be mistaken for it.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use thermokin_chain::Dataset;
use thermokin_diagnose::{Config, Validation, diagnose};
use thermokin_identify::FrameMode;
use thermokin_testdata::workspace;

/// `n` poses of the independent tracker on a robot standing at `actual(commanded)`, measured one after
/// the other over `minutes` (evenly spaced, from 0).
fn session(
    n: usize,
    minutes: f64,
    seed: u64,
    actual: impl Fn(&[f64]) -> Vec<f64>,
) -> (thermokin_chain::Robot, Dataset) {
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let mut data = crate::tracker::measure(robot.chain(), n, seed, actual);
    for (i, m) in data.measurements.iter_mut().enumerate() {
        m.time_min = minutes * i as f64 / (n - 1) as f64;
    }
    (robot, data)
}

/// Two static zero offsets, measured over three hours: nothing drifts, so no time law may be named —
/// an exponential drift over before all but a pose or two (τ of a tenth of a minute) is a static row,
/// and the offsets are what is named (issue #48's kept-aside case: `thermal_drift[3] (exponential)`
/// with τ = 0.1 min, whose export then refused `fk` without `--time`).
#[test]
fn static_offsets_in_a_timed_session_are_named_as_offsets_not_as_a_drift() {
    let (robot, data) = session(300, 180.0, 4821, |q| {
        let mut a = q.to_vec();
        a[1] += 0.04f64.to_radians();
        a[2] -= 0.03f64.to_radians();
        a
    });
    let config = Config { validation: Validation::SelectionOnly, ..Config::default() };
    let report = diagnose(&robot, &data, None, &config).unwrap();
    let chosen: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    eprintln!("chose {chosen:?}");
    assert!(chosen.iter().all(|e| !e.starts_with("thermal_drift")), "{chosen:?}");
    // Joint 2's and joint 3's offsets, as offsets or within the rows that contain them.
    for joint in [2, 3] {
        let named = report.effects.iter().any(|e| {
            e.label == format!("joint_offset[{joint}]")
                || e.contains.iter().any(|c| *c == format!("joint_offset[{joint}]"))
        });
        assert!(named, "joint {joint}'s offset not named: {chosen:?}");
    }
    assert!(report.additive.last().unwrap().stats.heldout_rms_mm < 2.0 * crate::tracker::NOISE_MM * 3f64.sqrt());
}

/// The tracker knocked after pose 150 of 300 (moved by 0.25 mm and 0.01°): the step is found within
/// ±3 poses of where it happened, fitted as the frame after it, and nothing else is named (issue #48:
/// `thermal_drift[1] (linear)` and 7 gross errors were named, and the fresh poses missed by more than
/// the nominal robot's). The poses after the step are not gross errors.
#[test]
fn a_knocked_tracker_is_a_step_of_the_frame_found_where_it_happened() {
    let (robot, mut data) = session(300, 180.0, 9157, <[f64]>::to_vec);
    let knocked = Isometry3::from_parts(
        Translation3::new(0.15, -0.2, 0.0),
        UnitQuaternion::from_scaled_axis(Vector3::new(0.0, 0.006, 0.008).normalize() * 0.01f64.to_radians()),
    );
    for m in &mut data.measurements[150..] {
        m.position_mm = (knocked * nalgebra::Point3::from(m.position_mm)).coords;
    }
    // Fresh poses, measured after the session with the tracker where it was knocked to.
    let mut fresh = crate::tracker::measure(robot.chain(), 100, 9158, <[f64]>::to_vec);
    for m in &mut fresh.measurements {
        m.position_mm = (knocked * nalgebra::Point3::from(m.position_mm)).coords;
    }
    let config = Config { frame: FrameMode::Tracker, validation: Validation::SelectionOnly, ..Config::default() };
    let report = diagnose(&robot, &data, Some(&fresh), &config).unwrap();
    let chosen: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    eprintln!("chose {chosen:?}; {} gross errors; warnings {:?}", report.outliers.len(), report.warnings);
    // As exported (nothing refitted: the frame the session ended in) and with the registration refitted:
    // at the noise (5 µm per axis), below the nominal robot.
    let holdout = report.holdout.as_ref().unwrap();
    let protocols = [
        ("as exported", holdout.same_frame.nominal, holdout.same_frame.selected),
        ("refitted", holdout.nominal, holdout.selected),
    ];
    for (protocol, nominal, selected) in protocols {
        eprintln!(
            "fresh poses {protocol}: nominal {:.4} → {:.4} mm",
            nominal.heldout_mean_mm, selected.heldout_mean_mm
        );
        // Refitted, the nominal robot is the truth here (only the tracker moved): not worse than it.
        assert!(selected.heldout_mean_mm <= 1.05 * nominal.heldout_mean_mm, "{protocol}: {selected:?}");
        assert!(selected.heldout_rms_mm < 2.0 * crate::tracker::NOISE_MM * 3f64.sqrt(), "{protocol}: {selected:?}");
    }
    assert_eq!(chosen.len(), 1, "{chosen:?}");
    let times: Vec<f64> = data.measurements.iter().map(|m| m.time_min).collect();
    let at: f64 = chosen[0]
        .strip_prefix("frame_step (")
        .and_then(|s| s.strip_suffix(" min)"))
        .unwrap_or_else(|| panic!("{chosen:?}"))
        .parse()
        .unwrap();
    assert!(times[147] < at && at <= times[153], "the step at {at} min, pose 150 at {} min", times[150]);
    assert!(report.outliers.is_empty(), "{:?}", report.outliers);
}

/// `n` poses of [`session`] on a robot whose joint 3 has a backlash of ±`half_deg`, joint 2 off by
/// `offset_deg`.
fn backlash_session(n: usize, seed: u64, half_deg: f64, offset_deg: f64) -> (thermokin_chain::Robot, Dataset) {
    backlash_session_on(2, n, seed, half_deg, offset_deg)
}

/// `n` poses of [`session`] on a robot whose joint `played` (0-based) has a backlash of ±`half_deg`: it
/// stands that far on the side it last moved towards — the direction taken here, in the test, from the
/// commanded values of the pose before (the first pose, with nothing before it, in the middle of the
/// play); joint 2 off by `offset_deg`.
fn backlash_session_on(
    played: usize,
    n: usize,
    seed: u64,
    half_deg: f64,
    offset_deg: f64,
) -> (thermokin_chain::Robot, Dataset) {
    let previous: std::cell::RefCell<Option<Vec<f64>>> = std::cell::RefCell::new(None);
    let side = std::cell::Cell::new(0.0f64);
    session(n, 180.0, seed, |q| {
        if let Some(before) = previous.borrow().as_ref() {
            let moved = q[played] - before[played];
            if moved != 0.0 {
                side.set(moved.signum());
            }
        }
        *previous.borrow_mut() = Some(q.to_vec());
        let mut a = q.to_vec();
        a[played] += (side.get() * half_deg).to_radians();
        a[1] += offset_deg.to_radians();
        a
    })
}

/// Backlash of ±0.015° on joint 3, poses in time order, with joint 2 off by 0.03° (issue #48's kept-aside
/// case: 25 poses were called gross errors and `joint_scale[3]` + `joint_offset[3]` named): named as
/// joint 3's backlash with its half play, nothing called a gross error, and the gain it claims confirmed
/// on a fresh session of the same robot, in both protocols.
#[test]
fn backlash_is_named_from_the_direction_each_pose_was_reached_in() {
    let (robot, data) = backlash_session(300, 6211, 0.015, 0.03);
    let (_, fresh) = backlash_session(100, 6212, 0.015, 0.03);
    let config = Config { frame: FrameMode::Tracker, validation: Validation::SelectionOnly, ..Config::default() };
    let report = diagnose(&robot, &data, Some(&fresh), &config).unwrap();
    let chosen: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    eprintln!("chose {chosen:?}; {} gross errors", report.outliers.len());
    assert!(report.outliers.is_empty(), "{:?}", report.outliers);
    let backlash = report.effects.iter().find(|e| e.label == "backlash[3]").unwrap_or_else(|| panic!("{chosen:?}"));
    let half = backlash.parameters.values().next().unwrap();
    let std = half.std.unwrap_or_else(|| panic!("the half play was not fitted: {half:?}"));
    eprintln!("half play {:.5} ± {std:.5}°", half.value);
    // Within three of its standard deviations of the truth (1e-4° at least: the fit's own linearisation).
    assert!((half.value - 0.015).abs() < 3.0 * std.max(1e-4), "{half:?}");
    assert!(chosen.iter().all(|e| !e.starts_with("joint_scale") && !e.starts_with("frame_step")), "{chosen:?}");
    assert!(report.warnings.iter().any(|w| w.starts_with("joint 3 sits")), "{:?}", report.warnings);
    // The gain the time blocks show holds on folds of neighbouring configurations too: nothing said.
    assert!(!report.warnings.iter().any(|w| w.contains("neighbouring arm configurations")), "{:?}", report.warnings);
    let holdout = report.holdout.as_ref().unwrap();
    for (protocol, nominal, selected) in [
        ("as exported", holdout.same_frame.nominal, holdout.same_frame.selected),
        ("refitted", holdout.nominal, holdout.selected),
    ] {
        eprintln!(
            "fresh poses {protocol}: nominal {:.4} → {:.4} mm",
            nominal.heldout_mean_mm, selected.heldout_mean_mm
        );
        assert!(selected.heldout_rms_mm < 2.0 * crate::tracker::NOISE_MM * 3f64.sqrt(), "{protocol}: {selected:?}");
    }
}

/// The tracker knocked twice — after pose 100 of 300 (0.2 mm) and after pose 210 (0.15 mm and 0.008°,
/// relative to where the first knock left it): both steps found within ±3 poses of where they happened,
/// nothing else named, nothing flagged, and fresh poses measured with the tracker where the second knock
/// left it at the noise as exported.
#[test]
fn a_tracker_knocked_twice_is_two_steps_of_the_frame() {
    let (robot, mut data) = session(300, 180.0, 7403, <[f64]>::to_vec);
    let first = Isometry3::from_parts(Translation3::new(0.0, 0.2, -0.05), UnitQuaternion::identity());
    let second = Isometry3::from_parts(
        Translation3::new(-0.1, 0.0, 0.11),
        UnitQuaternion::from_scaled_axis(Vector3::new(0.008, -0.004, 0.0).normalize() * 0.008f64.to_radians()),
    );
    for (i, m) in data.measurements.iter_mut().enumerate() {
        let frame = match i {
            ..100 => Isometry3::identity(),
            100..210 => first,
            _ => second * first,
        };
        m.position_mm = (frame * nalgebra::Point3::from(m.position_mm)).coords;
    }
    let mut fresh = crate::tracker::measure(robot.chain(), 100, 7404, <[f64]>::to_vec);
    for m in &mut fresh.measurements {
        m.position_mm = (second * first * nalgebra::Point3::from(m.position_mm)).coords;
    }
    let config = Config { frame: FrameMode::Tracker, validation: Validation::SelectionOnly, ..Config::default() };
    let report = diagnose(&robot, &data, Some(&fresh), &config).unwrap();
    let chosen: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    eprintln!("chose {chosen:?}; {} gross errors", report.outliers.len());
    assert!(report.outliers.is_empty(), "{:?}", report.outliers);
    assert_eq!(chosen.len(), 2, "{chosen:?}");
    let times: Vec<f64> = data.measurements.iter().map(|m| m.time_min).collect();
    let mut at: Vec<f64> = chosen
        .iter()
        .map(|c| {
            c.strip_prefix("frame_step (")
                .and_then(|s| s.strip_suffix(" min)"))
                .unwrap_or_else(|| panic!("{chosen:?}"))
                .parse()
                .unwrap()
        })
        .collect();
    at.sort_by(f64::total_cmp);
    assert!(
        times[97] < at[0] && at[0] <= times[103],
        "the first step at {} min, pose 100 at {} min",
        at[0],
        times[100]
    );
    assert!(times[207] < at[1] && at[1] <= times[213], "the second at {} min, pose 210 at {} min", at[1], times[210]);
    let holdout = report.holdout.as_ref().unwrap();
    eprintln!(
        "fresh poses as exported: nominal {:.4} → {:.4} mm",
        holdout.same_frame.nominal.heldout_mean_mm, holdout.same_frame.selected.heldout_mean_mm
    );
    assert!(holdout.same_frame.selected.heldout_rms_mm < 2.0 * crate::tracker::NOISE_MM * 3f64.sqrt());
}

/// A negative control of the claims of time: an error of one arm configuration (joint 2 off by 0.1°
/// wherever joint 1 stands above 30°, which no catalogue effect describes), measured in an order that
/// visits those configurations in one stretch of the session — joint 1's poses sorted, so that time and
/// configuration go together. The data cannot tell a tracker that moved in that stretch from the arm's
/// configuration there: a boundary between blocks of configurations is never said to be a moved tracker
/// (issue #59: a construction robot's column heights, measured one after the other, were). Before, a
/// step was named there (and a warning said it coincided with joint 1's range). The same poses without
/// a time column: no step either — not from the file's lines unless the user says they are the order
/// (`--order file`), and then not at the boundary.
#[test]
fn a_gain_of_one_configuration_is_not_claimed_as_one_of_time() {
    let (robot, mut data) = session(300, 180.0, 4851, |q| {
        let mut a = q.to_vec();
        if q[0] > 30f64.to_radians() {
            a[1] += 0.1f64.to_radians();
        }
        a
    });
    // Measured in order of joint 1's value, the times kept evenly spaced.
    let times: Vec<f64> = data.measurements.iter().map(|m| m.time_min).collect();
    data.measurements.sort_by(|a, b| a.q[0].total_cmp(&b.q[0]));
    for (m, t) in data.measurements.iter_mut().zip(times) {
        m.time_min = t;
    }
    // The same poses as a file without a time column, its lines in that order.
    let mut lined = data.clone();
    for m in &mut lined.measurements {
        m.time_min = 0.0;
    }
    lined.source_lines = (2..2 + lined.len()).collect();
    let config = Config { frame: FrameMode::Tracker, validation: Validation::SelectionOnly, ..Config::default() };
    let file_order = Config { order: thermokin_chain::MeasuringOrder::File, ..config.clone() };
    for (what, data, config) in
        [("timed", &data, &config), ("lines", &lined, &config), ("lines, --order file", &lined, &file_order)]
    {
        let report = diagnose(&robot, data, None, config).unwrap();
        let chosen: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
        eprintln!("{what}: chose {chosen:?}\n{:#?}", report.warnings);
        assert!(chosen.iter().all(|e| !e.starts_with("frame_step")), "{what}: {chosen:?}");
        assert!(
            report.warnings.iter().all(|w| !w.contains("measurement frame moved")),
            "{what}: {:?}",
            report.warnings
        );
    }
}

/// A play of ±0.015° on joint 2 (issue #48's older kept-aside case: `joint_compliance[2]` and
/// `joint_offset[2]` named, 0.126 → 0.0705 mm claimed held out, 0.1214 on fresh poses). In time order
/// it is named as joint 2's backlash, nothing flagged, fresh poses at the noise. Read as a bag — the
/// same poses with no time, so no direction of approach — the data cannot show a backlash: its poses
/// each depart along joint 2's own motion by their own amount, and before they were taken for gross errors
/// (65 of 300 here) and left out of the figures, which then claimed 0.0847 mm RMS nested against 0.1486
/// on fresh poses. Now the screen says they are a joint's motion and keeps them (`clusters.rs`,
/// `moved_joints`), the report says to measure in order, and the claim holds: nested 0.1517 mm, fresh
/// 0.1438 refitted. Fails if the play is not named in order, or if, as a bag, the fresh poses are missed
/// by more than 1.1 × the nested figure claimed, or the block is not said.
#[test]
fn a_play_read_without_its_order_claims_no_gain_fresh_poses_do_not_confirm() {
    let (robot, data) = backlash_session_on(1, 300, 7003, 0.015, 0.0);
    let (_, fresh) = backlash_session_on(1, 100, 7004, 0.015, 0.0);
    let config = Config { frame: FrameMode::Tracker, ..Config::default() };
    let rms = |r: &thermokin_diagnose::Report| {
        let h = r.holdout.as_ref().unwrap();
        (r.nested.as_ref().unwrap().selected.heldout_rms_mm, h.selected.heldout_rms_mm)
    };
    let ordered = diagnose(&robot, &data, Some(&fresh), &config).unwrap();
    let chosen: Vec<&str> = ordered.effects.iter().map(|e| e.label.as_str()).collect();
    let (nested, fresh_rms) = rms(&ordered);
    eprintln!("in time order: {chosen:?}, nested {nested:.4}, fresh {fresh_rms:.4} mm RMS");
    assert_eq!(chosen, ["backlash[2]"]);
    assert!(ordered.outliers.is_empty(), "{:?}", ordered.outliers);
    assert!(fresh_rms < 2.0 * crate::tracker::NOISE_MM * 3f64.sqrt(), "{fresh_rms}");

    let bag = |d: &Dataset| {
        let mut d = d.clone();
        d.measurements.iter_mut().for_each(|m| m.time_min = 0.0);
        d
    };
    let report = diagnose(&robot, &bag(&data), Some(&bag(&fresh)), &config).unwrap();
    let chosen: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    let (nested, fresh_rms) = rms(&report);
    eprintln!(
        "as a bag: {chosen:?}, {} gross errors, nested {nested:.4}, fresh {fresh_rms:.4} mm RMS",
        report.outliers.len()
    );
    assert!(fresh_rms <= 1.1 * nested, "claimed {nested}, fresh poses {fresh_rms}");
    let said = report
        .outlier_screen
        .clusters
        .iter()
        .any(|c| matches!(c.along, thermokin_diagnose::Along::JointMotion { joint: 2, .. }) && c.kept > 10);
    assert!(said, "{:?}", report.outlier_screen.clusters);
    assert!(report.warnings.iter().any(|w| w.contains("--order file")), "{:?}", report.warnings);
}
