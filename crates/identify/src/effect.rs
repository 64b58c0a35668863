//! Effects: the blocks of parameters a model is built from, each carrying its joint, and their
//! parameters' names and units.

use serde::Serialize;
use thermokin_chain::{ErrorParams, Robot, units};
use thermokin_deform::{AfterStabilization, TimeProfile};

use crate::error::IdentifyError;

/// Reference time of the linear drift: the parameters are the deviation at 180 minutes (section 4).
pub const LINEAR_DRIFT_REFERENCE_MIN: f64 = 180.0;
/// Largest time constant considered, minutes: beyond it the exponential is indistinguishable from the
/// linear drift over any warm-up a user measures.
const MAX_TAU_MIN: f64 = 1e4;
/// The time constants an exponential drift is evaluated and fitted in, minutes: from a thousandth of a
/// minute (a step) to `MAX_TAU_MIN`.
pub const TAU_RANGE_MIN: (f64, f64) = (1e-3, MAX_TAU_MIN);
/// Initial time constant of an exponential drift, minutes.
pub(crate) const INITIAL_TAU_MIN: f64 = 60.0;

/// Where a fit starts each element of a [`Effect::CompliancePair`]'s `w`, √(rad/N·m): `k = 1e-4` rad/N·m
/// (0.006 °/N·m) on each joint, between a stiff industrial wrist (1e-6) and a cable-driven one (1e-1) — at
/// `w = 0` the pair's columns vanish and nothing moves it.
pub const PAIR_START: f64 = 1e-2;

/// How a thermal drift grows with time — a family of [`TimeProfile`]s of `thermokin-deform`, whose law
/// ([`TimeProfile::time_factor`]) the fit evaluates. The six amplitudes of a drift are its deviation at
/// the reference time [`LINEAR_DRIFT_REFERENCE_MIN`] for every shape: `δ · f(t) / f(180)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, PartialOrd, Ord)]
pub enum DriftShape {
    /// [`TimeProfile::Linear`] without a plateau: `δ · t / 180 min`.
    Linear,
    /// [`TimeProfile::Exponential`] with τ fitted: `δ · (1 − e^(−t/τ)) / (1 − e^(−180/τ))`. The
    /// normalisation at 180 minutes lets a very slow exponential tend to the linear drift instead of
    /// trading a huge amplitude against a huge τ.
    Exponential,
    /// The law of [`TimeProfile::Temperature`]: `δ · (T(t) − T(0))` per kelvin of the joint's own logged
    /// temperature rise when a column names the joint (`sensor_joint`), of the mean rise otherwise.
    Temperature,
}

impl DriftShape {
    /// The deform profile of this shape (for a use of the identified drift outside the diagnosis: it
    /// scales a table of the deviation at 180 minutes to `(t / 180)` or `(1 − e^(−t/τ)) / (1 − e^(−180/τ))`
    /// only after that table is divided by `f(180)`; see [`DriftShape::reference_factor`]). `None` for the
    /// temperature shape, whose factor is the logged rise and needs the log.
    pub fn profile(self, tau_min: f64) -> Option<TimeProfile> {
        match self {
            DriftShape::Linear => Some(TimeProfile::Linear {
                stabilization_min: LINEAR_DRIFT_REFERENCE_MIN,
                after: AfterStabilization::KeepGrowing,
            }),
            DriftShape::Exponential => Some(TimeProfile::Exponential { tau_min }),
            DriftShape::Temperature => None,
        }
    }

    /// `f(180)` of the profile: the amplitudes a fitted drift reports (the deviation at 180 minutes)
    /// divided by this are the table that [`DriftShape::profile`] scales.
    pub fn reference_factor(self, tau_min: f64) -> f64 {
        self.profile(tau_min).and_then(|p| p.time_factor(LINEAR_DRIFT_REFERENCE_MIN)).unwrap_or(1.0)
    }
}

/// Where a step of the measurement frame happens ([`Effect::FrameStep`]): the poses measured at or after
/// this time (minutes), or read at or after this line of the measurements file, are in the moved frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum StepAt {
    /// At or after this time, minutes (stored as the bits of a finite `f64`, so that an effect stays
    /// hashable and ordered: [`StepAt::time`]).
    Time(u64),
    /// At or after this 1-based line of the measurements file (its order: the order of measuring).
    Line(usize),
}

impl StepAt {
    /// A step at `minutes` (finite, not negative).
    pub fn time(minutes: f64) -> Self {
        StepAt::Time(minutes.max(0.0).to_bits())
    }

    /// Whether a pose measured at `time_min`, read at `line`, is in the moved frame.
    pub fn applies(self, time_min: f64, line: Option<usize>) -> bool {
        match self {
            StepAt::Time(bits) => time_min >= f64::from_bits(bits),
            StepAt::Line(at) => line.is_some_and(|l| l >= at),
        }
    }

    /// `line 152` or `151.3 min`.
    pub fn describe(self) -> String {
        match self {
            StepAt::Time(bits) => format!("{:.1} min", f64::from_bits(bits)),
            StepAt::Line(at) => format!("line {at}"),
        }
    }
}

/// A sensor column of the measurements ([`thermokin_chain::Dataset::sensor_names`]) an effect follows:
/// its index and its name (up to [`SensorId::NAME_BYTES`] bytes kept, so that an effect stays `Copy`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SensorId {
    index: u8,
    len: u8,
    name: [u8; SensorId::NAME_BYTES],
}

impl SensorId {
    /// The most bytes of a sensor's name an effect keeps (a longer name is cut at a character boundary).
    pub const NAME_BYTES: usize = 30;

    /// Sensor column `index` of `data`; `None` past its columns or beyond 255.
    pub fn of(data: &thermokin_chain::Dataset, index: usize) -> Option<Self> {
        let full = data.sensor_names.get(index)?;
        let mut end = full.len().min(Self::NAME_BYTES);
        while !full.is_char_boundary(end) {
            end -= 1;
        }
        let mut name = [0u8; Self::NAME_BYTES];
        name[..end].copy_from_slice(&full.as_bytes()[..end]);
        Some(Self { index: u8::try_from(index).ok()?, len: end as u8, name })
    }

    /// The column's index among the set's sensor columns.
    pub fn index(self) -> usize {
        self.index as usize
    }

    /// The column's name (as kept).
    pub fn name(&self) -> &str {
        std::str::from_utf8(&self.name[..self.len as usize]).unwrap_or("sensor")
    }
}

/// A joint an effect acts on: a 0-based index checked against the robot — [`JointIndex::of`] is the only
/// way to make one, so that an effect cannot name a joint the robot lacks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, PartialOrd, Ord)]
pub struct JointIndex(usize);

impl JointIndex {
    /// Joint `index` (0-based) of `robot`.
    pub fn of(robot: &Robot, index: usize) -> Result<Self, IdentifyError> {
        let dof = robot.chain().dof();
        if index < dof { Ok(Self(index)) } else { Err(IdentifyError::NoSuchJoint { joint: index + 1, dof }) }
    }

    /// The 0-based index.
    pub fn index(self) -> usize {
        self.0
    }

    /// The 1-based joint number of reports and flags.
    pub fn number(self) -> usize {
        self.0 + 1
    }

    /// The next joint of `robot` (the second joint of a coupled pair), if it has one.
    pub fn next(self, robot: &Robot) -> Option<Self> {
        Self::of(robot, self.0 + 1).ok()
    }
}

/// An effect: a block of parameters that can be added to the model, carrying its joint where it has one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Effect {
    /// The tracker registration (tracker frame): always estimated, never reported as an effect (6).
    Registration,
    /// An unknown tool point: always estimated, never reported as an effect (3).
    ToolPoint,
    /// An unknown probe's rotation, when orientations are measured: always estimated with
    /// [`Effect::ToolPoint`], never reported as an effect (3).
    ToolRotation,
    /// A base misalignment (6).
    BaseFrame,
    /// A tool-frame error: the tool point (3) and the tool's rotation (3). The rotation moves no
    /// measured point; it is identified from measured orientations (6-D probes) and fixed otherwise.
    ToolFrame,
    /// A joint's zero offset (1).
    JointOffset(JointIndex),
    /// The paper's six error parameters of a joint (6).
    LinkDeviation(JointIndex),
    /// Gravity compliance of a joint: Δq = k · τ_gravity(q) (1).
    JointCompliance(JointIndex),
    /// Gravity compliance of a revolute joint when the robot file carries no masses: `Δq = Σ θ_b f_b(q)`,
    /// the functions of [`thermokin_chain::gravity_load_basis_into`] whose span holds the joint's
    /// gravity torque under any masses of the links it carries, the weights lumping the joint's
    /// stiffness with those links' unknown first moments (radians; radians per mm for a slide it
    /// carries). The count is the basis' length ([`thermokin_chain::gravity_load_basis_len`]), fixed by
    /// the robot: make one with [`Effect::named`] (`"joint_compliance"` on a robot without masses).
    LumpedCompliance(JointIndex, u8),
    /// Lateral gravity compliance of joint `j`: its row tilts, about the two directions across its axis
    /// ([`thermokin_chain::lateral_directions`], in its parent's frame), by the gravity moments across it
    /// of the links it carries ([`thermokin_chain::lateral_gravity_moments_into`]) times a compliance —
    /// a bearing's or a mount's tilt under the arm's moment (2, radians per N·m); a slide's, a column's,
    /// also bends as a beam of its extension's length and its foot shifts (6: `[c₁, c₂, c′₁, c′₂, s₁, s₂]`,
    /// [`thermokin_deform::lateral_row_error`]). The count is 2 for a revolute joint and 6 for a prismatic
    /// one: make one with [`Effect::named`] (`"lateral_compliance"` on a robot with masses).
    LateralCompliance(JointIndex, u8),
    /// Lateral gravity compliance of joint `j` when the robot file carries no masses: its row tilts about
    /// the two directions across its axis by `φₖ = Σ θₖ,b fₖ,b(q)`, the functions of
    /// [`thermokin_chain::lateral_load_basis_into`] whose span holds the gravity moments across the joint
    /// under any masses of the links it carries — the bearing's compliance lumped with their unknown first
    /// moments (radians; radians per mm for a slide it carries). A slide's ([`Support::Column`]) takes three
    /// such sets: its foot's tilt, its bending over the extension (radians per mm) and its foot's shift
    /// (mm) — [`Effect::LateralCompliance`]'s six coefficients, each lumped with the moments
    /// ([`thermokin_deform::lumped_lateral_row_error`]). The count is fixed by the robot: make one with
    /// [`Effect::named`] (`"lateral_compliance"` on a robot without masses).
    LumpedLateralCompliance(JointIndex, u8, Support),
    /// Straightness of a slide's guide ([`thermokin_deform::straightness_row_error`]): its row tilts about
    /// the two directions across its axis and rolls about it in proportion to the extension `d`, and the
    /// carriage bows across in proportion to `d²` — `[κ₁, κ₂, ρ, σ₁, σ₂]`, radians per mm and per mm (5;
    /// prismatic joints only: [`Effect::named`]).
    Straightness(JointIndex),
    /// The coupling of the gravity compliances of joint `j` and the next, `j + 1` — a drive the two
    /// share (a differential, a cable pair): `Δq_j += c · τ_{j+1}` and `Δq_{j+1} += c · τ_j`, the
    /// symmetric off-diagonal term of the two joints' compliance matrix (Maxwell–Betti reciprocity) (1).
    ComplianceCoupling(JointIndex),
    /// The compliance matrix of joint `j` and the next made positive semidefinite at its boundary: one
    /// elastic element both joints load — a cable or a differential they share — `K = w wᵀ`, so that
    /// `Δq_j += w_j (w_j τ_j + w_{j+1} τ_{j+1})` and `Δq_{j+1} += w_{j+1} (w_j τ_j + w_{j+1} τ_{j+1})`:
    /// `k_j = w_j²`, `k_{j+1} = w_{j+1}²`, `c = w_j w_{j+1}` (2, square roots of radians per N·m).
    /// Where a coupling's least-squares pair is not positive semidefinite the least-squares pair that is
    /// lies on the cone's boundary, which is this form (the cost is convex in `(k_j, c, k_{j+1})`). A
    /// fit starts it at [`PAIR_START`] for each joint (at `w = 0` its columns vanish).
    CompliancePair(JointIndex),
    /// A gear-ratio (scale) error of a revolute joint: Δq = s · q (1, dimensionless).
    JointScale(JointIndex),
    /// Backlash of a joint's gears: `Δq = b · s`, `s` = ±1 the direction the joint last moved in before
    /// the pose ([`thermokin_chain::Approach`], from the measuring order), 0 where unknown — `b` half the
    /// play between the two flanks (1).
    Backlash(JointIndex),
    /// A cyclic encoder error of a revolute joint, once and twice per revolution:
    /// Δq = a₁ sin q + b₁ cos q + a₂ sin 2q + b₂ cos 2q (4).
    Periodic(JointIndex),
    /// A link deviation growing with operating time or temperature (6, +1 for τ).
    ThermalDrift(JointIndex, DriftShape),
    /// A joint row's six error parameters following a sensor column linearly: `δ · s`, `s` the pose's
    /// reading (an accelerometer's tilt of a column, a load) — per unit of the reading (6).
    SensorDrift(JointIndex, SensorId),
    /// The measured tilt of the link an accelerometer sits on ([`thermokin_chain::TiltSensor`]): joint
    /// `j`'s row (the joint the link carries) turns by the tilt `ω` the three sensor columns from
    /// `SensorId` on hold — radians, no gain fitted — turned about the link's z axis by the sensor's
    /// mounting yaw `ψ`, about a pivot `r` (mm, from the row's origin: where the link rocks or bends
    /// from): `Δθ = R_z(ψ) ω`, `Δp = r × Δθ`; `[ψ, r_x, r_y, r_z]` (4). Over a sensor below it on the
    /// chain ([`TiltOver::Below`]), what it turns beyond that sensor's tilt (the next three columns),
    /// seen at that sensor's own yaw `ψ_b`: `Δθ = R_z(ψ) ω − R_z(ψ_b) ω_b`; `[ψ, r_x, r_y, r_z, ψ_b]` (5).
    Tilt(JointIndex, SensorId, TiltOver),
    /// The load of one of the robot's branches ([`thermokin_chain::Branch`], a second arm on a torso) on
    /// revolute joint `j`'s gravity compliance, without masses: `Δq_j = Σ θ_b g_b(q, q_branch)`, the
    /// functions of [`thermokin_chain::branch_load_basis_into`] whose span holds the torque of any masses
    /// on the branch, the weights lumping the joint's stiffness with them (radians) — or, when the robot
    /// file gives the branch's masses ([`BranchAt::masses`]), `Δq_j = k (τ_chain,j + τ_branch,j)`: the
    /// joint's one compliance under everything it carries. The branch's joint readings are the sensor
    /// columns from `SensorId` on, one per branch joint (degrees; mm for a slide), as
    /// [`thermokin_chain::Dataset::branch_columns`] places them.
    BranchLoad(JointIndex, SensorId, BranchAt),
    /// A step of the measurement frame — the tracker knocked, its stand or the robot's base moved — at
    /// a point of the measuring order: the poses from there on are measured in the frame moved by a
    /// translation (3, mm) and a rotation `Rx·Ry·Rz` (3), applied in the measurement frame (6).
    FrameStep(StepAt),
}

/// Which branch loads a joint ([`Effect::BranchLoad`]): its place among the robot's branches and its
/// functions' count ([`thermokin_chain::branch_load_basis_len`], fixed by the robot).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BranchAt {
    /// Its index in [`thermokin_chain::Robot::branches`].
    pub branch: u8,
    /// How many weights the effect takes.
    pub count: u8,
    /// Whether it tilts the joint's row across its axis (a bearing under the branch's moment: the
    /// functions of [`thermokin_chain::branch_lateral_basis_into`], a half per lateral direction, beside
    /// the joint's own lateral compliance without masses) rather than turning the joint about it.
    pub lateral: bool,
    /// Whether the robot file gives the branch's link masses ([`thermokin_chain::Branch::carries_masses`]):
    /// the functions are then the torque about the joint (one) or the moments across it (one per lateral
    /// direction), N·m, of everything the joint carries — the chain's own links with the file's masses
    /// and the branch's ([`thermokin_chain::branch_load_functions_into`]) — and the weights compliances (radians per
    /// N·m): the joint's compliance under the whole load, offered instead of its
    /// [`Effect::JointCompliance`] (across: [`Effect::LateralCompliance`]) — not lumped with first moments.
    pub masses: bool,
}

/// What a measured tilt is taken over ([`Effect::Tilt`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TiltOver {
    /// The ground: no declared sensor below it on the chain.
    Ground,
    /// The declared sensor below it, whose tilt already turns everything above it.
    Below,
}

/// What a lateral compliance without masses bends ([`Effect::LumpedLateralCompliance`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Support {
    /// A revolute joint's bearing: its row tilts (one set of weights).
    Bearing,
    /// A slide's column: its foot tilts, it bends over the extension and its foot shifts (three sets).
    Column,
}

impl Support {
    /// How many sets of weights it takes.
    pub fn sets(self) -> usize {
        match self {
            Support::Bearing => 1,
            Support::Column => 3,
        }
    }
}

/// The effect names of reports and flags, in catalogue order.
pub const EFFECT_NAMES: [&str; 13] = [
    "base_frame",
    "tool_frame",
    "joint_offset",
    "link_deviation",
    "joint_compliance",
    "compliance_coupling",
    "lateral_compliance",
    "straightness",
    "joint_scale",
    "periodic",
    "backlash",
    "thermal_drift",
    "thermal_drift_exp",
];

impl Effect {
    /// The effect named `name` (one of [`EFFECT_NAMES`]) on joint `joint` (0-based) of `robot`, where it
    /// takes one: `Effect::named(&robot, "joint_offset", Some(1))`.
    pub fn named(robot: &Robot, name: &str, joint: Option<usize>) -> Result<Self, IdentifyError> {
        let on = |j: Option<usize>| -> Result<JointIndex, IdentifyError> {
            JointIndex::of(robot, j.ok_or(IdentifyError::JointNeeded { effect: name.to_string() })?)
        };
        let global = |e: Effect| match joint {
            None => Ok(e),
            Some(_) => Err(IdentifyError::NoJointTaken { effect: name.to_string() }),
        };
        match name {
            "base_frame" => global(Effect::BaseFrame),
            "tool_frame" => global(Effect::ToolFrame),
            "joint_offset" => Ok(Effect::JointOffset(on(joint)?)),
            "link_deviation" => Ok(Effect::LinkDeviation(on(joint)?)),
            "joint_compliance" if robot.masses().iter().all(Option::is_none) => {
                Effect::lumped_compliance(robot, on(joint)?)
            }
            "joint_compliance" => Ok(Effect::JointCompliance(on(joint)?)),
            "lateral_compliance" if robot.masses().iter().all(Option::is_none) => {
                Effect::lumped_lateral_compliance(robot, on(joint)?)
            }
            "lateral_compliance" => Ok(Effect::lateral_compliance(robot, on(joint)?)),
            "straightness" => {
                let j = on(joint)?;
                if robot.chain().joints()[j.index()].kind != thermokin_chain::JointKind::Prismatic {
                    return Err(IdentifyError::NotPrismatic { effect: name.to_string(), joint: j.number() });
                }
                Ok(Effect::Straightness(j))
            }
            "compliance_coupling" => {
                let j = on(joint)?;
                // Joint j and the next: the next must exist.
                JointIndex::of(robot, j.index() + 1)?;
                Ok(Effect::ComplianceCoupling(j))
            }
            "joint_scale" => Ok(Effect::JointScale(on(joint)?)),
            "periodic" => Ok(Effect::Periodic(on(joint)?)),
            "backlash" => Ok(Effect::Backlash(on(joint)?)),
            "thermal_drift" => Ok(Effect::ThermalDrift(on(joint)?, DriftShape::Linear)),
            "thermal_drift_exp" => Ok(Effect::ThermalDrift(on(joint)?, DriftShape::Exponential)),
            _ => Err(IdentifyError::UnknownEffect { name: name.to_string(), known: EFFECT_NAMES.join(", ") }),
        }
    }

    /// Gravity compliance of joint `j` with no masses known ([`Effect::LumpedCompliance`]); an error for a
    /// prismatic joint or one whose basis does not fit the effect's count.
    pub fn lumped_compliance(robot: &Robot, j: JointIndex) -> Result<Self, IdentifyError> {
        let n = thermokin_chain::gravity_load_basis_len(robot.chain(), j.index());
        match u8::try_from(n) {
            Ok(count) if count > 0 => Ok(Effect::LumpedCompliance(j, count)),
            _ => Err(IdentifyError::NotRevolute { effect: "joint_compliance".into(), joint: j.number() }),
        }
    }

    /// Lateral gravity compliance of joint `j` with no masses known ([`Effect::LumpedLateralCompliance`]):
    /// a revolute joint's bearing tilting, a slide's column tilting, bending and shifting
    /// ([`thermokin_deform::lumped_lateral_weights_len`]); an error for an arm too long to count.
    pub fn lumped_lateral_compliance(robot: &Robot, j: JointIndex) -> Result<Self, IdentifyError> {
        let n = thermokin_deform::lumped_lateral_weights_len(robot.chain(), j.index());
        let support = match robot.chain().joints()[j.index()].kind {
            thermokin_chain::JointKind::Prismatic => Support::Column,
            thermokin_chain::JointKind::Revolute => Support::Bearing,
        };
        match u8::try_from(n) {
            Ok(count) if count > 0 => Ok(Effect::LumpedLateralCompliance(j, count, support)),
            _ => Err(IdentifyError::MassesNeeded { effect: format!("lateral_compliance of joint {}", j.number()) }),
        }
    }

    /// Lateral gravity compliance of joint `j` ([`Effect::LateralCompliance`]): two parameters for a
    /// revolute joint, six for a slide (it bends with its extension, and its foot shifts).
    pub fn lateral_compliance(robot: &Robot, j: JointIndex) -> Self {
        let slide = robot.chain().joints()[j.index()].kind == thermokin_chain::JointKind::Prismatic;
        Effect::LateralCompliance(j, if slide { 6 } else { 2 })
    }

    /// The effect a flag or a script names: `KIND[:JOINT]`, the joint numbered from 1 (`joint_offset:2`,
    /// `base_frame`).
    pub fn parse(robot: &Robot, spec: &str) -> Result<Self, IdentifyError> {
        let (name, joint) = match spec.split_once(':') {
            Some((k, j)) => match j.trim().parse::<usize>() {
                Ok(n) if n >= 1 => (k, Some(n - 1)),
                _ => return Err(IdentifyError::JointNumber { given: j.trim().to_string() }),
            },
            None => (spec, None),
        };
        Effect::named(robot, name.trim(), joint)
    }

    /// The joint the effect acts on, if it acts on one.
    pub fn joint(&self) -> Option<JointIndex> {
        match *self {
            Effect::JointOffset(j)
            | Effect::LinkDeviation(j)
            | Effect::JointCompliance(j)
            | Effect::LumpedCompliance(j, _)
            | Effect::LateralCompliance(j, _)
            | Effect::LumpedLateralCompliance(j, ..)
            | Effect::Straightness(j)
            | Effect::ComplianceCoupling(j)
            | Effect::CompliancePair(j)
            | Effect::JointScale(j)
            | Effect::Periodic(j)
            | Effect::Backlash(j)
            | Effect::ThermalDrift(j, _)
            | Effect::SensorDrift(j, _)
            | Effect::BranchLoad(j, ..)
            | Effect::Tilt(j, ..) => Some(j),
            Effect::Registration
            | Effect::ToolPoint
            | Effect::ToolRotation
            | Effect::BaseFrame
            | Effect::ToolFrame
            | Effect::FrameStep(_) => None,
        }
    }

    /// Checks the effect against a robot of `dof` joints (a [`JointIndex`] of another robot would index
    /// past this one's chain).
    pub fn validate(&self, dof: usize) -> Result<(), IdentifyError> {
        match self.joint() {
            Some(j) if j.index() >= dof => Err(IdentifyError::NoSuchJoint { joint: j.number(), dof }),
            Some(j)
                if matches!(self, Effect::ComplianceCoupling(_) | Effect::CompliancePair(_))
                    && j.index() + 1 >= dof =>
            {
                Err(IdentifyError::NoSuchJoint { joint: j.number() + 1, dof })
            }
            _ => Ok(()),
        }
    }

    /// Number of parameters.
    pub fn len(&self) -> usize {
        match self {
            Effect::Registration
            | Effect::BaseFrame
            | Effect::ToolFrame
            | Effect::LinkDeviation(_)
            | Effect::SensorDrift(..)
            | Effect::FrameStep(_) => 6,
            Effect::ThermalDrift(_, DriftShape::Exponential) => 7,
            Effect::ThermalDrift(..) => 6,
            Effect::ToolPoint | Effect::ToolRotation => 3,
            Effect::CompliancePair(_) => 2,
            Effect::JointOffset(_)
            | Effect::JointCompliance(_)
            | Effect::ComplianceCoupling(_)
            | Effect::JointScale(_)
            | Effect::Backlash(_) => 1,
            Effect::Tilt(_, _, TiltOver::Ground) => 4,
            Effect::Tilt(_, _, TiltOver::Below) => 5,
            Effect::Periodic(_) => 4,
            Effect::Straightness(_) => 5,
            Effect::BranchLoad(.., at) => at.count as usize,
            Effect::LumpedCompliance(_, n)
            | Effect::LateralCompliance(_, n)
            | Effect::LumpedLateralCompliance(_, n, _) => *n as usize,
        }
    }

    /// Never empty.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The name used in reports: `joint_offset` etc.
    pub fn kind_name(&self) -> &'static str {
        match self {
            Effect::Registration => "registration",
            Effect::ToolPoint => "tool_point",
            Effect::ToolRotation => "tool_rotation",
            Effect::BaseFrame => "base_frame",
            Effect::ToolFrame => "tool_frame",
            Effect::JointOffset(_) => "joint_offset",
            Effect::LinkDeviation(_) => "link_deviation",
            Effect::JointCompliance(_) | Effect::LumpedCompliance(..) => "joint_compliance",
            Effect::ComplianceCoupling(_) => "compliance_coupling",
            Effect::CompliancePair(_) => "compliance_pair",
            Effect::LateralCompliance(..) | Effect::LumpedLateralCompliance(..) => "lateral_compliance",
            Effect::Straightness(_) => "straightness",
            Effect::JointScale(_) => "joint_scale",
            Effect::Periodic(_) => "periodic",
            Effect::Backlash(_) => "backlash",
            Effect::ThermalDrift(..) => "thermal_drift",
            Effect::FrameStep(_) => "frame_step",
            Effect::SensorDrift(..) => "sensor_drift",
            Effect::Tilt(..) => "tilt",
            Effect::BranchLoad(.., at) if at.lateral => "lateral_branch_load",
            Effect::BranchLoad(..) => "branch_load",
        }
    }

    /// `joint_offset[3]`, `thermal_drift[2] (exponential)`, `base_frame`.
    pub fn label(&self) -> String {
        let shape = match self {
            Effect::ThermalDrift(_, DriftShape::Linear) => " (linear)",
            Effect::ThermalDrift(_, DriftShape::Exponential) => " (exponential)",
            Effect::ThermalDrift(_, DriftShape::Temperature) => " (temperature)",
            Effect::LumpedCompliance(..) | Effect::LumpedLateralCompliance(..) => " (no masses)",
            Effect::FrameStep(at) => return format!("frame_step ({})", at.describe()),
            Effect::SensorDrift(j, s) => return format!("sensor_drift[{}] (driven by {})", j.number(), s.name()),
            Effect::BranchLoad(j, s, at) => {
                let kind = self.kind_name();
                let masses = if at.masses { "with masses" } else { "no masses" };
                return format!("{kind}[{}] (the branch from joint {}, {masses})", j.number(), s.name());
            }
            Effect::Tilt(j, s, _) => {
                // Its columns are `NAME.tilt_x`, …: the sensor's name.
                let name = s.name();
                return format!("tilt[{}] (measured by {})", j.number(), name.strip_suffix(".tilt_x").unwrap_or(name));
            }
            _ => "",
        };
        match self.joint() {
            Some(j) => format!("{}[{}]{shape}", self.kind_name(), j.number()),
            None => format!("{}{shape}", self.kind_name()),
        }
    }

    /// The names of this effect's parameters, with their report units.
    pub fn parameter_names(&self) -> Vec<String> {
        let six = ["dx_mm", "dy_mm", "dz_mm", "rx_deg", "ry_deg", "rz_deg"];
        let prefix = self.label();
        match self {
            Effect::ToolPoint => six[..3].iter().map(|n| format!("{prefix}.{n}")).collect(),
            Effect::ToolRotation => six[3..].iter().map(|n| format!("{prefix}.{n}")).collect(),
            Effect::JointOffset(_) => vec![format!("{prefix}.offset_deg")],
            Effect::JointCompliance(_) => vec![format!("{prefix}.k_deg_per_Nm")],
            Effect::LumpedCompliance(_, n) => (1..=*n as usize).map(|b| format!("{prefix}.load{b:02}_deg")).collect(),
            Effect::BranchLoad(.., at) if at.masses && at.lateral => {
                (1..=at.count as usize).map(|k| format!("{prefix}.tilt{k}_deg_per_Nm")).collect()
            }
            Effect::BranchLoad(.., at) if at.masses => vec![format!("{prefix}.k_deg_per_Nm")],
            Effect::BranchLoad(.., at) if at.lateral => {
                let half = (at.count as usize / 2).max(1);
                (0..at.count as usize)
                    .map(|b| format!("{prefix}.tilt{}_load{:02}_deg", b / half + 1, b % half + 1))
                    .collect()
            }
            Effect::BranchLoad(.., at) => (1..=at.count as usize).map(|b| format!("{prefix}.load{b:02}_deg")).collect(),
            Effect::ComplianceCoupling(_) => vec![format!("{prefix}.c_deg_per_Nm")],
            Effect::CompliancePair(j) => {
                (0..2).map(|i| format!("{prefix}.w{}_sqrt_deg_per_Nm", j.number() + i)).collect()
            }
            Effect::LateralCompliance(_, n) => [
                "tilt1_deg_per_Nm",
                "tilt2_deg_per_Nm",
                "bend1_deg_per_Nm_mm",
                "bend2_deg_per_Nm_mm",
                "shift1_mm_per_Nm",
                "shift2_mm_per_Nm",
            ][..*n as usize]
                .iter()
                .map(|t| format!("{prefix}.{t}"))
                .collect(),
            Effect::LumpedLateralCompliance(_, n, support) => {
                // A bearing's one set (tilt) or a column's three (tilt, bend, shift), each a half per direction.
                let sets = [("tilt", "deg"), ("bend", "deg_per_mm"), ("shift", "mm")];
                let half = *n as usize / 2 / support.sets();
                (0..*n as usize)
                    .map(|b| {
                        let (set, at) = (b / (2 * half), b % (2 * half));
                        let (kind, unit) = sets[set];
                        format!("{prefix}.{kind}{}_load{:02}_{unit}", at / half + 1, at % half + 1)
                    })
                    .collect()
            }
            Effect::Straightness(_) => {
                ["tilt1_deg_per_mm", "tilt2_deg_per_mm", "roll_deg_per_mm", "bow1_per_mm", "bow2_per_mm"]
                    .iter()
                    .map(|t| format!("{prefix}.{t}"))
                    .collect()
            }
            Effect::JointScale(_) => vec![format!("{prefix}.scale")],
            Effect::Backlash(_) => vec![format!("{prefix}.half_play_deg")],
            Effect::Tilt(.., over) => {
                let below: &[&str] = if *over == TiltOver::Below { &["below_mounting_yaw_deg"] } else { &[] };
                ["mounting_yaw_deg", "pivot_x_mm", "pivot_y_mm", "pivot_z_mm"]
                    .iter()
                    .chain(below)
                    .map(|n| format!("{prefix}.{n}"))
                    .collect()
            }
            Effect::Periodic(_) => {
                ["sin1_deg", "cos1_deg", "sin2_deg", "cos2_deg"].iter().map(|n| format!("{prefix}.{n}")).collect()
            }
            Effect::ThermalDrift(_, DriftShape::Exponential) => {
                let mut v: Vec<String> = six.iter().map(|n| format!("{prefix}.{n}")).collect();
                v.push(format!("{prefix}.tau_min"));
                v
            }
            _ => six.iter().map(|n| format!("{prefix}.{n}")).collect(),
        }
    }

    /// The functions of the commanded joint value `q` and of the direction it was reached in (`approach`,
    /// ±1 or 0: [`thermokin_chain::Approach::sign`]) whose weighted sum is the joint error Δq, for the
    /// effects that act on the joint variable itself: `q` for a scale error, `sin q, cos q, sin 2q,
    /// cos 2q` for a cyclic one, the direction for a backlash. Empty for the others.
    pub fn joint_basis(&self, q: f64, approach: f64) -> JointBasis {
        match self {
            Effect::JointScale(_) => JointBasis { values: [q, 0.0, 0.0, 0.0], len: 1 },
            Effect::Backlash(_) => JointBasis { values: [approach, 0.0, 0.0, 0.0], len: 1 },
            Effect::Periodic(_) => {
                let (s1, c1) = q.sin_cos();
                // sin 2q = 2 sin q cos q, cos 2q = cos²q − sin²q: one sincos per joint.
                JointBasis { values: [s1, c1, 2.0 * s1 * c1, c1 * c1 - s1 * s1], len: 4 }
            }
            _ => JointBasis { values: [0.0; 4], len: 0 },
        }
    }

    /// Whether a robot file can hold the effect: the same for every pose and time (frames, offsets, link
    /// deviations), unlike compliance, joint-level errors, drift and a step of the measurement frame.
    pub fn is_static(&self) -> bool {
        !matches!(
            self,
            Effect::JointCompliance(_)
                | Effect::LumpedCompliance(..)
                | Effect::LateralCompliance(..)
                | Effect::LumpedLateralCompliance(..)
                | Effect::Straightness(_)
                | Effect::ComplianceCoupling(_)
                | Effect::CompliancePair(_)
                | Effect::JointScale(_)
                | Effect::Periodic(_)
                | Effect::Backlash(_)
                | Effect::ThermalDrift(..)
                | Effect::SensorDrift(..)
                | Effect::Tilt(..)
                | Effect::BranchLoad(..)
                | Effect::FrameStep(_)
        )
    }

    /// Time-dependent effects are judged with forward-chained cross-validation too.
    pub fn is_time_dependent(&self) -> bool {
        matches!(self, Effect::ThermalDrift(..))
    }

    /// Reported to the user as a cause (not a nuisance block).
    pub fn is_reported(&self) -> bool {
        !matches!(self, Effect::Registration | Effect::ToolPoint | Effect::ToolRotation)
    }

    /// Whether parameter `k` is an angle: radians inside, degrees in reports and flags (a compliance is
    /// radians per N·m inside, degrees per N·m outside). Lengths are millimetres and τ minutes on both
    /// sides.
    pub fn is_angle(&self, k: usize) -> bool {
        match (self, k) {
            (
                Effect::JointOffset(_)
                | Effect::JointCompliance(_)
                | Effect::LumpedCompliance(..)
                | Effect::BranchLoad(..)
                | Effect::ComplianceCoupling(_)
                | Effect::Periodic(_)
                | Effect::Backlash(_)
                | Effect::ToolRotation,
                _,
            ) => true,
            (Effect::Tilt(..), k) => k == 0 || k == 4,
            // A column's third set, its foot's shift, is millimetres.
            (Effect::LumpedLateralCompliance(_, n, Support::Column), k) => k < 2 * (*n as usize) / 3,
            (Effect::LumpedLateralCompliance(..), _) => true,
            // A slide's shift is millimetres per N·m.
            (Effect::LateralCompliance(..), k) => k < 4,
            // A bow is a length per squared length.
            (Effect::Straightness(_), k) => k < 3,
            (Effect::JointScale(_), _) => false,
            (Effect::ToolPoint, _) => false,
            (Effect::ThermalDrift(_, DriftShape::Exponential), 6) => false,
            (_, 3..=5) => true,
            _ => false,
        }
    }

    /// Parameter `k` from internal units (mm, radians, minutes, radians per N·m) to report units (mm,
    /// degrees, minutes, degrees per N·m).
    pub fn to_report_units(&self, k: usize, v: f64) -> f64 {
        match self {
            // √(rad/N·m) to √(°/N·m).
            Effect::CompliancePair(_) => v * units::degrees(1.0).sqrt(),
            _ if self.is_angle(k) => units::degrees(v),
            _ => v,
        }
    }

    /// Parameter `k` from report units to internal units (the inverse of [`Effect::to_report_units`]).
    pub fn from_report_units(&self, k: usize, v: f64) -> f64 {
        match self {
            Effect::CompliancePair(_) => v * units::radians(1.0).sqrt(),
            _ if self.is_angle(k) => units::radians(v),
            _ => v,
        }
    }
}

/// The functions of a joint value an effect's parameters weigh ([`Effect::joint_basis`]): at most four,
/// without allocating (it is evaluated at every measurement).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointBasis {
    values: [f64; 4],
    len: usize,
}

impl JointBasis {
    /// The values, in parameter order.
    pub fn as_slice(&self) -> &[f64] {
        &self.values[..self.len]
    }
}

/// The six error parameters of a row block starting at `theta[o]`.
pub(crate) fn six_at(theta: &[f64], o: usize) -> ErrorParams {
    ErrorParams::from_array([theta[o], theta[o + 1], theta[o + 2], theta[o + 3], theta[o + 4], theta[o + 5]])
}

/// The turn of a row by a measured tilt ([`Effect::Tilt`]): the three tilt columns from `column` of a
/// pose's `sensors` (radians, the sensor's axes) turned about z by the mounting yaw `psi`, and its
/// derivative in `psi`. A pose without the columns does not turn.
pub(crate) fn tilt_turn(sensors: &[f64], column: usize, psi: f64) -> (nalgebra::Vector3<f64>, nalgebra::Vector3<f64>) {
    let w = |c: usize| sensors.get(column + c).copied().unwrap_or(0.0);
    let (x, y, z) = (w(0), w(1), w(2));
    let (s, c) = psi.sin_cos();
    (
        nalgebra::Vector3::new(c * x - s * y, s * x + c * y, z),
        nalgebra::Vector3::new(-s * x - c * y, c * x - s * y, 0.0),
    )
}
