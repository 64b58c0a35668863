#![doc = include_str!("../README.md")]
//! `thermokin-compensate`: the paper's compensation procedure end to end (section 4, Figure 13).
//!
//! For every programmed target, inverse kinematics on the *deformed* model gives the joint angles that
//! bring the deformed robot onto the programmed pose. Static case: one deformed state. Transient case: a
//! cycle (the paper's 200 minutes, every minute, the program in a loop) in which the model is updated at
//! each step from a [`TimeProfile`](thermokin_deform::TimeProfile) and every target re-solved, seeded from its previous solution.
//!
//! Each result records the compensated joints, the pose the deformed robot reaches with them, its
//! deviation from the programmed pose (position per axis; orientation as a rotation vector — per-axis
//! small-angle errors — never as differences of Euler triplets, which are degenerate at the programmed
//! RY = 90°), and, for comparison, the deviation of the *uncompensated* program (nominal IK angles run
//! on the deformed robot). Which run a request is — static, transient, a calibrated robot's targets in
//! their states or over a warm-up — is decided once, by [`Plan::new`], for every front end.

mod export;
mod model_run;
mod plan;
mod program;
mod run;
mod stream;

pub use export::{ResultsFormat, SummaryOut, write_joint_csv, write_long_csv, write_results_csv, write_results_json};
pub use model_run::{
    command_solution, commanded_on_model, compensate_model, compensate_model_cycle, solve_on_model, solve_rows,
    state_or,
};
pub use plan::{Plan, PlanError, Request};
pub use program::{
    AbbTargets, ArmConfiguration, BranchOut, Controller, Motion, Program, ProgramError, ProgramSettings, SolutionRow,
    SolveOut, arm_configuration, confdata, kuka_status, kuka_turn, motion_program, poses_program, program_files,
    programs,
};
pub use run::{
    Accumulation, Axes, Cycle, RunOutput, RunSettings, Summary, TargetResult, compensate_static, compensate_transient,
    orientation_error,
};
pub use stream::{StreamSettings, compensate_static_stream};

/// Errors of a compensation run (per-target failures are records, not errors).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CompensateError {
    /// The deformation model could not be built.
    #[error(transparent)]
    Deform(#[from] thermokin_deform::DeformError),
    /// The IK inputs were invalid.
    #[error(transparent)]
    Ik(#[from] thermokin_ik::IkError),
    /// A target whose operating state the robot model cannot evaluate (a drifting robot without a time,
    /// a sensor without a reading).
    #[error("target {label}{}: {message}", line.map(|l| format!(" (line {l})")).unwrap_or_default())]
    TargetState {
        /// The target's label.
        label: String,
        /// Its line in the targets file, if read from one.
        line: Option<usize>,
        /// What is missing.
        message: String,
    },
    /// A cycle setting out of its range.
    #[error("{field} must be {expected}, got {value} min")]
    Cycle {
        /// `step` or `duration`.
        field: &'static str,
        /// What it must be.
        expected: &'static str,
        /// The value given.
        value: f64,
    },
    /// A cycle of more steps than a run holds in memory.
    #[error("{steps} steps is more than a million")]
    TooManySteps {
        /// Steps asked for.
        steps: usize,
    },
    /// The request is not a run (see [`PlanError`]).
    #[error(transparent)]
    Plan(#[from] crate::plan::PlanError),
    /// A robot program could not be written.
    #[error(transparent)]
    Program(#[from] crate::program::ProgramError),
    /// A streamed program's targets could not be read.
    #[error(transparent)]
    Read(#[from] thermokin_io::IoError),
    /// A streamed run's output could not be written.
    #[error("writing the results: {source}")]
    Write {
        /// The I/O error.
        source: std::io::Error,
    },
}
