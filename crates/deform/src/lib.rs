#![doc = include_str!("../README.md")]
//! `thermokin-deform`: the error-parameter model of the paper — deviation tables (six parameters per row,
//! section 3, Tables 6–11), how they grow with operating time (section 4: static, linear to the 180-minute
//! stabilization, exponential, cubic, temperature-driven), and how a table deforms a chain.
//!
//! A deviation table never mutates a chain: [`DeviationTable::apply`] returns a new one. The analytic
//! parameter Jacobian lives with the kinematics ([`Chain::parameter_jacobian`]) and is re-exported here.

mod coppeliasim;
mod model;
mod profile;

pub use coppeliasim::{CoppeliaSimEdits, coppeliasim_euler_angles, coppeliasim_object_rotation};
pub use model::{
    BranchLoad, DriftLaw, DriftRow, JointCorrection, MAX_CORRECTION_SLOPE, RobotModel, lateral_row_error,
    lumped_lateral_row_error, lumped_lateral_row_on, lumped_lateral_weights_len, lumped_tilts, straightness_row_error,
};
pub use profile::{AfterStabilization, ProfileSpec, RowFactors, TemperatureLog, TimeProfile};

use thermokin_chain::{Chain, ChainError, ErrorParams};

/// Errors of the deformation model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DeformError {
    /// A table with a different number of joint rows than the chain has joints.
    #[error("the deviation table has {rows} joint rows but the robot has {joints} joints")]
    RowCount {
        /// Rows in the table.
        rows: usize,
        /// Joints in the chain.
        joints: usize,
    },
    /// A profile parameter out of its domain.
    #[error("profile: {message}")]
    BadProfile {
        /// The profile's field (`tau_min`, `log.times_min`, …).
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// CoppeliaSim edits whose per-joint lists do not match the chain.
    #[error("CoppeliaSim edits need {joints} joint values and spins, got {at} and {spin}")]
    EditsShape {
        /// Joints of the chain.
        joints: usize,
        /// Joint values given.
        at: usize,
        /// Spins given.
        spin: usize,
    },
    /// A time outside what the profile can answer (negative or not finite, beyond a temperature log).
    #[error("time {time_min} min: {reason}")]
    BadTime {
        /// Requested time, minutes.
        time_min: f64,
        /// Why it cannot be answered.
        reason: String,
    },
    /// The operating state lacks what a correction needs (a time, a sensor reading).
    #[error("this robot needs {needed}: {why}")]
    MissingState {
        /// What to give.
        needed: String,
        /// Which correction needs it.
        why: String,
    },
    /// A joint correction out of its domain.
    #[error("joint {joint}: {message}")]
    BadCorrection {
        /// 1-based joint number.
        joint: usize,
        /// What is wrong.
        message: String,
    },
    /// The joint corrections could not be inverted (never expected for corrections below the checked slope).
    #[error("the joint corrections could not be inverted: {gap:e} rad left")]
    NotInvertible {
        /// Largest remaining joint error, radians.
        gap: f64,
    },
    /// The deformed chain is invalid (non-finite values).
    #[error(transparent)]
    Chain(#[from] ChainError),
    /// A state the robot cannot use: a time for a robot that does not drift with time, a reading of a
    /// sensor no row follows, a profile without a table, or a table's profile without a time.
    #[error("{0}")]
    State(StateError),
    /// A robot with identified corrections where the robot as described is needed (a diagnosis starts
    /// from the geometry alone).
    #[error("it carries identified corrections ({})", corrections.join("; "))]
    CarriesCorrections {
        /// What it carries beyond geometry, one item each.
        corrections: Vec<String>,
    },
}

/// A state or table setting a robot cannot use (the rule each front end words with its own flag or
/// argument).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum StateError {
    /// A time given for a robot none of whose rows drifts with time, and no table and profile.
    TimeWithoutDrift,
    /// A sensor reading no drifting row follows.
    UnknownSensor {
        /// The sensor given.
        name: String,
        /// The sensors the robot's rows follow.
        known: Vec<String>,
    },
    /// A time profile given without a deviation table.
    ProfileWithoutTable,
    /// A table under a time profile, but no time.
    ProfileNeedsTime,
    /// A time and a table, but no profile to grow the table with (and the robot does not drift).
    TimeNeedsProfile,
    /// Directions of approach given for a robot none of whose joints has a backlash.
    ApproachWithoutBacklash,
    /// Directions of approach given for another number of joints than the robot's.
    ApproachCount {
        /// Directions given.
        given: usize,
        /// The robot's joints.
        joints: usize,
    },
}

impl std::fmt::Display for StateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StateError::TimeWithoutDrift => f.write_str(
                "a time was given, but no row of this robot drifts with time (give a table and a profile to deform it)",
            ),
            StateError::UnknownSensor { name, known } => {
                let known = if known.is_empty() { "none".to_string() } else { known.join(", ") };
                write!(f, "no row of this robot drifts with sensor `{name}` (its sensors: {known})")
            }
            StateError::ProfileWithoutTable => f.write_str("a time profile needs a deviation table to grow"),
            StateError::ProfileNeedsTime => f.write_str("a time profile needs the time (minutes) to evaluate it at"),
            StateError::TimeNeedsProfile => {
                f.write_str("a time was given with a table but no profile: say how the table grows with time")
            }
            StateError::ApproachWithoutBacklash => f.write_str(
                "directions of approach were given, but no joint of this robot has a backlash (a `backlash` in its table)",
            ),
            StateError::ApproachCount { given, joints } => {
                write!(f, "{given} directions of approach were given for a robot of {joints} joints: give one per joint")
            }
        }
    }
}

/// The deviation table in force for a robot (`drifts_with_time`: some row of it drifts with time) given
/// a table, an optional time profile and an optional time: the profile's share of the table at that
/// time; the table in full without a profile (and without a time, or with a time the robot's own drift
/// uses). The one rule `fk`, `ik`, `urdf export` and Python's `Robot.deformed` follow.
pub fn table_in_force(
    table: &DeviationTable,
    profile: Option<&TimeProfile>,
    time_min: Option<f64>,
    drifts_with_time: bool,
) -> Result<DeviationTable, DeformError> {
    match (profile, time_min) {
        (Some(p), Some(t)) => p.table_at(table, t),
        (Some(_), None) => Err(DeformError::State(StateError::ProfileNeedsTime)),
        (None, Some(_)) if !drifts_with_time => Err(DeformError::State(StateError::TimeNeedsProfile)),
        (None, _) => Ok(table.clone()),
    }
}

/// A row of a deviation table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Row {
    /// Row 0 (base).
    Base,
    /// Joint `i` (0-based).
    Joint(usize),
    /// The tool row.
    Tool,
}

/// A deviation table: six error parameters for the base row, each joint and the tool row
/// (ΔX, ΔY, ΔZ in mm; Δθx, Δθy, Δθz in radians inside the library, degrees in files).
///
/// The authors' CSV files hold one row per joint (`Dx,Dy,Dz,Dox,Doy,Doz`); their base and tool rows are
/// zero (Table 9's seventh row, −0.0166 mm, is on joint 6 in the CSV).
#[derive(Clone, Debug, PartialEq)]
pub struct DeviationTable {
    /// Row 0 of Table 7.
    pub base: ErrorParams,
    /// One row per joint.
    pub joints: Vec<ErrorParams>,
    /// The tool row.
    pub tool: ErrorParams,
}

/// How the parameters of a table act on the chain.
#[derive(Clone, Debug, PartialEq)]
pub enum TableSemantics {
    /// Each row's parameters are the row's error parameters in the canonical grouping:
    /// `Trans(p + Δp) · Rx · Ry · Rz · Rot_axis(q)` (Table 7's reading; this library's model).
    Canonical,
    /// The way the authors' CoppeliaSim script applied a table (paper Appendix A, Figure A5): joint by
    /// joint, the joint object's world position += (Dx, Dy, Dz) and its world X-Y-Z Euler angles +=
    /// (Dox, Doy, Doz), children following, with the robot standing at `at` (joint values). The result is
    /// re-expressed exactly as canonical error parameters.
    CoppeliaSim(CoppeliaSimEdits),
}

/// How a table acts on a robot, by name — [`TableSemantics`] without the configuration CoppeliaSim's
/// edits are made at, which front ends take as the home configuration ([`SemanticsKind::at_home`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SemanticsKind {
    /// [`TableSemantics::Canonical`].
    #[default]
    Canonical,
    /// [`TableSemantics::CoppeliaSim`], at home.
    CoppeliaSim,
}

thermokin_chain::choices!(
    SemanticsKind,
    "table semantics",
    [
        (
            "canonical",
            "Table 7's reading: Trans·Rx·Ry·Rz at each joint (this library's model)",
            SemanticsKind::Canonical
        ),
        (
            "coppeliasim",
            "the authors' scene: world shift and Euler-angle addition of each joint object, at home",
            SemanticsKind::CoppeliaSim
        ),
    ]
);

impl SemanticsKind {
    /// The semantics of this name for a robot of `dof` joints, CoppeliaSim's edits made at home.
    pub fn at_home(self, dof: usize) -> TableSemantics {
        match self {
            SemanticsKind::Canonical => TableSemantics::Canonical,
            SemanticsKind::CoppeliaSim => TableSemantics::coppeliasim_at_home(dof),
        }
    }
}

impl TableSemantics {
    /// The authors' CoppeliaSim edits with the robot standing at home (every joint at zero): how their
    /// script applied the case-study table, and what `--semantics coppeliasim` means.
    pub fn coppeliasim_at_home(dof: usize) -> Self {
        TableSemantics::CoppeliaSim(CoppeliaSimEdits::at(vec![0.0; dof]))
    }
}

impl DeviationTable {
    /// A table of zeros for `dof` joints.
    pub fn zeros(dof: usize) -> Self {
        Self { base: ErrorParams::ZERO, joints: vec![ErrorParams::ZERO; dof], tool: ErrorParams::ZERO }
    }

    /// A table with the given joint rows and zero base and tool rows.
    pub fn from_joint_rows(joints: Vec<ErrorParams>) -> Self {
        Self { base: ErrorParams::ZERO, joints, tool: ErrorParams::ZERO }
    }

    /// Number of joint rows.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// Every row multiplied by `factor`.
    pub fn scaled(&self, factor: f64) -> Self {
        self.scaled_rows(|_| factor)
    }

    /// Every row multiplied by its own factor.
    pub fn scaled_rows(&self, factor: impl Fn(Row) -> f64) -> Self {
        Self {
            base: self.base.scaled(factor(Row::Base)),
            joints: self.joints.iter().enumerate().map(|(i, e)| e.scaled(factor(Row::Joint(i)))).collect(),
            tool: self.tool.scaled(factor(Row::Tool)),
        }
    }

    /// Row-by-row sum.
    pub fn add(&self, other: &DeviationTable) -> Result<Self, DeformError> {
        if self.dof() != other.dof() {
            return Err(DeformError::RowCount { rows: other.dof(), joints: self.dof() });
        }
        Ok(Self {
            base: self.base.add(&other.base),
            joints: self.joints.iter().zip(&other.joints).map(|(a, b)| a.add(b)).collect(),
            tool: self.tool.add(&other.tool),
        })
    }

    /// `true` when every parameter is zero.
    pub fn is_zero(&self) -> bool {
        self.base.is_zero() && self.tool.is_zero() && self.joints.iter().all(ErrorParams::is_zero)
    }

    /// The deformed chain: a new value, the nominal `chain` untouched. With [`TableSemantics::Canonical`]
    /// the table's parameters are added to the chain's own error parameters.
    ///
    /// ```
    /// use nalgebra::Vector3;
    /// use thermokin_chain::ErrorParams;
    /// use thermokin_deform::{DeviationTable, TableSemantics};
    ///
    /// let nominal = thermokin_testdata::irb140_table9();
    /// // 1 mm along X on joint 2's row (Table 7: the translation sits at the joint, in its parent's frame).
    /// let mut rows = vec![ErrorParams::ZERO; 6];
    /// rows[1] = ErrorParams::new(Vector3::new(1.0, 0.0, 0.0), Vector3::zeros());
    /// let deformed = DeviationTable::from_joint_rows(rows).apply(&nominal, &TableSemantics::Canonical).unwrap();
    /// let q = [0.0; 6];
    /// let shift = deformed.tool_pose(&q).unwrap().translation.vector - nominal.tool_pose(&q).unwrap().translation.vector;
    /// // Every joint frame is world-aligned at home, so the TCP moves by exactly that millimetre.
    /// assert!((shift - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-12);
    /// ```
    pub fn apply(&self, chain: &Chain, semantics: &TableSemantics) -> Result<Chain, DeformError> {
        if self.dof() != chain.dof() {
            return Err(DeformError::RowCount { rows: self.dof(), joints: chain.dof() });
        }
        match semantics {
            TableSemantics::Canonical => {
                let joints: Vec<ErrorParams> =
                    chain.joints().iter().zip(&self.joints).map(|(j, e)| j.error.add(e)).collect();
                Ok(chain.with_errors(
                    chain.base().error.add(&self.base),
                    &joints,
                    chain.tool().error.add(&self.tool),
                )?)
            }
            TableSemantics::CoppeliaSim(edits) => edits.apply(chain, self),
        }
    }
}
