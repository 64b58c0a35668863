//! Inputs shared by the subcommands: the robot with its deformation and overrides, joint lists, poses in
//! any orientation convention, target programs, progress. Units cross here, through
//! [`thermokin_io::units`]; the subcommands see millimetres and radians only.

use std::path::Path;

use anyhow::anyhow;
use indicatif::{ProgressBar, ProgressStyle};
use nalgebra::{Isometry3, Translation3, Vector3};
use thermokin_chain::{Chain, FixedRow};
use thermokin_compensate::Target;
use thermokin_deform::{CoppeliaSimEdits, DeviationTable, TableSemantics};
use thermokin_io::units::{joints_to_internal, rotation_from_matrix};
use thermokin_io::{Orientation, Robot, RobotOptions, read_deviation_table_for, read_robot_with, read_targets};

use crate::Failure;
use crate::args::{RobotArgs, Semantics, parse_list};

/// The loaded robot, its deviation table (if any) and the semantics.
pub struct Loaded {
    pub robot: Robot,
    pub table: Option<DeviationTable>,
    pub semantics: TableSemantics,
}

/// Reads the robot, applies `--tool-pose` / `--base-pose`, reads the deviation table.
pub fn load(args: &RobotArgs) -> Result<Loaded, Failure> {
    let options = RobotOptions { base: args.base.clone(), tip: args.tip.clone() };
    let mut robot = read_robot_with(&args.robot, &options).map_err(Failure::input)?;
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
    if table.is_none() && (args.profile.is_some() || args.time.is_some()) {
        return Err(Failure::input(anyhow!("--profile and --time need --deformation")));
    }
    if let Some(p) = &args.profile {
        p.validate(robot.chain().dof()).map_err(Failure::input)?;
    }
    let semantics = semantics(args.semantics, robot.chain().dof());
    Ok(Loaded { robot, table, semantics })
}

pub fn semantics(s: Semantics, dof: usize) -> TableSemantics {
    match s {
        Semantics::Canonical => TableSemantics::Canonical,
        Semantics::Coppeliasim => TableSemantics::CoppeliaSim(CoppeliaSimEdits::at(vec![0.0; dof])),
    }
}

/// The chain fk/ik work on: nominal, or deformed by the table at `--time` under `--profile`.
pub fn working_chain(args: &RobotArgs, loaded: &Loaded) -> Result<Chain, Failure> {
    let Some(table) = &loaded.table else { return Ok(loaded.robot.chain().clone()) };
    let table = match (&args.profile, args.time) {
        (Some(p), Some(t)) => p.table_at(table, t).map_err(Failure::input)?,
        (Some(_), None) => return Err(Failure::input(anyhow!("--profile needs --time (minutes)"))),
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

/// A progress bar that shows itself only when a run lasts more than a second.
pub fn progress_bar(len: u64, label: &str) -> ProgressBar {
    let bar = ProgressBar::hidden();
    bar.set_length(len);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} steps ({eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(label.to_string());
    bar
}
