//! The real-data table (`docs/real-data.md`, written by `cargo xtask real-data`) kept true: its commands
//! rerun here give its figures, and the README and the docs quote them as they are (issue #50).

use crate::cli::{UR10_SERIES_C, stderr, thermokin, tmp};

/// One row of the table: the set, its poses, and the `nominal → chosen` figures of each protocol.
#[derive(Debug)]
struct Row {
    set: String,
    poses: String,
    nested: String,
    exported: String,
    refitted: String,
    effects: String,
}

/// The table's rows and its commands, in order.
fn table() -> (Vec<Row>, Vec<String>) {
    let text = std::fs::read_to_string(thermokin_testdata::workspace("docs/real-data.md")).unwrap();
    let rows = text
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| set") && !l.starts_with("|---"))
        .map(|l| {
            let c: Vec<String> = l.trim_matches('|').split('|').map(|x| x.trim().to_string()).collect();
            Row {
                set: c[0].clone(),
                poses: c[1].clone(),
                nested: c[2].clone(),
                exported: c[3].clone(),
                refitted: c[4].clone(),
                effects: c[5].clone(),
            }
        })
        .collect();
    let commands = text.lines().filter_map(|l| l.strip_prefix("thermokin ")).map(str::to_string).collect();
    (rows, commands)
}

fn pair(report: &serde_json::Value, path: &[&str]) -> String {
    let at = path.iter().fold(report, |v, k| &v[*k]);
    let mean = |k: &str| at[k]["heldout_mean_mm"].as_f64();
    match (mean("nominal"), mean("selected")) {
        (Some(n), Some(s)) => format!("{n:.4} → {s:.4}"),
        _ => "—".into(),
    }
}

/// Every command of the table, rerun (series A's week included: a minute of the test's time), gives the
/// figures the table holds.
#[test]
fn the_real_data_table_is_what_the_commands_give() {
    let (rows, commands) = table();
    assert_eq!(rows.len(), 6, "{rows:?}");
    assert_eq!(commands.len(), rows.len());
    for (i, (row, command)) in rows.iter().zip(&commands).enumerate() {
        let json = tmp(&format!("real-{i}.json")).display().to_string();
        let mut args: Vec<&str> = command.split_whitespace().collect();
        args.extend(["--quiet", "--json", &json]);
        let o = thermokin(&args);
        assert!(o.status.success(), "{}: {}", row.set, stderr(&o));
        let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        let poses = report["poses"].as_array().unwrap().len() + report["outliers"].as_array().unwrap().len();
        assert_eq!(row.poses, poses.to_string(), "{}", row.set);
        assert_eq!(row.nested, pair(&report, &["nested"]), "{}: nested", row.set);
        assert_eq!(row.exported, pair(&report, &["holdout", "same_frame"]), "{}: as exported", row.set);
        assert_eq!(row.refitted, pair(&report, &["holdout"]), "{}: refitted", row.set);
        assert_eq!(row.effects, report["effects"].as_array().unwrap().len().to_string(), "{}", row.set);
    }
}

/// The README and docs/diagnosis.md quote the table's figures as the table holds them: each set's chosen
/// model's nested figure, and where the set has a hold-out file, both protocols'.
#[test]
fn the_readme_and_the_docs_quote_the_real_data_table() {
    let (rows, _) = table();
    let chosen = |cell: &str| cell.split(" → ").nth(1).map(str::to_string);
    // The README's table quotes every cell whole: the nominal figure beside the chosen one.
    let readme = std::fs::read_to_string(thermokin_testdata::workspace("README.md")).unwrap();
    for row in &rows {
        for cell in [&row.nested, &row.exported, &row.refitted].into_iter().filter(|c| c.contains(" → ")) {
            assert!(readme.contains(cell.as_str()), "README.md does not quote {} {cell} (docs/real-data.md)", row.set);
        }
    }
    for file in ["README.md", "docs/diagnosis.md"] {
        let text = std::fs::read_to_string(thermokin_testdata::workspace(file)).unwrap();
        for row in &rows {
            for (what, cell) in [("nested", &row.nested), ("as exported", &row.exported), ("refitted", &row.refitted)] {
                let Some(figure) = chosen(cell) else { continue };
                assert!(
                    text.contains(&figure),
                    "{file} does not quote {} {what} {figure} mm (docs/real-data.md)",
                    row.set
                );
            }
        }
    }
}

/// Issue #62: the real UR10's diagnosis (series C) exported, then written as Universal Robots' kinematics
/// YAML: the description's chain built here from the YAML's numbers alone — `base_link` turned π about z
/// to `base_link_inertia`, each origin `x y z` and URDF `roll pitch yaw` then a turn about z by the joint
/// value, `tool0` = `wrist_3_link` — and the tool point the header names, put the tool where the TOML
/// export's geometry does at every pose of series B, to 1e-6 mm; the compliance the YAML cannot hold is
/// named.
#[test]
fn the_ur10_export_as_ur_kinematics_yaml_is_the_toml_geometry() {
    use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
    let dir = std::env::temp_dir().join(format!("thermokin-ur-yaml-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (toml, yaml) = (dir.join("ur10-c.toml"), dir.join("ur10-c.yaml"));
    let run = |args: &[&str]| {
        let o = thermokin(args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    };
    let mut diagnose = UR10_SERIES_C.to_vec();
    diagnose.extend(["--quiet", "--export", toml.to_str().unwrap()]);
    run(&diagnose);
    run(&["urdf", "export", "--robot", toml.to_str().unwrap(), "-o", yaml.to_str().unwrap()]);
    let text = std::fs::read_to_string(&yaml).unwrap();
    assert!(text.contains("gravity compliance"), "the compliance named as left out:\n{text}");
    // The six origins, in the file's order.
    let mut values: Vec<f64> = Vec::new();
    for line in text.lines().filter(|l| !l.trim_start().starts_with('#')) {
        let Some((key, v)) = line.trim().split_once(": ") else { continue };
        if ["x", "y", "z", "roll", "pitch", "yaw"].contains(&key) {
            values.push(v.parse().unwrap());
        }
    }
    assert_eq!(values.len(), 36, "{text}");
    let origin = |v: &[f64]| {
        Isometry3::from_parts(
            Translation3::new(v[0] * 1000.0, v[1] * 1000.0, v[2] * 1000.0),
            UnitQuaternion::from_euler_angles(v[3], v[4], v[5]),
        )
    };
    // The tool point behind tool0, as the header names it (mm, degrees).
    let tcp_line = text.lines().find(|l| l.contains("the tool point behind tool0")).expect("the TCP named");
    let numbers: Vec<f64> = tcp_line
        .split('=')
        .skip(1)
        .flat_map(|part| part.split_whitespace().filter_map(|w| w.trim_end_matches(',').parse::<f64>().ok()).take(3))
        .collect();
    assert_eq!(numbers.len(), 6, "{tcp_line}");
    let tcp = Isometry3::from_parts(
        Translation3::new(numbers[0], numbers[1], numbers[2]),
        UnitQuaternion::from_euler_angles(numbers[3].to_radians(), numbers[4].to_radians(), numbers[5].to_radians()),
    );
    let model = thermokin_io::read_robot_model(&toml).unwrap();
    let chain = model.robot().chain();
    let kinds: Vec<_> = chain.joints().iter().map(|j| j.kind).collect();
    let b =
        thermokin_io::read_measurements(&thermokin_testdata::workspace("fixtures/real/ur10-ipa/series_B.csv"), &kinds)
            .unwrap();
    let mut worst = 0.0f64;
    for m in &b.measurements {
        let mut pose = Isometry3::from_parts(
            Translation3::identity(),
            UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::PI),
        );
        for (k, q) in m.q.iter().enumerate() {
            pose = pose * origin(&values[6 * k..6 * k + 6]) * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), *q);
        }
        let through_yaml = (pose * tcp).translation.vector;
        let toml_geometry = chain.tool_pose(&m.q).unwrap().translation.vector;
        worst = worst.max((through_yaml - toml_geometry).norm());
    }
    eprintln!("UR kinematics YAML vs the TOML export's geometry over {} poses of series B: {worst:.2e} mm", b.len());
    assert!(worst <= 1e-6, "{worst} mm");
}
