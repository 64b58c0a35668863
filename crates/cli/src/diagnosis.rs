//! `thermokin diagnose` and `thermokin simulate`: the sim-to-real diagnosis on a measurement set, and
//! measurement sets generated from hidden effects.

use std::path::Path;

use anyhow::anyhow;
use plotters::prelude::*;
use thermokin_chain::Robot;
use thermokin_diagnose::{Config, FoldGrouping, HiddenEffect, Report, SimulationConfig};
use thermokin_identify::{FrameMode, ToolMode};
use thermokin_io::{
    JointUnits, MeasurementFormat, read_measurements_joined, read_measurements_with, write_atomic, write_atomic_with,
    write_measurements,
};

use crate::args::{DiagnoseArgs, FoldsByArg, FrameArg, JointUnitsArg, SimulateArgs, ToolArg};
use crate::input::{load, working_chain};
use crate::{Failure, exit};

/// A library setting's error in the words of the command line: the flag that set it.
fn setting_error(e: thermokin_diagnose::DiagnoseError) -> Failure {
    match e {
        thermokin_diagnose::DiagnoseError::BadSetting { setting, rule, .. } => {
            let flag = match setting {
                "folds" => "--folds",
                "noise_mm" => "--noise",
                "orientation_lever_mm" => "--orientation-lever",
                "orientation_noise_rad" => "--orientation-noise",
                "poses" => "--poses",
                "minutes" => "--minutes",
                other => other,
            };
            Failure::input(anyhow!("{flag} {rule}"))
        }
        other => Failure::input(anyhow!(other)),
    }
}

/// The diagnosis with progress on stderr, one step per stage — the selection, each outer fold of the
/// nested validation, the hold-out set: a bar on a terminal, a line per stage with an estimate of the
/// time left otherwise (a log file, CI), nothing with --quiet. Stages cost about the same, so the
/// estimate is the mean time per stage so far times the stages left.
fn run_with_progress(
    a: &DiagnoseArgs,
    robot: &Robot,
    data: &thermokin_chain::Dataset,
    holdout: Option<&thermokin_chain::Dataset>,
    config: &Config,
) -> Result<Report, Failure> {
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
    let report = thermokin_diagnose::diagnose_with_progress(robot, data, holdout, config, &mut |p| {
        bar.set_length(p.total as u64);
        bar.set_position(p.done as u64);
        bar.set_message(format!("done: {}", p.stage));
        if !a.quiet && !terminal {
            let elapsed = started.elapsed().as_secs_f64();
            let left = elapsed / p.done.max(1) as f64 * (p.total - p.done) as f64;
            eprintln!("diagnose: {}/{} {} — {elapsed:.1} s elapsed, about {left:.0} s left", p.done, p.total, p.stage);
        }
    })
    .map_err(Failure::input);
    bar.finish_and_clear();
    report
}

/// `--export`: the model scored ([`Report::export_model`]) written as robot TOML, or as URDF with what
/// URDF cannot hold named in its header and here.
fn export(a: &DiagnoseArgs, path: &Path, robot: &Robot, report: &Report) -> Result<(), Failure> {
    let payload = a.robot.payload.as_deref().map(crate::input::parse_payload).transpose().map_err(Failure::input)?;
    let source = a.measurements.display().to_string();
    let model = report.export_model(robot, payload, &source).map_err(Failure::internal)?;
    let beyond = model.beyond_urdf();
    let urdf = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("urdf"));
    let text = if urdf {
        thermokin_urdf::export_robot_noting(model.robot(), &beyond)
    } else {
        thermokin_io::robot_model_to_toml(&model)
    };
    write_atomic(path, text.as_bytes()).map_err(Failure::internal)?;
    let carried: Vec<String> = report.effects.iter().map(|e| e.label.clone()).collect();
    println!(
        "\nidentified robot → {}: {}",
        path.display(),
        if carried.is_empty() { "the frames only".to_string() } else { carried.join(", ") }
    );
    if urdf && !beyond.is_empty() {
        println!("  URDF cannot hold (named in the file's header; write .toml for the complete record):");
        for line in &beyond {
            println!("    {line}");
        }
    }
    Ok(())
}

pub fn diagnose(a: DiagnoseArgs) -> Result<u8, Failure> {
    if a.robot.profile.is_some() || a.robot.time.is_some() || a.robot.temperature.is_some() {
        return Err(Failure::input(anyhow!(
            "diagnose takes a static robot: drop --profile/--time/--temperature (thermal drift is a candidate effect; the data's time_min and temp_* columns drive it)"
        )));
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
        orientation_noise_rad: a.orientation_noise.map(thermokin_io::units::radians),
        folds: a.folds,
        frame: if a.frame == FrameArg::Tracker { FrameMode::Tracker } else { FrameMode::Base },
        tool: if a.tool == ToolArg::Unknown { ToolMode::Unknown } else { ToolMode::Known },
        ..Config::default()
    };
    config.validate().map_err(setting_error)?;
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
    let robot = loaded.robot.with_chain(chain).map_err(Failure::input)?;
    // The robot as the fit sees it: with the payload (gravity only; the export keeps the file's masses).
    let fitted_robot = match &a.robot.payload {
        Some(spec) => robot
            .clone()
            .with_payload(crate::input::parse_payload(spec).map_err(Failure::input)?)
            .map_err(Failure::input)?,
        None => robot.clone(),
    };
    let report = run_with_progress(&a, &fitted_robot, &data, holdout.as_ref(), &config)?;
    print!("{}", report.text());
    if let (Some(p), Some(why)) = (&a.export, &report.honest_end)
        && !a.force_export
    {
        return Err(Failure::input(anyhow!("not writing {}: {why} (--force-export writes it anyway)", p.display())));
    }
    if let Some(p) = &a.export {
        export(&a, p, &robot, &report)?;
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

pub fn simulate(a: SimulateArgs) -> Result<u8, Failure> {
    let loaded = load(&a.robot)?;
    if !loaded.model.is_plain() {
        return Err(Failure::input(anyhow!(
            "{} carries identified corrections ({}): simulate hides effects on a plain robot (--effect)",
            a.robot.robot.display(),
            loaded.model.beyond_urdf().join("; ")
        )));
    }
    let chain = working_chain(&a.robot, &loaded)?;
    let robot = loaded.robot.with_chain(chain).map_err(Failure::input)?;
    let config = SimulationConfig {
        poses: a.poses,
        minutes: a.minutes,
        noise_mm: a.noise,
        seed: a.seed,
        orientation_noise_rad: a.orientation_noise.map(thermokin_io::units::radians),
        ..SimulationConfig::default()
    };
    let mut rng = config.effect_rng();
    let hidden = a
        .effects
        .iter()
        .map(|s| HiddenEffect::parse(s, &robot, &mut rng).map_err(|e| anyhow!("--effect {e}")))
        .collect::<anyhow::Result<Vec<_>>>()
        .map_err(Failure::input)?;
    let data = thermokin_diagnose::simulate(&robot, &hidden, &config).map_err(setting_error)?;
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
