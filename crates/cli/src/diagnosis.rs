//! `thermokin diagnose` and `thermokin simulate`: the sim-to-real diagnosis on a measurement set, and
//! measurement sets generated from hidden effects.

use std::path::Path;

use anyhow::anyhow;
use plotters::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_diagnose::{
    Config, DriftShape, Effect, FoldGrouping, FrameMode, HiddenEffect, Report, Robot, SimulationConfig, ToolMode,
};
use thermokin_io::{
    JointUnits, MeasurementFormat, read_measurements_joined, read_measurements_with, write_atomic, write_atomic_with,
    write_measurements,
};

use crate::args::{DiagnoseArgs, FoldsByArg, FrameArg, JointUnitsArg, SimulateArgs, ToolArg};
use crate::input::{load, working_chain};
use crate::{Failure, exit};

pub fn diagnose(a: DiagnoseArgs) -> Result<u8, Failure> {
    if a.robot.profile.is_some() || a.robot.time.is_some() || a.robot.temperature.is_some() {
        return Err(Failure::input(anyhow!(
            "diagnose takes a static robot: drop --profile/--time/--temperature (thermal drift is a candidate effect; the data's time_min and temp_* columns drive it)"
        )));
    }
    if a.folds < 2 {
        return Err(Failure::input(anyhow!("--folds must be at least 2")));
    }
    let loaded = load(&a.robot)?;
    if !loaded.model.is_plain() {
        return Err(Failure::input(anyhow!(
            "{} carries identified corrections ({}): diagnose the robot they were identified on (its geometry is the starting point), or the calibrated geometry alone",
            a.robot.robot.display(),
            loaded.model.beyond_urdf().join("; ")
        )));
    }
    let chain = working_chain(&a.robot, &loaded)?;
    let kinds: Vec<_> = chain.joints().iter().map(|j| j.kind).collect();
    let units = MeasurementFormat {
        joint_units: if a.joint_units == JointUnitsArg::Rad { JointUnits::Radians } else { JointUnits::Degrees },
        orientation: a.robot.orientation,
    };
    let data = match &a.poses {
        Some(poses) => read_measurements_joined(&a.measurements, poses, a.key.as_deref(), &kinds, units),
        None => read_measurements_with(&a.measurements, &kinds, units),
    }
    .map_err(Failure::input)?;
    let holdout = match &a.holdout {
        Some(p) => Some(read_measurements_with(p, &kinds, units).map_err(Failure::input)?),
        None => None,
    };
    if a.noise.is_some_and(|n| !(n.is_finite() && n > 0.0)) {
        return Err(Failure::input(anyhow!("--noise must be a positive standard deviation in mm")));
    }
    if !(a.orientation_lever.is_finite() && a.orientation_lever >= 0.0) {
        return Err(Failure::input(anyhow!("--orientation-lever must be ≥ 0 mm")));
    }
    if a.orientation_noise.is_some_and(|n| !(n.is_finite() && n > 0.0)) {
        return Err(Failure::input(anyhow!("--orientation-noise must be a positive standard deviation in degrees")));
    }
    let config = Config {
        folds_by: match a.folds_by {
            FoldsByArg::Neighbourhood => FoldGrouping::Neighbourhood,
            FoldsByArg::Time => FoldGrouping::Time,
            FoldsByArg::Region => FoldGrouping::WorkspaceRegion,
            FoldsByArg::Configuration => FoldGrouping::JointConfiguration,
        },
        noise_mm: a.noise,
        orientation_lever_mm: a.orientation_lever,
        orientation_noise_deg: a.orientation_noise,
        folds: a.folds,
        frame: if a.frame == FrameArg::Tracker { FrameMode::Tracker } else { FrameMode::Base },
        tool: if a.tool == ToolArg::Unknown { ToolMode::Unknown } else { ToolMode::Known },
        ..Config::default()
    };
    let robot = loaded.robot.with_chain(chain).map_err(Failure::input)?;
    // The robot as the fit sees it: with the payload (gravity only; the export keeps the file's masses).
    let fitted_robot = match &a.robot.payload {
        Some(spec) => robot
            .clone()
            .with_payload(crate::input::parse_payload(spec).map_err(Failure::input)?)
            .map_err(Failure::input)?,
        None => robot.clone(),
    };
    // Progress on stderr, one step per stage — the selection, each outer fold of the nested validation,
    // the hold-out set: a bar on a terminal, a line per stage with an estimate of the time left
    // otherwise (a log file, CI), nothing with --quiet. Stages cost about the same, so the estimate is
    // the mean time per stage so far times the stages left.
    let terminal = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let bar = if a.quiet || !terminal {
        indicatif::ProgressBar::hidden()
    } else {
        let bar = indicatif::ProgressBar::new(0).with_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} diagnosing: {msg} [{bar:20}] {pos}/{len} ({elapsed}, ETA {eta})",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
        bar.enable_steady_tick(std::time::Duration::from_millis(250));
        bar.set_message("selection on all measurements");
        bar
    };
    let started = std::time::Instant::now();
    let report =
        thermokin_diagnose::diagnose_with_progress(&fitted_robot, &data, holdout.as_ref(), &config, &mut |p| {
            bar.set_length(p.total as u64);
            bar.set_position(p.done as u64);
            bar.set_message(format!("done: {}", p.stage));
            if !a.quiet && !terminal {
                let elapsed = started.elapsed().as_secs_f64();
                let left = elapsed / p.done.max(1) as f64 * (p.total - p.done) as f64;
                eprintln!(
                    "diagnose: {}/{} {} — {elapsed:.1} s elapsed, about {left:.0} s left",
                    p.done, p.total, p.stage
                );
            }
        })
        .map_err(Failure::input);
    bar.finish_and_clear();
    let report = report?;
    print_report(&report);
    if let (Some(p), Some(why)) = (&a.export, &report.honest_end)
        && !a.force_export
    {
        return Err(Failure::input(anyhow!("not writing {}: {why} (--force-export writes it anyway)", p.display())));
    }
    if let Some(p) = &a.export {
        // The model scored, on the file's robot (its own masses; the payload the data were measured with
        // kept as the robot's default payload, which a later --payload replaces).
        let payload =
            a.robot.payload.as_deref().map(crate::input::parse_payload).transpose().map_err(Failure::input)?;
        let named = robot
            .with_chain(report.identified.robot().chain().clone())
            .map_err(Failure::internal)?
            .renamed(format!("{} (calibrated on {})", robot.name(), a.measurements.display()));
        let model = report
            .identified
            .clone()
            .with_robot(named)
            .and_then(|m| m.with_payload(payload))
            .map_err(Failure::internal)?;
        let beyond = model.beyond_urdf();
        let urdf = p.extension().is_some_and(|e| e.eq_ignore_ascii_case("urdf"));
        let text = if urdf {
            thermokin_urdf::export_robot_noting(model.robot(), &beyond)
        } else {
            thermokin_io::robot_model_to_toml(&model)
        };
        write_atomic(p, text.as_bytes()).map_err(Failure::internal)?;
        let carried: Vec<String> = report.effects.iter().map(|e| e.label.clone()).collect();
        println!(
            "\nidentified robot → {}: {}",
            p.display(),
            if carried.is_empty() { "the frames only".to_string() } else { carried.join(", ") }
        );
        if urdf && !beyond.is_empty() {
            println!("  URDF cannot hold (named in the file's header; write .toml for the complete record):");
            for line in &beyond {
                println!("    {line}");
            }
        }
    }
    if let Some(p) = &a.json {
        let text = serde_json::to_string_pretty(&report).map_err(Failure::internal)?;
        write_atomic(p, text.as_bytes()).map_err(Failure::internal)?;
    }
    if let Some(dir) = &a.plot {
        std::fs::create_dir_all(dir).map_err(|e| Failure::internal(anyhow!("{}: {e}", dir.display())))?;
        plot_residuals(&dir.join("residuals.svg"), &report).map_err(Failure::internal)?;
        plot_additive(&dir.join("heldout-per-effect.svg"), &report).map_err(Failure::internal)?;
    }
    Ok(exit::OK)
}

fn print_report(r: &Report) {
    if let Some(why) = &r.honest_end {
        println!("NOT BETTER THAN NOMINAL: {why}\n");
    }
    for w in &r.warnings {
        println!("warning: {w}");
    }
    if let Some(lever) = r.orientation_lever_mm {
        println!(
            "6-D measurements: orientations fitted with positions; every error below is √(|Δp|² + ({lever} mm · |δφ|)²) (--orientation-lever)"
        );
    }
    let line = |what: &str, s: &thermokin_diagnose::Stats| {
        println!(
            "  {what:<44} {:>9.4} {:>9.4} {:>9.4} {:>9.4} {:>9.4}",
            s.heldout_mean_mm, s.heldout_median_mm, s.heldout_p95_mm, s.heldout_rms_mm, s.heldout_max_mm
        )
    };
    let header = || println!("  {:<44} {:>9} {:>9} {:>9} {:>9} {:>9}", "model", "mean", "median", "p95", "RMS", "max");
    if let Some(n) = &r.nested {
        println!(
            "held-out error of the whole diagnosis, nested {}-fold (each outer test fold unseen by the selection), mm:",
            n.outer_folds
        );
        header();
        line("nominal", &n.nominal);
        line("the effects each outer selection chose", &n.selected);
        for f in &n.folds {
            let chosen = if f.effects.is_empty() { "none".to_string() } else { f.effects.join(", ") };
            let flag = if f.selected.heldout_rms_mm > f.nominal.heldout_rms_mm { "  WORSE THAN NOMINAL" } else { "" };
            println!(
                "    outer fold {} ({} poses): nominal {:.4} → {:.4} mm RMS{flag}; chose {chosen}",
                f.fold, f.poses, f.nominal.heldout_rms_mm, f.selected.heldout_rms_mm
            );
        }
        if let Some(d) = n.dominated_by {
            println!("    outer fold {d} holds more than half of the squared error: the RMS above is mostly that fold");
        }
    }
    if let Some(h) = &r.holdout {
        println!("\nexplicit hold-out set (fitted on all measurements; never used to choose), mm:");
        if !h.refitted.is_empty() {
            println!("  (its own frame and probe: {} refitted on it, the effects kept)", h.refitted.join(", "));
        }
        header();
        line("nominal", &h.nominal);
        line("the effects chosen below", &h.selected);
    }
    println!("\nselection: {} — scores that chose the effects (optimistic):", r.validation);
    println!("  {:<44} {:>9} {:>9} {:>9}", "model", "mean", "RMS", "max");
    for row in &r.additive {
        println!(
            "  {:<44} {:>9.4} {:>9.4} {:>9.4}",
            row.model, row.stats.heldout_mean_mm, row.stats.heldout_rms_mm, row.stats.heldout_max_mm
        );
    }
    if !r.leave_one_out.is_empty() {
        println!("\nleave one out (mm):");
        for row in &r.leave_one_out {
            println!(
                "  {:<44} {:>9.4} {:>9.4} {:>9.4}",
                row.model, row.stats.heldout_mean_mm, row.stats.heldout_rms_mm, row.stats.heldout_max_mm
            );
        }
    }
    println!("\neffects, main cause first (the one whose removal raises the held-out error most):");
    if r.effects.is_empty() {
        println!(
            "  none: no candidate lowers the held-out mean squared error by more than one standard error of the paired difference"
        );
    }
    for e in &r.effects {
        println!(
            "  {:<30} held-out RMS {:.4} → {:.4} mm (without it: {:.4}){}",
            e.label,
            e.heldout_rms_before_mm,
            e.heldout_rms_after_mm,
            e.heldout_rms_without_mm,
            if e.equivalent.is_empty() { String::new() } else { format!("; equivalent: {}", e.equivalent.join(", ")) }
                + &if e.contained_in.is_empty() {
                    String::new()
                } else {
                    format!("; contained in: {}", e.contained_in.join(", "))
                }
                + &if e.contains.is_empty() { String::new() } else { format!("; contains: {}", e.contains.join(", ")) }
        );
        for (name, v) in &e.parameters {
            match (&v.fixed, v.std) {
                (Some(why), _) => println!("      {name:<44} {:>12.6}   fixed, not fitted: {why}", v.value),
                (None, Some(sd)) => println!("      {name:<44} {:>12.6} ± {sd:.6}", v.value),
                (None, None) => {
                    println!("      {name:<44} {:>12.6}   (no uncertainty: singular normal matrix)", v.value)
                }
            }
        }
    }
    if let Some(reg) = &r.frames.registration {
        let [x, y, z] = reg.position_mm;
        let [a, b, c] = reg.xyz_euler_deg;
        println!(
            "\nfitted registration (measurement frame ← base): {x:.4}, {y:.4}, {z:.4} mm; {a:.5}, {b:.5}, {c:.5}° (X-Y-Z Euler)"
        );
    }
    if let Some([x, y, z]) = r.frames.tool_point_mm {
        println!("fitted tool point (flange frame): {x:.4}, {y:.4}, {z:.4} mm");
    }
    if let Some([x, y, z]) = r.frames.tool_rotation_deg {
        println!("fitted probe rotation (tool row's X-Y-Z error angles): {x:.5}, {y:.5}, {z:.5}°");
    }
    if !r.identifiability.correlated.is_empty() {
        println!(
            "\nnearly unidentifiable combinations (estimates correlated above 0.99: their combination is determined, not each):"
        );
        for c in &r.identifiability.correlated {
            println!("  {} ~ {} (correlation {:+.4})", c.a, c.b, c.correlation);
        }
    }
    println!("\nverdict: {}", r.verdict);
    println!("\nwhere the nominal model's residuals lie (RMS, mm; → after the effects found):");
    let (b, a) = (&r.residuals_before, &r.residuals_after);
    for (j, (qb, qa)) in b.by_joint.iter().zip(&a.by_joint).enumerate() {
        println!(
            "  joint {} angle quartiles   {}   →   {}",
            j + 1,
            qb.iter().map(|v| format!("{v:.4}")).collect::<Vec<_>>().join(" "),
            qa.iter().map(|v| format!("{v:.4}")).collect::<Vec<_>>().join(" ")
        );
    }
    let four = |v: &[f64; 4]| v.iter().map(|x| format!("{x:.4}")).collect::<Vec<_>>().join(" ");
    println!(
        "  workspace (near-low near-high far-low far-high)   {}   →   {}",
        four(&b.by_workspace_region),
        four(&a.by_workspace_region)
    );
    println!(
        "  joint space (elbow × wrist)                       {}   →   {}",
        four(&b.by_joint_space_region),
        four(&a.by_joint_space_region)
    );
    if !b.by_time.is_empty() {
        let list = |v: &[f64]| v.iter().map(|x| format!("{x:.4}")).collect::<Vec<_>>().join(" ");
        println!("  time quartiles                                    {}   →   {}", list(&b.by_time), list(&a.by_time));
    }
    if !r.identifiability.not_identifiable.is_empty() {
        println!("\nnot identifiable from these data (not selectable; --help of diagnose says the rules):");
        for x in &r.identifiability.not_identifiable {
            println!("  {:<30} {} — {}", x.effect, x.reason, x.remedy);
        }
    }
    if let Some(o) = &r.identifiability.observability {
        println!(
            "\nidentifiability: {} parameters from {} residuals; condition number {:.3e}; O1 {:.3e} O2 {:.3e} O3 {:.3e} O4 {:.3e} O5 {:.3e}",
            o.parameters, o.rows, o.condition_number, o.o1, o.o2, o.o3, o.o4, o.o5
        );
    }
    for f in &r.identifiability.fixed {
        println!("  fixed {}: {}", f.parameter, f.reason);
    }
}

fn plot_residuals(path: &Path, r: &Report) -> anyhow::Result<()> {
    let before = &r.residuals_before.per_measurement_mm;
    let after = &r.residuals_after.per_measurement_mm;
    let y_max = before.iter().chain(after).copied().fold(1e-6, f64::max) * 1.1;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 500)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption("Position residual per measurement, before and after", ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0usize..before.len().max(1), 0.0..y_max)?;
        chart.configure_mesh().x_desc("measurement").y_desc("|residual| [mm]").draw()?;
        chart
            .draw_series(before.iter().enumerate().map(|(i, v)| Circle::new((i, *v), 3, RED.filled())))?
            .label("nominal model")
            .legend(|(x, y)| Circle::new((x + 10, y), 3, RED.filled()));
        chart
            .draw_series(after.iter().enumerate().map(|(i, v)| Circle::new((i, *v), 3, BLUE.filled())))?
            .label("with the effects found")
            .legend(|(x, y)| Circle::new((x + 10, y), 3, BLUE.filled()));
        chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
        root.present()?;
    }
    write_atomic(path, svg.as_bytes()).map_err(|e| anyhow!(e))
}

fn plot_additive(path: &Path, r: &Report) -> anyhow::Result<()> {
    let rows = &r.additive;
    let y_max = rows.iter().map(|x| x.stats.heldout_rms_mm).fold(1e-6, f64::max) * 1.1;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 500)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption("Held-out RMS as effects are added", ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(60)
            .y_label_area_size(60)
            .build_cartesian_2d((0..rows.len()).into_segmented(), 0.0..y_max)?;
        chart
            .configure_mesh()
            .y_desc("held-out RMS [mm]")
            .x_label_formatter(&|v| match v {
                SegmentValue::CenterOf(i) => rows.get(*i).map_or(String::new(), |r| r.model.clone()),
                _ => String::new(),
            })
            .draw()?;
        chart.draw_series(
            Histogram::vertical(&chart)
                .style(BLUE.mix(0.6).filled())
                .data(rows.iter().enumerate().map(|(i, r)| (i, r.stats.heldout_rms_mm))),
        )?;
        root.present()?;
    }
    write_atomic(path, svg.as_bytes()).map_err(|e| anyhow!(e))
}

/// Parses `KIND[:JOINT][=VALUES]` into a hidden effect (report units → internal), with a seeded random
/// effect of typical size when no values are given.
fn parse_effect(spec: &str, robot: &Robot, rng: &mut ChaCha8Rng) -> anyhow::Result<HiddenEffect> {
    let (head, values) = match spec.split_once('=') {
        Some((h, v)) => (h, Some(crate::args::parse_list("effect", v)?)),
        None => (spec, None),
    };
    let (name, joint) = match head.split_once(':') {
        Some((k, j)) => {
            let j: usize = j.parse().map_err(|_| anyhow!("--effect {spec}: joint `{j}` is not a number"))?;
            anyhow::ensure!(j >= 1, "--effect {spec}: joints are numbered from 1");
            (k, Some(j - 1))
        }
        None => (head, None),
    };
    let effect = Effect::named(robot, name, joint).map_err(|e| anyhow!("--effect {spec}: {e}"))?;
    let report_units: Vec<f64> = match values {
        // A tool-frame error given as a point only (three values): no rotation.
        Some(mut v) if effect == Effect::ToolFrame && v.len() == 3 => {
            v.extend([0.0; 3]);
            v
        }
        Some(v) => {
            anyhow::ensure!(
                v.len() == effect.len(),
                "--effect {spec}: {} values for {} parameters",
                v.len(),
                effect.len()
            );
            v
        }
        None => (0..effect.len())
            .map(|k| match (effect, k) {
                (Effect::JointOffset(_), _) => {
                    rng.random_range(0.02..0.06) * if rng.random_bool(0.5) { 1.0 } else { -1.0 }
                }
                (Effect::JointCompliance(_), _) => rng.random_range(5e-4..1.5e-3),
                (Effect::JointScale(_), _) => rng.random_range(2e-4..6e-4),
                (Effect::Periodic(_), _) => rng.random_range(-0.03..0.03),
                (Effect::ThermalDrift(_, DriftShape::Exponential), 6) => rng.random_range(30.0..90.0),
                (_, 0..=2) => rng.random_range(-0.4..0.4),
                _ => rng.random_range(-0.02..0.02),
            })
            .collect(),
    };
    let values = report_units.iter().enumerate().map(|(k, &v)| effect.from_report_units(k, v)).collect();
    Ok(HiddenEffect { effect, values })
}

pub fn simulate(a: SimulateArgs) -> Result<u8, Failure> {
    let ok = a.noise.is_finite() && a.noise >= 0.0 && a.minutes.is_finite() && a.minutes >= 0.0 && a.poses > 0;
    if !ok {
        return Err(Failure::input(anyhow!("--noise and --minutes must be ≥ 0 and --poses positive")));
    }
    if a.orientation_noise.is_some_and(|n| !(n.is_finite() && n >= 0.0)) {
        return Err(Failure::input(anyhow!("--orientation-noise must be ≥ 0 degrees")));
    }
    let loaded = load(&a.robot)?;
    if !loaded.model.is_plain() {
        return Err(Failure::input(anyhow!(
            "{} carries identified corrections ({}): simulate hides effects on a plain robot (--effect)",
            a.robot.robot.display(),
            loaded.model.beyond_urdf().join("; ")
        )));
    }
    let chain = working_chain(&a.robot, &loaded)?;
    let mut rng = ChaCha8Rng::seed_from_u64(a.seed ^ 0x5eed);
    let robot = loaded.robot.with_chain(chain).map_err(Failure::input)?;
    let hidden = a
        .effects
        .iter()
        .map(|s| parse_effect(s, &robot, &mut rng))
        .collect::<anyhow::Result<Vec<_>>>()
        .map_err(Failure::input)?;
    let config = SimulationConfig {
        poses: a.poses,
        minutes: a.minutes,
        noise_mm: a.noise,
        seed: a.seed,
        orientation_noise_rad: a.orientation_noise.map(thermokin_io::units::radians),
        ..SimulationConfig::default()
    };
    let data = thermokin_diagnose::simulate(&robot, &hidden, &config).map_err(Failure::input)?;
    let kinds: Vec<_> = robot.chain().joints().iter().map(|j| j.kind).collect();
    write_atomic_with(&a.out, |w| write_measurements(w, &data, &kinds)).map_err(Failure::internal)?;
    for h in &hidden {
        let shown: Vec<String> = h
            .values
            .iter()
            .enumerate()
            .map(|(k, &v)| {
                if h.effect.is_angle(k) {
                    format!("{:.6}°", h.effect.to_report_units(k, v))
                } else {
                    format!("{v:.6}")
                }
            })
            .collect();
        println!("hidden {}: {} (mm, degrees, minutes)", h.effect.label(), shown.join(", "));
    }
    println!("{} poses over {} min, noise {} mm → {}", a.poses, a.minutes, a.noise, a.out.display());
    Ok(exit::OK)
}
