//! `thermokin-diagnose`: identification and the sim-to-real diagnosis — where the model and the measured
//! robot disagree, which unmodelled effect causes it, and how far the gap shrinks once that effect is
//! added, always judged on held-out data.
//!
//! Effects are parameter blocks on top of a chain ([`EffectKind`]). Identification is Levenberg–Marquardt
//! on faer with the analytic parameter Jacobian and column scaling; parameters the data cannot identify
//! are detected and fixed with a reason. The diagnosis climbs a ladder of candidate effects, each judged
//! by k-fold cross-validation (grouped in time, and forward-chained for time-dependent candidates) or an
//! explicit hold-out set, preferring the smaller block when two explain the data alike.

mod diagnose;
mod fit;
mod model;
mod simulate;

pub use diagnose::{
    Breakdown, Config, EffectReport, FrameMode, Identifiability, ParameterValue, Report, Stats, TableRow, ToolMode,
    diagnose,
};
pub use fit::{FixedParameter, Observability};
pub use model::{Base, DriftShape, Effect, EffectKind, Model, gravity_torques};
pub use simulate::{HiddenEffect, SimulationConfig, simulate};

use thermokin_chain::ChainError;
/// Measurement data are plain values of the core, so that readers need not depend on this crate.
pub use thermokin_chain::{Dataset, Measurement};

/// Errors of identification and diagnosis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DiagnoseError {
    /// The model could not be evaluated.
    #[error(transparent)]
    Chain(#[from] ChainError),
    /// Too few measurements or inconsistent inputs.
    #[error("{0}")]
    Input(String),
}
