//! Errors of the diagnosis.

use thermokin_chain::ChainError;
use thermokin_identify::IdentifyError;

/// Errors of identification and diagnosis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DiagnoseError {
    /// A model could not be built, evaluated or fitted.
    #[error(transparent)]
    Identify(#[from] IdentifyError),
    /// A robot could not be rebuilt (the identified robot on the file's robot).
    #[error(transparent)]
    Chain(#[from] ChainError),
    /// The identified robot could not be built (a correction out of its domain).
    #[error(transparent)]
    Deform(#[from] thermokin_deform::DeformError),
    /// A setting outside its domain ([`crate::Config::validate`], [`crate::SimulationConfig::validate`]):
    /// `setting` is the field's name, `rule` what it must be.
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
    /// An export refused: the chosen model does not beat the nominal one on data it never saw
    /// ([`crate::Report::honest_end`], the figures said there).
    #[error("{reason}")]
    DoesNotTransfer {
        /// Where it does not, with the figures (the report's [`crate::Report::honest_end`]).
        reason: String,
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
    /// The hold-out set lacks a sensor column the measurements carry: a model following it could only be
    /// scored there at a reading assumed, never at the one the robot had.
    #[error(
        "the hold-out set has no column `{sensor}`, which the measurements carry as a sensor (a joint row may follow it): give its readings at the hold-out poses, or leave the column out of the measurements"
    )]
    HoldoutLacksSensor {
        /// The sensor column's name.
        sensor: String,
    },
    /// A branch of the robot that the measurements log in part.
    #[error("branch `{name}`: {reason}")]
    Branch {
        /// Its name.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// A declared accelerometer that the data or the robot cannot read as a link's tilt.
    #[error("accelerometer `{name}`: {reason}")]
    Accelerometer {
        /// Its name.
        name: String,
        /// Why, with what to do.
        reason: String,
    },
}
