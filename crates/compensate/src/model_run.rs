//! Compensation on a calibrated robot ([`RobotModel`]): every target solved on the robot as it is in the
//! target's own operating state — its time of the warm-up, its sensor readings, its payload — and the
//! joint-space corrections inverted, so that the joints written are the values to command.
//!
//! Per target: the chain in force at the state ([`RobotModel::chain_at`]), IK on it for the joint values
//! the chain must take, [`RobotModel::commanded_for`] for the values to command; then the reached pose is
//! measured again through the whole model ([`RobotModel::tool_pose`] of the commanded values), and a
//! target is `Converged` only if that independent measurement is within the IK's tolerances.

use nalgebra::Isometry3;
use thermokin_chain::{OperatingState, Target};
use thermokin_deform::RobotModel;
use thermokin_ik::{Goal, Params, Seeds, Solution, Status, solve_batch};

use crate::CompensateError;
use crate::run::{Cycle, RunOutput, RunSettings, TargetResult, orientation_error};

/// Slack of the independent re-measurement over the IK's tolerances, mm (and, divided by the IK's length
/// scale, radians): the inversion leaves at most 1e-12 rad (1e-14 sought), 1e-10 mm at a 100 mm lever —
/// the IK's own check cannot see it, this one must not fail on it.
const REMEASURE_SLACK_MM: f64 = 1e-9;

/// `state` completed by `defaults` where it says nothing (a targets file's columns override the command
/// line's `--time`, `--temperature`, `--payload`).
pub fn state_or(state: &OperatingState, defaults: &OperatingState) -> OperatingState {
    let mut out = state.clone();
    if out.time_min.is_none() {
        out.time_min = defaults.time_min;
    }
    for (name, t) in &defaults.temperatures_c {
        if out.temperature(name).is_none() {
            out.temperatures_c.push((name.clone(), *t));
        }
    }
    if out.payload.is_none() {
        out.payload = defaults.payload;
    }
    out
}

/// A program on a robot model: each target solved on the robot in the target's state (its own, completed
/// by `defaults`). The uncompensated program is the IK of the model's cold chain (no drift, no joint
/// corrections: the file's geometry alone), chained from `settings.start`, run on the same states.
///
/// A state the model cannot evaluate (a drifting robot without a time, a sensor not read) is an error
/// naming the target. Semantics and accumulation settings do not apply (a model's drift is canonical and
/// depends on the state alone).
pub fn compensate_model(
    model: &RobotModel,
    program: &[Target],
    defaults: &OperatingState,
    settings: &RunSettings,
) -> Result<RunOutput, CompensateError> {
    let mut states: Vec<OperatingState> = program.iter().map(|t| state_or(&t.state, defaults)).collect();
    let nominal = cold_program(model, program, settings)?;
    let seeds: Vec<Vec<f64>> = nominal.iter().map(|s| s.q.clone()).collect();
    let planned: Vec<&[f64]> = nominal.iter().map(|s| s.q.as_slice()).collect();
    with_approach_along(model, &mut states, &settings.start, &defaults.approach, &planned);
    let mut rows = solve_in_states(model, program, &states, &seeds, &nominal, settings)?;
    // The directions were taken from the cold program's moves; the commanded ones decide. Where they
    // differ (a joint that barely moves between two targets), solved again in the directions commanded.
    let commanded: Vec<&[f64]> = rows.iter().map(|r| r.joints.as_slice()).collect();
    let mut again = states.clone();
    with_approach_along(model, &mut again, &settings.start, &defaults.approach, &commanded);
    if again != states {
        rows = solve_in_states(model, program, &again, &seeds, &nominal, settings)?;
    }
    Ok(RunOutput::new(model.robot().chain(), rows))
}

/// For a model with a backlash, each state's [`OperatingState::approach`] — where its target gives none —
/// from the program's moves: `path` the joint values of each target, reached from `start` (whose own
/// directions are `start_approach`, or unknown) in the order of the targets' times where every target
/// has one and they span time (targets of one time in file order), else in the program's order.
fn with_approach_along(
    model: &RobotModel,
    states: &mut [OperatingState],
    start: &[f64],
    start_approach: &[thermokin_chain::Approach],
    path: &[&[f64]],
) {
    if !model.has_backlash() {
        return;
    }
    let times: Vec<Option<f64>> = states.iter().take(path.len()).map(|s| s.time_min).collect();
    let order = thermokin_chain::time_order(&times);
    let mut last: Vec<thermokin_chain::Approach> = if start_approach.len() == start.len() {
        start_approach.to_vec()
    } else {
        vec![thermokin_chain::Approach::Unknown; start.len()]
    };
    let mut from = start;
    for k in order {
        let (state, to) = (&mut states[k], path[k]);
        thermokin_chain::Approach::advance(&mut last, from, to);
        if state.approach.is_empty() || state.approach.len() != last.len() {
            state.approach.clone_from(&last);
        } else {
            last.clone_from(&state.approach);
        }
        from = to;
    }
}

/// A warm-up on a robot model: at each time of `cycle`, every target solved on the robot at that time
/// (its other state from the target and `defaults`), seeded from its previous solution.
pub fn compensate_model_cycle(
    model: &RobotModel,
    cycle: Cycle,
    program: &[Target],
    defaults: &OperatingState,
    settings: &RunSettings,
    mut progress: impl FnMut(usize, usize),
) -> Result<RunOutput, CompensateError> {
    let times = cycle.times()?;
    let nominal = cold_program(model, program, settings)?;
    let mut seeds: Vec<Vec<f64>> = nominal.iter().map(|s| s.q.clone()).collect();
    let mut rows = Vec::with_capacity(times.len() * program.len());
    for (k, &t) in times.iter().enumerate() {
        let mut states: Vec<OperatingState> = program
            .iter()
            .map(|target| OperatingState { time_min: Some(t), ..state_or(&target.state, defaults) })
            .collect();
        // Each pass runs the program from its start: the directions of the cold program's moves.
        let planned: Vec<&[f64]> = nominal.iter().map(|s| s.q.as_slice()).collect();
        with_approach_along(model, &mut states, &settings.start, &defaults.approach, &planned);
        let step = solve_in_states(model, program, &states, &seeds, &nominal, settings)?;
        for (seed, r) in seeds.iter_mut().zip(&step) {
            if r.converged() {
                // The IK's seed is in the chain's joint values; the row holds commanded ones, which differ
                // by the small corrections only — a seed, not an answer.
                seed.clone_from(&r.chain_joints);
            }
        }
        rows.extend(step);
        progress(k + 1, times.len());
    }
    Ok(RunOutput::new(model.robot().chain(), rows))
}

/// The program solved on the model's cold chain, chained target to target.
fn cold_program(
    model: &RobotModel,
    program: &[Target],
    settings: &RunSettings,
) -> Result<Vec<Solution>, CompensateError> {
    let goals: Vec<Goal> = program.iter().map(|t| Goal::Pose(t.pose)).collect();
    Ok(solve_batch(model.robot().chain(), &goals, Seeds::ChainPrevious(&settings.start), &settings.ik)?)
}

/// Every target in its state: runs of consecutive targets in one state share one chain and one
/// (parallel) batch solve.
fn solve_in_states(
    model: &RobotModel,
    program: &[Target],
    states: &[OperatingState],
    seeds: &[Vec<f64>],
    nominal: &[Solution],
    settings: &RunSettings,
) -> Result<Vec<TargetResult>, CompensateError> {
    let mut rows = Vec::with_capacity(program.len());
    let mut start = 0;
    while start < program.len() {
        let state = &states[start];
        let end = start + states[start..].iter().take_while(|s| *s == state).count();
        let in_state = |e: thermokin_deform::DeformError| {
            let t = &program[start];
            CompensateError::TargetState { label: t.label.clone(), line: t.line, message: e.to_string() }
        };
        let goals: Vec<Goal> = program[start..end].iter().map(|t| Goal::Pose(t.pose)).collect();
        let solutions = if model.bends() {
            // The chain in force differs per target (its tilt follows the configuration): one solve each.
            let mut ws = thermokin_ik::Workspace::new(model.robot().chain().dof());
            let mut out = Vec::with_capacity(goals.len());
            for (k, goal) in goals.iter().enumerate() {
                let seed = &seeds[start + k];
                let index = (start + k) as u64;
                out.push(solve_bending(model, state, goal, seed, &settings.ik, &mut ws, index).map_err(
                    |e| match e {
                        CompensateError::Deform(d) => in_state(d),
                        other => other,
                    },
                )?);
            }
            out
        } else {
            let chain = model.chain_at(state).map_err(in_state)?;
            solve_batch(&chain, &goals, Seeds::PerTarget(&seeds[start..end]), &settings.ik)?
        };
        for (k, s) in solutions.iter().enumerate() {
            let i = start + k;
            rows.push(record(model, &program[i], &states[i], s, &nominal[i].q, settings).map_err(in_state)?);
        }
        start = end;
    }
    Ok(rows)
}

/// One goal solved on `model` in `state`, from a seed given as joints to command: IK on the chain in
/// force ([`RobotModel::chain_at`]) from the seed's chain values ([`RobotModel::joint_values`]), then, for
/// a robot that corrects its joint values, the solution made the joints to command and re-measured
/// ([`command_solution`]). What `thermokin ik` and the Python `Robot.ik` run; `index` seeds the solver's
/// restarts (a batch passes each target's position, so that the result does not depend on threads).
pub fn solve_on_model(
    model: &RobotModel,
    state: &OperatingState,
    goal: &Goal,
    seed: &[f64],
    params: &Params,
    ws: &mut thermokin_ik::Workspace,
    index: u64,
) -> Result<Solution, CompensateError> {
    let mut solution = if model.bends() {
        solve_bending(model, state, goal, &model.joint_values(seed, state)?, params, ws, index)?
    } else {
        let chain = model.chain_at(state)?;
        let seed = model.joint_values(seed, state)?;
        thermokin_ik::solve(&chain, goal, &seed, params, ws, index)?
    };
    commanded_on_model(model, state, goal, params, &mut solution)?;
    Ok(solution)
}

/// Most solves of the fixed point in [`solve_bending`]: a tilt of ~1e-4 rad per N·m·radian of motion
/// contracts by that factor per solve, so a few reach the IK's own tolerance.
const MAX_BENDING_SOLVES: usize = 8;

/// IK on a model whose chain in force depends on the configuration ([`RobotModel::bends`]): solved on the
/// chain at the commanded values of the last answer (from the seed's), again until those stop moving
/// (by 1e-12 rad or mm) or [`MAX_BENDING_SOLVES`]. Returns the chain values of the last solve; whether
/// they reach the goal is checked afterwards through the whole model ([`command_solution`]), which is
/// what makes a solve that did not settle `Unverified`.
fn solve_bending(
    model: &RobotModel,
    state: &OperatingState,
    goal: &Goal,
    seed_chain: &[f64],
    params: &Params,
    ws: &mut thermokin_ik::Workspace,
    index: u64,
) -> Result<Solution, CompensateError> {
    let commanded = model.commanded_for(seed_chain, state).unwrap_or_else(|_| seed_chain.to_vec());
    let mut solution =
        thermokin_ik::solve(&model.chain_at_joints(state, &commanded)?, goal, seed_chain, params, ws, index)?;
    let mut commanded = commanded;
    for _ in 1..MAX_BENDING_SOLVES {
        let next = model.commanded_for(&solution.q, state).unwrap_or_else(|_| solution.q.clone());
        let moved = next.iter().zip(&commanded).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        if moved <= 1e-12 {
            break;
        }
        commanded = next;
        let seed = solution.q.clone();
        solution = thermokin_ik::solve(&model.chain_at_joints(state, &commanded)?, goal, &seed, params, ws, index)?;
    }
    Ok(solution)
}

/// Every row of a targets file solved on `model` from `seed` (`ik --poses-file`, one output row per input
/// row): each target in its own state (its `time_min` / `temp_*` columns) or, where it gives none, in
/// `flags`; a row that could not be read, or not solved, is a record with its error. `index` of each
/// solve is its row's position, so that the results do not depend on threads.
///
/// On a model with a backlash whose directions neither the row nor the flags give, the rows are the
/// robot's moves: solved first with the directions unknown (each play at its middle), then each row's
/// directions taken from the moves between those solutions — in the order of the rows' times where
/// they have them, else of the file (as `compensate` takes them; the first row's from nothing: unknown) —
/// and the rows solved again in them.
pub fn solve_rows(
    model: &RobotModel,
    rows: Vec<Result<Target, thermokin_io::IoError>>,
    flags: &OperatingState,
    seed: &[f64],
    params: &Params,
) -> Vec<crate::SolutionRow> {
    let chain = model.robot().chain();
    let mut ws = thermokin_ik::Workspace::new(chain.dof());
    let failure = |line, label, e: String| crate::SolutionRow { line, label, error: Some(e), ..Default::default() };
    let mut solve = |k: usize, t: &Target, state: &OperatingState| match solve_on_model(
        model,
        state,
        &Goal::Pose(t.pose),
        seed,
        params,
        &mut ws,
        k as u64,
    ) {
        Ok(s) => (crate::SolutionRow::solved(chain, t.line, t.label.clone(), &s), Some(s.q)),
        Err(e) => (failure(t.line, t.label.clone(), e.to_string()), None),
    };
    let chained = model.has_backlash();
    let states: Vec<Option<OperatingState>> = rows
        .iter()
        .map(|r| {
            r.as_ref().ok().map(|t| {
                let mut state = if t.state == OperatingState::default() { flags.clone() } else { t.state.clone() };
                if chained && state.approach.is_empty() {
                    state.approach = vec![thermokin_chain::Approach::Unknown; chain.dof()];
                }
                state
            })
        })
        .collect();
    let given: Vec<bool> = states
        .iter()
        .map(|s| s.as_ref().is_some_and(|s| s.approach.iter().any(|a| *a != thermokin_chain::Approach::Unknown)))
        .collect();
    let mut out: Vec<(crate::SolutionRow, Option<Vec<f64>>)> = rows
        .iter()
        .zip(&states)
        .enumerate()
        .map(|(k, (row, state))| match (row, state) {
            (Ok(t), Some(state)) => solve(k, t, state),
            _ => (failure(None, String::new(), row.as_ref().err().map(ToString::to_string).unwrap_or_default()), None),
        })
        .collect();
    if chained && given.iter().all(|g| !g) {
        let solved: Vec<usize> = (0..out.len()).filter(|&k| out[k].1.is_some()).collect();
        let mut moved: Vec<OperatingState> = solved
            .iter()
            .filter_map(|&k| states[k].clone())
            .map(|s| OperatingState { approach: Vec::new(), ..s })
            .collect();
        let path: Vec<&[f64]> = solved.iter().filter_map(|&k| out[k].1.as_deref()).collect();
        // The moves start at the first row measured: the first of their order.
        let times: Vec<Option<f64>> = moved.iter().map(|s| s.time_min).collect();
        let first = thermokin_chain::time_order(&times).first().copied();
        let start = first.map(|i| path[i].to_vec()).unwrap_or_default();
        with_approach_along(model, &mut moved, &start, &[], &path);
        for (&k, state) in solved.iter().zip(moved) {
            if let Ok(t) = &rows[k] {
                out[k] = solve(k, t, &state);
            }
        }
    }
    out.into_iter().map(|(row, _)| row).collect()
}

/// A solution on the chain in force made the joints to command on `model`: [`command_solution`] when the
/// model corrects its joint values (gear ratio, cyclic error, compliance) or bends (a lateral compliance:
/// the pose is re-measured through the whole model), nothing otherwise — a plain or drifting robot's
/// chain values are the joints to command.
pub fn commanded_on_model(
    model: &RobotModel,
    state: &OperatingState,
    goal: &Goal,
    params: &Params,
    solution: &mut Solution,
) -> Result<(), thermokin_deform::DeformError> {
    if model.corrects_joints() || model.bends() {
        command_solution(model, state, goal, params, solution)?;
    }
    Ok(())
}

/// A solution on the chain in force made the joint values to command on `model` (its joint corrections
/// inverted, [`RobotModel::commanded_for`]), with the reached pose measured again through the whole
/// model, independently of the IK: `solution.q` becomes the commanded joints and its errors the
/// re-measured ones; a solve that converged on the chain but whose joints cannot be inverted, or whose
/// re-measured pose misses the tolerances (`params`, with `REMEASURE_SLACK_MM` (1e-9 mm) of slack), is
/// `Unverified`. Returns the reached pose.
pub fn command_solution(
    model: &RobotModel,
    state: &OperatingState,
    goal: &Goal,
    params: &Params,
    solution: &mut Solution,
) -> Result<Isometry3<f64>, thermokin_deform::DeformError> {
    let (joints, mut status) = match model.commanded_for(&solution.q, state) {
        Ok(q) => (q, solution.status),
        Err(_) => (solution.q.clone(), Status::Unverified),
    };
    let reached = model.tool_pose(&joints, state)?;
    let (dp, dr) = match goal {
        Goal::Pose(p) => {
            ((p.translation.vector - reached.translation.vector).norm(), orientation_error(p, &reached).norm())
        }
        Goal::Position(p) => ((p - reached.translation.vector).norm(), 0.0),
    };
    let slack_rad = REMEASURE_SLACK_MM / params.length_scale_mm;
    if status == Status::Converged
        && (dp > params.position_tolerance_mm + REMEASURE_SLACK_MM || dr > params.orientation_tolerance_rad + slack_rad)
    {
        status = Status::Unverified;
    }
    solution.q = joints;
    solution.status = status;
    solution.position_error_mm = dp;
    solution.orientation_error_rad = dr;
    Ok(reached)
}

/// One target's record: the commanded joints ([`command_solution`]), the pose the whole model reaches
/// with them, and the uncompensated pose.
fn record(
    model: &RobotModel,
    target: &Target,
    state: &OperatingState,
    solution: &Solution,
    nominal_q: &[f64],
    settings: &RunSettings,
) -> Result<TargetResult, thermokin_deform::DeformError> {
    let mut commanded = solution.clone();
    let reached = command_solution(model, state, &Goal::Pose(target.pose), &settings.ik, &mut commanded)?;
    let uncompensated = model.tool_pose(nominal_q, state)?;
    let dp = target.pose.translation.vector - reached.translation.vector;
    let dr = orientation_error(&target.pose, &reached);
    Ok(TargetResult {
        time_min: state.time_min.unwrap_or(0.0),
        label: target.label.clone(),
        programmed: target.pose,
        reached,
        joints: commanded.q,
        chain_joints: solution.q.clone(),
        position_deviation_mm: [dp.x, dp.y, dp.z],
        orientation_deviation_rad: [dr.x, dr.y, dr.z],
        uncompensated_error_mm: (target.pose.translation.vector - uncompensated.translation.vector).norm(),
        status: commanded.status,
        iterations: solution.iterations,
    })
}
