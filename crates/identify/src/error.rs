//! Errors of identification.

use thermokin_chain::ChainError;

/// Errors of a model, its evaluation and its fit.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum IdentifyError {
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
    /// A joint that is not a number from 1.
    #[error("joint `{given}`: joints are numbered from 1")]
    JointNumber {
        /// The text given.
        given: String,
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
    /// An effect of a revolute joint's angle given a prismatic joint (or one with no gravity basis).
    #[error("{effect} acts on a revolute joint; joint {joint} is not one")]
    NotRevolute {
        /// The effect's name.
        effect: String,
        /// 1-based joint number.
        joint: usize,
    },
    /// An effect of a slide's guide given a revolute joint.
    #[error("{effect} acts on a prismatic joint (a slide's guide); joint {joint} is revolute")]
    NotPrismatic {
        /// The effect's name.
        effect: String,
        /// 1-based joint number.
        joint: usize,
    },
    /// An effect computed from the robot file's masses, on a robot whose file carries none.
    #[error("{effect} needs the link masses, and the robot file carries none")]
    MassesNeeded {
        /// The effect's name.
        effect: String,
    },
    /// A name that is not in the catalogue.
    #[error("unknown effect `{name}` (known: {known})")]
    UnknownEffect {
        /// The name given.
        name: String,
        /// The catalogue's names, comma separated.
        known: String,
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
    /// A prior with a weight that is not a finite number ≥ 0, or a centre that is not finite.
    #[error(
        "the prior of parameter {index}: weight {weight}, centre {centre} (a weight must be finite and ≥ 0, a centre finite)"
    )]
    PriorValue {
        /// The parameter (0-based).
        index: usize,
        /// Its weight.
        weight: f64,
        /// Its centre.
        centre: f64,
    },
    /// A prior whose lengths are not the model's.
    #[error("a prior of {centre} centres and {weight} weights for a model of {expected} parameters")]
    PriorLength {
        /// The model's parameters.
        expected: usize,
        /// Centres given.
        centre: usize,
        /// Weights given.
        weight: usize,
    },
}
