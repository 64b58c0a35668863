//! The subcommands `fk`, `ik` and `urdf`, and the dispatch of every subcommand: load inputs (degrees →
//! radians at the edge), call the libraries, print.

use anyhow::anyhow;
use nalgebra::Vector3;
use serde_json::json;
use thermokin_chain::{Chain, OperatingState};
use thermokin_compensate::{BranchOut, SolutionRow, SolveOut};
use thermokin_deform::RobotModel;
use thermokin_ik::{Goal, Params, Workspace, solve_branches};
use thermokin_io::{PoseOut, PoseRow, RobotOptions, read_robot_with, robot_to_toml};

use crate::args::{Cli, Command, FkArgs, IkArgs, UrdfCommand, parse_list};
use crate::input::{joints, load, pose, working_model};
use crate::{Failure, exit, reproduce};

/// Runs a parsed command line; returns the exit status.
pub fn run(cli: Cli) -> Result<u8, Failure> {
    match cli.command {
        Command::Fk(a) => fk(a),
        Command::Ik(a) => ik(a),
        Command::Compensate(a) => crate::compensation::compensate(a),
        Command::Urdf(c) => urdf(c),
        Command::Diagnose(a) => crate::diagnosis::diagnose(a),
        Command::Simulate(a) => crate::diagnosis::simulate(a),
        Command::Plan(a) => crate::planning::plan(a),
        Command::ReproducePaper(a) => reproduce::run(a),
    }
}

fn fk(a: FkArgs) -> Result<u8, Failure> {
    let loaded = load(&a.robot)?;
    let model = working_model(&a.robot, &loaded)?;
    if let Some(path) = &a.joints_file {
        return fk_rows(path, &model, &loaded.state, a.json);
    }
    let Some(text) = &a.joints else {
        return Err(Failure::input(anyhow!("give --joints Q1,...,QN or --joints-file FILE")));
    };
    let chain = model.robot().chain();
    let q = joints(chain, "joints", text)?;
    // The commanded joints on the robot as it is in the flags' state (drift, joint corrections, payload).
    let pose = model.tool_pose(&q, &loaded.state).map_err(Failure::input)?;
    let outside = thermokin_io::outside_limits(chain, &q);
    for o in &outside {
        eprintln!("warning: {o} (the pose is computed anyway)");
    }
    let out = PoseOut::of(&pose);
    if a.json {
        let mut v = json!(out);
        v["outside_limits"] = json!(outside);
        say!("{v}");
    } else {
        say!("{}", out.to_string().trim_end());
    }
    Ok(exit::OK)
}

/// `fk --joints-file`: one output row per input row ([`PoseRow::of_file`]).
fn fk_rows(path: &std::path::Path, model: &RobotModel, flags: &OperatingState, json: bool) -> Result<u8, Failure> {
    let rows = PoseRow::of_file(model, path, flags).map_err(Failure::input)?;
    crate::out::rows(&rows, json, PoseRow::CSV_HEADER, PoseRow::csv)?;
    Ok(if rows.iter().any(|r| r.error.is_some()) { exit::PARTIAL } else { exit::OK })
}

fn ik(a: IkArgs) -> Result<u8, Failure> {
    let loaded = load(&a.robot)?;
    let model = working_model(&a.robot, &loaded)?;
    // IK on the chain in force in this state; the joint corrections are inverted after (`commanded`).
    let chain = model.chain_at(&loaded.state).map_err(Failure::input)?;
    let seed = crate::input::seed(&chain, a.seed.as_deref())?;
    let params = Params { restarts: a.restarts, ..Params::default() };
    if let Some(path) = &a.poses_file {
        return ik_rows(path, a.position_units, &model, &loaded.state, &seed, &params, a.json);
    }
    let Some(text) = &a.pose else { return Err(Failure::input(anyhow!("give --pose or --poses-file FILE"))) };
    let target = match (a.position_only, parse_list("pose", text)) {
        (true, Ok(v)) if v.len() >= 3 => Goal::Position(Vector3::new(v[0], v[1], v[2])),
        (true, Ok(_)) => return Err(Failure::input(anyhow!("--pose: --position-only needs at least x,y,z"))),
        (true, Err(e)) => return Err(Failure::input(e)),
        (false, Ok(v)) if v.len() == 3 => {
            return Err(Failure::input(anyhow!(
                "--pose: 3 values need --position-only (or give x,y,z and an orientation)"
            )));
        }
        (false, _) => Goal::Pose(pose(text, "pose", a.robot.orientation)?),
    };
    if a.branches {
        return ik_branches(&a, &model, &loaded.state, &chain, &target);
    }
    let mut ws = Workspace::new(chain.dof());
    let s = thermokin_compensate::solve_on_model(&model, &loaded.state, &target, &seed, &params, &mut ws, 0)
        .map_err(Failure::input)?;
    let out = SolveOut::of(&chain, &s);
    if a.json {
        say!("{}", json!(out))
    } else {
        say!("{}", out.to_string().trim_end())
    }
    Ok(if s.converged() { exit::OK } else { exit::PARTIAL })
}

/// `ik --poses-file`: one output row per target row ([`thermokin_compensate::solve_rows`]).
fn ik_rows(
    path: &std::path::Path,
    units: Option<thermokin_io::PositionUnits>,
    model: &RobotModel,
    flags: &OperatingState,
    seed: &[f64],
    params: &Params,
    json: bool,
) -> Result<u8, Failure> {
    let read = crate::input::target_rows(path, units, model)?;
    let dof = model.robot().chain().dof();
    let rows = thermokin_compensate::solve_rows(model, read.rows, flags, seed, params);
    crate::out::rows(&rows, json, &SolutionRow::csv_header(dof), |r| r.csv(dof))?;
    let failed = rows.iter().any(|r| r.status.as_deref() != Some("Converged"));
    Ok(if failed { exit::PARTIAL } else { exit::OK })
}

/// `ik --branches`: every configuration of a closed-form arm, refined on the working robot.
fn ik_branches(
    a: &IkArgs,
    model: &RobotModel,
    state: &OperatingState,
    chain: &Chain,
    target: &Goal,
) -> Result<u8, Failure> {
    let Goal::Pose(goal) = target else {
        return Err(Failure::input(anyhow!("--branches needs a full pose (drop --position-only)")));
    };
    let mut ws = Workspace::new(chain.dof());
    let Some(mut found) = solve_branches(chain, goal, &Params::default(), &mut ws).map_err(Failure::input)? else {
        return Err(Failure::input(anyhow!(
            "--branches: this robot has no closed form (it needs six revolute joints with axes 2 and 3 parallel and a spherical wrist, or axes 2, 3, 4 parallel)"
        )));
    };
    for (_, s) in &mut found {
        thermokin_compensate::commanded_on_model(model, state, target, &Params::default(), s)
            .map_err(Failure::input)?;
    }
    let rows: Vec<BranchOut> = found.iter().map(|(_, s)| BranchOut::of(chain, s)).collect();
    if a.json {
        say!("{}", json!(rows));
    } else {
        say!("{}", BranchOut::table(&rows).trim_end());
    }
    let any = found.iter().any(|(_, s)| s.converged());
    Ok(if any { exit::OK } else { exit::PARTIAL })
}

fn urdf(c: UrdfCommand) -> Result<u8, Failure> {
    match c {
        UrdfCommand::Import { file, base, tip, out } => {
            let robot = read_robot_with(&file, &RobotOptions { base, tip }).map_err(Failure::input)?;
            crate::out::save(&out, robot_to_toml(&robot))?;
            say!("{}: {} joints → {}", robot.name(), robot.chain().dof(), out.display());
        }
        UrdfCommand::Export { robot, out } => {
            let loaded = load(&robot)?;
            let model = working_model(&robot, &loaded)?;
            // The geometry in force in the flags' state (a drifting robot at --time, --temperature).
            // A UR kinematics YAML by its extension, URDF otherwise.
            let (text, beyond, format) = if thermokin_io::is_ur_yaml(&out) {
                let (t, b) =
                    thermokin_io::ur_kinematics_in_state(&model, &loaded.state, &out).map_err(Failure::input)?;
                (t, b, "UR kinematics YAML")
            } else {
                let (t, b) = thermokin_io::urdf_in_state(&model, &loaded.state).map_err(Failure::input)?;
                (t, b, "URDF")
            };
            for line in &beyond {
                eprintln!("note: not in the {format} (kept in the TOML): {line}");
            }
            crate::out::save(&out, text)?;
            say!("{}: {} joints → {}", model.robot().name(), model.robot().chain().dof(), out.display());
        }
    }
    Ok(exit::OK)
}
