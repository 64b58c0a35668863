//! `thermokin diagnose` and `thermokin simulate`: the sim-to-real diagnosis on a measurement set, and
//! measurement sets generated from hidden effects.

use std::path::Path;

use anyhow::anyhow;
use thermokin_chain::Robot;
use thermokin_diagnose::{Config, DiagnoseError, HiddenEffect, Report, SimulationConfig};
use thermokin_io::{MeasurementFormat, read_measurements_joined, read_measurements_with, write_measurements};

use crate::args::{DiagnoseArgs, SimulateArgs};
use crate::input::{load, units_error, working_chain};
use crate::{Failure, exit};

/// A library setting's error in the words of the command line: the flag that set it.
fn setting_error(e: DiagnoseError) -> Failure {
    const FLAGS: [(&str, &str); 6] = [
        ("folds", "--folds"),
        ("noise_mm", "--noise"),
        ("orientation_lever_mm", "--orientation-lever"),
        ("orientation_noise_rad", "--orientation-noise"),
        ("poses", "--poses"),
        ("minutes", "--minutes"),
    ];
    let DiagnoseError::BadSetting { setting, rule, .. } = &e else { return Failure::input(e) };
    let flag = FLAGS.iter().find(|(s, _)| s == setting).map_or(*setting, |(_, f)| *f);
    Failure::input(anyhow!("{flag} {rule}"))
}

/// The diagnosis with progress on stderr, a step per stage (selection, outer folds, hold-out): a bar on a
/// terminal, else a line per stage with the time left (mean per stage × stages left); none with --quiet.
fn run_with_progress(
    a: &DiagnoseArgs,
    robot: &Robot,
    data: &thermokin_chain::Dataset,
    holdout: Option<&thermokin_chain::Dataset>,
    config: &Config,
) -> Result<Report, Failure> {
    let terminal = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let bar = crate::input::progress_bar(1, "diagnosing");
    let started = std::time::Instant::now();
    let report =
        thermokin_diagnose::diagnose_with_progress(robot, data, holdout, config, &mut |p| match (a.quiet, terminal) {
            (true, _) => {}
            (false, true) => bar.set_position(p.done as u64, p.total as u64),
            (false, false) => {
                let elapsed = started.elapsed().as_secs_f64();
                let left = elapsed / p.done.max(1) as f64 * (p.total - p.done) as f64;
                eprintln!(
                    "diagnose: {}/{} {} — {elapsed:.1} s elapsed, about {left:.0} s left",
                    p.done, p.total, p.stage
                );
            }
        })
        .map_err(Failure::input);
    bar.finish();
    report
}

/// `--export`: the model scored ([`Report::export_model`]) written as robot TOML, or as URDF with what
/// URDF cannot hold named in its header and here.
fn export(a: &DiagnoseArgs, path: &Path, robot: &Robot, report: &Report) -> Result<(), Failure> {
    let payload = a.robot.payload.as_deref().map(crate::input::parse_payload).transpose().map_err(Failure::input)?;
    let source = a.measurements.display().to_string();
    let model = report.export_model(robot, payload, &source).map_err(Failure::internal)?;
    let (text, beyond) = thermokin_io::robot_file_text(&model, path).map_err(Failure::input)?;
    crate::out::save(path, text)?;
    let carried: Vec<String> = report.effects.iter().chain(&report.completed).map(|e| e.label.clone()).collect();
    say!(
        "\nidentified robot → {}: {}",
        path.display(),
        if carried.is_empty() { "the frames only".to_string() } else { carried.join(", ") }
    );
    if !beyond.is_empty() {
        let format = if thermokin_io::is_ur_yaml(path) { "A UR kinematics YAML" } else { "URDF" };
        say!("  {format} cannot hold (named in the file's header; write .toml for the complete record):");
        for line in &beyond {
            say!("    {line}");
        }
    }
    Ok(())
}

/// Where the report refused effects for what the poses cover (a joint's arc, a gravity-torque range), the
/// command that plans the poses to measure next, from these measurements, and what it pins down.
fn next_poses(a: &DiagnoseArgs, report: &Report) -> Option<(String, String)> {
    let refused = report.refused_for_coverage();
    if refused.is_empty() {
        return None;
    }
    let tip = a.robot.tip.as_deref().map(|t| format!(" --tip {}", shell_word(t))).unwrap_or_default();
    let command = format!(
        "thermokin plan --robot {}{tip} --frame {} --tool {} --measured {} --criterion parameters --poses 20 --out next.csv",
        shell_word(&a.robot.robot.display().to_string()),
        a.frame,
        a.tool,
        shell_word(&a.measurements.display().to_string()),
    );
    Some((command, refused.join(", ")))
}

/// `word` as a POSIX shell reads it back as one word: as it is where every character is one no shell
/// splits or interprets, else in single quotes (a quote inside written `'\''`) — so that a printed
/// command pastes as printed, whatever a folder is called (`a b<c>`).
fn shell_word(word: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "_-./:=@%+,".contains(c);
    if !word.is_empty() && word.chars().all(plain) {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', "'\\''"))
    }
}

/// `--for`: the configurations of a joints file (radians; empty without one).
fn poses_of_use(
    path: Option<&Path>,
    kinds: &[thermokin_chain::JointKind],
    units: Option<thermokin_io::JointUnits>,
) -> Result<Vec<Vec<f64>>, Failure> {
    let Some(path) = path else { return Ok(Vec::new()) };
    Ok(thermokin_io::read_configurations_checked(path, kinds, units).map_err(crate::input::units_error)?.0)
}

/// `--plan`: the promise of the plan's JSON (`promise.planned_rms_mm` at `promise.noise_mm`), made for
/// `poses` poses of use.
fn promised(path: &Path, poses: usize) -> Result<thermokin_diagnose::Promised, Failure> {
    let text = std::fs::read_to_string(path).map_err(|e| Failure::input(anyhow!("{}: {e}", path.display())))?;
    let json: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| Failure::input(anyhow!("{}:{}: not a plan's JSON: {e}", path.display(), e.line())))?;
    let field = |name: &str| {
        json["promise"][name].as_f64().filter(|v| v.is_finite() && *v > 0.0).ok_or_else(|| {
            Failure::input(anyhow!(
                "{}: promise.{name}: missing or not a positive number (the JSON `thermokin plan --json` writes)",
                path.display()
            ))
        })
    };
    let made_for = field("poses_of_use")? as usize;
    if made_for != poses {
        return Err(Failure::input(anyhow!(
            "{}: promise.poses_of_use: the plan promised at {made_for} poses of use, --for gives {poses}: give the file the plan was made --for",
            path.display()
        )));
    }
    // Absent from a plan written before stand-ins existed: none then.
    let at_nearest = json["promise"]["planned_at_nearest"].as_u64().map_or(0, |n| n as usize);
    Ok(thermokin_diagnose::Promised {
        rms_mm: field("planned_rms_mm")?,
        noise_mm: field("noise_mm")?,
        poses: made_for,
        at_nearest,
    })
}

pub fn diagnose(a: DiagnoseArgs) -> Result<u8, Failure> {
    if a.robot.profile.is_some() || a.robot.time.is_some() || a.robot.temperature.is_some() {
        return Err(Failure::input(anyhow!(
            "diagnose takes a static robot: drop --profile/--time/--temperature (thermal drift is a candidate effect; the data's time_min and temp_* columns drive it)"
        )));
    }
    let mut config = Config {
        folds_by: a.folds_by,
        outliers: a.outliers,
        masses: a.masses,
        lateral: a.lateral,
        order: a.order,
        accelerometers: a.accelerometers.clone(),
        shrinkage: a.shrinkage,
        extrapolation: a.extrapolation,
        noise_mm: a.noise,
        orientation_lever_mm: a.orientation_lever,
        orientation_noise_rad: a.orientation_noise.map(thermokin_io::units::radians),
        folds: a.folds,
        frame: a.frame,
        tool: a.tool,
        ..Config::default()
    };
    config.validate().map_err(setting_error)?;
    let loaded = load(&a.robot)?;
    loaded.model.require_plain().map_err(|e| {
        Failure::input(anyhow!(
            "{}: {e}: diagnose the robot they were identified on (its geometry is the starting point), or the calibrated geometry alone",
            a.robot.robot.display()
        ))
    })?;
    let chain = working_chain(&a.robot, &loaded)?;
    let kinds: Vec<_> = chain.joints().iter().map(|j| j.kind).collect();
    let units = MeasurementFormat {
        joint_units: a.joint_units,
        position_units: a.position_units,
        orientation: a.robot.orientation,
    };
    let data = match &a.poses {
        Some(poses) => read_measurements_joined(&a.measurements, poses, a.key.as_deref(), &kinds, units),
        None => read_measurements_with(&a.measurements, &kinds, units),
    }
    .map_err(units_error)?;
    if a.poses.is_none() {
        // No column ignored in silence (an accelerometer's, a load's): the diagnosis does not read it.
        let unread = thermokin_io::unread_columns(&a.measurements, &kinds, units).unwrap_or_default();
        crate::input::warn_ignored(&a.measurements, &unread);
        say_sensors(&a.measurements, &data, &loaded.robot, &a.accelerometers);
    }
    let holdout = match &a.holdout {
        Some(p) => Some(read_measurements_with(p, &kinds, units).map_err(units_error)?),
        None => None,
    };
    config.poses_of_use = poses_of_use(a.region.as_deref(), &kinds, a.joint_units)?;
    config.promised = a.plan.as_deref().map(|p| promised(p, config.poses_of_use.len())).transpose()?;
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
    say!("{}", report.text().to_string().trim_end());
    let next = next_poses(&a, &report);
    if let Some((command, pins)) = &next {
        say!(
            "\nnext poses: `{command}` plans the poses that pin down {pins}, sampled within the joint limits — add --candidates FILE with the poses you can reach (docs/planner.md)"
        );
    }
    if let Some(p) = &a.html {
        let context = thermokin_report::PageContext {
            holdout: a.holdout.as_ref().map(|h| h.display().to_string()),
            next_poses: next.map(|(command, _)| command),
            ..thermokin_report::PageContext::new(
                a.robot.robot.display().to_string(),
                a.measurements.display().to_string(),
            )
        };
        crate::out::save(p, thermokin_report::diagnosis_page(&report, &context))?;
    }
    if let Some(p) = &a.json {
        let text = serde_json::to_string_pretty(&report).map_err(Failure::internal)?;
        crate::out::save(p, text)?;
    }
    if let Some(dir) = &a.plot {
        crate::out::save_plots(dir, thermokin_plot::diagnosis_plots(&report))?;
    }
    if let Some(p) = &a.export {
        if let Err(e) = report.check_export(a.force_export) {
            let error = anyhow!("not writing {}: {e} (--force-export writes it anyway)", p.display());
            return Err(Failure { code: exit::REFUSED, error });
        }
        export(&a, p, &robot, &report)?;
    }
    Ok(exit::OK)
}

pub fn simulate(a: SimulateArgs) -> Result<u8, Failure> {
    let loaded = load(&a.robot)?;
    loaded.model.require_plain().map_err(|e| {
        Failure::input(anyhow!("{}: {e}: simulate hides effects on a plain robot (--effect)", a.robot.robot.display()))
    })?;
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
    crate::out::save_with(&a.out, |w| write_measurements(w, &data, &kinds))?;
    for h in &hidden {
        say!("hidden {h}");
    }
    say!("{} poses over {} min, noise {} mm → {}", a.poses, a.minutes, a.noise, a.out.display());
    Ok(exit::OK)
}

/// The sensor columns of `data` (read from `path`) said on stderr: each read as a declared accelerometer's
/// tilt (`flags` and `robot`'s file: [`thermokin_diagnose::declared_accelerometers`]), as a sensor, or not
/// and why ([`thermokin_diagnose::not_sensors`]).
fn say_sensors(
    path: &std::path::Path,
    data: &thermokin_chain::Dataset,
    robot: &thermokin_chain::Robot,
    flags: &[thermokin_diagnose::Accelerometer],
) {
    let declared = thermokin_diagnose::declared_accelerometers(robot, flags);
    let branch_of = |s: &str| robot.branches().iter().find(|b| b.joints.iter().any(|j| j.name == s));
    let of = |s: &str| {
        declared
            .iter()
            .find(|a| ["x", "y", "z"].iter().any(|c| format!("{}_{c}", a.name) == s))
            .map(|_| ())
            .or(branch_of(s).map(|_| ()))
    };
    for s in &data.sensor_names {
        if let Some(b) = branch_of(s) {
            let known = if b.carries_masses() {
                "the torque of its links' masses, as the robot file gives them"
            } else {
                "lumped, the robot file giving no masses on it"
            };
            eprintln!(
                "note: {}: column `{s}` read as the position of joint `{s}` of branch `{}` (degrees; mm for a slide): what the branch carries loads the joints below link {} ({known})",
                path.display(),
                b.name,
                b.link
            );
        } else if let Some(a) =
            declared.iter().find(|a| ["x", "y", "z"].iter().any(|c| format!("{}_{c}", a.name) == *s))
        {
            eprintln!(
                "note: {}: column `{s}` read as accelerometer {}'s tilt (link {})",
                path.display(),
                a.name,
                a.link
            );
        }
    }
    let not_sensors = thermokin_diagnose::not_sensors(data);
    for s in data.sensor_names.iter().filter(|s| of(s).is_none() && !not_sensors.iter().any(|(n, _)| n == *s)) {
        eprintln!("note: {}: column `{s}` read as a sensor (a joint row may follow it)", path.display());
    }
    for (s, why) in not_sensors.iter().filter(|(s, _)| of(s).is_none()) {
        eprintln!("note: {}: column `{s}` is not read as a sensor: {why}", path.display());
    }
}
