//! Inputs shared by the subcommands: the robot with its deformation and overrides, joint lists, poses in
//! any orientation convention, target programs, progress. Units cross here, through
//! [`thermokin_io::units`]; the subcommands see millimetres and radians only.

use std::path::Path;

use anyhow::anyhow;
use indicatif::{ProgressBar, ProgressStyle};
use nalgebra::Isometry3;
use thermokin_chain::{Chain, OperatingState, Target};
use thermokin_deform::{DeformError, RobotModel, StateError};
use thermokin_io::units::joints_to_internal;
use thermokin_io::{LoadError, LoadedRobot, Orientation, PositionUnits, RobotOptions, RobotRequest};

use crate::Failure;
use crate::args::{RobotArgs, parse_list};

/// Reads the robot as the flags ask ([`LoadedRobot::load`]): the file, `--tool-pose` / `--base-pose`,
/// the deviation table and profile, and the state (`--time`, `--temperature`, `--payload`).
pub fn load(args: &RobotArgs) -> Result<LoadedRobot, Failure> {
    let mut state = OperatingState { time_min: args.time, ..OperatingState::default() };
    if let Some(text) = &args.temperature {
        state.temperatures_c =
            thermokin_io::parse_temperatures(text).map_err(|m| Failure::input(anyhow!("--temperature: {m}")))?;
    }
    if let Some(text) = &args.approach {
        state.approach = parse_approach(text).map_err(Failure::input)?;
    }
    if let Some(spec) = &args.payload {
        state.payload = Some(parse_payload(spec).map_err(Failure::input)?);
    }
    let request = RobotRequest {
        path: args.robot.clone(),
        options: RobotOptions { base: args.base.clone(), tip: args.tip.clone() },
        tool: args.tool_pose.as_deref().map(|t| pose(t, "tool-pose", args.orientation)).transpose()?,
        base: args.base_pose.as_deref().map(|t| pose(t, "base-pose", args.orientation)).transpose()?,
        deformation: args.deformation.clone(),
        profile: args.profile.clone(),
        semantics: args.semantics,
        state,
    };
    LoadedRobot::load(&request).map_err(|e| load_error(args, e))
}

/// Parses `--approach +,-,?` (one direction per joint).
pub fn parse_approach(text: &str) -> anyhow::Result<Vec<thermokin_chain::Approach>> {
    text.split(',')
        .enumerate()
        .map(|(k, v)| {
            thermokin_chain::Approach::parse(v).ok_or_else(|| {
                anyhow!("--approach: value {} is `{}`; give + (rising), - (falling) or ? per joint", k + 1, v.trim())
            })
        })
        .collect()
}

/// Parses `--payload KG@X,Y,Z` (kg; mm in the flange's frame).
pub fn parse_payload(spec: &str) -> anyhow::Result<thermokin_chain::LinkMass> {
    thermokin_io::parse_payload(spec).map_err(|m| anyhow!("--payload {m}"))
}

/// The robot fk/ik work on ([`LoadedRobot::working_model`]).
pub fn working_model(args: &RobotArgs, loaded: &LoadedRobot) -> Result<RobotModel, Failure> {
    loaded.working_model().map_err(|e| load_error(args, e))
}

/// The chain the table deforms ([`LoadedRobot::working_chain`]).
pub fn working_chain(args: &RobotArgs, loaded: &LoadedRobot) -> Result<Chain, Failure> {
    loaded.working_chain().map_err(|e| load_error(args, e))
}

/// A robot the library could not load as asked, in the words of the command line: a state or table rule
/// names the flag.
fn load_error(args: &RobotArgs, e: LoadError) -> Failure {
    let robot = args.robot.display();
    let LoadError::Deform(DeformError::State(rule)) = &e else { return Failure::input(e) };
    Failure::input(match rule {
        StateError::TimeWithoutDrift => {
            anyhow!("--time: {robot} has no row drifting with time (give --deformation and --profile to deform it)")
        }
        StateError::UnknownSensor { name, known } => {
            let known = if known.is_empty() { "none".to_string() } else { known.join(", ") };
            anyhow!("--temperature: {robot} has no row drifting with sensor `{name}` (its sensors: {known})")
        }
        StateError::ProfileWithoutTable => anyhow!("--profile needs --deformation"),
        StateError::ProfileNeedsTime => anyhow!("--profile needs --time (minutes)"),
        StateError::TimeNeedsProfile => anyhow!("--time needs --profile"),
        StateError::ApproachWithoutBacklash => {
            anyhow!("--approach: {robot} has no joint with a backlash (a `backlash` line in a joint's table)")
        }
        StateError::ApproachCount { given, joints } => {
            anyhow!("--approach: {given} directions for {robot}'s {joints} joints; give one per joint (+, - or ?)")
        }
        other => anyhow!("{other}"),
    })
}

/// A flag's joint list (degrees, mm for prismatic joints) in the library's radians and mm.
pub fn joints(chain: &Chain, flag: &str, text: &str) -> Result<Vec<f64>, Failure> {
    let values = parse_list(flag, text).map_err(Failure::input)?;
    joints_to_internal(chain, &values).ok_or_else(|| {
        Failure::input(anyhow!("--{flag}: {} values for a robot with {} joints", values.len(), chain.dof()))
    })
}

/// `--seed` (degrees, mm for prismatic joints) in radians and mm; all zero when not given.
pub fn seed(chain: &Chain, text: Option<&str>) -> Result<Vec<f64>, Failure> {
    text.map_or_else(|| Ok(vec![0.0; chain.dof()]), |s| joints(chain, "seed", s))
}

/// A pose flag ([`thermokin_io::parse_pose`]): `x,y,z` (mm) and orientation in `convention`, or JSON.
pub fn pose(text: &str, flag: &str, convention: Orientation) -> Result<Isometry3<f64>, Failure> {
    thermokin_io::parse_pose(text, convention).map_err(|m| Failure::input(anyhow!("--{flag}: {m}")))
}

/// Says which columns of a file nothing reads.
pub fn warn_ignored(path: &Path, columns: &[String]) {
    for c in columns {
        eprintln!("warning: {}: column `{c}` is not read", path.display());
    }
}

/// Reads a targets file row by row, its positions in `units` ([`thermokin_io::TargetRows::settle_units`]),
/// a column named as a sensor of `model` its reading ([`thermokin_io::read_target_rows_for`]); the columns
/// nothing reads are said.
pub fn target_rows(
    path: &Path,
    units: Option<PositionUnits>,
    model: &thermokin_deform::RobotModel,
) -> Result<thermokin_io::TargetRows, Failure> {
    let (_, sensors) = model.needs();
    let read = thermokin_io::read_target_rows_for(path, &sensors).map_err(Failure::input)?.settle_units(path, units);
    let read = read.map_err(units_error)?;
    warn_ignored(path, &read.ignored_columns);
    Ok(read)
}

/// Reads a targets file into a program for `model` ([`target_rows`]).
pub fn program(
    path: &Path,
    units: Option<PositionUnits>,
    model: &thermokin_deform::RobotModel,
) -> Result<Vec<Target>, Failure> {
    target_rows(path, units, model)?.rows.into_iter().collect::<Result<_, _>>().map_err(Failure::input)
}

/// A file's unit the numbers contradict, in the command line's words: the flag to state it.
pub fn units_error(e: thermokin_io::IoError) -> Failure {
    let thermokin_io::IoError::UnitsUnclear { unclear, .. } = &e else { return Failure::input(e) };
    let flag = match unclear {
        thermokin_io::UnitsUnclear::JointsLookLikeRadians { .. } => {
            "give --joint-units rad (or --joint-units deg to read them as degrees)"
        }
        thermokin_io::UnitsUnclear::PositionsLookLikeMetres { .. } => {
            "give --position-units m (or --position-units mm to read them as millimetres)"
        }
    };
    Failure::input(anyhow!("{e}: {flag}"))
}

/// A progress bar of `len` steps that shows itself only when a run lasts more than a second.
pub fn progress_bar(len: u64, label: &str) -> DelayedBar {
    let bar = ProgressBar::hidden();
    bar.set_length(len);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} steps ({eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(label.to_string());
    DelayedBar::new(bar)
}

/// A progress display on stderr that appears once its run has lasted a second: a short run prints
/// nothing (the one rule for every command's progress).
pub struct DelayedBar {
    bar: ProgressBar,
    started: std::time::Instant,
}

impl DelayedBar {
    /// `bar` (hidden until the first second has passed).
    pub fn new(bar: ProgressBar) -> Self {
        Self { bar, started: std::time::Instant::now() }
    }

    /// `done` steps so far, of `len`.
    pub fn set_position(&self, done: u64, len: u64) {
        if self.started.elapsed() > std::time::Duration::from_secs(1) && self.bar.is_hidden() {
            self.bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
        }
        self.bar.set_length(len);
        self.bar.set_position(done);
    }

    /// Removes the bar from the terminal.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// The controller language of a `--program` file ([`thermokin_compensate::Controller::for_file`]).
pub fn program_controller(
    path: &Path,
    flag: Option<thermokin_compensate::Controller>,
) -> Result<thermokin_compensate::Controller, Failure> {
    thermokin_compensate::Controller::for_file(path, flag)
        .map_err(|e| Failure::input(anyhow!("--program {e}, or say --controller abb, kuka or ur")))
}
