//! The real-data table (`docs/real-data.md`, written by `cargo xtask real-data`) kept true: its commands
//! rerun here give its figures, and the README and the docs quote them as they are (issue #50).

use crate::cli::{stderr, thermokin, tmp};

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
