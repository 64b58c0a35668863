//! Which run a compensation request is — decided once, here, for every front end (the CLI's
//! `compensate`, the Python `compensate`): a plain robot with a deviation table runs the paper's static
//! or transient case; a calibrated robot (corrections, drift, payload — or an operating state given)
//! solves each target in its own state, or every target at every step of a warm-up.

use thermokin_chain::{OperatingState, Target};
use thermokin_deform::{DeviationTable, RobotModel, TableSemantics, TimeProfile};

use crate::run::{Accumulation, Cycle, RunOutput, RunSettings, compensate_static, compensate_transient};
use crate::{CompensateError, compensate_model, compensate_model_cycle};

/// A compensation request, as a front end read it.
#[derive(Clone, Copy, Debug)]
pub struct Request<'a> {
    /// The robot, with what its file carries.
    pub model: &'a RobotModel,
    /// A deviation table to deform it with.
    pub table: Option<&'a DeviationTable>,
    /// How the table grows with time (`None`: static).
    pub profile: Option<&'a TimeProfile>,
    /// The operating state given for every target (a target's own columns override it).
    pub state: &'a OperatingState,
    /// How the table acts on a plain robot's chain.
    pub semantics: &'a TableSemantics,
    /// How a transient run moves from one update to the next.
    pub accumulation: Accumulation,
    /// A warm-up's length, minutes, when one is asked for.
    pub duration_min: Option<f64>,
    /// A warm-up's step, minutes.
    pub step_min: f64,
}

/// What a request cannot be, each a variant a front end words in its own terms (flags, keywords).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// A nominal robot and no table: nothing deforms it.
    #[error(
        "nothing to compensate: the robot is as designed (no error parameters, zero offsets or corrections) and no deviation table is given"
    )]
    NothingToCompensate,
    /// Accumulation by increments asked for without a growing profile.
    #[error("accumulation by increments needs a transient run (a growing profile)")]
    IncrementsNeedTransient,
    /// Accumulation by increments on a calibrated robot (it replays the authors' edits of a plain one).
    #[error("accumulation by increments replays the authors' CoppeliaSim updates on a plain robot's table")]
    IncrementsOnCalibrated,
    /// CoppeliaSim semantics on a calibrated robot (its rows drift canonically).
    #[error("the CoppeliaSim semantics applies to a plain robot's table; a calibrated robot's rows drift canonically")]
    SemanticsOnCalibrated,
    /// A temperature-log profile added to a calibrated robot.
    #[error(
        "a temperature-log profile cannot be combined with a calibrated robot: give the targets' temp_* columns instead"
    )]
    TemperatureLogOnCalibrated,
}

/// The run a request is.
#[derive(Clone, Debug, PartialEq)]
pub enum Plan {
    /// A plain robot deformed by a table, statically (the paper's static case, Tables 13–16).
    Static {
        /// The table.
        table: DeviationTable,
    },
    /// A plain robot whose table grows with a profile over a warm-up (Tables 17–18).
    Transient {
        /// The table.
        table: DeviationTable,
        /// How it grows.
        profile: TimeProfile,
        /// The warm-up's times.
        cycle: Cycle,
    },
    /// A calibrated robot (the table, if any, added to its rows): each target in its own state.
    InStates {
        /// The robot with the table added.
        model: RobotModel,
    },
    /// A calibrated robot over a warm-up: every target at every step.
    Warmup {
        /// The robot with the table added.
        model: RobotModel,
        /// The warm-up's times.
        cycle: Cycle,
    },
}

impl Plan {
    /// Decides the run: a plain robot with a table and no state given runs the static case, or the
    /// transient one under a profile that is not static; any other robot with corrections — or any robot
    /// with a state given — is a calibrated robot's run, a warm-up when a duration is asked for or its
    /// table grows with no time given, each target in its state otherwise.
    pub fn new(request: &Request<'_>) -> Result<Plan, CompensateError> {
        let r = request;
        // A warm-up lasts the paper's 200 minutes unless a duration is given.
        let cycle = Cycle { duration_min: r.duration_min.unwrap_or(Cycle::PAPER.duration_min), step_min: r.step_min };
        let increments = r.accumulation == Accumulation::Increments;
        match r.table {
            Some(table) if r.model.is_plain() && r.state.is_empty() => {
                match r.profile.filter(|p| **p != TimeProfile::Static) {
                    None if increments => Err(PlanError::IncrementsNeedTransient.into()),
                    None => Ok(Plan::Static { table: table.clone() }),
                    Some(profile) => Ok(Plan::Transient { table: table.clone(), profile: profile.clone(), cycle }),
                }
            }
            None if r.model.is_nominal() => Err(PlanError::NothingToCompensate.into()),
            _ => {
                let profile = r.profile.cloned().unwrap_or(TimeProfile::Static);
                let mut model = r.model.clone();
                if let Some(table) = r.table {
                    if *r.semantics != TableSemantics::Canonical {
                        return Err(PlanError::SemanticsOnCalibrated.into());
                    }
                    if matches!(profile, TimeProfile::Temperature { .. }) {
                        return Err(PlanError::TemperatureLogOnCalibrated.into());
                    }
                    // The table becomes drifting rows of the robot, each with the profile's law.
                    model = model.with_table(table, &profile)?;
                }
                if increments {
                    return Err(PlanError::IncrementsOnCalibrated.into());
                }
                let growing = !matches!(profile, TimeProfile::Static);
                if r.duration_min.is_some() || (growing && r.state.time_min.is_none()) {
                    Ok(Plan::Warmup { model, cycle })
                } else {
                    Ok(Plan::InStates { model })
                }
            }
        }
    }

    /// The warm-up's times, for a plan that runs one.
    pub fn cycle(&self) -> Option<Cycle> {
        match self {
            Plan::Transient { cycle, .. } | Plan::Warmup { cycle, .. } => Some(*cycle),
            Plan::Static { .. } | Plan::InStates { .. } => None,
        }
    }

    /// Runs the plan on `program` with `settings` (the request's `model`, `state` and `semantics` are
    /// those the plan was decided on); `progress` is called after each step of a warm-up with (steps done,
    /// steps in all).
    pub fn run(
        &self,
        request: &Request<'_>,
        program: &[Target],
        settings: &RunSettings,
        progress: impl FnMut(usize, usize),
    ) -> Result<RunOutput, CompensateError> {
        let chain = request.model.robot().chain();
        match self {
            Plan::Static { table } => compensate_static(chain, table, program, settings),
            Plan::Transient { table, profile, cycle } => {
                // A transient run has its time column even when every step is minute 0.
                compensate_transient(chain, table, profile, *cycle, program, settings, progress)
                    .map(|run| RunOutput { timed: true, ..run })
            }
            Plan::InStates { model } => compensate_model(model, program, request.state, settings),
            Plan::Warmup { model, cycle } => {
                compensate_model_cycle(model, *cycle, program, request.state, settings, progress)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::panic)]

    use thermokin_chain::{OperatingState, Robot};
    use thermokin_deform::{AfterStabilization, DeviationTable, RobotModel, TableSemantics, TimeProfile};

    use super::{Plan, PlanError, Request};
    use crate::{Accumulation, CompensateError};

    fn plan(
        model: &RobotModel,
        table: Option<&DeviationTable>,
        profile: Option<&TimeProfile>,
        state: &OperatingState,
        semantics: &TableSemantics,
        accumulation: Accumulation,
        duration_min: Option<f64>,
    ) -> Result<Plan, CompensateError> {
        Plan::new(&Request { model, table, profile, state, semantics, accumulation, duration_min, step_min: 1.0 })
    }

    #[test]
    fn each_request_is_the_run_the_paper_or_the_calibrated_robot_needs() {
        let plain = RobotModel::new(Robot::new("irb140", thermokin_testdata::irb140_table9()));
        let table = DeviationTable::zeros(6);
        let grow = TimeProfile::Linear { stabilization_min: 180.0, after: AfterStabilization::KeepGrowing };
        let cold = OperatingState::default();
        let canonical = TableSemantics::Canonical;
        let nominal = Accumulation::FromNominal;
        // A plain robot's table: the static case, or the transient one under a growing profile.
        let p = plan(&plain, Some(&table), None, &cold, &canonical, nominal, None).unwrap();
        assert!(matches!(p, Plan::Static { .. }) && p.cycle().is_none());
        let p = plan(&plain, Some(&table), Some(&TimeProfile::Static), &cold, &canonical, nominal, None).unwrap();
        assert!(matches!(p, Plan::Static { .. }));
        let p = plan(&plain, Some(&table), Some(&grow), &cold, &canonical, nominal, Some(30.0)).unwrap();
        let Plan::Transient { cycle, .. } = p else { panic!("{p:?}") };
        assert_eq!((cycle.duration_min, cycle.step_min), (30.0, 1.0));
        // The paper's 200 minutes when no duration is given.
        let p = plan(&plain, Some(&table), Some(&grow), &cold, &canonical, nominal, None).unwrap();
        assert_eq!(p.cycle().unwrap().duration_min, crate::Cycle::PAPER.duration_min);
        // A state given makes it a calibrated robot's run: each target in its state, or a warm-up.
        let at_60 = OperatingState::at_time(60.0);
        let p = plan(&plain, Some(&table), Some(&grow), &at_60, &canonical, nominal, None).unwrap();
        assert!(matches!(p, Plan::InStates { .. }), "{p:?}");
        let p = plan(&plain, Some(&table), Some(&grow), &at_60, &canonical, nominal, Some(10.0)).unwrap();
        assert!(matches!(p, Plan::Warmup { .. }), "{p:?}");
        // Refusals, each its own variant.
        let refused = |r: Result<Plan, CompensateError>| match r {
            Err(CompensateError::Plan(e)) => e,
            other => panic!("{other:?}"),
        };
        let e = refused(plan(&plain, None, None, &cold, &canonical, nominal, None));
        assert_eq!(e, PlanError::NothingToCompensate);
        let e = refused(plan(&plain, Some(&table), None, &cold, &canonical, Accumulation::Increments, None));
        assert_eq!(e, PlanError::IncrementsNeedTransient);
        let coppelia = TableSemantics::coppeliasim_at_home(6);
        let e = refused(plan(&plain, Some(&table), Some(&grow), &at_60, &coppelia, nominal, None));
        assert_eq!(e, PlanError::SemanticsOnCalibrated);
        let e = refused(plan(&plain, Some(&table), Some(&grow), &at_60, &canonical, Accumulation::Increments, None));
        assert_eq!(e, PlanError::IncrementsOnCalibrated);
    }
}
