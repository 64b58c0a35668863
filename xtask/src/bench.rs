//! `cargo xtask bench`: the criterion benches and their summary, the diagnosis's cost phase by phase on
//! the real sets, and the real sets run by an earlier commit's build beside ours (`--baseline`), measured
//! in one run on one machine — the only way a speed ratio means anything.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use anyhow::{Context, Result, bail};

use crate::{cargo, run, workspace_root};

/// One statistic (`median`, `mean`) of a criterion estimate file, nanoseconds.
fn estimate_ns(bench: &str, statistic: &str) -> Option<f64> {
    let p = Path::new("target/criterion").join(bench).join("new/estimates.json");
    let text = std::fs::read_to_string(p).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v[statistic]["point_estimate"].as_f64()
}

fn median_ns(bench: &str) -> Option<f64> {
    estimate_ns(bench, "median")
}

fn mean_ns(bench: &str) -> Option<f64> {
    estimate_ns(bench, "mean")
}

/// The processor the figures were taken on (`model name` of /proc/cpuinfo, and the cores): a speed figure
/// is quoted with it.
pub(crate) fn processor() -> String {
    let cores = std::thread::available_parallelism().map_or(0, usize::from);
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    format!("{model}, {cores} cores")
}

/// Every criterion bench, then the summary table (and one JSON object with `json`), the diagnosis's
/// phases on the real sets, and — with `baseline` — the real sets run by that commit's build beside ours.
pub(crate) fn bench(json: bool, baseline: Option<&str>) -> Result<()> {
    run(cargo().args([
        "bench",
        "--package",
        "thermokin-chain",
        "--package",
        "thermokin-ik",
        "--package",
        "thermokin-compensate",
        "--package",
        "thermokin-diagnose",
        "--package",
        "thermokin-planner",
        "--bench",
        "kinematics",
        "--bench",
        "ik",
        "--bench",
        "program",
        "--bench",
        "diagnose",
        "--bench",
        "tracker_scale",
        "--bench",
        "plan",
        "--bench",
        "phases",
    ]))?;
    let stream: serde_json::Value = std::fs::read_to_string("target/criterion/program_stream.json")
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or(serde_json::Value::Null);
    let rate = |file: &str| {
        std::fs::read_to_string(Path::new("target/criterion").join(file))
            .ok()
            .and_then(|s| s.trim().parse::<f64>().ok())
    };
    let scale: serde_json::Value = std::fs::read_to_string("target/criterion/diagnose_scale.json")
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or(serde_json::Value::Null);
    let success = rate("ik_random_success.txt");
    let k_success = rate("k_ik_near_success.txt");
    let us = |v: Option<f64>| v.map(|n| n / 1e3);
    let ratio = |a: Option<f64>, b: Option<f64>| a.zip(b).map(|(a, b)| a / b);
    let rows: Vec<(&str, Option<f64>, &str, f64)> = vec![
        ("fk_us", median_ns("fk_irb140_deformed").map(|n| n / 1e3), "median FK, IRB 140 with error parameters", 0.2),
        ("jacobian_us", median_ns("jacobian_irb140_deformed").map(|n| n / 1e3), "median pose + Jacobian", 0.3),
        ("ik_near_us", median_ns("ik_near_seed").map(|n| n / 1e3), "median IK from a seed within 0.25 rad", 5.0),
        (
            "ik_near_nalgebra_us",
            median_ns("ik_near_seed").map(|n| n / 1e3),
            "same: the default step is nalgebra's fixed-size 6 × 6",
            5.0,
        ),
        (
            "ik_near_faer_us",
            median_ns("ik_near_seed_faer").map(|n| n / 1e3),
            "same, faer's dynamic step (chains of other sizes)",
            5.0,
        ),
        ("ik_random_us", mean_ns("ik_random_seed").map(|n| n / 1e3), "mean IK from random seeds with restarts", 50.0),
        (
            "ik_random_random_restarts_us",
            us(mean_ns("ik_random_seed_random_restarts")),
            "same, random restarts only (no closed-form branches)",
            f64::NAN,
        ),
        (
            "branches_ratio",
            ratio(mean_ns("ik_random_seed"), mean_ns("ik_random_seed_random_restarts")),
            "random-seed IK with branches / without, same run",
            f64::NAN,
        ),
        ("k_fk_us", us(median_ns("k_fk")), "peer: k crate FK, same robot and configurations", f64::NAN),
        ("k_jacobian_us", us(median_ns("k_jacobian")), "peer: k crate FK + Jacobian", f64::NAN),
        ("k_ik_near_us", us(median_ns("k_ik_near_seed")), "peer: k crate Jacobian IK near seed (1e-6 m)", f64::NAN),
        ("k_fk_ratio", ratio(median_ns("fk_irb140_deformed"), median_ns("k_fk")), "ours / k, FK", 1.0),
        (
            "k_jacobian_ratio",
            ratio(median_ns("jacobian_irb140_deformed"), median_ns("k_jacobian")),
            "ours / k, pose + Jacobian",
            1.0,
        ),
        (
            "k_ik_near_ratio",
            ratio(median_ns("ik_near_seed"), median_ns("k_ik_near_seed")),
            "ours (1e-9 mm, limits) / k (1e-6 m), IK near seed",
            1.0,
        ),
        ("k_ik_near_success", k_success, "peer: k's success rate near seed", f64::NAN),
        (
            "program_1m_s",
            stream["1000000"]["seconds"].as_f64(),
            "1,000,000 targets streamed (CSV in and out), every core",
            10.0,
        ),
        (
            "program_1m_peak_mib",
            stream["1000000"]["peak_rss_mib"].as_f64(),
            "peak memory after 1,000,000 targets, MiB",
            f64::NAN,
        ),
        (
            "program_300k_peak_mib",
            stream["300000"]["peak_rss_mib"].as_f64(),
            "peak memory after 300,000 targets, MiB (flat: same as 1M)",
            f64::NAN,
        ),
        (
            "diagnose_240_s",
            mean_ns("diagnose/diagnose_240_poses").map(|n| n / 1e9),
            "diagnosis of 240 poses over 240 min, nested 5×5-fold, every candidate",
            f64::NAN,
        ),
        (
            "diagnose_selection_60_s",
            mean_ns("diagnose_scaling/selection/60").map(|n| n / 1e9),
            "selection alone (5-fold ladder), 60 poses",
            f64::NAN,
        ),
        (
            "diagnose_selection_480_s",
            mean_ns("diagnose_scaling/selection/480").map(|n| n / 1e9),
            "selection alone, 480 poses",
            f64::NAN,
        ),
        (
            "diagnose_growth_480_over_60",
            ratio(mean_ns("diagnose_scaling/selection/480"), mean_ns("diagnose_scaling/selection/60")),
            "cost growth for 8× the poses (8 = linear)",
            8.0,
        ),
        (
            "diagnose_ur10_3k_s",
            scale["3000"]["seconds"].as_f64(),
            "simulated UR10, 3,000 poses with time and temperatures, nested diagnosis",
            f64::NAN,
        ),
        ("diagnose_ur10_12k_s", scale["12000"]["seconds"].as_f64(), "the same, 12,000 poses (a tracker's week)", 30.0),
        (
            "diagnose_growth_12k_over_3k",
            ratio(scale["12000"]["seconds"].as_f64(), scale["3000"]["seconds"].as_f64()),
            "cost growth for 4× the poses (4 = linear)",
            4.5,
        ),
        (
            "diagnose_ur10_12k_peak_mib",
            scale["12000"]["peak_rss_mib"].as_f64(),
            "peak memory of that process, MiB",
            300.0,
        ),
        ("diagnose_ur10_100k_s", scale["100000"]["seconds"].as_f64(), "the same, 100,000 poses", f64::NAN),
        (
            "diagnose_growth_100k_over_12k",
            ratio(scale["100000"]["seconds"].as_f64(), scale["12000"]["seconds"].as_f64()),
            "cost growth for 8.3× the poses (issue #60: at most 10)",
            10.0,
        ),
        (
            "diagnose_ur10_100k_ms_per_pose",
            scale["100000"]["ms_per_pose"].as_f64(),
            "its time per pose, ms (12,000 poses: diagnose_ur10_12k_s / 12,000)",
            f64::NAN,
        ),
        (
            "diagnose_ur10_100k_peak_mib",
            scale["100000"]["peak_rss_mib"].as_f64(),
            "peak memory of the process after 100,000 poses, MiB (issue #60: at most 1,024)",
            1024.0,
        ),
        (
            "plan_60_of_3000_s",
            mean_ns("plan/60_of_3000").map(|n| n / 1e9),
            "plan 60 poses of 3,000 sampled IRB 140 candidates (tracker, unknown tool)",
            2.0,
        ),
        (
            "plan_growth_6000_over_3000",
            ratio(mean_ns("plan/60_of_6000"), mean_ns("plan/60_of_3000")),
            "the plan's cost, 6,000 candidates over 3,000 (linear: 2)",
            2.2,
        ),
        (
            "diagnose_wam_real_s",
            scale["real_wam"]["seconds"].as_f64(),
            "the real Barrett WAM: 216 grid poses nested, 20 random held out",
            5.0,
        ),
        (
            "diagnose_ur10_real_s",
            scale["real_ur10"]["seconds"].as_f64(),
            "the real UR10: series C (2,773 poses) nested, series B held out",
            15.0,
        ),
        (
            "transient_10050_s",
            mean_ns("program/transient_10050").map(|n| n / 1e9),
            "10,050 targets, warm-started (paper's 200 min)",
            0.1,
        ),
    ];
    println!("processor: {}", processor());
    println!("{:<28} {:>12} {:>8}  what", "metric", "measured", "goal");
    for (k, v, what, goal) in &rows {
        let goal = if goal.is_nan() { "–".to_string() } else { goal.to_string() };
        println!("{k:<28} {:>12} {goal:>8}  {what}", v.map_or("n/a".into(), |x| format!("{x:.4}")));
    }
    println!(
        "{:<28} {:>12} {:>8}  success rate of random-seed IK over the bench's targets",
        "ik_random_success",
        success.map_or("n/a".into(), |x| format!("{x:.4}")),
        "0.999"
    );
    phase_tables()?;
    if let Some(commit) = baseline {
        beside_baseline(commit)?;
    }
    if json {
        let mut obj = serde_json::Map::new();
        for (k, v, _, _) in rows {
            obj.insert(k.into(), v.map_or(serde_json::Value::Null, |x| serde_json::json!(x)));
        }
        obj.insert("ik_random_success".into(), success.map_or(serde_json::Value::Null, |x| serde_json::json!(x)));
        obj.insert("processor".into(), serde_json::json!(processor()));
        println!("{}", serde_json::Value::Object(obj));
    }
    Ok(())
}

/// The diagnosis's phases on the real sets (`target/criterion/diagnose_phases.json`, written by the
/// `phases` bench): wall seconds per phase on all measurements and summed over the nested validation's
/// outer folds, with the run's wall and CPU seconds and peak memory.
fn phase_tables() -> Result<()> {
    let Some(sets) = std::fs::read_to_string("target/criterion/diagnose_phases.json")
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
    else {
        println!("diagnosis phases: no target/criterion/diagnose_phases.json (the phases bench did not run)");
        return Ok(());
    };
    for (name, what) in [
        ("ur10_c_b", "UR10 series C (nested) with series B held out"),
        ("ur10_a", "UR10 series A, 11,911 poses over 4.7 days (nested, time folds)"),
    ] {
        let s = &sets[name];
        if s.is_null() {
            continue;
        }
        let f = |k: &str| s[k].as_f64().map_or("n/a".into(), |x| format!("{x:.3}"));
        println!(
            "\ndiagnosis phases, {what}: {} s wall, {} CPU s, peak {} MiB; nested mean {} mm, hold-out mean {} mm refitted, {} mm same frame",
            f("wall_s"),
            f("cpu_s"),
            f("peak_rss_mib"),
            f("nested_mean_mm"),
            f("holdout_mean_mm"),
            f("holdout_same_frame_mean_mm")
        );
        println!("  {:<16} {:>12} {:>18}", "phase", "all data [s]", "outer folds Σ [s]");
        for p in s["phases"].as_array().into_iter().flatten() {
            println!(
                "  {:<16} {:>12.3} {:>18.3}",
                p["phase"].as_str().unwrap_or("?"),
                p["seconds"].as_f64().unwrap_or(f64::NAN),
                p["outer_fold_seconds"].as_f64().unwrap_or(f64::NAN)
            );
        }
    }
    Ok(())
}

/// The real sets the baseline comparison runs, as a user runs them: name, `thermokin diagnose` arguments
/// (the JSON report's path appended).
const REAL_RUNS: &[(&str, &[&str])] = &[
    (
        "UR10 C + B",
        &[
            "diagnose",
            "--robot",
            "fixtures/urdf/ur10.urdf",
            "--tip",
            "tool0",
            "--frame",
            "tracker",
            "--tool",
            "unknown",
            "--measurements",
            "fixtures/real/ur10-ipa/series_C.csv",
            "--holdout",
            "fixtures/real/ur10-ipa/series_B.csv",
            "--noise",
            "0.01",
        ],
    ),
    (
        "UR10 series A",
        &[
            "diagnose",
            "--robot",
            "fixtures/urdf/ur10.urdf",
            "--tip",
            "tool0",
            "--frame",
            "tracker",
            "--tool",
            "unknown",
            "--measurements",
            "fixtures/real/ur10-ipa/series_A.csv",
            "--noise",
            "0.01",
        ],
    ),
];

/// What one command cost: CPU (user, system), wall, peak resident memory.
pub(crate) struct Cost {
    pub(crate) user_s: f64,
    pub(crate) system_s: f64,
    pub(crate) wall_s: f64,
    pub(crate) peak_mib: f64,
}

/// The headline figures of a diagnosis' JSON report, in words.
fn figures(report: &serde_json::Value) -> String {
    let mean = |v: &serde_json::Value| v["heldout_mean_mm"].as_f64().map_or("–".into(), |x| format!("{x:.4}"));
    format!(
        "nested {}, hold-out {} refitted / {} same frame",
        mean(&report["nested"]["selected"]),
        mean(&report["holdout"]["selected"]),
        mean(&report["holdout"]["same_frame"]["selected"])
    )
}

/// Builds `commit`'s command line in a worktree under `target/baseline/` (once; reused after), and ours;
/// then runs every real set with the baseline's build and ours, one after the other in that order,
/// each in a process of its own, and prints CPU seconds (user + system), wall seconds and peak memory
/// side by side with their ratios — both builds measured in the same run on the same machine.
fn beside_baseline(commit: &str) -> Result<()> {
    let root = workspace_root();
    let dir = root.join("target/baseline").join(commit);
    if !dir.join("Cargo.toml").exists() {
        std::fs::create_dir_all(dir.parent().unwrap_or(&root))?;
        run(Command::new("git").args(["worktree", "add", "--detach"]).arg(&dir).arg(commit))?;
    }
    eprintln!("bench: building {commit}'s command line in {} (minutes the first time)", dir.display());
    run(cargo().current_dir(&dir).env("CARGO_TARGET_DIR", dir.join("target")).args([
        "build",
        "--release",
        "--package",
        "thermokin",
    ]))?;
    run(cargo().args(["build", "--release", "--package", "thermokin"]))?;
    let builds = [
        (commit.to_string(), dir.join("target/release/thermokin")),
        ("ours".to_string(), root.join("target/release/thermokin")),
    ];
    println!(
        "\nthe real sets, {commit}'s build beside ours (one process each, in this order; {}):",
        crate::bench::processor()
    );
    println!(
        "  {:<14} {:<10} {:>8} {:>8} {:>8} {:>9}  figures (mm)",
        "set", "build", "CPU s", "wall s", "peak MiB", "CPU ratio"
    );
    for (name, args) in REAL_RUNS {
        let mut first: Option<f64> = None;
        for (who, bin) in &builds {
            let (c, report) = measure(bin, args)?;
            let cpu = c.user_s + c.system_s;
            let ratio = first.map_or("–".to_string(), |b| format!("{:.2}", cpu / b));
            first.get_or_insert(cpu);
            println!(
                "  {name:<14} {who:<10} {cpu:>8.2} {:>8.2} {:>8.1} {ratio:>9}  {}",
                c.wall_s,
                c.peak_mib,
                figures(&report)
            );
        }
    }
    Ok(())
}

/// Runs `bin args --json FILE` in a process of its own under `cargo xtask measure`, which reports its
/// resource use; returns it with the JSON report the command wrote.
pub(crate) fn measure(bin: &Path, args: &[&str]) -> Result<(Cost, serde_json::Value)> {
    let json: PathBuf = std::env::temp_dir().join(format!("thermokin-bench-{}.json", std::process::id()));
    let me = std::env::current_exe()?;
    let out = Command::new(me)
        .arg("measure")
        .arg(bin)
        .args(args)
        .arg("--json")
        .arg(&json)
        .stderr(Stdio::inherit())
        .output()
        .with_context(|| format!("measuring {}", bin.display()))?;
    if !out.status.success() {
        bail!("{} {} failed", bin.display(), args.join(" "));
    }
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).context("the measure task's report")?;
    let report: serde_json::Value =
        std::fs::read_to_string(&json).ok().and_then(|t| serde_json::from_str(&t).ok()).unwrap_or_default();
    let _ = std::fs::remove_file(&json);
    let f = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    Ok((
        Cost { user_s: f("user_s"), system_s: f("system_s"), wall_s: f("wall_s"), peak_mib: f("peak_kib") / 1024.0 },
        report,
    ))
}

/// `cargo xtask measure BIN ARGS…`: runs the command (its output discarded) and prints its resource use
/// as one JSON object — user and system CPU seconds and peak resident memory from `getrusage` of the
/// children (this process has no other child), and wall seconds.
pub(crate) fn measure_task(args: &[String]) -> Result<()> {
    let (bin, rest) = args.split_first().context("measure: which command?")?;
    let t0 = Instant::now();
    let status = Command::new(bin)
        .args(rest)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .with_context(|| format!("running {bin}"))?;
    let wall_s = t0.elapsed().as_secs_f64();
    if !status.success() {
        bail!("{bin} exited with {status}");
    }
    let usage = nix::sys::resource::getrusage(nix::sys::resource::UsageWho::RUSAGE_CHILDREN)?;
    let secs = |t: nix::sys::time::TimeVal| t.tv_sec() as f64 + t.tv_usec() as f64 * 1e-6;
    println!(
        "{}",
        serde_json::json!({
            "user_s": secs(usage.user_time()),
            "system_s": secs(usage.system_time()),
            "wall_s": wall_s,
            // Linux reports ru_maxrss in KiB.
            "peak_kib": usage.max_rss(),
        })
    );
    Ok(())
}
