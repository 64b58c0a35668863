//! Static and transient compensation runs and their summaries (Tables 13, 15, 17, 18).

use nalgebra::{Isometry3, Vector3};
use serde::Serialize;
use thermokin_chain::{Chain, JointKind, Target, rotation_log};
use thermokin_deform::{DeviationTable, TableSemantics, TimeProfile};
use thermokin_ik::{Goal, Params, Seeds, Solution, Status, solve_batch};

use crate::CompensateError;

/// The orientation error of `reached` against `programmed` as a rotation vector in radians (world
/// frame): the axis of `R_reached R_programmedᵀ` times its angle; for small errors, the per-axis
/// rotations (the DRX, DRY, DRZ of the authors' files, in degrees there).
pub fn orientation_error(programmed: &Isometry3<f64>, reached: &Isometry3<f64>) -> Vector3<f64> {
    let programmed_to_reached = (reached.rotation * programmed.rotation.inverse()).to_rotation_matrix();
    rotation_log(programmed_to_reached.matrix())
}

/// The run's time axis: from 0 to `duration_min` every `step_min` (the paper: 200 min, every minute).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Cycle {
    /// Total duration, minutes.
    pub duration_min: f64,
    /// Model update interval, minutes.
    pub step_min: f64,
}

impl Cycle {
    /// The paper's transient cycle: 200 minutes, updated every minute (201 states, 0..=200).
    pub const PAPER: Cycle = Cycle { duration_min: 200.0, step_min: 1.0 };

    /// The update times, 0 included, `duration_min` included when it falls on a step.
    pub fn times(&self) -> Result<Vec<f64>, CompensateError> {
        if !(self.step_min.is_finite() && self.step_min > 0.0) {
            return Err(CompensateError::Cycle { field: "step", expected: "positive", value: self.step_min });
        }
        if !(self.duration_min.is_finite() && self.duration_min >= 0.0) {
            return Err(CompensateError::Cycle { field: "duration", expected: "≥ 0", value: self.duration_min });
        }
        let n = (self.duration_min / self.step_min + 1e-9).floor() as usize;
        if n > 1_000_000 {
            return Err(CompensateError::TooManySteps { steps: n + 1 });
        }
        Ok((0..=n).map(|k| k as f64 * self.step_min).collect())
    }
}

/// How a transient run brings the table into force from one model update to the next.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Accumulation {
    /// At each update the profile's share of the table is applied to the undeformed robot: the state at
    /// t depends on t alone (this library's reading of section 4).
    #[default]
    FromNominal,
    /// At each update only the *change* of the profile's share since the previous update is applied, to
    /// the robot as already deformed — what the authors' script does every minute (section 4: "the
    /// forward geometric model was updated minute by minute"; Appendix A, Figure A5: each call adds
    /// table/180 to every joint object). Under the canonical semantics both readings give the same
    /// state; under the CoppeliaSim semantics each increment is added to the Euler angles the scene
    /// reports at that moment, and near an X-axis joint object's gimbal lock (IRB 140 joints 4 and 6 at
    /// home) the reported angles drop part of the rotation, so the state depends on the path taken
    /// (`thermokin_deform::coppeliasim_euler_angles`). No update is made while the share does not change
    /// (minute 0, or a plateau).
    Increments,
}

thermokin_chain::choices!(
    Accumulation,
    "accumulation",
    [
        (
            "from-nominal",
            "the profile's share applied to the undeformed robot at each update (the state at t depends on t alone)",
            Accumulation::FromNominal
        ),
        (
            "increments",
            "the change of the share since the previous update applied to the robot as deformed (the authors' minute-by-minute updates)",
            Accumulation::Increments
        ),
    ]
);

/// Settings of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct RunSettings {
    /// How the deviation table acts on the chain.
    pub semantics: TableSemantics,
    /// How a transient run moves from one update's state to the next (static runs ignore it).
    pub accumulation: Accumulation,
    /// IK settings.
    pub ik: Params,
    /// Seed of the first solve (radians / mm); the program is then chained target to target.
    pub start: Vec<f64>,
}

/// One solved target at one time, in the library's units (mm, radians; the writers convert).
#[derive(Clone, Debug, PartialEq)]
pub struct TargetResult {
    /// Operating time, minutes.
    pub time_min: f64,
    /// Target label.
    pub label: String,
    /// Programmed pose.
    pub programmed: Isometry3<f64>,
    /// Pose the deformed robot reaches with the compensated joints.
    pub reached: Isometry3<f64>,
    /// Compensated joint values to command, radians (mm for prismatic joints).
    pub joints: Vec<f64>,
    /// The joint values the chain takes with them: [`TargetResult::joints`] unless a calibrated robot
    /// corrects its joint values (gear ratio, cyclic error, compliance; [`crate::compensate_model`]).
    pub chain_joints: Vec<f64>,
    /// Programmed − reached position, mm (the authors' sign).
    pub position_deviation_mm: [f64; 3],
    /// Orientation error as a rotation vector ([`orientation_error`]), radians.
    pub orientation_deviation_rad: [f64; 3],
    /// Position error of the uncompensated program (nominal IK angles on the deformed robot), mm.
    pub uncompensated_error_mm: f64,
    /// IK outcome.
    pub status: Status,
    /// IK iterations.
    pub iterations: usize,
}

impl TargetResult {
    /// `true` when the IK reached the target (its status is `Converged`, which the solver verified).
    pub fn converged(&self) -> bool {
        self.status == Status::Converged
    }
}

/// Min and max per axis.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Axes {
    /// Minimum per axis.
    pub min: [f64; 3],
    /// Maximum per axis.
    pub max: [f64; 3],
}

impl Axes {
    /// No value yet: +∞ minima, −∞ maxima.
    const EMPTY: Axes = Axes { min: [f64::INFINITY; 3], max: [f64::NEG_INFINITY; 3] };

    fn add(&mut self, v: [f64; 3]) {
        for k in 0..3 {
            self.min[k] = self.min[k].min(v[k]);
            self.max[k] = self.max[k].max(v[k]);
        }
    }
}

/// A summary built as rows arrive — one pass, constant memory but for the failed targets' names (at most
/// `named` of them; the count is always exact). [`RunOutput`]s and streamed runs share it.
pub(crate) struct SummaryBuilder {
    summary: Summary,
    transient: bool,
    named: usize,
}

impl SummaryBuilder {
    pub(crate) fn new(transient: bool, named: usize) -> Self {
        let summary = Summary {
            solves: 0,
            failures: 0,
            failed: Vec::new(),
            position_mm: Axes::EMPTY,
            orientation_rad: Axes::EMPTY,
            max_position_error_mm: 0.0,
            max_orientation_error_rad: 0.0,
            max_uncompensated_error_mm: 0.0,
        };
        Self { summary, transient, named }
    }

    pub(crate) fn add(&mut self, r: &TargetResult) {
        let s = &mut self.summary;
        s.solves += 1;
        if !r.converged() {
            s.failures += 1;
            if s.failed.len() < self.named {
                let at = if self.transient { format!(" @ {} min", r.time_min) } else { String::new() };
                s.failed.push(format!("{}{at} ({:?})", r.label, r.status));
            }
            return;
        }
        s.position_mm.add(r.position_deviation_mm);
        s.orientation_rad.add(r.orientation_deviation_rad);
        s.max_position_error_mm = s.max_position_error_mm.max(Vector3::from(r.position_deviation_mm).norm());
        s.max_orientation_error_rad =
            s.max_orientation_error_rad.max(Vector3::from(r.orientation_deviation_rad).norm());
        s.max_uncompensated_error_mm = s.max_uncompensated_error_mm.max(r.uncompensated_error_mm);
    }

    pub(crate) fn finish(mut self) -> Summary {
        let s = &mut self.summary;
        if s.failures > s.failed.len() {
            s.failed.push(format!("… and {} more", s.failures - s.failed.len()));
        }
        self.summary
    }
}

/// The summary of Tables 15, 17 (position) and 13, 18 (orientation), over converged targets, in the
/// library's units (the tables print degrees: the writers and the paper's report convert).
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// Solves in the run.
    pub solves: usize,
    /// Solves that did not converge.
    pub failures: usize,
    /// The failed targets, named: `label (status)`, with `@ t min` in a transient run. They are left out
    /// of every statistic below.
    pub failed: Vec<String>,
    /// Programmed − reached, mm.
    pub position_mm: Axes,
    /// Orientation error rotation vector, radians.
    pub orientation_rad: Axes,
    /// Largest position error, mm.
    pub max_position_error_mm: f64,
    /// Largest orientation error angle, radians.
    pub max_orientation_error_rad: f64,
    /// Largest position error of the uncompensated program over the reached targets, mm.
    pub max_uncompensated_error_mm: f64,
}

/// A run's results and summary.
#[derive(Clone, Debug, PartialEq)]
pub struct RunOutput {
    /// One row per target and time, in time order then program order.
    pub rows: Vec<TargetResult>,
    /// The kind of each joint of the robot (what the writers need to put joint values in degrees or mm).
    pub kinds: Vec<JointKind>,
    /// Min/max over the converged rows.
    pub summary: Summary,
    /// Whether the rows have times to write (a time column in the authors' layout): a transient run,
    /// or targets at their own times.
    pub timed: bool,
}

impl RunOutput {
    pub(crate) fn new(chain: &Chain, rows: Vec<TargetResult>) -> Self {
        let transient = rows.iter().any(|r| r.time_min != 0.0);
        let mut summary = SummaryBuilder::new(transient, usize::MAX);
        rows.iter().for_each(|r| summary.add(r));
        Self {
            rows,
            kinds: chain.joints().iter().map(|j| j.kind).collect(),
            summary: summary.finish(),
            timed: transient,
        }
    }
}

fn to_goals(program: &[Target]) -> Vec<Goal> {
    program.iter().map(|t| Goal::Pose(t.pose)).collect()
}

pub(crate) fn record(
    deformed: &Chain,
    time_min: f64,
    target: &Target,
    solution: &Solution,
    nominal_q: &[f64],
) -> Result<TargetResult, CompensateError> {
    let reached = deformed.tool_pose(&solution.q).map_err(thermokin_deform::DeformError::from)?;
    let uncompensated = deformed.tool_pose(nominal_q).map_err(thermokin_deform::DeformError::from)?;
    let dp = target.pose.translation.vector - reached.translation.vector;
    let dr = orientation_error(&target.pose, &reached);
    Ok(TargetResult {
        time_min,
        label: target.label.clone(),
        programmed: target.pose,
        reached,
        joints: solution.q.clone(),
        chain_joints: solution.q.clone(),
        position_deviation_mm: [dp.x, dp.y, dp.z],
        orientation_deviation_rad: [dr.x, dr.y, dr.z],
        uncompensated_error_mm: (target.pose.translation.vector - uncompensated.translation.vector).norm(),
        status: solution.status,
        iterations: solution.iterations,
    })
}

/// IK of the program on the nominal robot, chained target to target from `start`: the uncompensated
/// program, and the seeds of the compensated one.
fn nominal_program(
    chain: &Chain,
    program: &[Target],
    settings: &RunSettings,
) -> Result<Vec<Solution>, CompensateError> {
    Ok(solve_batch(chain, &to_goals(program), Seeds::ChainPrevious(&settings.start), &settings.ik)?)
}

/// Static case: one deformed state (the full table), every target solved on it.
///
/// ```
/// use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
/// use thermokin_chain::Target;
/// use thermokin_compensate::{RunSettings, compensate_static};
/// use thermokin_deform::{DeviationTable, TableSemantics};
///
/// let robot = thermokin_testdata::irb140_table9();
/// // Tables 10–11: 1 mm and 1° on every axis of every joint.
/// let table = DeviationTable::from_joint_rows(vec![thermokin_testdata::error_mm_deg([1.0; 6]); 6]);
/// // Table 12's first target: tool Z along world +X, i.e. X-Y-Z Euler (0, 90°, 0).
/// let tool_along_x = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
/// let program = vec![Target::new("P1", Isometry3::from_parts(Translation3::new(641.0, 21.0, 473.0), tool_along_x))];
/// let settings = RunSettings {
///     semantics: TableSemantics::Canonical,
///     accumulation: Default::default(),
///     ik: thermokin_ik::Params::default(),
///     start: [0.0, 20.0, 20.0, 0.0, -45.0, 0.0].map(f64::to_radians).to_vec(),
/// };
/// let run = compensate_static(&robot, &table, &program, &settings).unwrap();
/// // The deformed robot, driven by the compensated joints, is back on the target; the uncompensated
/// // program (nominal IK angles) misses it by millimetres.
/// assert_eq!(run.summary.failures, 0);
/// assert!(run.summary.max_position_error_mm < 1e-9);
/// assert!(run.summary.max_uncompensated_error_mm > 1.0);
/// ```
pub fn compensate_static(
    chain: &Chain,
    table: &DeviationTable,
    program: &[Target],
    settings: &RunSettings,
) -> Result<RunOutput, CompensateError> {
    let deformed = table.apply(chain, &settings.semantics)?;
    let nominal = nominal_program(chain, program, settings)?;
    let seeds: Vec<Vec<f64>> = nominal.iter().map(|s| s.q.clone()).collect();
    let solutions = solve_batch(&deformed, &to_goals(program), Seeds::PerTarget(&seeds), &settings.ik)?;
    let rows = program
        .iter()
        .zip(&solutions)
        .zip(&nominal)
        .map(|((t, s), n)| record(&deformed, 0.0, t, s, &n.q))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(RunOutput::new(chain, rows))
}

/// Transient case: at each time of `cycle` the model is updated from `profile` and every target
/// re-solved, seeded from its solution at the previous step (the first step from the nominal program).
/// `progress` is called after each step with (steps done, steps in all).
pub fn compensate_transient(
    chain: &Chain,
    table: &DeviationTable,
    profile: &TimeProfile,
    cycle: Cycle,
    program: &[Target],
    settings: &RunSettings,
    mut progress: impl FnMut(usize, usize),
) -> Result<RunOutput, CompensateError> {
    profile.validate(chain.dof())?;
    let times = cycle.times()?;
    let goals = to_goals(program);
    let nominal = nominal_program(chain, program, settings)?;
    let mut seeds: Vec<Vec<f64>> = nominal.iter().map(|s| s.q.clone()).collect();
    let mut rows = Vec::with_capacity(times.len() * program.len());
    // Under `Accumulation::Increments`: the state reached so far and the share of the table in it.
    let mut carried = (chain.clone(), DeviationTable::zeros(chain.dof()));
    for (k, &t) in times.iter().enumerate() {
        let in_force = profile.table_at(table, t)?;
        let deformed = match settings.accumulation {
            Accumulation::FromNominal => in_force.apply(chain, &settings.semantics)?,
            Accumulation::Increments => {
                let increment = in_force.add(&carried.1.scaled(-1.0))?;
                if !increment.is_zero() {
                    carried.0 = increment.apply(&carried.0, &settings.semantics)?;
                }
                carried.1 = in_force;
                carried.0.clone()
            }
        };
        let solutions = solve_batch(&deformed, &goals, Seeds::PerTarget(&seeds), &settings.ik)?;
        for ((target, s), n) in program.iter().zip(&solutions).zip(&nominal) {
            rows.push(record(&deformed, t, target, s, &n.q)?);
        }
        for (seed, s) in seeds.iter_mut().zip(&solutions) {
            if s.converged() {
                seed.clone_from(&s.q);
            }
        }
        progress(k + 1, times.len());
    }
    Ok(RunOutput::new(chain, rows))
}
