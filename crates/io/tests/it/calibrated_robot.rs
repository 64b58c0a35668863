//! A calibrated robot file: every correction written and read back to the same forward model, the
//! authors' table with one profile as drift rows, targets with state columns, and located errors.

use nalgebra::Vector3;
use thermokin_chain::{LinkMass, OperatingState};
use thermokin_deform::{AfterStabilization, DriftLaw, DriftRow, JointCorrection, RobotModel, Row, TimeProfile};
use thermokin_io::{parse_robot_model_toml, parse_robot_toml, parse_targets, read_robot, robot_model_to_toml};
use thermokin_testdata::{error_mm_deg, workspace};

fn calibrated() -> RobotModel {
    let robot = read_robot(&workspace("configs/irb140.toml")).unwrap();
    let mut joints = vec![JointCorrection::NONE; 6];
    joints[0].scale = 3.5e-4;
    joints[2].cyclic_rad = [0.02f64.to_radians(), 0.0, -0.004f64.to_radians(), 0.001f64.to_radians()];
    joints[1].compliance_rad_per_nm = 0.0021f64.to_radians();
    joints[1].coupling_rad_per_nm = -0.0008f64.to_radians();
    // The shoulder's bearing tilting under the arm's moment.
    joints[1].lateral = [3e-4f64.to_radians(), -2e-4f64.to_radians(), 0.0, 0.0, 0.0, 0.0];
    // Play in joint 4's gears.
    joints[3].backlash = 0.012f64.to_radians();
    let drift = vec![
        DriftRow {
            row: Row::Joint(1),
            deviation: error_mm_deg([0.2, -0.1, 0.3, 0.01, 0.02, 0.005]),
            law: DriftLaw::Time(TimeProfile::Exponential { tau_min: 41.7 }),
        },
        DriftRow {
            row: Row::Joint(2),
            deviation: error_mm_deg([0.1, 0.0, -0.05, 0.0, 0.004, 0.0]),
            law: DriftLaw::Time(TimeProfile::Linear {
                stabilization_min: 180.0,
                after: AfterStabilization::KeepGrowing,
            }),
        },
        DriftRow {
            row: Row::Tool,
            deviation: error_mm_deg([0.01, 0.02, 0.0, 0.0, 0.0, 0.0]),
            law: DriftLaw::PerKelvin { sensors: vec![("temp_j2".into(), 22.25), ("temp_j3".into(), 21.0)] },
        },
    ];
    // Joint 3's gravity compliance known without masses: 8 weights (two per revolute link it carries).
    let mut loads = vec![Vec::new(); 6];
    loads[2] = (0..8).map(|k| (0.01 * (k as f64 - 3.5)).to_radians()).collect();
    // Joint 4's bearing tilting without masses: 2 × (3 + 2 · 2) weights.
    let mut lateral = vec![Vec::new(); 6];
    lateral[3] = (0..14).map(|k| (0.004 * (k as f64 - 6.0)).to_radians()).collect();
    RobotModel::new(robot)
        .with_joint_corrections(joints)
        .unwrap()
        .with_gravity_loads(loads)
        .unwrap()
        .with_lateral_loads(lateral)
        .unwrap()
        .with_drift(drift)
        .unwrap()
        .with_payload(Some(LinkMass { mass_kg: 1.5, com_mm: Vector3::new(40.0, 0.0, 10.0) }))
        .unwrap()
        .with_gravity(nalgebra::Unit::new_normalize(Vector3::new(0.01, 0.0, -1.0)))
}

#[test]
fn a_calibrated_robot_reads_back_to_the_same_forward_model() {
    let model = calibrated();
    let text = robot_model_to_toml(&model);
    let back = parse_robot_model_toml("cal.toml".as_ref(), &text).unwrap();
    assert_eq!(back.drift().len(), 3);
    use thermokin_chain::Approach::{Falling, Rising, Unknown};
    let mut state = OperatingState {
        time_min: Some(75.0),
        temperatures_c: vec![("temp_j2".into(), 30.0), ("temp_j3".into(), 26.0)],
        ..OperatingState::default()
    };
    // Without the directions the joints came from, a backlash cannot be evaluated: the error says so.
    let q0 = [0.1, 0.2, -0.3, 0.4, 0.5, 0.6];
    let e = back.tool_pose(&q0, &state).unwrap_err().to_string();
    assert!(e.contains("direction") && e.contains("joint 4's backlash"), "{e}");
    for k in 0..30 {
        let t = k as f64 * 0.37;
        let q = [t.sin(), 0.4 * t.cos(), -0.3 + 0.2 * t.sin(), t, 0.5 * t.cos(), -t];
        state.approach = vec![Unknown, Rising, Falling, [Rising, Falling, Unknown][k % 3], Rising, Falling];
        let a = model.tool_pose(&q, &state).unwrap();
        let b = back.tool_pose(&q, &state).unwrap();
        // Written to 1e-12 mm and degrees (coefficients in full): the same pose to 1e-9.
        assert!((a.translation.vector - b.translation.vector).norm() < 1e-9);
        assert!(a.rotation.angle_to(&b.rotation) < 1e-12);
    }
    // Joint 4's backlash, read back, moves it by its half play toward the side it came from.
    let with = |a| OperatingState { approach: vec![Unknown, Unknown, Unknown, a, Unknown, Unknown], ..state.clone() };
    let half = 0.012f64.to_radians();
    for (a, sign) in [(Rising, 1.0), (Falling, -1.0)] {
        let moved = back.joint_values(&q0, &with(a)).unwrap()[3] - back.joint_values(&q0, &with(Unknown)).unwrap()[3];
        assert!((moved - sign * half).abs() < 1e-15, "{moved:e}");
    }
    // The coupling is written with the joint it couples to, and read back.
    assert!(text.contains("compliance_coupling_deg_per_nm = -8e-4  # with joint 3"), "{text}");
    assert_eq!(back.joint_corrections()[1].coupling_rad_per_nm, model.joint_corrections()[1].coupling_rad_per_nm);
    // The robot alone would drop the corrections: refused, naming them.
    let e = parse_robot_toml("cal.toml".as_ref(), &text).unwrap_err().to_string();
    assert!(e.contains("gear-ratio") && e.contains("thermal drift") && e.contains("compliance coupling"), "{e}");
    assert!(e.contains("joint 3 (") && e.contains("gravity compliance without masses"), "{e}");
    assert!(e.contains("joint 2 (") && e.contains("lateral compliance"), "{e}");
    // The tilt moves the tool: the file without it is another robot.
    let q = [0.3, -0.4, 0.2, 0.1, 0.5, -0.2];
    let flat = text.lines().filter(|l| !l.starts_with("lateral_compliance_deg_per_nm")).collect::<Vec<_>>().join("\n");
    let flat = parse_robot_model_toml("cal.toml".as_ref(), &flat).unwrap();
    let (a, b) = (model.tool_pose(&q, &state), flat.tool_pose(&q, &state));
    let gap = (a.unwrap().translation.vector - b.unwrap().translation.vector).norm();
    assert!(gap > 0.01, "{gap}");
    // A lateral compliance of three numbers, or a revolute joint's with a slide's terms, is refused at its line.
    for (bad, says) in [("[1e-4, 2e-4, 3e-4]", "3 values"), ("[1e-4, 2e-4, 1e-7, 0, 0, 0]", "a slide's")] {
        let wrong = text
            .lines()
            .map(|l| {
                if l.starts_with("lateral_compliance_deg_per_nm") {
                    format!("lateral_compliance_deg_per_nm = {bad}")
                } else {
                    l.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        let e = parse_robot_model_toml("cal.toml".as_ref(), &wrong).unwrap_err().to_string();
        assert!(e.contains("cal.toml") && e.contains("joint[2]") && e.contains(says), "{e}");
    }
    assert!(e.contains("joint 4 (") && e.contains("lateral compliance without masses"), "{e}");
    // A weight count that is not the joint's is refused, naming the joint and its line.
    let wrong = text.replacen("gravity_load_deg = [", "gravity_load_deg = [0.1, ", 1);
    let e = parse_robot_model_toml("cal.toml".as_ref(), &wrong).unwrap_err().to_string();
    assert!(e.contains("cal.toml") && e.contains("joint[3]") && e.contains("9 gravity-load weights for the 8"), "{e}");
    let wrong = text.replacen("lateral_load_deg = [", "lateral_load_deg = [0.1, ", 1);
    let e = parse_robot_model_toml("cal.toml".as_ref(), &wrong).unwrap_err().to_string();
    assert!(
        e.contains("cal.toml") && e.contains("joint[4]") && e.contains("15 lateral-load weights for the 14"),
        "{e}"
    );
}

#[test]
fn a_drifting_robot_without_its_state_says_what_to_give() {
    let model = calibrated();
    let q = [0.0; 6];
    let approach = vec![thermokin_chain::Approach::Rising; 6];
    let no_time = OperatingState { temperatures_c: vec![("temp_j2".into(), 30.0)], approach, ..Default::default() };
    let e = model.tool_pose(&q, &no_time).unwrap_err().to_string();
    assert!(e.contains("operating time") && e.contains("joint 2"), "{e}");
    let one_sensor = OperatingState { time_min: Some(10.0), ..no_time };
    let e = model.tool_pose(&q, &one_sensor).unwrap_err().to_string();
    assert!(e.contains("temp_j3"), "{e}");
}

#[test]
fn bad_corrections_are_located() {
    let base = std::fs::read_to_string(workspace("configs/irb140.toml")).unwrap();
    let cases = [
        ("[[drift]]\nrow = 9\nerror = [0.1, 0, 0, 0, 0, 0]\nprofile = { kind = \"static\" }\n", "drift[1].row"),
        ("[[drift]]\nrow = 2\nerror = [0.1, 0, 0, 0, 0, 0]\n", "drift[1].profile"),
        (
            "[[drift]]\nrow = 2\nerror = [0.1, 0, 0, 0, 0, 0]\nper_kelvin = { sensors = [\"temp_j2\"], reference_c = [] }\n",
            "drift[1].per_kelvin",
        ),
        (
            "[[drift]]\nrow = 2\nerror = [0.1, 0, 0, 0, 0, 0]\nprofile = { kind = \"exponential\", tau_min = -3.0 }\n",
            "drift[1].profile",
        ),
        ("[payload]\nmass_kg = -2.0\n", "payload"),
    ];
    for (extra, field) in cases {
        let text = format!("{base}\n{extra}");
        let e = parse_robot_model_toml("bad.toml".as_ref(), &text).unwrap_err().to_string();
        assert!(e.contains("bad.toml") && e.contains(field), "{field}: {e}");
    }
    // A cyclic error on joint 1 as large as its motion is not a correction.
    let text = base.replacen("max_velocity = 200.0\n", "max_velocity = 200.0\ncyclic_deg = [5.0, 0.0, 0.0, 0.0]\n", 1);
    let e = parse_robot_model_toml("bad.toml".as_ref(), &text).unwrap_err().to_string();
    assert!(e.contains("bad.toml:") && e.contains("joint[1]"), "{e}");
}

#[test]
fn targets_carry_their_time_and_temperatures() {
    let text = "label,X,Y,Z,time_min,temp_j2,TEMP_J3\nP1,500,0,600,12.5,30.1,28\nP2,510,0,600,60,31,28.5\n";
    let t = parse_targets("t.csv".as_ref(), text).unwrap();
    assert_eq!(t[0].label, "P1");
    assert_eq!(t[1].state.time_min, Some(60.0));
    assert_eq!(t[1].state.temperature("temp_j2"), Some(31.0));
    assert_eq!(t[1].state.temperature("temp_J3"), Some(28.5));
    let e = parse_targets("t.csv".as_ref(), "label,X,Y,Z,time_min\nP1,1,2,3,-4\n").unwrap_err().to_string();
    assert!(e.contains("t.csv:2") && e.contains("time_min"), "{e}");
}

/// A slide's straightness (an IRB 140 on a lift) written and read back to the same forward model; on a
/// revolute joint it is refused at the joint's line.
#[test]
fn a_slides_straightness_reads_back_and_a_revolute_joint_refuses_one() {
    let text = std::fs::read_to_string(workspace("configs/irb140.toml")).unwrap();
    let lifted = thermokin_testdata::lifted_irb140_toml("straightness = [1.5e-5, -1e-5, 4e-6, 2e-7, -1e-7]\n");
    let model = parse_robot_model_toml("lift.toml".as_ref(), &lifted).unwrap();
    let c = model.joint_corrections()[0].straightness;
    assert!((c[0] - 1.5e-5f64.to_radians()).abs() < 1e-20 && c[3] == 2e-7, "{c:?}");
    assert!(model.bends());
    let back = parse_robot_model_toml("lift.toml".as_ref(), &robot_model_to_toml(&model)).unwrap();
    let plain = parse_robot_model_toml("lift.toml".as_ref(), &lifted.replace("straightness = ", "# ")).unwrap();
    let state = OperatingState::default();
    let mut moved = 0.0f64;
    for k in 0..20 {
        let t = k as f64 * 0.41;
        let q = [40.0 * k as f64, t.sin(), 0.4 * t.cos(), -0.3 + 0.2 * t.sin(), t, 0.5 * t.cos(), -t];
        let (a, b) = (model.tool_pose(&q, &state).unwrap(), back.tool_pose(&q, &state).unwrap());
        assert!((a.translation.vector - b.translation.vector).norm() < 1e-9);
        let p = plain.tool_pose(&q, &state).unwrap();
        moved = moved.max((a.translation.vector - p.translation.vector).norm());
    }
    // 1.5e-5 °/mm over 760 mm of travel turns the arm by 0.011°: a tenth of a millimetre at its reach.
    assert!(moved > 0.1, "{moved}");
    let on_revolute = text.replacen("[[joint]]\n", "[[joint]]\nstraightness = [1e-5, 0, 0, 0, 0]\n", 1);
    let e = parse_robot_model_toml("arm.toml".as_ref(), &on_revolute).unwrap_err().to_string();
    assert!(e.contains("arm.toml") && e.contains("joint[1]") && e.contains("slide's guide"), "{e}");
}

/// A lift's column whose lateral compliance is known without masses (its tilt, bend and shift weights):
/// written and read back to the same weights and tool poses; its shift weights are millimetres in the
/// file (written as given, not as degrees), its tilt and bend weights degrees.
#[test]
fn a_columns_lumped_lateral_compliance_is_written_and_read_back() {
    let text = thermokin_testdata::lifted_irb140_toml("");
    let robot = parse_robot_toml("lift.toml".as_ref(), &text).unwrap();
    let n = thermokin_deform::lumped_lateral_weights_len(robot.chain(), 0);
    assert_eq!(n, 90);
    // Tilt weights 1e-5 rad, bend 1e-8 rad/mm, shift 0.01 mm, each signed by its place.
    let weights: Vec<f64> = (0..n).map(|k| [1e-5, 1e-8, 0.01][k / 30] * if k % 2 == 0 { 1.0 } else { -0.5 }).collect();
    let mut loads = vec![Vec::new(); 7];
    loads[0] = weights.clone();
    let model = RobotModel::new(robot).with_lateral_loads(loads).unwrap();
    let written = robot_model_to_toml(&model);
    let line = written.lines().find(|l| l.starts_with("lateral_load_deg")).unwrap();
    assert!(
        line.contains("1e-2") && line.contains("-5e-3") && line.contains(&format!("{:e}", 1e-5f64.to_degrees())),
        "{line}"
    );
    let back = parse_robot_model_toml("lift.toml".as_ref(), &written).unwrap();
    for (a, b) in back.lateral_loads()[0].iter().zip(&weights) {
        assert!((a - b).abs() <= 1e-9 * b.abs(), "{a} vs {b}");
    }
    let state = OperatingState::default();
    let q = [420.0, 0.3, -0.4, 0.2, 0.1, 0.5, -0.2];
    let (a, b) = (model.tool_pose(&q, &state).unwrap(), back.tool_pose(&q, &state).unwrap());
    assert!((a.translation.vector - b.translation.vector).norm() < 1e-9);
    assert!((a.translation.vector - model.robot().chain().tool_pose(&q).unwrap().translation.vector).norm() > 0.01);
}

/// A row driven by a sensor that is not a temperature (an accelerometer's column, exported as its file
/// names it: `acc_col_x`) takes its reading under either spelling — the exported name, or the `temp_`
/// prefix the command line's `--temperature NAME=V` and a targets file's columns add (issue #59: every
/// spelling was refused as a sensor no row follows, so the guide's own command failed) — and the reading
/// moves the tool by the row's gain; a sensor the robot does not follow is still refused.
#[test]
fn a_sensor_row_takes_its_reading_as_exported_and_as_the_command_line_gives_it() {
    let text = std::fs::read_to_string(workspace("configs/irb140.toml")).unwrap();
    let text = format!(
        "{text}\n[[drift]]\nrow = 2\nerror = [0, 0, 0, 0, 0.5, 0]\nper_kelvin = {{ sensors = [\"acc_col_x\"], reference_c = [0.1] }}\n"
    );
    let model = parse_robot_model_toml("sensor.toml".as_ref(), &text).unwrap();
    let q = [0.3, -0.4, 0.2, 0.1, 0.5, -0.2];
    let reading = |name: &str, v: f64| OperatingState { temperatures_c: vec![(name.into(), v)], ..Default::default() };
    let at = |name: &str, v: f64| {
        model.check_state(&reading(name, v), false, false).unwrap();
        model.tool_pose(&q, &reading(name, v)).unwrap().translation.vector
    };
    let (exported, prefixed) = (at("acc_col_x", 1.1), at(&thermokin_io::sensor_name("acc_col_x"), 1.1));
    assert!((exported - prefixed).norm() < 1e-12, "{exported} vs {prefixed}");
    // One unit of the reading above its reference tilts joint 2's row by 0.5°: the tool moves.
    assert!((at("acc_col_x", 1.1) - at("acc_col_x", 0.1)).norm() > 1.0);
    let e = model.check_state(&reading("temp_other", 1.0), false, false).unwrap_err().to_string();
    assert!(e.contains("temp_other") && e.contains("acc_col_x"), "{e}");
    // A targets file gives the reading under the measurements' name too, read for this robot (any case);
    // without the robot's sensors that column is one nothing reads.
    let (_, sensors) = model.needs();
    let text = ",X,Y,Z,RX,RY,RZ,ACC_col_x\nP1,400,0,600,0,90,0,1.1\n";
    let read = thermokin_io::parse_target_rows_for("t.csv".as_ref(), text, &sensors).unwrap();
    let target = read.rows[0].as_ref().unwrap();
    assert_eq!(target.state.temperatures_c, vec![("acc_col_x".to_string(), 1.1)]);
    assert!(read.ignored_columns.is_empty(), "{:?}", read.ignored_columns);
    model.check_state(&target.state, false, false).unwrap();
    let plain = thermokin_io::parse_target_rows("t.csv".as_ref(), text).unwrap();
    assert!(plain.rows[0].as_ref().unwrap().state.temperatures_c.is_empty());
    assert_eq!(plain.ignored_columns, vec!["ACC_col_x".to_string()]);
}

/// A branch whose joints carry masses (a second arm on the IRB 140's upper arm) and its load on joint 2:
/// read, written and read back to the same text and the same forward model, the masses kept; the load
/// moves the tool with the branch's joints, given by name; a branch's mass that is not a finite one is
/// refused naming its file, line and key.
#[test]
fn a_branch_with_masses_and_its_load_are_written_and_read_back() {
    let text = std::fs::read_to_string(workspace("configs/irb140.toml")).unwrap();
    let branch = "\n[[branch]]\nname = \"second\"\nlink = 2\n[[branch.joint]]\nname = \"b1\"\naxis = \"y\"\noffset_mm = [0, 200, 100]\nmass_kg = 5\ncom_mm = [20, 0, -80]\n[[branch.joint]]\nname = \"b2\"\naxis = \"x\"\noffset_mm = [0, 0, -300]\nmass_kg = 3\ncom_mm = [0, 30, -150]\n";
    let load = "\n[[branch_load]]\njoint = 2\nbranch = \"second\"\nload_deg = [0.01]\n";
    let model = parse_robot_model_toml("branch.toml".as_ref(), &format!("{text}{branch}{load}")).unwrap();
    let b = &model.robot().branches()[0];
    assert!(b.carries_masses() && b.masses.len() == 2, "{b:?}");
    let written = robot_model_to_toml(&model);
    assert!(written.contains("with its masses"), "{written}");
    let back = parse_robot_model_toml("back.toml".as_ref(), &written).unwrap();
    assert_eq!(robot_model_to_toml(&back), written);
    assert_eq!(back.robot().branches(), model.robot().branches());
    let q = [0.3, -0.4, 0.2, 0.1, 0.5, -0.2];
    let state = |b1: f64, b2: f64| OperatingState {
        temperatures_c: vec![("b1".into(), b1), ("b2".into(), b2)],
        ..Default::default()
    };
    let at = |m: &RobotModel, b1, b2| m.tool_pose(&q, &state(b1, b2)).unwrap().translation.vector;
    assert!((at(&model, 30.0, -20.0) - at(&back, 30.0, -20.0)).norm() < 1e-9);
    assert!((at(&model, 30.0, -20.0) - at(&model, -60.0, 40.0)).norm() > 0.05);
    // A program gives the branch's joints per target in columns named as the joints, as measurements do.
    let (_, sensors) = model.needs();
    let program = ",X,Y,Z,RX,RY,RZ,b1,b2\nP1,400,0,600,0,90,0,30,-20\n";
    let read = thermokin_io::parse_target_rows_for("t.csv".as_ref(), program, &sensors).unwrap();
    assert_eq!(read.rows[0].as_ref().unwrap().state, state(30.0, -20.0));
    let bad = format!("{text}{}", branch.replace("mass_kg = 3", "mass_kg = -3"));
    let e = parse_robot_model_toml("bad.toml".as_ref(), &bad).unwrap_err().to_string();
    assert!(e.starts_with("bad.toml:") && e.contains("branch[1].joint[2].mass_kg: must be a finite mass"), "{e}");
}
