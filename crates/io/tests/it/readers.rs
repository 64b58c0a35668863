//! The authors' files load; the TOML and CSV forms agree.

use thermokin_io::{read_deviation_table, read_paper_results, read_targets, read_temperature_log};
use thermokin_testdata::authors;

#[test]
fn published_deviation_tables_load() {
    let case = authors("deformations-case-study.csv");
    let t = read_deviation_table(&case).unwrap();
    assert_eq!(t.dof(), 6);
    for row in &t.joints {
        assert_eq!(thermokin_io::units::error_params_out(row).map(|v| (v * 1e9).round() / 1e9), [1.0; 6]);
    }
    let measured = authors("deformations-measured.csv");
    let m = read_deviation_table(&measured).unwrap();
    assert_eq!(m.dof(), 6);
    // Table 9 row 1 ΔX and Table 8 row 1 Δθz.
    assert_eq!(m.joints[0].translation.x, -0.0200698);
    assert!((m.joints[0].rotation.z.to_degrees() + 0.0137).abs() < 1e-12);
    // Table 9's seventh row (−0.0166 mm along X) sits on joint 6 in the CSV.
    assert!((m.joints[5].translation.x + 0.0166).abs() < 1e-3, "{:?}", m.joints[5]);
    let zero = authors("deformations-zero.csv");
    assert!(read_deviation_table(&zero).unwrap().is_zero());
}

#[test]
fn targets_and_results_load() {
    let front = authors("targets-cube-front.csv");
    let t = read_targets(&front).unwrap();
    assert_eq!(t[0].label, "P1");
    assert_eq!(t[0].pose.translation.vector.as_slice(), &[400.0, 300.0, 250.0]);
    assert_eq!(thermokin_io::units::xyz_euler_deg(&t[0].pose.rotation), [0.0, 90.0, 0.0]);
    assert_eq!(t[0].line, Some(2));
    let stat = authors("results-static-case-study.csv");
    let rows = read_paper_results(&stat).unwrap();
    assert_eq!(rows.len(), 50);
    assert_eq!(rows[0].joints[0], 2.810995f64.to_radians());
    assert_eq!(rows[49].label, "P50");
}

#[test]
fn toml_table_equals_csv_table() {
    let dir = std::env::temp_dir().join(format!("thermokin-io-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("t.csv");
    std::fs::write(&csv, "Dx,Dy,Dz,Dox,Doy,Doz\r\n1,2,3,0.1,0.2,0.3\n0,0,0,0,0,1\r\n").unwrap();
    let toml = dir.join("t.toml");
    std::fs::write(&toml, "joints = [[1, 2, 3, 0.1, 0.2, 0.3], [0, 0, 0, 0, 0, 1]]\n").unwrap();
    assert_eq!(read_deviation_table(&csv).unwrap(), read_deviation_table(&toml).unwrap());
    let log = dir.join("temps.csv");
    std::fs::write(&log, "time_min,temp_j1,temp_j2\n0,20,20\n60,25,22\n").unwrap();
    let l = read_temperature_log(&log).unwrap();
    assert_eq!(l.series("j1").unwrap(), &[20.0, 25.0]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn robot_toml_round_trip_keeps_fk_names_limits_and_masses() {
    let robot = thermokin_io::read_robot(&thermokin_testdata::workspace("configs/irb140.toml")).unwrap();
    let errs: Vec<_> = (0..6)
        .map(|i| thermokin_testdata::error_mm_deg([0.1 * i as f64, -0.2, 0.3, 0.01, -0.02, 0.03 * i as f64]))
        .collect();
    let chain = robot
        .chain()
        .with_errors(
            thermokin_testdata::error_mm_deg([1.0, 0.0, 0.0, 0.0, 0.0, 0.5]),
            &errs,
            robot.chain().tool().error,
        )
        .unwrap();
    let deformed = robot.with_chain(chain).unwrap();
    let text = thermokin_io::robot_to_toml(&deformed);
    let back = thermokin_io::parse_robot_toml(std::path::Path::new("round-trip.toml"), &text).unwrap();
    assert_eq!(back.name(), deformed.name());
    assert_eq!(back.masses(), deformed.masses());
    for (a, b) in back.chain().joints().iter().zip(deformed.chain().joints()) {
        assert_eq!(a.name, b.name);
        let (la, lb) = (a.limits.unwrap(), b.limits.unwrap());
        assert!((la.lower - lb.lower).abs() < 1e-12 && (la.upper - lb.upper).abs() < 1e-12);
    }
    for q in [[0.0; 6], [0.3, -0.2, 0.5, 1.0, -0.7, 2.0]] {
        let a = back.chain().tool_pose(&q).unwrap();
        let b = deformed.chain().tool_pose(&q).unwrap();
        assert!((a.translation.vector - b.translation.vector).norm() < 1e-9);
    }
}

#[test]
fn measurements_convert_per_joint_kind() {
    // A revolute joint in degrees and a prismatic one in millimetres: only the first becomes radians.
    use thermokin_chain::JointKind;
    let kinds = [JointKind::Revolute, JointKind::Prismatic];
    let text = "time_min,q1,q2,x,y,z\n0,90,250,1,2,3\n5,-45,10.5,4,5,6\n";
    let data = thermokin_io::parse_measurements(std::path::Path::new("m.csv"), text, &kinds).unwrap();
    assert!((data.measurements[0].q[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    assert_eq!(data.measurements[0].q[1], 250.0);
    assert_eq!(data.measurements[1].q[1], 10.5);
    // And back: the writer gives degrees and millimetres again, which read back to the same values.
    let mut out = Vec::new();
    thermokin_io::write_measurements(&mut out, &data, &kinds).unwrap();
    let again =
        thermokin_io::parse_measurements(std::path::Path::new("m.csv"), std::str::from_utf8(&out).unwrap(), &kinds)
            .unwrap();
    assert_eq!(again, data);
}

#[test]
fn numeric_columns_nothing_else_reads_are_sensors_and_text_columns_are_not() {
    use thermokin_chain::JointKind;
    let kinds = [JointKind::Revolute];
    let text = "q1,x,y,z,acc_col_x,point,temp_j1\n10,1,2,3,0.25,P1,21.5\n20,4,5,6,-0.5,P2,22.0\n";
    let path = std::path::Path::new("m.csv");
    let data = thermokin_io::parse_measurements(path, text, &kinds).unwrap();
    assert_eq!(data.sensor_names, vec!["acc_col_x".to_string()]);
    assert_eq!(data.sensor_values, vec![vec![0.25], vec![-0.5]]);
    // A temperature stays a temperature; the point names are said as not read.
    assert_eq!(data.temperature_names, vec!["j1".to_string()]);
    let fmt = thermokin_io::MeasurementFormat::default();
    std::fs::write(std::env::temp_dir().join("sensors-m.csv"), text).unwrap();
    let unread = thermokin_io::unread_columns(&std::env::temp_dir().join("sensors-m.csv"), &kinds, fmt).unwrap();
    assert_eq!(unread, vec!["point".to_string()]);
    // One cell that is not a number: the column is no sensor.
    let text = "q1,x,y,z,acc_col_x\n10,1,2,3,0.25\n20,4,5,6,n/a\n";
    assert!(thermokin_io::parse_measurements(path, text, &kinds).unwrap().sensor_names.is_empty());
}

#[test]
fn tracker_exports_in_every_dialect_and_unit_read_alike() {
    use thermokin_chain::JointKind;
    use thermokin_io::{JointUnits, MeasurementFormat, parse_measurements, parse_measurements_with};
    let kinds = [JointKind::Revolute, JointKind::Prismatic];
    let path = std::path::Path::new("m.csv");
    let commas = "time_min,q1,q2,x,y,z,temp_j1\n0,90,250,1.5,2,3,20.25\n5,-45,10.5,4,-5.125,6,21\n";
    let reference = parse_measurements(path, commas, &kinds).unwrap();
    // A European spreadsheet: semicolons, decimal commas.
    let semicolons = "time_min;q1;q2;x;y;z;temp_j1\r\n0;90;250;1,5;2;3;20,25\r\n5;-45;10,5;4;-5,125;6;21\r\n";
    assert_eq!(parse_measurements(path, semicolons, &kinds).unwrap(), reference);
    // A whitespace-separated tracker report (tabs and runs of spaces), with a comment line.
    // Its measurements keep their own file lines (the comment is line 1, the header line 2).
    let spaces = "# exported by the tracker\ntime_min\tq1  q2 x y z temp_j1\n0 90 250   1.5 2 3 20.25\n5\t-45 10.5 4 -5.125 6 21\n";
    let from_spaces = parse_measurements(path, spaces, &kinds).unwrap();
    assert_eq!(
        (&from_spaces.measurements, &from_spaces.temperature_names),
        (&reference.measurements, &reference.temperature_names)
    );
    assert_eq!((from_spaces.source_lines, &reference.source_lines), (vec![3, 4], &vec![2, 3]));
    // Radians by flag: the revolute column only (the prismatic one stays millimetres).
    let radians = format!(
        "time_min,q1,q2,x,y,z,temp_j1\n0,{},250,1.5,2,3,20.25\n5,{},10.5,4,-5.125,6,21\n",
        std::f64::consts::FRAC_PI_2,
        -std::f64::consts::FRAC_PI_4
    );
    let read = parse_measurements_with(
        path,
        &radians,
        &kinds,
        MeasurementFormat { joint_units: Some(JointUnits::Radians), ..MeasurementFormat::default() },
    )
    .unwrap();
    for (a, b) in read.measurements.iter().zip(&reference.measurements) {
        assert!((a.q[0] - b.q[0]).abs() < 1e-15 && a.q[1] == b.q[1] && a.position_mm == b.position_mm);
    }
    // A bad number in a semicolon file is located like any other.
    let bad = "q1;q2;x;y;z\n1;2;3;4;5\n1;2;drei;4;5\n";
    let e = parse_measurements(path, bad, &kinds).unwrap_err().to_string();
    assert!(e.contains("m.csv:3") && e.contains('x'), "{e}");
}

/// A file in this test process's own temporary directory.
fn temp_file(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("thermokin-io-readers-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn joints_and_poses_in_two_files_join_by_row_or_by_key() {
    use thermokin_chain::JointKind;
    use thermokin_io::{MeasurementFormat, read_measurements_joined};
    let kinds = [JointKind::Revolute; 6];
    let f = MeasurementFormat::default();
    // Rokae robot B as delivered: joints and tracker poses in two files, same row order.
    let (joints, poses) =
        (thermokin_testdata::rokae_robot_b("joints-deg.csv"), thermokin_testdata::rokae_robot_b("tracker-poses.csv"));
    let by_row = read_measurements_joined(&joints, &poses, None, &kinds, f).unwrap();
    assert_eq!(by_row.len(), 30);
    let first_pose = std::fs::read_to_string(&poses).unwrap();
    let x0: f64 = first_pose.lines().nth(1).unwrap().split(',').next().unwrap().parse().unwrap();
    assert_eq!(by_row.measurements[0].position_mm.x, x0);
    assert!(by_row.has_orientation());
    // By a key, the poses in another order and with their own extra column.
    let j = temp_file("j.csv", "point,q1,q2,q3,q4,q5,q6,temp_j2\nP1,0,10,20,0,0,0,21.5\nP2,5,15,25,0,0,0,22.0\n");
    let p = temp_file("p.csv", "point;x;y;z;note\nP2;2,5;0;0;b\nP1;1,5;0;0;a\n");
    let keyed = read_measurements_joined(&j, &p, Some("point"), &kinds, f).unwrap();
    let xs: Vec<f64> = keyed.measurements.iter().map(|m| m.position_mm.x).collect();
    assert_eq!(xs, [1.5, 2.5]);
    assert_eq!(keyed.measurements[1].q[1], 15f64.to_radians());
    assert_eq!(keyed.temperature_names, ["j2"]);
    // Every failure names the file, the line and the field.
    let cases = [
        ("p-nokey.csv", "x,y,z\n1,0,0\n2,0,0\n", "p-nokey.csv:1: point: missing key column"),
        ("p-dup.csv", "point,x,y,z\nP1,1,0,0\nP1,2,0,0\n", "p-dup.csv:3: point: `P1` again (first on line 2)"),
        ("p-miss.csv", "point,x,y,z\nP1,1,0,0\nP3,2,0,0\n", "j.csv:3: point: `P2` has no pose"),
        ("p-extra.csv", "point,x,y,z\nP1,1,0,0\nP2,2,0,0\nP9,3,0,0\n", "p-extra.csv:4: point: `P9` has no joints"),
        ("p-bad.csv", "point,x,y,z\nP1,1,0,0\nP2,two,0,0\n", "p-bad.csv:3: x"),
    ];
    for (name, text, needle) in cases {
        let p = temp_file(name, text);
        let err = read_measurements_joined(&j, &p, Some("point"), &kinds, f).unwrap_err().to_string();
        assert!(err.contains(needle), "{name}: {err}");
    }
    let short = temp_file("p-short.csv", "x,y,z\n1,0,0\n");
    let err = read_measurements_joined(&j, &short, None, &kinds, f).unwrap_err().to_string();
    assert!(err.contains("2 joint rows") && err.contains("but 1 poses"), "{err}");
}

#[test]
fn orientation_columns_in_each_convention_read_alike() {
    use thermokin_chain::JointKind;
    use thermokin_io::{MeasurementFormat, Orientation, parse_measurements_with};
    let kinds = [JointKind::Revolute; 6];
    let path = std::path::Path::new("m.csv");
    // One rotation written three ways: X-Y-Z Euler, roll-pitch-yaw, a quaternion (w, x, y, z).
    let r = nalgebra::UnitQuaternion::from_euler_angles(0.3, -0.4, 1.1);
    let [a, b, c] = thermokin_io::units::xyz_euler_deg(&r);
    let [roll, pitch, yaw] = thermokin_io::units::ros_rpy_deg(&r);
    let head = "q1,q2,q3,q4,q5,q6,x,y,z";
    let texts = [
        (format!("{head},rx,ry,rz\n0,0,0,0,0,0,1,2,3,{a},{b},{c}\n"), Orientation::XyzEuler),
        (format!("{head},rx,ry,rz\n0,0,0,0,0,0,1,2,3,{roll},{pitch},{yaw}\n"), Orientation::Rpy),
        (format!("{head},qw,qx,qy,qz\n0,0,0,0,0,0,1,2,3,{},{},{},{}\n", r.w, r.i, r.j, r.k), Orientation::Quaternion),
    ];
    for (text, orientation) in texts {
        let f = MeasurementFormat { orientation, ..MeasurementFormat::default() };
        let d = parse_measurements_with(path, &text, &kinds, f).unwrap();
        let angle = d.measurements[0].orientation.unwrap().angle_to(&r);
        assert!(angle < 1e-12, "{orientation:?}: {angle}");
    }
    // A quaternion that is not of unit norm is refused with its line and columns.
    let f = MeasurementFormat { orientation: Orientation::Quaternion, ..MeasurementFormat::default() };
    let err = parse_measurements_with(path, &format!("{head},qw,qx,qy,qz\n0,0,0,0,0,0,1,2,3,2,0,0,0\n"), &kinds, f)
        .unwrap_err()
        .to_string();
    assert!(err.contains("m.csv:2: qw,qx,qy,qz") && err.contains("norm"), "{err}");
}

#[test]
fn a_profile_file_is_checked_against_the_robots_joints() {
    // A temperature profile naming one sensor per joint: right for six joints, refused (named) for five.
    // Before, the file was checked against zero joints and refused for every robot.
    let dir = std::env::temp_dir().join(format!("thermokin-profile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("warmup.toml");
    let sensors: Vec<String> = (1..=6).map(|j| format!("\"temp_j{j}\"")).collect();
    let series: Vec<String> = (1..=6).map(|j| format!("[\"temp_j{j}\", [20.0, 2{j}.0]]")).collect();
    let text = format!(
        "kind = \"temperature\"\nsensors = [{}]\n[log]\ntimes_min = [0.0, 60.0]\nsensors = [{}]\n",
        sensors.join(", "),
        series.join(", ")
    );
    std::fs::write(&path, text).unwrap();
    let spec = thermokin_deform::ProfileSpec::TomlFile(path.clone());
    let profile = thermokin_io::read_profile_spec(&spec, 6).unwrap();
    assert!(matches!(profile, thermokin_deform::TimeProfile::Temperature { ref sensors, .. } if sensors.len() == 6));
    let err = thermokin_io::read_profile_spec(&spec, 5).unwrap_err().to_string();
    assert!(err.contains("warmup.toml") && err.contains("6 sensors named for 5 joints"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
