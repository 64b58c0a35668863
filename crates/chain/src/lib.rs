#![doc = include_str!("../README.md")]
//! `thermokin-chain`: the kinematic core — DH, modified DH and the same-orientation extended table of
//! the paper (sections 2.2 and 3), forward kinematics and the geometric Jacobian.
//!
//! Units inside: millimetres and radians. Degrees exist only at the file and CLI boundary (other crates).
//! This crate does no I/O.

mod bending;
mod branches;
mod chain;
mod choices;
mod dh;
mod error_params;
mod factors;
mod frame;
mod gravity_loads;
mod link_mass;
mod measurements;
mod robot;
mod so3;
mod trig;
pub mod units;

pub use bending::{branch_load_functions_into, lateral_directions, lateral_gravity_moments_into};
pub use branches::{
    Branch, branch_lateral_basis_into, branch_lateral_basis_len, branch_load_basis_into, branch_load_basis_len,
};
pub use chain::{
    Chain, FixedRow, Joint, JointKind, JointLimits, ParameterLayout, ParameterRows, PoseAndJacobian, sin_cos,
};
pub use choices::UnknownChoice;
pub use dh::{DhConvention, DhRow, DhTable};
pub use error_params::{ErrorGrouping, ErrorParams, xyz_angles, xyz_angles_for_output, xyz_rotation};
pub use factors::JointFactor;
pub use gravity_loads::{
    gravity_load_basis_into, gravity_load_basis_len, lateral_load_basis_into, lateral_load_basis_len,
};
pub use link_mass::LinkMass;
pub use measurements::{
    Approach, BranchColumns, Dataset, Measurement, MeasuringOrder, STILL_MOVE, TiltSensor, time_order,
};
pub use robot::{JointRatings, LinkSensor, OperatingState, Robot, Target, gravity_torques, gravity_torques_into};
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
    /// A caller's sine and cosine of a joint value that are not those of one angle.
    #[error("joint {joint}: the given sine and cosine are not those of one angle (s² + c² = {norm})")]
    BadSinCos {
        /// 1-based joint number.
        joint: usize,
        /// `s² + c²`.
        norm: f64,
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
    /// A payload without a positive finite mass and a finite centre, or a robot without joints to carry it.
    #[error("payload of {mass_kg} kg: a payload needs a positive finite mass, a finite centre and a joint to carry it")]
    BadPayload {
        /// The mass given, kg.
        mass_kg: f64,
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
    /// Per-joint description data (masses, ratings) whose length is not the chain's joint count.
    #[error("{field}: expected one entry per joint ({expected}), got {got}")]
    DescriptionLength {
        /// `masses` or `ratings`.
        field: &'static str,
        /// Number of joints of the chain.
        expected: usize,
        /// Number given.
        got: usize,
    },
    /// A replacement chain with another number of joints than the robot's.
    #[error("the new chain has {got} joints, the robot {expected}")]
    JointCountChanged {
        /// Joints of the robot.
        expected: usize,
        /// Joints of the new chain.
        got: usize,
    },
    /// No modified-DH table reproduces this chain.
    #[error("no modified-DH table exists: joint {joint}: {reason}")]
    NoModifiedDh {
        /// 1-based joint number where the construction fails.
        joint: usize,
        /// What fails.
        reason: String,
    },
    /// An accelerometer declared on a link the robot does not have, or without a name.
    #[error(
        "accelerometer `{name}` on link {link}: the robot's links are 0 (its base) to {last} (the link joint {last} moves), and a sensor needs a name"
    )]
    BadSensor {
        /// Its name.
        name: String,
        /// The link given.
        link: usize,
        /// The robot's last link (its joint count).
        last: usize,
    },
    /// A branch that does not fit the measured chain ([`Branch`]).
    #[error("branch `{name}`: {message}")]
    BadBranch {
        /// Its name.
        name: String,
        /// What is wrong.
        message: String,
    },
}
