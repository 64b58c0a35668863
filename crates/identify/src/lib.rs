#![doc = include_str!("../README.md")]
//! `thermokin-identify`: identification of a robot's errors from measured poses — the layer the
//! diagnosis and the measurement planner share.
//!
//! Effects are parameter blocks on top of a robot ([`Effect`], each carrying its joint), assembled into a
//! [`Model`] whose prediction of a measured pose and its analytic Jacobian come from the chain's
//! parameter Jacobian ([`residuals_and_jacobian`]). [`fit`] is Levenberg–Marquardt on faer with column
//! scaling; the parameters the data cannot identify are found first ([`identifiable`]: ordered
//! Gram–Schmidt on the column-scaled Jacobian, by an orthogonal factorisation) and fixed with a reason;
//! [`observability`] gives the indices of the rest. [`Setup`] says which blocks a measurement setup always
//! estimates (a tracker registration, an unknown tool) and which effects are candidates.
//!
//! Units inside are millimetres, radians, minutes and newton-metres; [`Effect::to_report_units`] converts
//! a parameter for reports.

mod catalogue;
mod coverage;
mod effect;
mod error;
mod fit;
mod identifiability;
mod lm;
mod model;
mod predict;
mod registration;
mod residuals;
mod sampling;
mod tally;
mod terms;
mod use_error;

pub use catalogue::{FrameMode, Lateral, Setup, ToolMode, approach_counts, gravity_compliance};
pub use coverage::{Eligibility, arc_needed, needed_arc, travel};
pub use effect::{
    BranchAt, DriftShape, EFFECT_NAMES, Effect, JointBasis, JointIndex, LINEAR_DRIFT_REFERENCE_MIN, PAIR_START,
    SensorId, StepAt, Support, TAU_RANGE_MIN, TiltOver,
};
pub use error::IdentifyError;
pub use fit::{
    CorrelatedPair, Fit, GiveUp, GiveUpTest, MAX_ITERATIONS, NEARLY_DEPENDENT, Prior, Start, fit, fit_from,
    release_scratch,
};
pub use identifiability::{
    DEPENDENT, Dependence, DependsOn, FixedParameter, Identifiable, Observability, identifiable, observability,
    project_out,
};
pub use lm::Settle;
pub use model::{EQUIVALENT_COS, Model, StartFrames};
pub use predict::{ChainCache, PoseInputs};
pub use registration::{initial_frames, kabsch};
pub use residuals::{norms, residuals, residuals_and_jacobian};
pub use sampling::{normal, random_configuration};
pub use tally::{Evaluated, evaluated};
pub use terms::{PoseTerms, gravity_torques, max_gravity_torques, sensor_joint};
pub use use_error::{frame_refitted_weight, heldout_resolution, heldout_rms, refitted_frame, trace_of_product};
