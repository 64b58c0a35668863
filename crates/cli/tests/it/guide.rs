//! `docs/guide.md` run as a newcomer runs it (issue #50): every `sh` block of the page, in order, in an
//! empty directory with the built `thermokin` on the PATH (the robot and the UR10 series come from the
//! binary's bundle), and every figure the page quotes checked against what the commands wrote.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::cli::tmp;

/// The page's `sh` blocks, in order.
fn blocks(page: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut current: Option<String> = None;
    for line in page.lines() {
        match (&mut current, line.trim_end()) {
            (None, "```sh") => current = Some(String::new()),
            (Some(_), "```") => out.extend(current.take()),
            (Some(block), text) => {
                block.push_str(text);
                block.push('\n');
            }
            (None, _) => {}
        }
    }
    out
}

/// A figure the page quotes: present in its text (line breaks read as spaces), and equal to what the run
/// gave.
fn quotes(page: &str, quoted: &str, measured: &str) {
    let folded = page.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(folded.contains(quoted), "docs/guide.md no longer quotes {quoted:?}");
    assert_eq!(quoted, measured, "docs/guide.md quotes {quoted:?}; the run gives {measured:?}");
}

fn mean(json: &serde_json::Value, path: &[&str]) -> String {
    let v = path.iter().fold(json, |v, k| &v[*k]);
    format!("{:.4}", v["heldout_mean_mm"].as_f64().unwrap())
}

#[test]
fn guide_runs_from_an_empty_directory_and_its_figures_hold() {
    let page = std::fs::read_to_string(thermokin_testdata::workspace("docs/guide.md")).unwrap();
    let dir: PathBuf = tmp("guide");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let bin = Path::new(env!("CARGO_BIN_EXE_thermokin")).parent().unwrap().to_path_buf();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let mut outputs = Vec::new();
    for block in blocks(&page) {
        let o =
            Command::new("sh").arg("-e").arg("-c").arg(&block).current_dir(&dir).env("PATH", &path).output().unwrap();
        let (out, err) =
            (String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned());
        assert!(o.status.success(), "this block of docs/guide.md failed:\n{block}\n{err}");
        outputs.push(out);
    }
    assert_eq!(outputs.len(), 5, "the guide's blocks: plan, diagnose, fk, ik, compensate");
    // 1. The plan.
    assert!(outputs[0].contains("PLAN: 60 poses of 2773 candidates"), "{}", outputs[0]);
    quotes(&page, "`PLAN: 60 poses of 2773 candidates`", "`PLAN: 60 poses of 2773 candidates`");
    for f in ["plan.csv", "plan.script", "plan.html"] {
        assert!(dir.join(f).exists(), "{f}");
    }
    // 2. The diagnosis.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    quotes(&page, "0.4348", &mean(&report, &["nested", "selected"]));
    quotes(&page, "0.9439", &mean(&report, &["nested", "nominal"]));
    quotes(&page, "0.5412", &mean(&report, &["holdout", "same_frame", "selected"]));
    quotes(&page, "1.7898", &mean(&report, &["holdout", "same_frame", "nominal"]));
    quotes(&page, "0.4112", &mean(&report, &["holdout", "selected"]));
    quotes(&page, "1.0248", &mean(&report, &["holdout", "nominal"]));
    let lines: Vec<String> = report["outliers"].as_array().unwrap().iter().map(|o| o["line"].to_string()).collect();
    quotes(&page, "lines 421 and 2512", &format!("lines {}", lines.join(" and ")));
    let labels = |key: &str| -> Vec<String> {
        report[key].as_array().unwrap().iter().map(|e| format!("`{}`", e["label"].as_str().unwrap())).collect()
    };
    let effects = labels("effects");
    let (last, rest) = effects.split_last().unwrap();
    quotes(&page, &format!("{} and {last}", rest.join(", ")), &format!("{} and {last}", rest.join(", ")));
    let rows: Vec<String> = report["completed"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["label"].as_str().unwrap().trim_start_matches("link_deviation[").trim_end_matches(']').to_string())
        .collect();
    quotes(&page, "rows of joints 1, 3, 5 and 6", &{
        let mut r = rows.clone();
        r.sort();
        let (last, rest) = r.split_last().unwrap();
        format!("rows of joints {} and {last}", rest.join(", "))
    });
    let rms = report["nested"]["selected"]["heldout_rms_mm"].as_f64().unwrap();
    quotes(&page, "(0.49 mm RMS)", &format!("({rms:.2} mm RMS)"));
    let noise_rms = 0.01 * 3f64.sqrt();
    quotes(&page, "28 times the stated noise", &format!("{:.0} times the stated noise", (rms / noise_rms).floor()));
    assert!(outputs[1].contains("next poses: `thermokin plan --robot fixtures/urdf/ur10.urdf --tip tool0 --frame tracker --tool unknown --measured fixtures/real/ur10-ipa/series_C.csv --criterion parameters --poses 20 --out next.csv`"));
    let refused = report["identifiability"]["not_identifiable"].as_array().unwrap();
    let reason = |effect: &str| {
        refused.iter().find(|r| r["effect"] == effect).map(|r| r["reason"].as_str().unwrap().to_string())
    };
    let scale = reason("joint_scale[1]").expect("joint_scale[1] refused");
    assert!(reason("periodic[1]").is_some());
    assert!(scale.contains("-308.4° … -180.0° only (18% of its"), "{scale}");
    quotes(&page, "joint 1 covers −308° … −180° only, 18 %", "joint 1 covers −308° … −180° only, 18 %");
    // 4. The calibrated robot: series B's second pose, measured at (−0.507, −3343.152, −426.950) mm.
    let position: Vec<f64> = outputs[2]
        .lines()
        .find(|l| l.starts_with("position_mm"))
        .unwrap()
        .split_whitespace()
        .skip(1)
        .map(|v| v.parse().unwrap())
        .collect();
    let measured = [-0.507, -3343.152, -426.950];
    let gap = position.iter().zip(measured).map(|(p, m)| (p - m) * (p - m)).sum::<f64>().sqrt();
    quotes(&page, "probe 0.39 mm from it", &format!("probe {gap:.2} mm from it"));
    assert!(outputs[3].contains("Converged"), "{}", outputs[3]);
    assert!(outputs[4].contains("solves 2  failed 0"), "{}", outputs[4]);
    let largest: f64 = outputs[4]
        .split("compensated ")
        .nth(1)
        .and_then(|s| s.split(" mm").next())
        .and_then(|s| s.parse().ok())
        .unwrap();
    assert!(largest < 1e-9, "compensated to {largest} mm");
    quotes(&page, "(to 1e-9 mm)", "(to 1e-9 mm)");
    let script = std::fs::read_to_string(dir.join("cell.script")).unwrap();
    assert_eq!(script.matches("movej(").count(), 2, "{script}");
}
