//! The solver's vocabulary: what to reach ([`Goal`]), the settings ([`Params`]), and how a solve ended
//! ([`Status`], [`Solution`]).

use std::time::Duration;

use nalgebra::{Isometry3, Vector3};
use serde::Serialize;

/// What the solver must reach.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Goal {
    /// Position and orientation of the TCP in the base frame.
    Pose(Isometry3<f64>),
    /// TCP position only (mm); orientation free.
    Position(Vector3<f64>),
}

impl Goal {
    pub(crate) fn position(&self) -> Vector3<f64> {
        match self {
            Goal::Pose(p) => p.translation.vector,
            Goal::Position(p) => *p,
        }
    }
    pub(crate) fn is_finite(&self) -> bool {
        match self {
            Goal::Pose(p) => {
                p.translation.vector.iter().all(|v| v.is_finite()) && p.rotation.coords.iter().all(|v| v.is_finite())
            }
            Goal::Position(p) => p.iter().all(|v| v.is_finite()),
        }
    }
}

/// Whether joint limits bind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum LimitPolicy {
    /// Every iterate is clamped into the limits; seeds are drawn inside them.
    Enforce,
    /// Limits are ignored.
    Ignore,
}

/// Where the restarts after a failed first attempt start from.
///
/// The branches pay: on the IRB 140 under the case-study deformation, from random seeds, the mean solve
/// takes 16.7 µs with them and 43.4 µs without (0.38×, `cargo xtask bench`, one run, AMD EPYC, 2 cores),
/// both at 100 % success — most random first attempts land on a branch outside the limits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum RestartSeeds {
    /// The closed-form solutions of the chain's ideal geometry ([`crate::ClosedForm`]) inside the
    /// limits, nearest to the seed first, then seeded random ones. Chains without a closed form go
    /// straight to the random ones.
    BranchesThenRandom,
    /// Seeded random seeds only (near the seed first, then anywhere inside the limits).
    RandomOnly,
}

/// Which linear algebra runs the step.
///
/// Kept because the bench says so: on the IRB 140 from a seed within 0.25 rad (`cargo bench -p
/// thermokin-ik -- ik_near_seed`, one run, AMD EPYC, 2 cores) the fixed-size 6 × 6 path takes a median
/// 3.89 µs per solve against 4.82 µs for faer's dynamic path (0.81×): at six joints the stack-allocated
/// Cholesky beats the general one. It is therefore the default; chains of other sizes use faer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Backend {
    /// faer, dynamic sizes, in-place Cholesky on a reused stack (any number of joints).
    Faer,
    /// nalgebra fixed-size 6 × 6 for six-joint chains (the default); other chains fall back to faer.
    NalgebraFixed6,
}

/// Solver settings.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Params {
    /// Iterations per attempt (one attempt per seed).
    pub max_iterations: usize,
    /// Converged when the position error is at most this (mm).
    pub position_tolerance_mm: f64,
    /// … and the orientation error at most this (radians).
    pub orientation_tolerance_rad: f64,
    /// Restarts after the first attempt fails: the closed-form branches first (see [`RestartSeeds`]),
    /// then random seeds.
    pub restarts: usize,
    /// Where restarts start from.
    pub restart_seeds: RestartSeeds,
    /// Optional wall-clock budget for one target, all attempts together. `None` (the default) makes the
    /// result a function of the inputs alone: the iteration and restart budgets bound the work, and the
    /// same target gives the same answer on a busy or an idle machine, on 1 or N threads.
    pub time_budget: Option<Duration>,
    /// Joint limits.
    pub limits: LimitPolicy,
    /// Seed of the restart generator (combined with the target index: the batch is deterministic).
    pub rng_seed: u64,
    /// Weight of orientation against position, mm per radian.
    pub length_scale_mm: f64,
    /// Initial damping λ (relative to the diagonal of JᵀJ).
    pub initial_damping: f64,
    /// Reject a solution farther than this from its seed (∞-norm over joints, radians or mm).
    pub max_distance_from_seed: Option<f64>,
    /// Largest move of a revolute joint in one iteration, radians (a trust region), once the TCP is
    /// within 50 mm of the target.
    pub max_step_rad: f64,
    /// The same while the TCP is farther than 50 mm from the target.
    pub max_step_far_rad: f64,
    /// Linear algebra of the step.
    pub backend: Backend,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            position_tolerance_mm: 1e-9,
            // 1e-9° (1.7e-11 rad): the published results' precision is 1e-6°, and 1e-9° over a 1 m
            // lever is 1.7e-8 mm, below the position tolerance's order.
            orientation_tolerance_rad: 1.745_329_251_994_329_5e-11,
            restarts: 100,
            restart_seeds: RestartSeeds::BranchesThenRandom,
            time_budget: None,
            limits: LimitPolicy::Enforce,
            rng_seed: 0x7e57_0140,
            length_scale_mm: 100.0,
            initial_damping: 1e-3,
            max_distance_from_seed: None,
            max_step_rad: 0.3,
            max_step_far_rad: 1.0,
            backend: Backend::NalgebraFixed6,
        }
    }
}

/// How a solve ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[non_exhaustive]
pub enum Status {
    /// Within both tolerances.
    Converged,
    /// The best solution found sits on a joint limit: the target needs a joint beyond it.
    JointLimit,
    /// The target cannot be reached (beyond the workspace, or no attempt could reduce the error).
    Unreachable,
    /// The best solution is at a singular configuration where the error stopped decreasing.
    Singular,
    /// A solution was found, but farther from the seed than `max_distance_from_seed` allows.
    FarFromSeed,
    /// The solver's residual reached the tolerances but the independent recomputation of the pose error
    /// (see [`crate::solve`]) did not: the answer is not trusted. Never expected; a bug if seen.
    Unverified,
}

/// The result of one solve.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Solution {
    /// Joint values (radians / mm): the converged solution, or the best found.
    pub q: Vec<f64>,
    /// How it ended.
    pub status: Status,
    /// Iterations over all attempts.
    pub iterations: usize,
    /// Random restarts used.
    pub restarts: usize,
    /// Final position error, mm.
    pub position_error_mm: f64,
    /// Final orientation error, radians (0 for position targets).
    pub orientation_error_rad: f64,
}

impl Solution {
    /// `true` when converged.
    pub fn converged(&self) -> bool {
        self.status == Status::Converged
    }
}
