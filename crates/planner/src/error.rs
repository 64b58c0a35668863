//! Errors of a plan.

use thermokin_identify::IdentifyError;

/// Why a plan cannot be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// The model could not be built or evaluated.
    #[error(transparent)]
    Identify(#[from] IdentifyError),
    /// A candidate (or measured pose) with the wrong number of joint values.
    #[error("{what} {index}: {got} joint values for a robot of {dof} joints")]
    JointCount {
        /// `candidate` or `measured pose`, as the user calls them.
        what: &'static str,
        /// 1-based line in its file, or its 1-based index when it was not read from one.
        index: usize,
        /// Values given.
        got: usize,
        /// Joints of the robot.
        dof: usize,
    },
    /// A joint value that is not a finite number.
    #[error("{what} {index}: joint {joint} is not a finite number")]
    NotFinite {
        /// `candidate` or `measured pose`.
        what: &'static str,
        /// 1-based line in its file, or its 1-based index.
        index: usize,
        /// 1-based joint.
        joint: usize,
    },
    /// A candidate outside the joint limits: the robot cannot be sent there.
    #[error("candidate {index}: joint {joint} is outside its limits")]
    OutsideLimits {
        /// 1-based line in its file, or its 1-based index.
        index: usize,
        /// 1-based joint.
        joint: usize,
    },
    /// Fewer distinct candidates than poses asked for.
    #[error("{poses} poses asked for, but only {candidates} {}", distinct(*.copies))]
    TooFewCandidates {
        /// Poses asked for.
        poses: usize,
        /// Distinct candidates available.
        candidates: usize,
        /// Candidates set aside as copies.
        copies: usize,
    },
    /// No pose asked for.
    #[error("a plan needs at least one pose (--poses)")]
    NoPoses,
    /// A setting out of its domain.
    #[error("{setting} = {value}: {rule}")]
    Setting {
        /// The setting's name.
        setting: &'static str,
        /// Its value, as given.
        value: String,
        /// The rule it breaks.
        rule: &'static str,
    },
    /// An effect that poses cannot plan for: a thermal drift is identified over operating time, not
    /// from where the robot stands.
    #[error("{effect} is identified over operating time, not from poses: plan the warm-up's schedule instead")]
    TimeDependent {
        /// The effect's label.
        effect: String,
    },
    /// An effect the direction of approach decides, which the poses alone do not show.
    #[error(
        "{effect} follows the direction each joint comes from, which the measuring order decides, not the poses: planned from configurations alone it moves nothing — measure some poses from both sides (approached rising and falling) in the session, with a time column or --order file, and plan without it"
    )]
    OrderDependent {
        /// The effect's label.
        effect: String,
    },
    /// Sampling within the workspace box found too few configurations.
    #[error(
        "{found} of {wanted} sampled configurations put the tool inside the box after {tried} draws: is the box reachable?"
    )]
    EmptyBox {
        /// Configurations found inside.
        found: usize,
        /// Configurations wanted.
        wanted: usize,
        /// Draws made.
        tried: usize,
    },
    /// The information matrix could not be factorised (a ridge keeps it positive definite: this is a
    /// non-finite Jacobian).
    #[error("the information matrix of the candidates could not be factorised (a non-finite Jacobian?)")]
    Singular,
}

/// How [`PlanError::TooFewCandidates`] names the candidates: plainly, or with the copies set aside.
fn distinct(copies: usize) -> String {
    if copies == 0 {
        "candidates".into()
    } else {
        format!("distinct candidates ({copies} more repeat one of them exactly)")
    }
}
