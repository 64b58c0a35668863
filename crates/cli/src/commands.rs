//! The subcommands: load inputs (degrees → radians here, at the edge), run the library, print and write.

use std::path::Path;
use std::time::Duration;

use anyhow::{Context, anyhow};
use indicatif::{ProgressBar, ProgressStyle};
use nalgebra::{Isometry3, Vector3};
use serde_json::json;
use thermokin_chain::{Chain, JointKind, xyz_angles};
use thermokin_compensate::{
    Cycle, ProgramTarget, RapidSettings, RunOutput, RunSettings, compensate_static, compensate_transient,
    pose_from_xyz_deg, rapid_module, write_joint_csv, write_results_csv,
};
use thermokin_deform::{CoppeliaSimEdits, DeviationTable, TableSemantics, TimeProfile};
use thermokin_ik::{Params, Target, Workspace, solve};
use thermokin_io::{
    Robot, RobotOptions, read_deviation_table_for, read_robot_with, read_targets, robot_to_toml, write_atomic,
    write_atomic_with,
};

use crate::args::{Cli, Command, CompensateArgs, FkArgs, IkArgs, RobotArgs, Semantics, UrdfCommand, parse_list};
use crate::{Failure, exit, plots, reproduce};

/// Runs a parsed command line; returns the exit status.
pub fn run(cli: Cli) -> Result<u8, Failure> {
    match cli.command {
        Command::Fk(a) => fk(a),
        Command::Ik(a) => ik(a),
        Command::Compensate(a) => compensate(a),
        Command::Urdf(c) => urdf(c),
        Command::Diagnose(a) => crate::diagnosis::diagnose(a),
        Command::Simulate(a) => crate::diagnosis::simulate(a),
        Command::ReproducePaper(a) => reproduce::run(a),
    }
}

/// The loaded robot, its deviation table (if any) and the semantics.
pub struct Loaded {
    pub robot: Robot,
    pub table: Option<DeviationTable>,
    pub semantics: TableSemantics,
}

pub fn load(args: &RobotArgs) -> Result<Loaded, Failure> {
    let options = RobotOptions { base: args.base.clone(), tip: args.tip.clone() };
    let robot = read_robot_with(&args.robot, &options).map_err(Failure::input)?;
    let table = match &args.deformation {
        Some(p) => Some(read_deviation_table_for(p, robot.chain.dof()).map_err(Failure::input)?),
        None => None,
    };
    if table.is_none() && (args.profile.is_some() || args.time.is_some()) {
        return Err(Failure::input(anyhow!("--profile and --time need --deformation")));
    }
    if let Some(p) = &args.profile {
        p.validate(robot.chain.dof()).map_err(Failure::input)?;
    }
    let semantics = semantics(args.semantics, robot.chain.dof());
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
    let Some(table) = &loaded.table else { return Ok(loaded.robot.chain.clone()) };
    let table = match (&args.profile, args.time) {
        (Some(p), Some(t)) => p.table_at(table, t).map_err(Failure::input)?,
        (Some(_), None) => return Err(Failure::input(anyhow!("--profile needs --time (minutes)"))),
        (None, Some(_)) => return Err(Failure::input(anyhow!("--time needs --profile"))),
        (None, None) => table.clone(),
    };
    table.apply(&loaded.robot.chain, &loaded.semantics).map_err(Failure::input)
}

/// Degrees (or mm) → the library's radians (or mm), per joint kind.
pub fn joints_in(chain: &Chain, flag: &str, values: &[f64]) -> Result<Vec<f64>, Failure> {
    if values.len() != chain.dof() {
        return Err(Failure::input(anyhow!(
            "--{flag}: {} values for a robot with {} joints",
            values.len(),
            chain.dof()
        )));
    }
    Ok(chain
        .joints()
        .iter()
        .zip(values)
        .map(|(j, &v)| if j.kind == JointKind::Revolute { v.to_radians() } else { v })
        .collect())
}

pub fn joints_out(chain: &Chain, q: &[f64]) -> Vec<f64> {
    chain.joints().iter().zip(q).map(|(j, &v)| if j.kind == JointKind::Revolute { v.to_degrees() } else { v }).collect()
}

fn pose_json(pose: &Isometry3<f64>) -> serde_json::Value {
    let r = pose.rotation.to_rotation_matrix();
    let m = r.matrix();
    let rpy = xyz_angles(m).map(f64::to_degrees);
    let p = pose.translation.vector;
    json!({
        "position_mm": [p.x, p.y, p.z],
        "rotation": [[m[(0, 0)], m[(0, 1)], m[(0, 2)]], [m[(1, 0)], m[(1, 1)], m[(1, 2)]], [m[(2, 0)], m[(2, 1)], m[(2, 2)]]],
        "rpy_deg": [rpy.x, rpy.y, rpy.z],
    })
}

fn fk(a: FkArgs) -> Result<u8, Failure> {
    let loaded = load(&a.robot)?;
    let chain = working_chain(&a.robot, &loaded)?;
    let values = parse_list("joints", &a.joints).map_err(Failure::input)?;
    let q = joints_in(&chain, "joints", &values)?;
    let pose = chain.tool_pose(&q).map_err(Failure::input)?;
    if a.json {
        println!("{}", pose_json(&pose));
    } else {
        let p = pose.translation.vector;
        let r = xyz_angles(pose.rotation.to_rotation_matrix().matrix()).map(f64::to_degrees);
        println!("position_mm  {:.6} {:.6} {:.6}", p.x, p.y, p.z);
        println!("rpy_deg      {:.6} {:.6} {:.6}   (X-Y-Z Euler, R = Rx·Ry·Rz)", r.x, r.y, r.z);
    }
    Ok(exit::OK)
}

fn ik(a: IkArgs) -> Result<u8, Failure> {
    let loaded = load(&a.robot)?;
    let chain = working_chain(&a.robot, &loaded)?;
    let v = parse_list("pose", &a.pose).map_err(Failure::input)?;
    let target = match (v.len(), a.position_only) {
        (6, false) => Target::Pose(pose_from_xyz_deg(Vector3::new(v[0], v[1], v[2]), Vector3::new(v[3], v[4], v[5]))),
        (3, true) | (6, true) => Target::Position(Vector3::new(v[0], v[1], v[2])),
        (3, false) => {
            return Err(Failure::input(anyhow!("--pose: 3 values need --position-only (or give x,y,z,rx,ry,rz)")));
        }
        (n, _) => return Err(Failure::input(anyhow!("--pose: expected 6 values (x,y,z,rx,ry,rz), got {n}"))),
    };
    let seed = match &a.seed {
        Some(s) => joints_in(&chain, "seed", &parse_list("seed", s).map_err(Failure::input)?)?,
        None => vec![0.0; chain.dof()],
    };
    let params = Params { restarts: a.restarts, ..Params::default() };
    let mut ws = Workspace::new(chain.dof());
    let s = solve(&chain, &target, &seed, &params, &mut ws, 0).map_err(Failure::input)?;
    let deg = joints_out(&chain, &s.q);
    if a.json {
        println!(
            "{}",
            json!({"joints_deg": deg, "status": format!("{:?}", s.status), "iterations": s.iterations, "restarts": s.restarts,
                   "position_error_mm": s.position_error_mm, "orientation_error_deg": s.orientation_error_deg})
        );
    } else {
        let list: Vec<String> = deg.iter().map(|d| format!("{d:.6}")).collect();
        println!("joints_deg   {}", list.join(","));
        println!(
            "status       {:?} after {} iterations, {} restarts; error {:.3e} mm, {:.3e}°",
            s.status, s.iterations, s.restarts, s.position_error_mm, s.orientation_error_deg
        );
    }
    Ok(if s.converged() { exit::OK } else { exit::PARTIAL })
}

/// Reads a targets file into a program.
pub fn program(path: &Path) -> Result<Vec<ProgramTarget>, Failure> {
    Ok(read_targets(path)
        .map_err(Failure::input)?
        .into_iter()
        .map(|t| ProgramTarget { label: t.label, pose: pose_from_xyz_deg(t.position_mm, t.rotation_xyz_deg) })
        .collect())
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

fn compensate(a: CompensateArgs) -> Result<u8, Failure> {
    let loaded = load(&a.robot)?;
    let table = loaded.table.clone().ok_or_else(|| Failure::input(anyhow!("compensate needs --deformation")))?;
    if a.robot.time.is_some() {
        return Err(Failure::input(anyhow!("--time is for fk/ik; compensate runs over --duration with --profile")));
    }
    let chain = &loaded.robot.chain;
    let prog = program(&a.targets)?;
    let start = match &a.seed {
        Some(s) => joints_in(chain, "seed", &parse_list("seed", s).map_err(Failure::input)?)?,
        None => vec![0.0; chain.dof()],
    };
    let settings = RunSettings { semantics: loaded.semantics.clone(), ik: Params::default(), start };
    let started = std::time::Instant::now();
    let (run, transient) = match &a.robot.profile {
        None | Some(TimeProfile::Static) => {
            (compensate_static(chain, &table, &prog, &settings).map_err(Failure::input)?, false)
        }
        Some(profile) => {
            let cycle = Cycle { duration_min: a.duration, step_min: a.step };
            let steps = cycle.times().map_err(Failure::input)?.len();
            let bar = progress_bar(steps as u64, "compensating");
            let run = compensate_transient(chain, &table, profile, cycle, &prog, &settings, |done, _| {
                if started.elapsed() > Duration::from_secs(1) && bar.is_hidden() {
                    bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
                }
                bar.set_position(done as u64);
            })
            .map_err(Failure::input)?;
            bar.finish_and_clear();
            (run, true)
        }
    };
    write_outputs(&a, &loaded, &run, transient)?;
    print_summary(&run, a.json);
    Ok(if run.summary.failures > 0 { exit::PARTIAL } else { exit::OK })
}

fn write_outputs(a: &CompensateArgs, loaded: &Loaded, run: &RunOutput, transient: bool) -> Result<(), Failure> {
    write_atomic_with(&a.out, |w| write_results_csv(w, run, transient)).map_err(Failure::internal)?;
    if let Some(p) = &a.joints_out {
        write_atomic_with(p, |w| write_joint_csv(w, run)).map_err(Failure::internal)?;
    }
    if let Some(p) = &a.rapid {
        let module = rapid_module(run, &RapidSettings::default());
        write_atomic(p, module.as_bytes()).map_err(Failure::internal)?;
    }
    if let Some(dir) = &a.plot {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("creating {}", dir.display()))
            .map_err(Failure::internal)?;
        if transient {
            plots::deviation_vs_time(&dir.join("deviation-vs-time.svg"), run).map_err(Failure::internal)?;
        }
        if let Some(table) = &loaded.table {
            let deformed = table.apply(&loaded.robot.chain, &loaded.semantics).map_err(Failure::input)?;
            plots::structure(&dir.join("structure.svg"), &loaded.robot.chain, &deformed, 20.0)
                .map_err(Failure::internal)?;
        }
    }
    Ok(())
}

fn print_summary(run: &RunOutput, as_json: bool) {
    let s = &run.summary;
    if as_json {
        println!("{}", serde_json::to_string(s).unwrap_or_default());
        return;
    }
    println!("solves {}  failed {}", s.solves, s.failures);
    println!(
        "position deviation (programmed − reached), mm:  min {:+.3e} {:+.3e} {:+.3e}   max {:+.3e} {:+.3e} {:+.3e}",
        s.position_mm.min[0],
        s.position_mm.min[1],
        s.position_mm.min[2],
        s.position_mm.max[0],
        s.position_mm.max[1],
        s.position_mm.max[2]
    );
    println!(
        "orientation deviation (rotation vector), deg:   min {:+.3e} {:+.3e} {:+.3e}   max {:+.3e} {:+.3e} {:+.3e}",
        s.orientation_deg.min[0],
        s.orientation_deg.min[1],
        s.orientation_deg.min[2],
        s.orientation_deg.max[0],
        s.orientation_deg.max[1],
        s.orientation_deg.max[2]
    );
    println!(
        "largest error: compensated {:.3e} mm, {:.3e}°; uncompensated program {:.3} mm",
        s.max_position_error_mm, s.max_orientation_error_deg, s.max_uncompensated_error_mm
    );
}

fn urdf(c: UrdfCommand) -> Result<u8, Failure> {
    match c {
        UrdfCommand::Import { file, base, tip, out } => {
            let robot = read_robot_with(&file, &RobotOptions { base, tip }).map_err(Failure::input)?;
            write_atomic(&out, robot_to_toml(&robot).as_bytes()).map_err(Failure::internal)?;
            println!("{}: {} joints → {}", robot.name, robot.chain.dof(), out.display());
        }
        UrdfCommand::Export { robot, out } => {
            let loaded = load(&robot)?;
            let chain = working_chain(&robot, &loaded)?;
            let xml = thermokin_urdf::export_urdf(&chain, &loaded.robot.name);
            write_atomic(&out, xml.as_bytes()).map_err(Failure::internal)?;
            println!("{}: {} joints → {}", loaded.robot.name, chain.dof(), out.display());
        }
    }
    Ok(exit::OK)
}
