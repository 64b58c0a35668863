//! A lift on a chassis that rocks (issue #59): the IRB 140 on a prismatic column whose chassis tilts
//! under the arm's moment about a point of its own, and whose column bends beyond it the more the higher
//! it stands, measured height by height (no time column); an accelerometer on the chassis (link 0) and
//! one on the carriage (link 1), each mounted at its own yaw and slightly off level. Fitted on one
//! session, scored on another whose chassis rests differently. The truth is written here with
//! isometries about the pivots, independently of the diagnosis's rows.

use nalgebra::Vector3;
use thermokin_chain::{Dataset, Robot};
use thermokin_diagnose::{Accelerometer, Config, Validation, diagnose};
use thermokin_identify::FrameMode;
use thermokin_testdata::rocking_lift_session as session;

/// The lift's robot: joint 1 the column (a slide along z, 0–800 mm), then the IRB 140.
fn lift() -> Robot {
    let text = thermokin_testdata::lifted_irb140_toml("");
    thermokin_io::parse_robot_toml("lift.toml".as_ref(), &text).unwrap()
}

/// The diagnosis's settings for the lift (tracker frame, the selection alone): as they are, and with the
/// two accelerometers declared on the chassis (link 0) and the carriage (link 1).
fn configs() -> (Config, Config) {
    let base = Config { frame: FrameMode::Tracker, validation: Validation::SelectionOnly, ..Config::default() };
    let declared = declared(&base);
    (base, declared)
}

/// `base` with the lift's two accelerometers declared: `acc_base` on the chassis (link 0), `acc_top` on
/// the carriage (link 1).
pub fn declared(base: &Config) -> Config {
    Config {
        accelerometers: vec![
            Accelerometer { name: "acc_base".into(), link: 0 },
            Accelerometer { name: "acc_top".into(), link: 1 },
        ],
        ..base.clone()
    }
}

/// Declared, the two accelerometers name the chassis's tilt and the column's bend and take the other
/// session to the noise in both protocols; without them, or read as free drivers of rows, the same
/// poses are far from it.
#[test]
fn a_rocking_lifts_accelerometers_are_read_as_the_tilts_they_measure() {
    let robot = lift();
    let train = session(robot.chain(), 300, 5901, Vector3::new(0.0004, -0.0003, 0.0));
    // The other session: the chassis rests 0.05° otherwise.
    let other = session(robot.chain(), 150, 5902, Vector3::new(-0.0005, 0.0006, 0.0));
    let (base, declared) = configs();
    let without = |d: &Dataset| Dataset { sensor_names: Vec::new(), sensor_values: Vec::new(), ..d.clone() };
    let noise_rms = crate::tracker::NOISE_MM * 3f64.sqrt();
    let mut rms = Vec::new();
    for (what, config, train, other) in [
        ("declared", &declared, train.clone(), other.clone()),
        ("as drivers", &base, train.clone(), other.clone()),
        ("no columns", &base, without(&train), without(&other)),
    ] {
        let report = diagnose(&robot, &train, Some(&other), config).unwrap();
        let chosen: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
        let h = report.holdout.as_ref().unwrap();
        eprintln!(
            "{what}: {chosen:?}; other session refitted {:.4}, as exported {:.4} mm RMS",
            h.selected.heldout_rms_mm, h.same_frame.selected.heldout_rms_mm
        );
        if what == "declared" {
            assert!(chosen.contains(&"tilt[1] (measured by acc_base)"), "{chosen:?}");
            assert!(chosen.contains(&"tilt[2] (measured by acc_top)"), "{chosen:?}");
            // The chassis's sensor's mounting and the point it rocks about, as the truth has them: its
            // yaw 0.35 rad, the pivot 150, −100, 0 mm from the base — −300 from the column's row.
            let tilt = report.effects.iter().find(|e| e.label.starts_with("tilt[1]")).unwrap();
            let value = |n: &str| tilt.parameters[&format!("{}.{n}", tilt.label)].value;
            assert!((value("mounting_yaw_deg") - 0.35f64.to_degrees()).abs() < 1.5, "{:?}", tilt.parameters);
            for (n, truth) in [("pivot_x_mm", 150.0), ("pivot_y_mm", -100.0), ("pivot_z_mm", -300.0)] {
                assert!((value(n) - truth).abs() < 10.0, "{n}: {:?}", tilt.parameters);
            }
            exported_robot_takes_the_readings(&robot, &report, &other);
        }
        rms.push((h.selected.heldout_rms_mm, h.same_frame.selected.heldout_rms_mm));
    }
    let (declared_rms, drivers, none) = (rms[0], rms[1], rms[2]);
    assert!(declared_rms.0 < 2.0 * noise_rms && declared_rms.1 < 2.0 * noise_rms, "{declared_rms:?}");
    assert!(none.0 > 5.0 * declared_rms.0, "{none:?} vs {declared_rms:?}");
    assert!(drivers.0 > 2.0 * declared_rms.0, "{drivers:?} vs {declared_rms:?}");
}

/// The robot `--export` writes, read back from its text, given each pose's raw accelerometer readings as
/// `fk --temperature` gives them (`temp_acc_base_x=…`): it stands where the other session measured, to
/// the hold-out's own figure (the frame it was trained in is the one the other session is measured in);
/// without its readings it says what it needs.
fn exported_robot_takes_the_readings(robot: &Robot, report: &thermokin_diagnose::Report, other: &Dataset) {
    let e = crate::tracker::export_given_the_columns(robot, report, other, "tilt = { sensor = \"acc_base\"");
    assert!(e.contains("acc_base") || e.contains("acc_top"), "{e}");
}

/// Declared in the robot file (`[[accelerometer]]`, written back by the export) instead of on the command
/// line: the same diagnosis. A link the robot does not have is refused at its line.
#[test]
fn accelerometers_declared_in_the_robot_file_are_the_flags() {
    let text = thermokin_testdata::lifted_irb140_toml("");
    let declared = format!(
        "{text}\n[[accelerometer]]\nname = \"acc_base\"\nlink = 0\n\n[[accelerometer]]\nname = \"acc_top\"\nlink = 1\n"
    );
    let in_file = thermokin_io::parse_robot_toml("lift.toml".as_ref(), &declared).unwrap();
    assert_eq!(in_file.accelerometers().len(), 2);
    let robot = lift();
    let train = session(robot.chain(), 150, 5921, Vector3::new(0.0004, -0.0003, 0.0));
    let (base, flags) = configs();
    let (a, b) = (diagnose(&robot, &train, None, &flags).unwrap(), diagnose(&in_file, &train, None, &base).unwrap());
    assert_eq!(a.text().to_string(), b.text().to_string());
    // The export keeps the declaration.
    let export = thermokin_io::robot_model_to_toml(&b.export_model(&in_file, None, "lift").unwrap());
    assert!(export.contains("[[accelerometer]]\nname = \"acc_top\"\nlink = 1"), "{export}");
    let wrong = format!("{text}\n[[accelerometer]]\nname = \"acc_top\"\nlink = 9\n");
    let e = thermokin_io::parse_robot_toml("lift.toml".as_ref(), &wrong).unwrap_err().to_string();
    assert!(e.contains("lift.toml") && e.contains("acc_top") && e.contains("link 9"), "{e}");
}

/// Sensors with offsets (issue #59): the other session's accelerometers remounted — their readings
/// offset by a few hundredths of g, a tilt of up to half a degree the robot does not have. The refitted
/// protocol takes each session's readings on its own reference (its mean direction, as it refits the
/// registration), so the offsets cost nothing there: declared, the other session is at the noise (1.73
/// mm RMS when the training session's references were kept); read as drivers, no worse than without
/// the columns.
#[test]
fn a_remounted_sensor_is_read_on_its_sessions_own_reference() {
    let robot = lift();
    let train = session(robot.chain(), 300, 5901, Vector3::new(0.0004, -0.0003, 0.0));
    let mut other = session(robot.chain(), 150, 5902, Vector3::new(-0.0005, 0.0006, 0.0));
    for r in &mut other.sensor_values {
        r[0] -= 0.03;
        r[3] += 0.08;
        r[4] -= 0.05;
    }
    let (base, declared) = configs();
    let without = |d: &Dataset| Dataset { sensor_names: Vec::new(), sensor_values: Vec::new(), ..d.clone() };
    let mut refitted = Vec::new();
    for (what, config, train, other) in [
        ("declared", &declared, train.clone(), other.clone()),
        ("as drivers", &base, train.clone(), other.clone()),
        ("no columns", &base, without(&train), without(&other)),
    ] {
        let report = diagnose(&robot, &train, Some(&other), config).unwrap();
        let h = report.holdout.as_ref().unwrap();
        eprintln!(
            "{what}: refitted {:.4}, as exported {:.4} mm RMS",
            h.selected.heldout_rms_mm, h.same_frame.selected.heldout_rms_mm
        );
        refitted.push(h.selected.heldout_rms_mm);
    }
    let noise_rms = crate::tracker::NOISE_MM * 3f64.sqrt();
    assert!(refitted[0] < 2.0 * noise_rms, "{refitted:?}");
    assert!(refitted[1] <= refitted[2], "{refitted:?}");
}
