#![doc = include_str!("../README.md")]
//! `thermokin-ik`: inverse kinematics on any chain (nominal or deformed) — damped least squares /
//! Levenberg–Marquardt with adaptive damping, the Jacobian and its linear solve in faer on the
//! allocation-free path, joint limits, random restarts, and a deterministic parallel batch API.
//!
//! This is the compensation step of the paper (section 4, Figure 13): the joint angles that bring the
//! *deformed* model onto the programmed pose.
//!
//! # Keeping one arm configuration through a program
//! A local solver stays on the branch (elbow up/down, wrist flip) of its seed as long as the seed is
//! close. To keep one configuration through a whole program: seed every target from the previous
//! solution ([`Seeds::ChainPrevious`], or [`Seeds::PerTarget`] with the previous time step's solutions
//! in a transient run), set `restarts = 0` (a random restart may land on another branch), and bound the
//! move with [`Params::max_distance_from_seed`] so that a solution on another branch is reported as a
//! failure rather than silently accepted.

mod analytic;
mod batch;
mod lm;
mod params;
mod solve;

pub use analytic::{Branch, ClosedForm, Family};
pub use batch::{Seeds, solve_batch};
pub use lm::Workspace;
pub use params::{Backend, Goal, LimitPolicy, Params, RestartSeeds, Solution, Status};
pub use solve::{solve, solve_branches};

/// Errors of the solver's inputs (failures to converge are a [`Status`], not an error).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum IkError {
    /// A seed with the wrong number of joint values.
    #[error("seed: {got} values for {expected} joints")]
    SeedLength {
        /// Joints of the chain.
        expected: usize,
        /// Values given.
        got: usize,
    },
    /// A seed with a NaN or infinite value.
    #[error("seed: joint {joint} is not finite")]
    SeedNotFinite {
        /// 1-based joint.
        joint: usize,
    },
    /// A batch with a different number of seeds and targets.
    #[error("{seeds} seeds for {targets} targets")]
    SeedCount {
        /// Seeds given.
        seeds: usize,
        /// Targets given.
        targets: usize,
    },
    /// A target with a non-finite value.
    #[error("target {index}: not finite")]
    BadTarget {
        /// 0-based target index.
        index: usize,
    },
    /// A solver setting out of its range.
    #[error("params: {field} must be positive and finite, got {value}")]
    BadParams {
        /// The field of [`Params`].
        field: &'static str,
        /// Its value.
        value: f64,
    },
}
