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

/// The same torso with the robot file giving every link's mass (the masses the truth sags under): the
/// other arm's load on the torso's bend is the torque of its masses, and with the chain's own the bend's
/// compliance under everything it carries — one compliance, where the lumped form takes ten weights
/// beside the bend's own — recovered within three standard deviations of the truth's 1.5e-4 rad per
/// N·m. The other session is reached at the noise, and the export, given the left arm's joints, is the
/// model scored.
#[test]
fn a_torsos_other_arm_with_its_masses_loads_it_by_their_torque() {
    let options = thermokin_urdf::ImportOptions { base: None, tip: Some("right_tool".into()) };
    let urdf = thermokin_testdata::two_armed_torso_urdf_with_masses(true);
    let two = thermokin_urdf::import_urdf(&urdf, "torso.urdf", &options).unwrap().robot;
    assert!(two.branches()[0].carries_masses() && two.masses().iter().all(Option::is_some));
    let train = session(300, 5911, NOISE_MM);
    let other = session(120, 5912, NOISE_MM);
    let config = Config { frame: FrameMode::Tracker, validation: Validation::SelectionOnly, ..Config::default() };
    let report = diagnose(&two, &train, Some(&other), &config).unwrap();
    let chosen: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    let h = report.holdout.as_ref().unwrap();
    eprintln!(
        "{chosen:?}; other session refitted {:.4}, as exported {:.4} mm RMS",
        h.selected.heldout_rms_mm, h.same_frame.selected.heldout_rms_mm
    );
    let truth_deg = 1.5e-4_f64.to_degrees();
    assert!(!chosen.iter().any(|c| c.starts_with("joint_compliance[2]")), "{chosen:?}");
    let (label, name) = ("branch_load[2]", "k_deg_per_Nm");
    let e = report.effects.iter().find(|e| e.label.starts_with(label)).unwrap_or_else(|| panic!("{chosen:?}"));
    assert_eq!(e.parameters.len(), 1, "{:?}", e.parameters);
    let (_, p) = e.parameters.iter().find(|(k, _)| k.ends_with(name)).unwrap();
    let std = p.std.unwrap();
    eprintln!("{label}: {:.6e} ± {:.1e} deg/N·m (truth {truth_deg:.6e})", p.value, std);
    assert!((p.value - truth_deg).abs() < 3.0 * std, "{label}: {} ± {std} against {truth_deg}", p.value);
    assert!(chosen.iter().any(|c| c.contains("with masses")), "{chosen:?}");
    let noise_rms = NOISE_MM * 3f64.sqrt();
    assert!(h.selected.heldout_rms_mm < 2.0 * noise_rms && h.same_frame.selected.heldout_rms_mm < 2.0 * noise_rms);
    let e = crate::tracker::export_given_the_columns(&two, &report, &other, "with its masses");
    assert!(e.contains("left_1"), "{e}");
    // The export carries the branch's masses, which its load's torque is computed from.
    let text = thermokin_io::robot_model_to_toml(&report.export_model(&two, None, "exported").unwrap());
    let branch = &text[text.find("[[branch]]").unwrap()..];
    assert_eq!(branch.matches("mass_kg").count(), 5, "{branch}");
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

/// An elastic torso (issue #59's humanoid, as the real one is shaped): every joint five times as
/// compliant — the torso's bend sags by degrees over the poses — and the torso's bearing tilting under
/// the moment of both arms, measured by a camera system at 0.5 mm per axis, 400 poses fitted and 100 of
/// another draw held out, nested. The torso's sag is beyond the size an industrial arm's bounds allow,
/// and traded with no other block: it stands, named first, and with the left arm's joints the other
/// session is reached near the noise; the same columns as drivers, or none, stay above it.
#[test]
fn an_elastic_torsos_sag_beyond_an_arms_bounds_is_what_the_poses_show() {
    let elastic = thermokin_testdata::Elastic { joints: 5.0, torso_bearing: 5e-5 };
    let noise_mm = 0.5;
    let train = thermokin_testdata::elastic_torso_session(400, 5941, noise_mm, elastic);
    let other = thermokin_testdata::elastic_torso_session(100, 5942, noise_mm, elastic);
    let config = Config { frame: FrameMode::Tracker, noise_mm: Some(noise_mm), ..Config::default() };
    let without = |d: &Dataset| Dataset { sensor_names: Vec::new(), sensor_values: Vec::new(), ..d.clone() };
    let mut mean = Vec::new();
    for (what, robot, train, other) in [
        ("branch", robot(true), train.clone(), other.clone()),
        ("as drivers", robot(false), train.clone(), other.clone()),
        ("no columns", robot(false), without(&train), without(&other)),
    ] {
        let report = diagnose(&robot, &train, Some(&other), &config).unwrap();
        let chosen: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
        let h = report.holdout.as_ref().unwrap();
        let nested = report.nested.as_ref().unwrap().selected.heldout_mean_mm;
        eprintln!(
            "{what}: {chosen:?}; nested {nested:.4}, other session refitted {:.4} mm mean",
            h.selected.heldout_mean_mm
        );
        // The torso's sag is chosen on every set, never refused for its size.
        assert!(chosen.iter().any(|c| c.starts_with("joint_compliance[2]")), "{what}: {chosen:?}");
        assert!(
            report.identifiability.not_identifiable.iter().all(|r| !r.effect.starts_with("joint_compliance[2]")),
            "{:?}",
            report.identifiability.not_identifiable
        );
        if what == "branch" {
            assert!(chosen.iter().any(|c| c.starts_with("branch_load[2]")), "{chosen:?}");
        }
        mean.push((nested, h.selected.heldout_mean_mm));
    }
    // The noise alone: σ · 2√(2/π) mean.
    let noise_mean = noise_mm * 1.595_769_121_6;
    let (branch, drivers, none) = (mean[0], mean[1], mean[2]);
    assert!(branch.0 < 1.25 * noise_mean && branch.1 < 1.25 * noise_mean, "{branch:?}");
    assert!(drivers.1 <= none.1 && none.1 > 2.0 * branch.1, "{drivers:?} {none:?} {branch:?}");
}

/// The elastic torso's bearing tilting under both arms (3e-4 rad per N·m, up to ~0.5°): with every
/// joint's lateral compliance offered (`--lateral joints`), the left arm's joints give the moment of what
/// hangs from the torso across its turning axis too — `lateral_branch_load[1]` is chosen and the other
/// session is reached near the noise; the robot the diagnosis writes, given the left arm's joints, is the
/// model it scored.
#[test]
fn an_elastic_torsos_bearing_tilts_under_the_other_arm_it_logs() {
    let elastic = thermokin_testdata::Elastic { joints: 5.0, torso_bearing: 3e-4 };
    let noise_mm = 0.5;
    let train = thermokin_testdata::elastic_torso_session(400, 5941, noise_mm, elastic);
    let other = thermokin_testdata::elastic_torso_session(100, 5942, noise_mm, elastic);
    let config = Config {
        frame: FrameMode::Tracker,
        noise_mm: Some(noise_mm),
        lateral: thermokin_identify::Lateral::Joints,
        ..Config::default()
    };
    let two = robot(true);
    let report = diagnose(&two, &train, Some(&other), &config).unwrap();
    let chosen: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    let h = report.holdout.as_ref().unwrap();
    let nested = report.nested.as_ref().unwrap().selected.heldout_mean_mm;
    eprintln!("{chosen:?}; nested {nested:.4}, other session refitted {:.4} mm mean", h.selected.heldout_mean_mm);
    assert!(chosen.iter().any(|c| c.starts_with("lateral_branch_load[1]")), "{chosen:?}");
    let noise_mean = noise_mm * 1.595_769_121_6;
    assert!(h.selected.heldout_mean_mm < 1.25 * noise_mean && nested < 1.25 * noise_mean, "{nested}");
    crate::tracker::export_given_the_columns(&two, &report, &other, "lateral = true");
}

/// The elastic torso with its robot file giving every link's mass (camera 0.5 mm, 400 → 100, nested):
/// the torso bend's compliance under everything it carries, the other arm by its logged joints, is
/// chosen in the selection on all poses and in every outer fold — as a separate compliance beside the
/// bend's own under the chain's masses, two outer folds of five had left it out (their columns nearly
/// alike, the same stiffness fitted twice), and the nested mean was 1.46 mm — and both the nested and
/// the other session's mean are near the noise's.
#[test]
fn an_elastic_torso_with_its_masses_sags_by_their_torque_in_every_fold() {
    let elastic = thermokin_testdata::Elastic { joints: 5.0, torso_bearing: 5e-5 };
    let noise_mm = 0.5;
    let train = thermokin_testdata::elastic_torso_session(400, 5941, noise_mm, elastic);
    let other = thermokin_testdata::elastic_torso_session(100, 5942, noise_mm, elastic);
    let config = Config { frame: FrameMode::Tracker, noise_mm: Some(noise_mm), ..Config::default() };
    let options = thermokin_urdf::ImportOptions { base: None, tip: Some("right_tool".into()) };
    let urdf = thermokin_testdata::two_armed_torso_urdf_with_masses(true);
    let two = thermokin_urdf::import_urdf(&urdf, "torso.urdf", &options).unwrap().robot;
    let report = diagnose(&two, &train, Some(&other), &config).unwrap();
    let chosen: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    let nested = report.nested.as_ref().unwrap();
    let h = report.holdout.as_ref().unwrap();
    eprintln!(
        "{chosen:?}; nested {:.4}, other session refitted {:.4} mm mean",
        nested.selected.heldout_mean_mm, h.selected.heldout_mean_mm
    );
    let whole = |labels: &[String]| labels.iter().any(|l| l.starts_with("branch_load[2]") && l.contains("with masses"));
    assert!(whole(&chosen.iter().map(|c| c.to_string()).collect::<Vec<_>>()), "{chosen:?}");
    for f in &nested.folds {
        assert!(whole(&f.effects), "outer fold {}: {:?}", f.fold, f.effects);
    }
    let noise_mean = noise_mm * 1.595_769_121_6;
    assert!(nested.selected.heldout_mean_mm < 1.25 * noise_mean, "{}", nested.selected.heldout_mean_mm);
    assert!(h.selected.heldout_mean_mm < 1.25 * noise_mean, "{}", h.selected.heldout_mean_mm);
}
