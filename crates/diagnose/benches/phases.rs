//! Where the diagnosis spends its time on the real sets, phase by phase (issue #49): the UR10's series C
//! with series B held out, and series A — 11,911 poses over 4.7 days in their own tracker frame, folds
//! grouped in time — each as a user runs it (`--frame tracker --tool unknown`, nested). Timed once each
//! (minutes of work do not fit criterion's sampling); the process's CPU seconds (user + system, read from
//! `/proc/self/stat`) around each run, and its peak resident memory after it. Written to
//! `target/criterion/diagnose_phases.json` for `cargo xtask bench`, which prints the table.
//!
//! `cargo bench -p thermokin-diagnose --bench phases -- ur10` runs the UR10 only.
#![allow(missing_docs, clippy::unwrap_used)] // a bench binary; it unwraps to fail.

use std::time::Instant;

use thermokin_diagnose::{Config, diagnose_profiled};
use thermokin_identify::{FrameMode, ToolMode};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    // `cargo test --benches` runs this binary without `--bench`: nothing to time there.
    if !std::env::args().any(|a| a == "--bench") {
        return;
    }
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let options = thermokin_io::RobotOptions { base: None, tip: Some("tool0".into()) };
    let robot = thermokin_io::read_robot_with(&root.join("fixtures/urdf/ur10.urdf"), &options).unwrap();
    let kinds: Vec<_> = robot.chain().joints().iter().map(|j| j.kind).collect();
    let read = |f: &str| thermokin_io::read_measurements(&root.join("fixtures/real/ur10-ipa").join(f), &kinds).unwrap();
    let config = Config { frame: FrameMode::Tracker, tool: ToolMode::Unknown, ..Config::default() };
    let mut results = serde_json::Map::new();
    for (name, train, test) in [("ur10_c_b", "series_C.csv", Some("series_B.csv")), ("ur10_a", "series_A.csv", None)] {
        if !args.is_empty() && !args.iter().any(|a| name.contains(a.as_str())) {
            continue;
        }
        let (train, test) = (read(train), test.map(read));
        let cpu0 = thermokin_testdata::cpu_seconds();
        let t0 = Instant::now();
        let (report, profile) = diagnose_profiled(&robot, &train, test.as_ref(), &config).unwrap();
        let wall = t0.elapsed().as_secs_f64();
        let cpu = thermokin_testdata::cpu_seconds().zip(cpu0).map(|(b, a)| b - a);
        let rss = thermokin_testdata::peak_rss_mib();
        let nested = report.nested.as_ref().map(|n| n.selected.heldout_mean_mm);
        let holdout =
            report.holdout.as_ref().map(|h| (h.selected.heldout_mean_mm, h.same_frame.selected.heldout_mean_mm));
        let chosen: Vec<String> = report.effects.iter().map(|e| e.label.clone()).collect();
        println!(
            "diagnose_phases {name}: {wall:.2} s wall, {} CPU s, peak {} MiB; nested mean {nested:?} mm, hold-out (refitted, same frame) {holdout:?}; chose {chosen:?}",
            cpu.map_or("n/a".into(), |c| format!("{c:.2}")),
            rss.map_or("n/a".into(), |m| format!("{m:.1}")),
        );
        print!("{}", profile.table());
        results.insert(
            name.into(),
            serde_json::json!({
                "wall_s": wall, "cpu_s": cpu, "peak_rss_mib": rss, "nested_mean_mm": nested,
                "holdout_mean_mm": holdout.map(|h| h.0), "holdout_same_frame_mean_mm": holdout.map(|h| h.1),
                "chosen": chosen,
                "phases": profile.phases,
            }),
        );
    }
    let dir = root.join("target/criterion");
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join("diagnose_phases.json");
    // Runs of a subset keep the other set's last figures.
    let mut all: serde_json::Map<String, serde_json::Value> =
        std::fs::read_to_string(&path).ok().and_then(|t| serde_json::from_str(&t).ok()).unwrap_or_default();
    all.extend(results);
    let _ = std::fs::write(&path, serde_json::Value::Object(all).to_string());
}
