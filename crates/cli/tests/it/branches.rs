//! A torso with two arms through the command line (issue #59): `diagnose --robot torso.urdf --tip
//! right_tool` reads the columns named as the left arm's joints as their positions, `--export` writes the
//! branch and its load, and `fk --temperature left_1=…` takes them.

use nalgebra::Vector3;
use thermokin_chain::Dataset;

use crate::cli::{stderr, stdout, thermokin, tmp};

/// `data` as a measurements file: the measured chain's joints and the left arm's in degrees, the position.
fn write(path: &std::path::Path, data: &Dataset) {
    crate::accelerometers::write_columns(path, data, |_, v| format!("{}", v.to_degrees()));
}

#[test]
fn a_torsos_other_arm_from_diagnose_to_fk() {
    let robot_path = tmp("two-armed-torso.urdf");
    std::fs::write(&robot_path, thermokin_testdata::two_armed_torso_urdf(true)).unwrap();
    let train = thermokin_testdata::two_armed_torso_session(300, 5921, 0.02);
    let other = thermokin_testdata::two_armed_torso_session(40, 5922, 0.02);
    let (m, h, out) = (tmp("torso-train.csv"), tmp("torso-other.csv"), tmp("torso-cal.toml"));
    write(&m, &train);
    write(&h, &other);
    let r = robot_path.to_str().unwrap();
    let o = thermokin(&[
        "diagnose",
        "--robot",
        r,
        "--tip",
        "right_tool",
        "--frame",
        "tracker",
        "--measurements",
        m.to_str().unwrap(),
        "--holdout",
        h.to_str().unwrap(),
        "--export",
        out.to_str().unwrap(),
        "--noise",
        "0.02",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("branch_load[2]"), "{}", stdout(&o));
    assert!(
        stderr(&o).contains("column `left_3` read as the position of joint `left_3` of branch `left_1_link`"),
        "{}",
        stderr(&o)
    );
    // The exported robot at the other session's first pose, given the left arm's joints.
    let (q, left) = (&other.measurements[0].q, &other.sensor_values[0]);
    let joints: Vec<String> = q.iter().map(|v| format!("{}", v.to_degrees())).collect();
    let readings: Vec<String> = other.sensor_names.iter().zip(left).map(|(n, v)| format!("{n}={v}")).collect();
    let fk = |extra: &[&str]| {
        let mut args = vec!["fk", "--robot", out.to_str().unwrap(), "--joints"];
        let joints = joints.join(",");
        let mut owned = vec![joints];
        owned.extend(extra.iter().map(|s| s.to_string()));
        args.extend(owned.iter().map(String::as_str));
        thermokin(&args)
    };
    let o = fk(&["--temperature", &readings.join(",")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let line = stdout(&o).lines().find(|l| l.starts_with("position_mm")).unwrap().to_string();
    let p: Vec<f64> = line.split_whitespace().skip(1).map(|v| v.parse().unwrap()).collect();
    let gap = (Vector3::new(p[0], p[1], p[2]) - other.measurements[0].position_mm).norm();
    // Where the other session measured it, to its noise (20 µm per axis: four σ of the 3-D distance).
    assert!(gap < 0.14, "{gap} mm");
    // Without them, fk names the joint it needs.
    let o = fk(&[]);
    assert!(!o.status.success() && stderr(&o).contains("left_1"), "{}", stderr(&o));
}
