//! `thermokin-diagnose`: identification and the sim-to-real diagnosis — where the model and the measured
//! robot disagree, which unmodelled effect causes it, and how far the gap shrinks once that effect is
//! added, always judged on held-out data.
//!
//! Effects are parameter blocks on top of a robot ([`Effect`], each carrying its joint). Identification is Levenberg–Marquardt
//! on faer with the analytic parameter Jacobian and column scaling; parameters the data cannot identify
//! are detected and fixed with a reason. The diagnosis climbs a ladder of candidate effects, each judged
//! by k-fold cross-validation (grouped in time, and forward-chained for time-dependent candidates) or an
//! explicit hold-out set, preferring the smaller block when two explain the data alike.

mod eligibility;
mod fit;
mod ladder;
mod model;
mod render;
mod report;
mod screen;
mod select;
mod simulate;
mod validation;

pub use eligibility::{Eligibility, Refusal};
pub use fit::{CorrelatedPair, FixedParameter, NEARLY_DEPENDENT, Observability};
pub use ladder::{
    Config, FoldGrouping, FrameMode, Progress, ToolMode, Validation, diagnose, diagnose_with_progress, evaluate,
};
pub use model::{
    DriftShape, EFFECT_NAMES, Effect, JointIndex, LINEAR_DRIFT_REFERENCE_MIN, Model, gravity_torques, sensor_joint,
};
pub use render::ReportText;
pub use report::{
    Breakdown, EffectReport, HoldoutStats, Identifiability, Nested, OuterFold, ParameterValue, Report, Stats, TableRow,
};
pub use screen::Screen;
pub use select::Plausibility;
pub use simulate::{HiddenEffect, SimulationConfig, simulate};

use thermokin_chain::ChainError;
use thermokin_chain::{Dataset, Measurement};

/// Errors of identification and diagnosis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DiagnoseError {
    /// The model could not be evaluated.
    #[error(transparent)]
    Chain(#[from] ChainError),
    /// The identified robot could not be built (a correction out of its domain).
    #[error(transparent)]
    Deform(#[from] thermokin_deform::DeformError),
    /// A temperature drift identified from data that hold no temperature readings.
    #[error("{effect} needs temperature readings in the data")]
    NoTemperatures {
        /// The effect's label.
        effect: String,
    },
    /// An effect names a joint the robot does not have.
    #[error("joint {joint} is not in 1..={dof}")]
    NoSuchJoint {
        /// 1-based joint number.
        joint: usize,
        /// Joints of the robot.
        dof: usize,
    },
    /// A per-joint effect given without its joint.
    #[error("{effect} needs a joint")]
    JointNeeded {
        /// The effect's name.
        effect: String,
    },
    /// A whole-robot effect given a joint.
    #[error("{effect} acts on the whole robot and takes no joint")]
    NoJointTaken {
        /// The effect's name.
        effect: String,
    },
    /// A name that is not in the catalogue.
    #[error("unknown effect `{name}` (known: {})", model::EFFECT_NAMES.join(", "))]
    UnknownEffect {
        /// The name given.
        name: String,
    },
    /// An effect given the wrong number of parameter values.
    #[error("{effect}: {got} values for {expected} parameters")]
    ParameterCount {
        /// The effect's label.
        effect: String,
        /// Its number of parameters.
        expected: usize,
        /// Values given.
        got: usize,
    },
    /// A setting outside its domain ([`Config::validate`], [`SimulationConfig::validate`]): `setting` is the
    /// field's name, `rule` what it must be.
    #[error("{setting} {rule} (got {value})")]
    BadSetting {
        /// The field of the settings.
        setting: &'static str,
        /// The value given.
        value: f64,
        /// What the value must be.
        rule: &'static str,
    },
    /// An effect spec (`KIND[:JOINT][=VALUES]`) that cannot be read.
    #[error("{spec}: {message}")]
    BadEffectSpec {
        /// The spec as given.
        spec: String,
        /// What is wrong.
        message: String,
    },
    /// Too few measurements for the validation asked for.
    #[error("{count} measurements are too few for {folds}-fold cross-validation (at least {needed})")]
    TooFewMeasurements {
        /// Measurements given.
        count: usize,
        /// Folds asked for.
        folds: usize,
        /// Measurements needed.
        needed: usize,
    },
    /// A measurement with another number of joint values than the robot has joints.
    #[error("{set} measurement {measurement}: {got} joint values for {expected} joints")]
    JointCount {
        /// `training` or `hold-out`.
        set: &'static str,
        /// 1-based measurement number.
        measurement: usize,
        /// Values given.
        got: usize,
        /// Joints of the robot.
        expected: usize,
    },
}
