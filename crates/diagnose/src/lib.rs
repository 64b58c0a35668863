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

use nalgebra::Vector3;
use thermokin_chain::ChainError;

/// One measured pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// Operating time, minutes (0 when the file has none).
    pub time_min: f64,
    /// Joint values, radians (mm for prismatic joints).
    pub q: Vec<f64>,
    /// Measured TCP position, mm.
    pub position_mm: Vector3<f64>,
    /// Temperatures, °C, in the order of [`Dataset::temperature_names`].
    pub temps: Vec<f64>,
}

/// A set of measurements.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Dataset {
    /// The measurements.
    pub measurements: Vec<Measurement>,
    /// Names of the temperature columns.
    pub temperature_names: Vec<String>,
}

impl Dataset {
    /// Number of measurements.
    pub fn len(&self) -> usize {
        self.measurements.len()
    }
    /// `true` when there are none.
    pub fn is_empty(&self) -> bool {
        self.measurements.is_empty()
    }
    /// The time span covered, minutes.
    pub fn time_span(&self) -> f64 {
        let (lo, hi) = self
            .measurements
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), m| (l.min(m.time_min), h.max(m.time_min)));
        if lo.is_finite() { hi - lo } else { 0.0 }
    }
}

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
