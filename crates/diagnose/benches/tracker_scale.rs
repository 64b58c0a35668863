//! A week of tracker data at the scale issue #23 names: a simulated UR10 (its URDF, flange `tool0`) with a
//! joint offset, a link deviation, gravity compliance and a linear thermal drift, measured at 3,000 and
//! 12,000 poses (and 100,000: issue #60's linear growth) over a 240-minute warm-up with two joint temperature columns, diagnosed with nested
//! validation (5 outer folds, the default). Timed once per size (minutes of work do not fit criterion's
//! sampling; `THERMOKIN_BENCH_REPEAT` keeps the fastest of several runs, `THERMOKIN_BENCH_SIZES` picks
//! the sizes), with the phase table of the run kept; the process's peak resident memory is read after
//! each size. Then the real sets as a user
//! runs them, each timed once: the Barrett WAM (grid, the random poses held out; issue #36's goal ≤ 5 s)
//! and the UR10 (series C, series B held out). Written to `target/criterion/diagnose_scale.json` for
//! `cargo xtask bench`.
#![allow(missing_docs, clippy::unwrap_used)] // a bench binary; it unwraps to fail.

use std::time::Instant;

use thermokin_diagnose::{Config, HiddenEffect, SimulationConfig, diagnose, diagnose_profiled, simulate};
use thermokin_identify::{DriftShape, Effect, FrameMode, JointIndex, ToolMode};

fn main() {
    // `cargo bench` passes `--bench`; anything else (`cargo test --benches`) runs a tiny size only.
    let full = std::env::args().any(|a| a == "--bench");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let options = thermokin_io::RobotOptions { base: None, tip: Some("tool0".into()) };
    let robot = thermokin_io::read_robot_with(&root.join("fixtures/urdf/ur10.urdf"), &options).unwrap();
    let joint = |j| JointIndex::of(&robot, j).unwrap();
    let hidden = [
        HiddenEffect { effect: Effect::JointOffset(joint(1)), values: vec![0.03f64.to_radians()] },
        HiddenEffect {
            effect: Effect::LinkDeviation(joint(2)),
            values: vec![0.2, -0.1, 0.15, 0.01f64.to_radians(), 0.0, 0.005f64.to_radians()],
        },
        HiddenEffect { effect: Effect::JointCompliance(joint(1)), values: vec![0.0004f64.to_radians()] },
        HiddenEffect {
            effect: Effect::ThermalDrift(joint(2), DriftShape::Linear),
            values: vec![0.1, 0.05, -0.2, 0.0, 0.004f64.to_radians(), 0.0],
        },
    ];
    // 100,000 poses (issue #60): the cost must grow with the poses and nothing else.
    // `THERMOKIN_BENCH_SIZES=12000,100000` runs those sizes only (a profile of one size, or the ratio
    // of two); `THERMOKIN_BENCH_REPEAT=3` times each size that many times and keeps the fastest run: the
    // ratio of two sizes on a machine whose runs differ by ±10 % from one to the next.
    let chosen_sizes: Option<Vec<usize>> = std::env::var("THERMOKIN_BENCH_SIZES")
        .ok()
        .map(|v| v.split(',').map(|s| s.trim().parse().expect("THERMOKIN_BENCH_SIZES: pose counts")).collect());
    let repeat: usize = std::env::var("THERMOKIN_BENCH_REPEAT")
        .ok()
        .map_or(1, |v| v.trim().parse().expect("THERMOKIN_BENCH_REPEAT: a count"));
    let sizes: &[usize] = match &chosen_sizes {
        Some(s) if full => s,
        _ if full => &[3_000, 12_000, 100_000],
        _ => &[300],
    };
    let mut results = serde_json::Map::new();
    for &poses in sizes {
        let mut data = simulate(&robot, &hidden, &SimulationConfig { poses, ..SimulationConfig::default() }).unwrap();
        // Two joint temperature sensors warming up: what a tracker log beside the controller carries.
        data.temperature_names = vec!["j2".into(), "j3".into()];
        for m in &mut data.measurements {
            let t = m.time_min;
            m.temps = vec![22.0 + 8.0 * (1.0 - (-t / 30.0).exp()), 21.0 + 4.0 * t / 240.0];
        }
        // The fastest run's time, report, phases and evaluated rows: every line printed for a size is one
        // run's.
        type Run = (f64, thermokin_diagnose::Report, thermokin_diagnose::Profile, thermokin_identify::Evaluated);
        let mut fastest: Option<Run> = None;
        for run in 0..repeat.max(1) {
            let (t0, before) = (Instant::now(), thermokin_identify::evaluated());
            let (report, profile) = diagnose_profiled(&robot, &data, None, &Config::default()).unwrap();
            let seconds = t0.elapsed().as_secs_f64();
            let rows = thermokin_identify::evaluated().since(before);
            if repeat > 1 {
                println!("diagnose_scale {poses} poses, run {}: {seconds:.1} s", run + 1);
            }
            if fastest.as_ref().is_none_or(|f| seconds < f.0) {
                fastest = Some((seconds, report, profile, rows));
            }
        }
        let Some((seconds, report, profile, rows)) = fastest else { unreachable!("at least one run") };
        let rss = thermokin_testdata::peak_rss_mib();
        let chosen: Vec<String> = report.effects.iter().map(|e| e.label.clone()).collect();
        // Per pose: what linear growth keeps constant.
        let ms_per_pose = 1e3 * seconds / poses as f64;
        println!(
            "diagnose_scale {poses} poses: {seconds:.1} s nested ({ms_per_pose:.2} ms per pose), peak RSS {} MiB; chose {chosen:?}",
            rss.map_or("n/a".into(), |m| format!("{m:.1}"))
        );
        // What the fits evaluated per pose: constant where the work grows with the poses alone, larger
        // where the fits iterate more.
        let per_pose = |n: u64| n as f64 / poses as f64;
        let (jacobian_per_pose, residual_per_pose) = (per_pose(rows.jacobian_rows), per_pose(rows.residual_rows));
        println!(
            "  the fits evaluated {jacobian_per_pose:.0} Jacobian rows and {residual_per_pose:.0} residual rows per pose"
        );
        // Where the time went, phase by phase: which phases grow faster than the poses.
        print!("{}", profile.table());
        results.insert(
            format!("{poses}"),
            serde_json::json!({
                "seconds": seconds, "ms_per_pose": ms_per_pose, "peak_rss_mib": rss, "chosen": chosen,
                "runs": repeat.max(1), "phases": profile.phases,
                "jacobian_rows_per_pose": jacobian_per_pose, "residual_rows_per_pose": residual_per_pose
            }),
        );
    }
    // The real sets with every size only: a run of chosen sizes leaves them out.
    if full && chosen_sizes.is_none() {
        for (name, urdf, tip, train, test) in [
            ("wam", "fixtures/real/jacobi-wam/wam.urdf", None, "jacobi-wam/wam-grid.csv", "jacobi-wam/wam-random.csv"),
            ("ur10", "fixtures/urdf/ur10.urdf", Some("tool0"), "ur10-ipa/series_C.csv", "ur10-ipa/series_B.csv"),
        ] {
            let options = thermokin_io::RobotOptions { base: None, tip: tip.map(String::from) };
            let robot = thermokin_io::read_robot_with(&root.join(urdf), &options).unwrap();
            let kinds: Vec<_> = robot.chain().joints().iter().map(|j| j.kind).collect();
            let read = |f: &str| thermokin_io::read_measurements(&root.join("fixtures/real").join(f), &kinds).unwrap();
            let (train, test) = (read(train), read(test));
            let config = Config { frame: FrameMode::Tracker, tool: ToolMode::Unknown, ..Config::default() };
            let t0 = Instant::now();
            let report = diagnose(&robot, &train, Some(&test), &config).unwrap();
            let seconds = t0.elapsed().as_secs_f64();
            let h = report.holdout.unwrap();
            println!(
                "diagnose_real {name}: {seconds:.2} s nested with hold-out; {:.4} mm refitted, {:.4} same frame",
                h.selected.heldout_mean_mm, h.same_frame.selected.heldout_mean_mm
            );
            results.insert(format!("real_{name}"), serde_json::json!({"seconds": seconds}));
        }
    }
    if full {
        let dir = root.join("target/criterion");
        let _ = std::fs::create_dir_all(&dir);
        let _ = std::fs::write(dir.join("diagnose_scale.json"), serde_json::Value::Object(results).to_string());
    }
}
