//! The subcommands: load inputs (degrees → radians here, at the edge), run the library, print and write.

use anyhow::{Context, anyhow};
use nalgebra::{Isometry3, Vector3};
use serde_json::json;
use thermokin_chain::Chain;
use thermokin_compensate::{
    AbbTargets, Controller, Cycle, Plan, PlanError, ProgramSettings, Request, RunOutput, RunSettings, StreamSettings,
    Summary, SummaryOut, arm_configuration, compensate_static_stream, programs, write_joint_csv, write_long_csv,
    write_results_csv, write_results_json,
};
use thermokin_ik::{Goal, Params, Workspace, solve_branches};
use thermokin_io::units::{degrees, joints_to_external, quaternion_wxyz, ros_rpy_deg, rounded, xyz_euler_deg};
use thermokin_io::{RobotOptions, TargetReader, read_robot_with, robot_to_toml, write_atomic, write_atomic_with};

use std::path::{Path, PathBuf};

use crate::args::{
    Cli, Command, CompensateArgs, ControllerArg, FkArgs, IkArgs, ResultsFormat, UrdfCommand, parse_list,
};
use crate::input::{Loaded, joints, load, pose, program, progress_bar, working_model};
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

/// A pose in every convention: position, rotation matrix, X-Y-Z Euler (the paper's), ROS rpy and the
/// quaternion; numbers at their meaningful precision, not binary noise: 1e-10 mm and degrees (a tenth of
/// the solver's 1e-9 tolerance, so a printed pose fed back to `ik` loses nothing), 1e-13 for matrix and
/// quaternion entries.
fn pose_json(pose: &Isometry3<f64>) -> serde_json::Value {
    let m = pose.rotation.to_rotation_matrix().into_inner();
    let p = pose.translation.vector;
    let mm_deg = |x: f64| rounded(x, 10);
    let unitless = |x: f64| rounded(x, 13);
    json!({
        "position_mm": [mm_deg(p.x), mm_deg(p.y), mm_deg(p.z)],
        "rotation": [[unitless(m[(0, 0)]), unitless(m[(0, 1)]), unitless(m[(0, 2)])], [unitless(m[(1, 0)]), unitless(m[(1, 1)]), unitless(m[(1, 2)])], [unitless(m[(2, 0)]), unitless(m[(2, 1)]), unitless(m[(2, 2)])]],
        "xyz_euler_deg": xyz_euler_deg(&pose.rotation).map(mm_deg),
        "ros_rpy_deg": ros_rpy_deg(&pose.rotation).map(mm_deg),
        "quaternion_wxyz": quaternion_wxyz(&pose.rotation).map(unitless),
    })
}

fn print_pose(pose: &Isometry3<f64>) {
    let p = pose.translation.vector;
    let [a, b, c] = xyz_euler_deg(&pose.rotation);
    let [roll, pitch, yaw] = ros_rpy_deg(&pose.rotation);
    let [w, x, y, z] = quaternion_wxyz(&pose.rotation);
    println!("position_mm     {:.6} {:.6} {:.6}", p.x, p.y, p.z);
    println!("xyz_euler_deg   {a:.6} {b:.6} {c:.6}   (R = Rx·Ry·Rz, the paper's convention)");
    println!("ros_rpy_deg     {roll:.6} {pitch:.6} {yaw:.6}   (R = Rz(yaw)·Ry(pitch)·Rx(roll))");
    println!("quaternion_wxyz {w:.9} {x:.9} {y:.9} {z:.9}");
    if b.abs() == 90.0 {
        println!("note: RY = ±90° is the X-Y-Z Euler singularity; only RX ± RZ is defined, shown as RX = 0");
    }
}

/// Joints outside the robot's limits ([`Chain::outside_limits`]), named, in degrees (mm for prismatic joints).
fn outside_limits(chain: &Chain, q: &[f64]) -> Vec<String> {
    let lower: Vec<f64> = chain.joints().iter().map(|j| j.limits.map_or(f64::NEG_INFINITY, |l| l.lower)).collect();
    let upper: Vec<f64> = chain.joints().iter().map(|j| j.limits.map_or(f64::INFINITY, |l| l.upper)).collect();
    let (lo, hi, v) =
        (joints_to_external(chain, &lower), joints_to_external(chain, &upper), joints_to_external(chain, q));
    let joints = chain.joints();
    chain
        .outside_limits(q)
        .into_iter()
        .map(|i| format!("{} = {:.6} outside [{:.6}, {:.6}]", joints[i].name, v[i], lo[i], hi[i]))
        .collect()
}

fn fk(a: FkArgs) -> Result<u8, Failure> {
    let loaded = load(&a.robot)?;
    let model = working_model(&a.robot, &loaded)?;
    let chain = model.robot().chain();
    let q = joints(chain, "joints", &a.joints)?;
    // The commanded joints on the robot as it is in the flags' state (drift, joint corrections, payload).
    let pose = model.tool_pose(&q, &loaded.state).map_err(Failure::input)?;
    let outside = outside_limits(chain, &q);
    for o in &outside {
        eprintln!("warning: {o} (the pose is computed anyway)");
    }
    if a.json {
        let mut v = pose_json(&pose);
        v["outside_limits"] = json!(outside);
        println!("{v}");
    } else {
        print_pose(&pose);
    }
    Ok(exit::OK)
}

fn ik(a: IkArgs) -> Result<u8, Failure> {
    let loaded = load(&a.robot)?;
    let model = working_model(&a.robot, &loaded)?;
    // IK on the chain in force in this state; the joint corrections are inverted after (`commanded`).
    let chain = model.chain_at(&loaded.state).map_err(Failure::input)?;
    let target = if a.position_only {
        let v = parse_list("pose", &a.pose).map_err(Failure::input)?;
        if v.len() < 3 {
            return Err(Failure::input(anyhow!("--pose: --position-only needs at least x,y,z")));
        }
        Goal::Position(Vector3::new(v[0], v[1], v[2]))
    } else {
        let v = parse_list("pose", &a.pose).ok();
        if v.as_ref().is_some_and(|v| v.len() == 3) {
            return Err(Failure::input(anyhow!(
                "--pose: 3 values need --position-only (or give x,y,z and an orientation)"
            )));
        }
        Goal::Pose(pose(&a.pose, "pose", a.robot.orientation)?)
    };
    if a.branches {
        return ik_branches(&a, &model, &loaded.state, &chain, &target);
    }
    let seed = match &a.seed {
        Some(s) => joints(&chain, "seed", s)?,
        None => vec![0.0; chain.dof()],
    };
    let params = Params { restarts: a.restarts, ..Params::default() };
    let mut ws = Workspace::new(chain.dof());
    let s = thermokin_compensate::solve_on_model(&model, &loaded.state, &target, &seed, &params, &mut ws, 0)
        .map_err(Failure::input)?;
    let deg = joints_to_external(&chain, &s.q);
    if a.json {
        println!(
            "{}",
            json!({"joints_deg": deg.iter().map(|&d| rounded(d, 12)).collect::<Vec<_>>(), "status": format!("{:?}", s.status), "iterations": s.iterations, "restarts": s.restarts,
                   "position_error_mm": s.position_error_mm, "orientation_error_deg": degrees(s.orientation_error_rad)})
        );
    } else {
        let list: Vec<String> = deg.iter().map(|&d| format!("{:.6}", rounded(d, 6))).collect();
        println!("joints_deg   {}", list.join(","));
        println!(
            "status       {:?} after {} iterations, {} restarts; error {:.3e} mm, {:.3e}° (checked by FK)",
            s.status,
            s.iterations,
            s.restarts,
            s.position_error_mm,
            degrees(s.orientation_error_rad)
        );
    }
    Ok(if s.converged() { exit::OK } else { exit::PARTIAL })
}

/// `ik --branches`: every configuration of a closed-form arm, refined on the working robot.
fn ik_branches(
    a: &IkArgs,
    model: &thermokin_deform::RobotModel,
    state: &thermokin_chain::OperatingState,
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
    let rows: Vec<serde_json::Value> = found
        .iter()
        .map(|(_, s)| {
            let deg = joints_to_external(chain, &s.q);
            let conf = arm_configuration(chain, &s.q);
            let side = |behind: bool| if behind { "behind" } else { "in front" };
            json!({
                "wrist_centre_vs_axis1": side(conf.wrist_centre_behind_axis1),
                "wrist_centre_vs_lower_arm": side(conf.wrist_centre_behind_lower_arm),
                "axis5": if conf.axis5_negative { "negative" } else { "positive" },
                "status": format!("{:?}", s.status),
                "joints_deg": deg.iter().map(|&d| rounded(d, 12)).collect::<Vec<_>>(),
                "abb_confdata": conf.abb_confdata,
                "kuka_status": conf.kuka_status,
                "kuka_turn": conf.kuka_turn,
                "position_error_mm": s.position_error_mm,
            })
        })
        .collect();
    if a.json {
        println!("{}", serde_json::Value::Array(rows));
    } else {
        println!(
            "{:<10} {:<10} {:<8} {:<12} {:<66} {:<14} S  T",
            "vs axis 1", "vs arm", "axis 5", "status", "joints_deg", "confdata"
        );
        for r in &rows {
            let joints: Vec<String> = r["joints_deg"]
                .as_array()
                .into_iter()
                .flatten()
                .map(|v| format!("{:.4}", v.as_f64().unwrap_or(f64::NAN)))
                .collect();
            println!(
                "{:<10} {:<10} {:<8} {:<12} {:<66} {:<14} {:<2} {}",
                r["wrist_centre_vs_axis1"].as_str().unwrap_or(""),
                r["wrist_centre_vs_lower_arm"].as_str().unwrap_or(""),
                r["axis5"].as_str().unwrap_or(""),
                r["status"].as_str().unwrap_or(""),
                joints.join(","),
                r["abb_confdata"].to_string(),
                r["kuka_status"],
                r["kuka_turn"]
            );
        }
    }
    let any = found.iter().any(|(_, s)| s.converged());
    Ok(if any { exit::OK } else { exit::PARTIAL })
}

fn compensate(a: CompensateArgs) -> Result<u8, Failure> {
    let loaded = load(&a.robot)?;
    // Which run this is — the paper's static or transient case on a plain robot's table, or a calibrated
    // robot's targets in their states or over a warm-up — is the library's decision (`Plan::new`).
    let request = Request {
        model: &loaded.model,
        table: loaded.table.as_ref(),
        profile: loaded.profile.as_ref(),
        state: &loaded.state,
        semantics: &loaded.semantics,
        accumulation: a.accumulate.into(),
        duration_min: a.duration,
        step_min: a.step,
    };
    let plan = Plan::new(&request).map_err(|e| plan_error(&a, e))?;
    let settings = run_settings(&a, loaded.semantics.clone(), loaded.model.robot().chain())?;
    if a.stream {
        return match &plan {
            Plan::Static { table } => compensate_streamed(&a, &loaded, table, settings),
            Plan::Transient { .. } => Err(Failure::input(anyhow!("--stream runs the static case: drop --profile"))),
            Plan::InStates { .. } | Plan::Warmup { .. } => Err(Failure::input(anyhow!(
                "--stream runs a plain robot's static case; a calibrated robot's run holds its targets in memory"
            ))),
        };
    }
    let prog = program(&a.targets)?;
    let run = match plan.cycle() {
        Some(cycle) => with_cycle_bar(cycle, |progress| plan.run(&request, &prog, &settings, progress))?,
        None => plan.run(&request, &prog, &settings, |_, _| {}),
    }
    .map_err(Failure::input)?;
    // A time column when the run has times: a transient run, or a calibrated robot's targets at theirs.
    let with_time = matches!(plan, Plan::Transient { .. }) || run.rows.iter().any(|r| r.time_min != 0.0);
    write_outputs(&a, &loaded, &run, with_time)?;
    print_summary(&run.summary, a.json);
    Ok(if run.summary.failures > 0 { exit::PARTIAL } else { exit::OK })
}

/// A request the library refuses, in the words of the command line.
fn plan_error(a: &CompensateArgs, e: thermokin_compensate::CompensateError) -> Failure {
    let thermokin_compensate::CompensateError::Plan(plan) = &e else { return Failure::input(e) };
    Failure::input(match plan {
        PlanError::NothingToCompensate => anyhow!(
            "nothing to compensate: {} is a robot as designed (no error parameters, zero offsets or corrections); give --deformation TABLE, or the calibrated robot `diagnose --export` writes",
            a.robot.robot.display()
        ),
        PlanError::IncrementsNeedTransient => {
            anyhow!("--accumulate increments needs a transient run: give --profile (e.g. linear-grow:180)")
        }
        PlanError::IncrementsOnCalibrated => {
            anyhow!("--accumulate increments replays the authors' CoppeliaSim updates on a plain robot's table")
        }
        PlanError::SemanticsOnCalibrated => anyhow!(
            "--semantics coppeliasim applies to a plain robot's table; a calibrated robot's rows drift canonically"
        ),
        PlanError::TemperatureLogOnCalibrated => anyhow!(
            "a temperature-log profile cannot be combined with a calibrated robot: give the targets' temp_* columns instead"
        ),
        other => anyhow!("{other}"),
    })
}

/// A run's settings: the semantics, `--accumulate`, the IK's defaults, and `--seed` (degrees; all zero by
/// default) for the first solve.
fn run_settings(
    a: &CompensateArgs,
    semantics: thermokin_deform::TableSemantics,
    chain: &Chain,
) -> Result<RunSettings, Failure> {
    let start = match &a.seed {
        Some(s) => joints(chain, "seed", s)?,
        None => vec![0.0; chain.dof()],
    };
    Ok(RunSettings { semantics, accumulation: a.accumulate.into(), ik: Params::default(), start })
}

/// `run` given a progress callback over `cycle`'s steps: a bar on stderr once the run has lasted a second.
fn with_cycle_bar<T>(cycle: Cycle, run: impl FnOnce(&mut dyn FnMut(usize, usize)) -> T) -> Result<T, Failure> {
    let steps = cycle.times().map_err(Failure::input)?.len();
    let bar = progress_bar(steps as u64, "compensating");
    let out = run(&mut |done, _| bar.set_position(done as u64));
    bar.finish();
    Ok(out)
}

/// `compensate --stream`: the static run in chunks, --out written as it goes (atomically: a temporary file
/// renamed at the end, removed on an error).
fn compensate_streamed(
    a: &CompensateArgs,
    loaded: &Loaded,
    table: &thermokin_deform::DeviationTable,
    settings: RunSettings,
) -> Result<u8, Failure> {
    if a.format != ResultsFormat::Joints {
        return Err(Failure::input(anyhow!("--stream writes the joints only: add --format joints")));
    }
    if a.joints_out.is_some() || a.program.is_some() || a.plot.is_some() {
        return Err(Failure::input(anyhow!("--stream writes --out only: drop --joints-out, --program and --plot")));
    }
    let file = std::fs::File::open(&a.targets)
        .with_context(|| format!("{}: cannot open", a.targets.display()))
        .map_err(Failure::input)?;
    let mut targets = TargetReader::new(&a.targets, std::io::BufReader::new(file)).map_err(Failure::input)?;
    let stream = StreamSettings::new(settings);
    let spinner = indicatif::ProgressBar::hidden();
    spinner.set_style(
        indicatif::ProgressStyle::with_template("{spinner} compensating: {human_pos} targets, {per_sec}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    let bar = crate::input::DelayedBar::new(spinner);
    let mut failure: Option<thermokin_compensate::CompensateError> = None;
    let mut summary = None;
    let written = write_atomic_with(&a.out, |w| {
        let run = compensate_static_stream(loaded.robot.chain(), table, &mut targets, w, &stream, |done| {
            bar.set_position(done as u64)
        });
        match run {
            Ok(s) => {
                summary = Some(s);
                Ok(())
            }
            Err(e) => {
                let message = e.to_string();
                failure = Some(e);
                Err(std::io::Error::other(message))
            }
        }
    });
    bar.finish();
    if let Some(e) = failure {
        return Err(Failure::input(e));
    }
    written.map_err(Failure::internal)?;
    let Some(summary) = summary else { return Err(Failure::internal(anyhow!("the streamed run returned nothing"))) };
    print_summary(&summary, a.json);
    Ok(if summary.failures > 0 { exit::PARTIAL } else { exit::OK })
}

fn write_outputs(a: &CompensateArgs, loaded: &Loaded, run: &RunOutput, transient: bool) -> Result<(), Failure> {
    match a.format {
        ResultsFormat::Authors => write_atomic_with(&a.out, |w| write_results_csv(w, run, transient)),
        ResultsFormat::Long => write_atomic_with(&a.out, |w| write_long_csv(w, run)),
        ResultsFormat::Json => write_atomic_with(&a.out, |w| write_results_json(w, run)),
        ResultsFormat::Joints => write_atomic_with(&a.out, |w| write_joint_csv(w, run)),
    }
    .map_err(Failure::internal)?;
    if let Some(p) = &a.joints_out {
        write_atomic_with(p, |w| write_joint_csv(w, run)).map_err(Failure::internal)?;
    }
    if let Some(p) = &a.program {
        for (path, text) in robot_programs(a, p, loaded.robot.chain(), run)? {
            write_atomic(&path, text.as_bytes()).map_err(Failure::internal)?;
        }
    }
    if let Some(dir) = &a.plot {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("creating {}", dir.display()))
            .map_err(Failure::internal)?;
        if transient {
            plots::deviation_vs_time(&dir.join("deviation-vs-time.svg"), run).map_err(Failure::internal)?;
        }
        if let Some(table) = &loaded.table {
            let deformed = table.apply(loaded.robot.chain(), &loaded.semantics).map_err(Failure::input)?;
            plots::structure(&dir.join("structure.svg"), loaded.robot.chain(), &deformed, 20.0)
                .map_err(Failure::internal)?;
        }
    }
    Ok(())
}

/// The program files of `--program`: one, or one per time step of a transient run.
fn robot_programs(
    a: &CompensateArgs,
    path: &Path,
    nominal: &Chain,
    run: &RunOutput,
) -> Result<Vec<(PathBuf, String)>, Failure> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let controller = match (a.controller, ext.as_deref()) {
        (Some(ControllerArg::Abb), _) | (None, Some("mod" | "modx" | "prg")) => Controller::Abb,
        (Some(ControllerArg::Kuka), _) | (None, Some("src")) => Controller::Kuka,
        (Some(ControllerArg::Ur), _) | (None, Some("script" | "urscript")) => Controller::UniversalRobots,
        (None, _) => {
            return Err(Failure::input(anyhow!(
                "--program {}: say --controller abb, kuka or ur (or use .mod, .src or .script)",
                path.display()
            )));
        }
    };
    let mut settings = ProgramSettings::new(controller);
    if let Some(stem) = path.file_stem().and_then(|s| s.to_str()) {
        settings.name = stem.to_string();
    }
    if let Some(v) = &a.speed {
        settings.speed.clone_from(v);
    }
    if let Some(v) = &a.zone {
        settings.zone.clone_from(v);
    }
    settings.tool.clone_from(&a.tooldata);
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("program");
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or(controller.extension());
    settings.abb_targets = if a.robtargets { AbbTargets::Robtarget } else { AbbTargets::Joint };
    Ok(programs(run, nominal, &settings)
        .map_err(Failure::input)?
        .into_iter()
        .map(|p| (path.with_file_name(format!("{stem}{}.{ext}", p.suffix)), p.text))
        .collect())
}

fn print_summary(summary: &Summary, as_json: bool) {
    let s = &SummaryOut::of(summary);
    if as_json {
        println!("{}", serde_json::to_string(s).unwrap_or_default());
        return;
    }
    println!("solves {}  failed {}", s.solves, s.failures);
    if !s.failed.is_empty() {
        let shown: Vec<&str> = s.failed.iter().take(20).map(String::as_str).collect();
        let more = if s.failed.len() > 20 {
            format!(" … and {} more (status column of the results)", s.failed.len() - 20)
        } else {
            String::new()
        };
        println!("not reached (left out of the statistics below): {}{more}", shown.join(", "));
    }
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
            println!("{}: {} joints → {}", robot.name(), robot.chain().dof(), out.display());
        }
        UrdfCommand::Export { robot, out } => {
            let loaded = load(&robot)?;
            let model = working_model(&robot, &loaded)?;
            let working = model.robot();
            let beyond = model.beyond_urdf();
            for line in &beyond {
                eprintln!("note: not in the URDF (kept in the TOML): {line}");
            }
            let xml = thermokin_urdf::export_robot_noting(working, &beyond);
            write_atomic(&out, xml.as_bytes()).map_err(Failure::internal)?;
            println!("{}: {} joints → {}", working.name(), working.chain().dof(), out.display());
        }
    }
    Ok(exit::OK)
}
