//! Inputs shared by the subcommands: the robot with its deformation and overrides, joint lists, poses in
//! any orientation convention, target programs, progress. Units cross here, through
//! [`thermokin_io::units`]; the subcommands see millimetres and radians only.

use std::path::Path;

use anyhow::anyhow;
use indicatif::{ProgressBar, ProgressStyle};
use nalgebra::{Isometry3, Translation3, Vector3};
use thermokin_chain::Robot;
use thermokin_chain::Target;
use thermokin_chain::{Chain, FixedRow, OperatingState};
use thermokin_deform::{DeviationTable, RobotModel, TableSemantics, TimeProfile};
use thermokin_io::units::{joints_to_internal, rotation_from_matrix};
use thermokin_io::{Orientation, RobotOptions, read_deviation_table_for, read_robot_model_with, read_targets};

use crate::Failure;
use crate::args::{RobotArgs, Semantics, parse_list};

/// The loaded robot with the corrections its file carries, its deviation table (if any), the semantics,
/// and the operating state the flags give (`--time`, `--temperature`, `--payload`).
pub struct Loaded {
    pub robot: Robot,
    pub model: RobotModel,
    pub table: Option<DeviationTable>,
    pub semantics: TableSemantics,
    pub state: OperatingState,
    /// `--profile`, its file (if it names one) read.
    pub profile: Option<TimeProfile>,
}

/// Reads the robot, applies `--tool-pose` / `--base-pose`, reads the deviation table and the state.
pub fn load(args: &RobotArgs) -> Result<Loaded, Failure> {
    let options = RobotOptions { base: args.base.clone(), tip: args.tip.clone() };
    let model = read_robot_model_with(&args.robot, &options).map_err(Failure::input)?;
    let mut robot = model.robot().clone();
    if let Some(text) = &args.tool_pose {
        let flange_from_tool = pose(text, "tool-pose", args.orientation)?;
        let chain = robot.chain().with_tool(FixedRow::from_isometry(&flange_from_tool)).map_err(Failure::input)?;
        robot = robot.with_chain(chain).map_err(Failure::input)?;
    }
    if let Some(text) = &args.base_pose {
        let world_from_base = pose(text, "base-pose", args.orientation)?;
        let chain = robot.chain().with_base(FixedRow::from_isometry(&world_from_base)).map_err(Failure::input)?;
        robot = robot.with_chain(chain).map_err(Failure::input)?;
    }
    let table = match &args.deformation {
        Some(p) => Some(read_deviation_table_for(p, robot.chain().dof()).map_err(Failure::input)?),
        None => None,
    };
    let model = model.with_robot(robot.clone()).map_err(Failure::input)?;
    let (drifts_with_time, sensors) = model.needs();
    if table.is_none() && args.profile.is_some() {
        return Err(Failure::input(anyhow!("--profile needs --deformation")));
    }
    if table.is_none() && args.time.is_some() && !drifts_with_time {
        return Err(Failure::input(anyhow!(
            "--time: {} has no row drifting with time (give --deformation and --profile to deform it)",
            args.robot.display()
        )));
    }
    let dof = robot.chain().dof();
    let profile =
        args.profile.as_ref().map(|p| thermokin_io::read_profile_spec(p, dof)).transpose().map_err(Failure::input)?;
    let mut state = OperatingState { time_min: args.time, ..OperatingState::default() };
    if let Some(text) = &args.temperature {
        state.temperatures_c = temperatures(text).map_err(Failure::input)?;
        if let Some((unknown, _)) = state.temperatures_c.iter().find(|(n, _)| !sensors.contains(n)) {
            let known = if sensors.is_empty() { "none".to_string() } else { sensors.join(", ") };
            return Err(Failure::input(anyhow!(
                "--temperature: {} has no row drifting with sensor `{unknown}` (its sensors: {known})",
                args.robot.display()
            )));
        }
    }
    if let Some(spec) = &args.payload {
        state.payload = Some(parse_payload(spec).map_err(Failure::input)?);
    }
    let semantics = semantics(args.semantics, robot.chain().dof());
    Ok(Loaded { robot, model, table, semantics, state, profile })
}

/// Parses `--temperature temp_j2=35.1,temp_j3=30.2` (°C; the `temp_` prefix added when left out).
pub fn temperatures(text: &str) -> anyhow::Result<Vec<(String, f64)>> {
    let mut out: Vec<(String, f64)> = Vec::new();
    for item in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (name, value) = item
            .split_once('=')
            .ok_or_else(|| anyhow!("--temperature `{item}`: expected NAME=°C, e.g. temp_j2=35.1"))?;
        let name = thermokin_io::sensor_name(name.trim());
        let value: f64 = value
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| anyhow!("--temperature `{item}`: `{}` is not a temperature in °C", value.trim()))?;
        anyhow::ensure!(!out.iter().any(|(n, _)| *n == name), "--temperature: `{name}` given twice");
        out.push((name, value));
    }
    anyhow::ensure!(!out.is_empty(), "--temperature: no reading given");
    Ok(out)
}

/// Parses `--payload KG@X,Y,Z` (kg; mm in the flange's frame).
pub fn parse_payload(spec: &str) -> anyhow::Result<thermokin_chain::LinkMass> {
    let (kg, at) = spec.split_once('@').ok_or_else(|| anyhow!("--payload {spec}: expected KG@X,Y,Z (kg @ mm)"))?;
    let mass_kg: f64 = kg.trim().parse().map_err(|_| anyhow!("--payload {spec}: mass `{kg}` is not a number"))?;
    let c = crate::args::parse_list("payload", at)?;
    anyhow::ensure!(c.len() == 3, "--payload {spec}: the centre takes 3 values (mm), got {}", c.len());
    Ok(thermokin_chain::LinkMass { mass_kg, com_mm: nalgebra::Vector3::new(c[0], c[1], c[2]) })
}

/// The robot fk/ik work on: the file's model, with the deviation table (at `--time` under `--profile`)
/// added to its chain when one is given.
pub fn working_model(args: &RobotArgs, loaded: &Loaded) -> Result<RobotModel, Failure> {
    if loaded.table.is_none() {
        return Ok(loaded.model.clone());
    }
    let chain = working_chain(args, loaded)?;
    let robot = loaded.robot.with_chain(chain).map_err(Failure::input)?;
    loaded.model.clone().with_robot(robot).map_err(Failure::input)
}

pub fn semantics(s: Semantics, dof: usize) -> TableSemantics {
    match s {
        Semantics::Canonical => TableSemantics::Canonical,
        Semantics::Coppeliasim => TableSemantics::coppeliasim_at_home(dof),
    }
}

/// The chain fk/ik work on: nominal, or deformed by the table at `--time` under `--profile`.
pub fn working_chain(args: &RobotArgs, loaded: &Loaded) -> Result<Chain, Failure> {
    let Some(table) = &loaded.table else { return Ok(loaded.robot.chain().clone()) };
    let table = match (&loaded.profile, args.time) {
        (Some(p), Some(t)) => p.table_at(table, t).map_err(Failure::input)?,
        (Some(_), None) => return Err(Failure::input(anyhow!("--profile needs --time (minutes)"))),
        // --time for the robot file's own drift: the table is in force in full.
        (None, Some(_)) if loaded.model.needs().0 => table.clone(),
        (None, Some(_)) => return Err(Failure::input(anyhow!("--time needs --profile"))),
        (None, None) => table.clone(),
    };
    table.apply(loaded.robot.chain(), &loaded.semantics).map_err(Failure::input)
}

/// A flag's joint list (degrees, mm for prismatic joints) in the library's radians and mm.
pub fn joints(chain: &Chain, flag: &str, text: &str) -> Result<Vec<f64>, Failure> {
    let values = parse_list(flag, text).map_err(Failure::input)?;
    joints_to_internal(chain, &values).ok_or_else(|| {
        Failure::input(anyhow!("--{flag}: {} values for a robot with {} joints", values.len(), chain.dof()))
    })
}

/// A pose flag: `x,y,z` (mm) followed by the orientation in `convention` (three angles in degrees, or a
/// quaternion w,x,y,z), or a JSON object `{"position_mm": [..], "rotation": [[..],[..],[..]]}` (a
/// rotation matrix, as `fk --json` prints it), with `quaternion_wxyz`, `xyz_euler_deg` or `ros_rpy_deg`
/// in place of `rotation`.
pub fn pose(text: &str, flag: &str, convention: Orientation) -> Result<Isometry3<f64>, Failure> {
    if text.trim_start().starts_with('{') {
        return pose_json(text, flag);
    }
    let v = parse_list(flag, text).map_err(Failure::input)?;
    let want = 3 + convention.arity();
    if v.len() != want {
        return Err(Failure::input(anyhow!(
            "--{flag}: expected {want} values (x,y,z then the {convention:?} orientation), got {}",
            v.len()
        )));
    }
    let rotation = convention.rotation(&v[3..]).map_err(|m| Failure::input(anyhow!("--{flag}: {m}")))?;
    Ok(Isometry3::from_parts(Translation3::new(v[0], v[1], v[2]), rotation))
}

fn pose_json(text: &str, flag: &str) -> Result<Isometry3<f64>, Failure> {
    let bad = |m: String| Failure::input(anyhow!("--{flag}: {m}"));
    let v: serde_json::Value = serde_json::from_str(text).map_err(|e| bad(format!("not JSON: {e}")))?;
    let numbers = |key: &str, n: usize| -> Result<Option<Vec<f64>>, Failure> {
        let Some(value) = v.get(key) else { return Ok(None) };
        let list: Option<Vec<f64>> = value.as_array().map(|a| a.iter().filter_map(serde_json::Value::as_f64).collect());
        match list {
            Some(l) if l.len() == n => Ok(Some(l)),
            _ => Err(bad(format!("`{key}` must be an array of {n} numbers"))),
        }
    };
    let p = numbers("position_mm", 3)?.ok_or_else(|| bad("`position_mm` is missing".into()))?;
    let rotation = if let Some(rows) = v.get("rotation") {
        let m: Option<Vec<Vec<f64>>> = rows.as_array().map(|r| {
            r.iter()
                .map(|row| {
                    row.as_array().map_or_else(Vec::new, |x| x.iter().filter_map(serde_json::Value::as_f64).collect())
                })
                .collect()
        });
        let m = m
            .filter(|m| m.len() == 3 && m.iter().all(|r| r.len() == 3))
            .ok_or_else(|| bad("`rotation` must be a 3 × 3 array".into()))?;
        rotation_from_matrix([[m[0][0], m[0][1], m[0][2]], [m[1][0], m[1][1], m[1][2]], [m[2][0], m[2][1], m[2][2]]])
            .map_err(bad)?
    } else if let Some(q) = numbers("quaternion_wxyz", 4)? {
        Orientation::Quaternion.rotation(&q).map_err(bad)?
    } else if let Some(e) = numbers("xyz_euler_deg", 3)? {
        Orientation::XyzEuler.rotation(&e).map_err(bad)?
    } else if let Some(e) = numbers("ros_rpy_deg", 3)? {
        Orientation::Rpy.rotation(&e).map_err(bad)?
    } else {
        return Err(bad("give `rotation`, `quaternion_wxyz`, `xyz_euler_deg` or `ros_rpy_deg`".into()));
    };
    Ok(Isometry3::from_parts(Translation3::from(Vector3::new(p[0], p[1], p[2])), rotation))
}

/// Reads a targets file into a program.
pub fn program(path: &Path) -> Result<Vec<Target>, Failure> {
    read_targets(path).map_err(Failure::input)
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

    /// `done` steps so far.
    pub fn set_position(&self, done: u64) {
        if self.started.elapsed() > std::time::Duration::from_secs(1) && self.bar.is_hidden() {
            self.bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
        }
        self.bar.set_position(done);
    }

    /// Removes the bar from the terminal.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
