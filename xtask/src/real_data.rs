//! `cargo xtask real-data`: every shared real set rerun by the release build, as a user runs it, in both
//! protocols where the set has a hold-out file — one table of figures, time, memory, processor and date,
//! written to `docs/real-data.md` (the README and the docs quote it; a test reruns its commands and fails
//! when a figure moved, another when a quoted figure differs from it).

use anyhow::Result;

use crate::bench::{measure, processor};
use crate::{cargo, run};

/// The table's file.
pub(crate) const TABLE: &str = "docs/real-data.md";

/// Each real set: its name, and the `thermokin` arguments that diagnose it (paths in the repository,
/// which the binary also bundles).
pub(crate) const SETS: &[(&str, &str)] = &[
    (
        "UR10, series C → B",
        "diagnose --robot fixtures/urdf/ur10.urdf --tip tool0 --frame tracker --tool unknown --measurements fixtures/real/ur10-ipa/series_C.csv --holdout fixtures/real/ur10-ipa/series_B.csv --noise 0.01",
    ),
    (
        "UR10, series A (4.7 days)",
        "diagnose --robot fixtures/urdf/ur10.urdf --tip tool0 --frame tracker --tool unknown --measurements fixtures/real/ur10-ipa/series_A.csv --noise 0.01",
    ),
    (
        "Barrett WAM, grid → random",
        "diagnose --robot fixtures/real/jacobi-wam/wam.urdf --frame tracker --tool unknown --measurements fixtures/real/jacobi-wam/wam-grid.csv --holdout fixtures/real/jacobi-wam/wam-random.csv",
    ),
    (
        "Barrett WAM, grid → random, files in measuring order",
        "diagnose --robot fixtures/real/jacobi-wam/wam.urdf --frame tracker --tool unknown --measurements fixtures/real/jacobi-wam/wam-grid.csv --holdout fixtures/real/jacobi-wam/wam-random.csv --order file",
    ),
    (
        "Rokae B, positions",
        "diagnose --robot fixtures/real/rokae-robot-b/rokae.toml --frame tracker --tool unknown --measurements fixtures/real/rokae-robot-b/joints-deg.csv --poses fixtures/real/rokae-robot-b/tracker-poses.csv --orientation-lever 0",
    ),
    (
        "Rokae B, 6-D (rpy)",
        "diagnose --robot fixtures/real/rokae-robot-b/rokae.toml --frame tracker --tool unknown --measurements fixtures/real/rokae-robot-b/joints-deg.csv --poses fixtures/real/rokae-robot-b/tracker-poses.csv --orientation rpy",
    ),
];

/// Today's date, `YYYY-MM-DD` (UTC), from the system clock (days since 1970 to the civil calendar).
fn today() -> String {
    let days =
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs() / 86_400) as i64;
    // Howard Hinnant's days-to-civil algorithm.
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

/// A statistic as the table prints it: `nominal → chosen`, four decimals, or `—`.
fn pair(report: &serde_json::Value, path: &[&str]) -> String {
    let at = path.iter().fold(report, |v, k| &v[*k]);
    let mean = |k: &str| at[k]["heldout_mean_mm"].as_f64();
    match (mean("nominal"), mean("selected")) {
        (Some(n), Some(s)) => format!("{n:.4} → {s:.4}"),
        _ => "—".into(),
    }
}

/// Reruns every set, prints the table and writes it to [`TABLE`].
pub(crate) fn real_data() -> Result<()> {
    run(cargo().args(["build", "--release", "--package", "thermokin"]))?;
    let bin = crate::workspace_root().join("target/release/thermokin");
    let mut rows = Vec::new();
    for (name, args) in SETS {
        eprintln!("real-data: {name}");
        let args: Vec<&str> = args.split_whitespace().collect();
        let (cost, report) = measure(&bin, &args)?;
        let poses = report["poses"].as_array().map_or(0, Vec::len) + report["outliers"].as_array().map_or(0, Vec::len);
        rows.push(format!(
            "| {name} | {poses} | {} | {} | {} | {} | {:.1} | {:.1} | {:.0} |",
            pair(&report, &["nested"]),
            pair(&report, &["holdout", "same_frame"]),
            pair(&report, &["holdout"]),
            report["effects"].as_array().map_or(0, Vec::len),
            cost.wall_s,
            cost.user_s + cost.system_s,
            cost.peak_mib
        ));
    }
    let mut text = format!(
        "# The real sets, rerun\n\nRecorded {} on {} by `cargo xtask real-data` (the release build; each set in a process of its own, one after the other). Checked by `the_real_data_table_is_what_the_commands_give`.\n\n",
        today(),
        processor()
    );
    text.push_str("Mean 3-D error, mm, nominal robot → the diagnosis' choice: nested (each outer fold unseen by the selection run on the others), and on the hold-out file as exported (nothing refitted: the frame the training measurements ended in) and with the registration and probe refitted on it (the effects kept). `effects`: the causes named (the completion's rows aside).\n\n");
    text.push_str("| set | poses | nested | hold-out as exported | hold-out refitted | effects | wall s | CPU s | peak MiB |\n|---|---|---|---|---|---|---|---|---|\n");
    for r in &rows {
        text.push_str(r);
        text.push('\n');
    }
    text.push_str("\nThe commands, from the repository's root (or from anywhere: the binary bundles every file here but series A's 2 MB):\n\n```sh\n");
    for (_, args) in SETS {
        text.push_str(&format!("thermokin {args}\n"));
    }
    text.push_str("```\n");
    std::fs::write(TABLE, &text)?;
    println!("{text}");
    Ok(())
}
