//! `thermokin-chain`: the kinematic core — DH, modified DH and the same-orientation extended table of
//! the paper (sections 2.2 and 3), forward kinematics and the geometric Jacobian.
//!
//! Units inside: millimetres and radians. Degrees exist only at the file and CLI boundary (other crates).
//! This crate does no I/O.

mod chain;
mod dh;
mod error_params;
mod frame;
mod measurements;
mod so3;

pub use chain::{Chain, FixedRow, Joint, JointKind, JointLimits, ParameterLayout};
/// Mass (kg) and centre of mass (mm, in the same-orientation frame of the joint that moves the link) of
/// one link: what gravity compliance needs. Description data carried beside the chain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkMass {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Centre of mass, mm, in the frame of the joint that moves the link.
    pub com_mm: nalgebra::Vector3<f64>,
}

/// Rated maximum speed and effort of a joint — what URDF's `<limit velocity effort>` and a controller's
/// axis data carry: rad/s and N·m for a revolute joint, mm/s and N for a prismatic one. Description data
/// carried beside the chain, like [`LinkMass`]; `None` where the robot's description does not say.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointRatings {
    /// Largest joint speed.
    pub velocity: Option<f64>,
    /// Largest joint torque or force.
    pub effort: Option<f64>,
}

pub use dh::{DhConvention, DhRow, DhTable, JointFactor};
pub use error_params::{ErrorGrouping, ErrorParams, xyz_angles, xyz_angles_for_output, xyz_rotation};
pub use measurements::{Dataset, Measurement};
pub use so3::{quaternion_wxyz, rotation_angle, rotation_log};

/// Errors of the kinematic core.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ChainError {
    /// A joint vector of the wrong length.
    #[error("expected {expected} joint values, got {got}")]
    WrongJointCount {
        /// Number of joints of the chain.
        expected: usize,
        /// Number given.
        got: usize,
    },
    /// A joint value that is NaN or infinite.
    #[error("joint {joint}: value is not finite")]
    NonFiniteJoint {
        /// 1-based joint number.
        joint: usize,
    },
    /// A parameter of a joint row that is NaN or infinite.
    #[error("joint {joint}: {field} is not finite")]
    NonFinite {
        /// 1-based joint number.
        joint: usize,
        /// Which field.
        field: &'static str,
    },
    /// A base or tool row with a NaN or infinite value.
    #[error("{row} row: a value is not finite")]
    NonFiniteRow {
        /// `base` or `tool`.
        row: &'static str,
    },
    /// A joint axis that is zero, not finite or not of unit length.
    #[error("joint {joint}: the axis must be a finite unit vector")]
    BadAxis {
        /// 1-based joint number.
        joint: usize,
    },
    /// Limits that are not finite or have lower > upper.
    #[error("joint {joint}: bad limits [{lower}, {upper}]")]
    BadLimits {
        /// 1-based joint number.
        joint: usize,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// No modified-DH table reproduces this chain.
    #[error("no modified-DH table exists: joint {joint}: {reason}")]
    NoModifiedDh {
        /// 1-based joint number where the construction fails.
        joint: usize,
        /// What fails.
        reason: String,
    },
}
