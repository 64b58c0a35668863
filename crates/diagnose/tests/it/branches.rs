//! A torso carrying two arms (issue #59): measured at the right arm's tool while the robot logs the left
//! arm's joints, every joint sagging under masses the robot file does not carry. The truth is written in
//! `thermokin_testdata::two_armed_torso_session` with its own rotations and torques, independently of the
//! diagnosis's functions.

use thermokin_chain::{Dataset, Robot};
use thermokin_diagnose::{Config, Validation, diagnose};
use thermokin_identify::FrameMode;
use thermokin_testdata::{two_armed_torso_session as session, two_armed_torso_urdf};

/// The robot file: the tree with both arms (the left a branch of the measured chain), or the measured
/// chain alone.
fn robot(left_arm: bool) -> Robot {
    let options = thermokin_urdf::ImportOptions { base: None, tip: Some("right_tool".into()) };
    thermokin_urdf::import_urdf(&two_armed_torso_urdf(left_arm), "torso.urdf", &options).unwrap().robot
}

const NOISE_MM: f64 = 0.02;

/// With the two-armed robot file, the left arm's columns are its joints' positions: what it carries
/// loads the torso, and the other session is reached at the noise; the same columns read as drivers of
/// rows on the one-chain file, or left out, stay far from it.
#[test]
fn a_torsos_other_arm_loads_it_through_its_logged_joints() {
    let two = robot(true);
    assert_eq!(two.branches().len(), 1, "{:?}", two.branches());
    assert_eq!(two.branches()[0].joints.len(), 5);
    let train = session(300, 5911, NOISE_MM);
    let other = session(120, 5912, NOISE_MM);
    let config = Config { frame: FrameMode::Tracker, validation: Validation::SelectionOnly, ..Config::default() };
    let without = |d: &Dataset| Dataset { sensor_names: Vec::new(), sensor_values: Vec::new(), ..d.clone() };
    let mut rms = Vec::new();
    for (what, robot, train, other) in [
        ("branch", two.clone(), train.clone(), other.clone()),
        ("as drivers", robot(false), train.clone(), other.clone()),
        ("no columns", robot(false), without(&train), without(&other)),
    ] {
        let report = diagnose(&robot, &train, Some(&other), &config).unwrap();
        let chosen: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
        let h = report.holdout.as_ref().unwrap();
        eprintln!(
            "{what}: {chosen:?}; other session refitted {:.4}, as exported {:.4} mm RMS",
            h.selected.heldout_rms_mm, h.same_frame.selected.heldout_rms_mm
        );
        if what == "branch" {
            assert!(chosen.iter().any(|c| c.starts_with("branch_load[2]")), "{chosen:?}");
            exported_robot_takes_the_other_arms_joints(&robot, &report, &other);
        }
        rms.push((h.selected.heldout_rms_mm, h.same_frame.selected.heldout_rms_mm));
    }
    let noise_rms = NOISE_MM * 3f64.sqrt();
    let (branch, drivers, none) = (rms[0], rms[1], rms[2]);
    assert!(branch.0 < 2.0 * noise_rms && branch.1 < 2.0 * noise_rms, "{branch:?}");
    assert!(drivers.0 > 2.0 * branch.0, "{drivers:?} vs {branch:?}");
    assert!(none.0 > 3.0 * branch.0, "{none:?} vs {branch:?}");
}

/// The robot `--export` writes, read back from its text (the branch and its loads in it), given each
/// pose's left-arm joints as `fk --temperature` gives readings: it stands where the other session
/// measured, to the hold-out's own figure; without them it says which joint it needs.
fn exported_robot_takes_the_other_arms_joints(robot: &Robot, report: &thermokin_diagnose::Report, other: &Dataset) {
    let e = crate::tracker::export_given_the_columns(robot, report, other, "[[branch_load]]");
    assert!(e.contains("left_1"), "{e}");
}

/// A branch logged in part cannot load the torso: refused, naming the branch and the joint missing.
#[test]
fn a_branch_logged_in_part_is_refused_by_name() {
    let data = session(40, 5913, NOISE_MM);
    let part = data.without_sensor_columns(&["left_3".to_string()]);
    let config = Config { frame: FrameMode::Tracker, validation: Validation::SelectionOnly, ..Config::default() };
    let e = diagnose(&robot(true), &part, None, &config).unwrap_err().to_string();
    assert!(e.contains("left_1_link") && e.contains("left_3"), "{e}");
}
