//! Accelerometers declared on a lift's links, through the command line (issue #59): `diagnose
//! --accelerometer NAME=LINK` reads their columns as the tilts they measure, `--export` writes a robot
//! that `fk --temperature NAME_x=…` takes the readings of, and a declaration the data or the robot cannot
//! carry is refused naming it.

use nalgebra::Vector3;
use thermokin_chain::Dataset;

use crate::cli::{stderr, stdout, thermokin, tmp};

/// `data` as a measurements file: `q1` in mm (the column), the arm's joints in degrees, the position and
/// the accelerometers' columns.
fn write(path: &std::path::Path, data: &Dataset) {
    write_columns(path, data, |j, v| if j == 0 { format!("{v}") } else { format!("{}", v.to_degrees()) });
}

/// `data` as a measurements file with seven joint columns `q1…q7` (each joint's value as `cell` writes
/// it from radians or mm), the position and every sensor column by its name.
pub(crate) fn write_columns(path: &std::path::Path, data: &Dataset, cell: impl Fn(usize, f64) -> String) {
    let mut text = String::from("q1,q2,q3,q4,q5,q6,q7,x,y,z");
    for n in &data.sensor_names {
        text.push_str(&format!(",{n}"));
    }
    text.push('\n');
    for (m, s) in data.measurements.iter().zip(&data.sensor_values) {
        let mut cells: Vec<String> = m.q.iter().enumerate().map(|(j, v)| cell(j, *v)).collect();
        cells.extend(m.position_mm.iter().map(|v| format!("{v}")));
        cells.extend(s.iter().map(|v| format!("{v}")));
        text.push_str(&cells.join(","));
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

#[test]
fn a_lifts_accelerometers_from_diagnose_to_fk() {
    let robot_path = tmp("rocking-lift.toml");
    std::fs::write(&robot_path, thermokin_testdata::lifted_irb140_toml("")).unwrap();
    let robot = thermokin_io::read_robot(&robot_path).unwrap();
    let train = thermokin_testdata::rocking_lift_session(robot.chain(), 300, 5911, Vector3::new(0.0004, -0.0003, 0.0));
    let other = thermokin_testdata::rocking_lift_session(robot.chain(), 60, 5912, Vector3::new(-0.0005, 0.0006, 0.0));
    let (m, h, out) = (tmp("rocking-train.csv"), tmp("rocking-other.csv"), tmp("rocking-cal.toml"));
    write(&m, &train);
    write(&h, &other);
    let r = robot_path.to_str().unwrap();
    let base = ["diagnose", "--robot", r, "--frame", "tracker", "--measurements", m.to_str().unwrap()];
    let declared = ["--accelerometer", "acc_base=0", "--accelerometer", "acc_top=1"];
    let mut args: Vec<&str> = base.to_vec();
    args.extend(declared);
    args.extend(["--holdout", h.to_str().unwrap(), "--export", out.to_str().unwrap(), "--noise", "0.005"]);
    let o = thermokin(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("tilt[1] (measured by acc_base)"), "{}", stdout(&o));
    assert!(stdout(&o).contains("tilt[2] (measured by acc_top)"), "{}", stdout(&o));
    assert!(
        stderr(&o).contains("column `acc_base_x` read as accelerometer acc_base's tilt (link 0)"),
        "{}",
        stderr(&o)
    );
    // The exported robot at the other session's first pose, given its readings as the guide says.
    let (q, readings) = (&other.measurements[0].q, &other.sensor_values[0]);
    let joints: Vec<String> =
        std::iter::once(format!("{}", q[0])).chain(q[1..].iter().map(|v| format!("{}", v.to_degrees()))).collect();
    let temperatures: Vec<String> = other.sensor_names.iter().zip(readings).map(|(n, v)| format!("{n}={v}")).collect();
    let o = thermokin(&[
        "fk",
        "--robot",
        out.to_str().unwrap(),
        "--joints",
        &joints.join(","),
        "--temperature",
        &temperatures.join(","),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let line = stdout(&o).lines().find(|l| l.starts_with("position_mm")).unwrap().to_string();
    let p: Vec<f64> = line.split_whitespace().skip(1).map(|v| v.parse().unwrap()).collect();
    let gap = (Vector3::new(p[0], p[1], p[2]) - other.measurements[0].position_mm).norm();
    // Where the other session measured it, to its noise (5 µm per axis: four σ of the 3-D distance).
    assert!(gap < 0.035, "{gap} mm");
    // ik and compensate take the same readings: the pose fk gave, solved on the exported robot at them
    // (ik with --temperature; compensate from a targets file's columns named as the measurements name
    // them), lands there by fk at the same readings.
    let euler = stdout(&o).lines().find(|l| l.starts_with("xyz_euler_deg")).unwrap().to_string();
    let a: Vec<f64> = euler.split_whitespace().skip(1).take(3).map(|v| v.parse().unwrap()).collect();
    let reached = |solved: &str| -> f64 {
        let o = thermokin(&[
            "fk",
            "--robot",
            out.to_str().unwrap(),
            "--joints",
            solved,
            "--temperature",
            &temperatures.join(","),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let line = stdout(&o).lines().find(|l| l.starts_with("position_mm")).unwrap().to_string();
        let r: Vec<f64> = line.split_whitespace().skip(1).map(|v| v.parse().unwrap()).collect();
        (Vector3::new(r[0], r[1], r[2]) - Vector3::new(p[0], p[1], p[2])).norm()
    };
    let pose = format!("{},{},{},{},{},{}", p[0], p[1], p[2], a[0], a[1], a[2]);
    let o = thermokin(&[
        "ik",
        "--robot",
        out.to_str().unwrap(),
        "--pose",
        &pose,
        "--seed",
        &joints.join(","),
        "--temperature",
        &temperatures.join(","),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let solved = stdout(&o)
        .lines()
        .find(|l| l.starts_with("joints_deg"))
        .unwrap()
        .split_whitespace()
        .nth(1)
        .unwrap()
        .to_string();
    // fk prints six decimals of a millimetre: the solution reproduces the pose to that.
    assert!(reached(&solved) < 1e-4, "ik: {} mm", reached(&solved));
    let targets = tmp("rocking-targets.csv");
    let names: Vec<&str> = other.sensor_names.iter().map(String::as_str).collect();
    let values: Vec<String> = readings.iter().map(|v| format!("{v}")).collect();
    let text = format!(",X,Y,Z,RX,RY,RZ,{}\nP1,{pose},{}\n", names.join(","), values.join(","));
    std::fs::write(&targets, text).unwrap();
    let solved_csv = tmp("rocking-solved.csv");
    let o = thermokin(&[
        "compensate",
        "--robot",
        out.to_str().unwrap(),
        "--targets",
        targets.to_str().unwrap(),
        "--seed",
        &joints.join(","),
        "--format",
        "joints",
        "--out",
        solved_csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let written = std::fs::read_to_string(&solved_csv).unwrap();
    let row = written.lines().find(|l| l.contains("P1")).unwrap().to_string();
    let cells: Vec<&str> = row.split(',').collect();
    let solved = cells[2..2 + joints.len()].join(",");
    assert!(reached(&solved) < 1e-4, "compensate: {} mm ({row})", reached(&solved));
    // Without the readings, fk names what it needs.
    let o = thermokin(&["fk", "--robot", out.to_str().unwrap(), "--joints", &joints.join(",")]);
    assert!(!o.status.success() && stderr(&o).contains("acc_"), "{}", stderr(&o));
    // Declarations the data or the robot cannot carry are refused, naming the sensor.
    for (flag, says) in [
        ("acc_top", "NAME=LINK"),
        ("acc_top=top", "LINK is a link number"),
        ("acc_top=3", "joint 2 below link 3 turns it"),
        ("acc_side=1", "acc_side_x"),
    ] {
        let mut args: Vec<&str> = base.to_vec();
        args.extend(["--accelerometer", flag]);
        let o = thermokin(&args);
        assert!(!o.status.success(), "{flag}");
        assert!(stderr(&o).contains(says), "{flag}: {}", stderr(&o));
    }
}
