//! The parameterised model: effects as parameter blocks on top of a chain, the prediction of a measured
//! TCP position and its analytic Jacobian (from [`Chain::parameter_jacobian`]).

use nalgebra::{Isometry3, Matrix3, Matrix6xX, Vector3};
use serde::Serialize;
use thermokin_chain::{Chain, ErrorParams, JointKind, LinkMass, ParameterRows, Robot};
use thermokin_deform::{AfterStabilization, DriftLaw, DriftRow, JointCorrection, RobotModel, Row, TimeProfile};

use crate::{Dataset, DiagnoseError, Measurement};

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
    /// temperature rise when a column names the joint ([`sensor_joint`]), of the mean rise otherwise.
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

/// A joint an effect acts on: a 0-based index checked against the robot — [`JointIndex::of`] is the only
/// way to make one, so that an effect cannot name a joint the robot lacks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, PartialOrd, Ord)]
pub struct JointIndex(usize);

impl JointIndex {
    /// Joint `index` (0-based) of `robot`.
    pub fn of(robot: &Robot, index: usize) -> Result<Self, DiagnoseError> {
        let dof = robot.chain().dof();
        if index < dof { Ok(Self(index)) } else { Err(DiagnoseError::NoSuchJoint { joint: index + 1, dof }) }
    }

    /// The 0-based index.
    pub fn index(self) -> usize {
        self.0
    }

    /// The 1-based joint number of reports and flags.
    pub fn number(self) -> usize {
        self.0 + 1
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
    /// A gear-ratio (scale) error of a revolute joint: Δq = s · q (1, dimensionless).
    JointScale(JointIndex),
    /// A cyclic encoder error of a revolute joint, once and twice per revolution:
    /// Δq = a₁ sin q + b₁ cos q + a₂ sin 2q + b₂ cos 2q (4).
    Periodic(JointIndex),
    /// A link deviation growing with operating time or temperature (6, +1 for τ).
    ThermalDrift(JointIndex, DriftShape),
}

/// The effect names of reports and flags, in catalogue order.
pub const EFFECT_NAMES: [&str; 9] = [
    "base_frame",
    "tool_frame",
    "joint_offset",
    "link_deviation",
    "joint_compliance",
    "joint_scale",
    "periodic",
    "thermal_drift",
    "thermal_drift_exp",
];

impl Effect {
    /// The effect named `name` (one of [`EFFECT_NAMES`]) on joint `joint` (0-based) of `robot`, where it
    /// takes one: `Effect::named(&robot, "joint_offset", Some(1))`.
    pub fn named(robot: &Robot, name: &str, joint: Option<usize>) -> Result<Self, DiagnoseError> {
        let on = |j: Option<usize>| -> Result<JointIndex, DiagnoseError> {
            JointIndex::of(robot, j.ok_or(DiagnoseError::JointNeeded { effect: name.to_string() })?)
        };
        let global = |e: Effect| match joint {
            None => Ok(e),
            Some(_) => Err(DiagnoseError::NoJointTaken { effect: name.to_string() }),
        };
        match name {
            "base_frame" => global(Effect::BaseFrame),
            "tool_frame" => global(Effect::ToolFrame),
            "joint_offset" => Ok(Effect::JointOffset(on(joint)?)),
            "link_deviation" => Ok(Effect::LinkDeviation(on(joint)?)),
            "joint_compliance" => Ok(Effect::JointCompliance(on(joint)?)),
            "joint_scale" => Ok(Effect::JointScale(on(joint)?)),
            "periodic" => Ok(Effect::Periodic(on(joint)?)),
            "thermal_drift" => Ok(Effect::ThermalDrift(on(joint)?, DriftShape::Linear)),
            "thermal_drift_exp" => Ok(Effect::ThermalDrift(on(joint)?, DriftShape::Exponential)),
            _ => Err(DiagnoseError::UnknownEffect { name: name.to_string() }),
        }
    }

    /// The joint the effect acts on, if it acts on one.
    pub fn joint(&self) -> Option<JointIndex> {
        match *self {
            Effect::JointOffset(j)
            | Effect::LinkDeviation(j)
            | Effect::JointCompliance(j)
            | Effect::JointScale(j)
            | Effect::Periodic(j)
            | Effect::ThermalDrift(j, _) => Some(j),
            Effect::Registration | Effect::ToolPoint | Effect::ToolRotation | Effect::BaseFrame | Effect::ToolFrame => {
                None
            }
        }
    }

    /// Checks the effect against a robot of `dof` joints (a [`JointIndex`] of another robot would index
    /// past this one's chain).
    pub fn validate(&self, dof: usize) -> Result<(), DiagnoseError> {
        match self.joint() {
            Some(j) if j.index() >= dof => Err(DiagnoseError::NoSuchJoint { joint: j.number(), dof }),
            _ => Ok(()),
        }
    }

    /// Number of parameters.
    pub fn len(&self) -> usize {
        match self {
            Effect::Registration | Effect::BaseFrame | Effect::ToolFrame | Effect::LinkDeviation(_) => 6,
            Effect::ThermalDrift(_, DriftShape::Exponential) => 7,
            Effect::ThermalDrift(..) => 6,
            Effect::ToolPoint | Effect::ToolRotation => 3,
            Effect::JointOffset(_) | Effect::JointCompliance(_) | Effect::JointScale(_) => 1,
            Effect::Periodic(_) => 4,
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
            Effect::JointCompliance(_) => "joint_compliance",
            Effect::JointScale(_) => "joint_scale",
            Effect::Periodic(_) => "periodic",
            Effect::ThermalDrift(..) => "thermal_drift",
        }
    }

    /// `joint_offset[3]`, `thermal_drift[2] (exponential)`, `base_frame`.
    pub fn label(&self) -> String {
        let shape = match self {
            Effect::ThermalDrift(_, DriftShape::Linear) => " (linear)",
            Effect::ThermalDrift(_, DriftShape::Exponential) => " (exponential)",
            Effect::ThermalDrift(_, DriftShape::Temperature) => " (temperature)",
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
            Effect::JointScale(_) => vec![format!("{prefix}.scale")],
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

    /// The functions of the commanded joint value whose weighted sum is the joint error Δq, for the
    /// effects that act on the joint variable itself: `q` for a scale error, `sin q, cos q, sin 2q,
    /// cos 2q` for a cyclic one. Empty for the others.
    pub fn joint_basis(&self, q: f64) -> JointBasis {
        match self {
            Effect::JointScale(_) => JointBasis { values: [q, 0.0, 0.0, 0.0], len: 1 },
            Effect::Periodic(_) => {
                let (s1, c1) = q.sin_cos();
                // sin 2q = 2 sin q cos q, cos 2q = cos²q − sin²q: one sincos per joint.
                JointBasis { values: [s1, c1, 2.0 * s1 * c1, c1 * c1 - s1 * s1], len: 4 }
            }
            _ => JointBasis { values: [0.0; 4], len: 0 },
        }
    }

    /// Whether a robot file can hold the effect: the same for every pose and time (frames, offsets, link
    /// deviations), unlike compliance, joint-level errors and drift.
    pub fn is_static(&self) -> bool {
        !matches!(
            self,
            Effect::JointCompliance(_) | Effect::JointScale(_) | Effect::Periodic(_) | Effect::ThermalDrift(..)
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
            (Effect::JointOffset(_) | Effect::JointCompliance(_) | Effect::Periodic(_) | Effect::ToolRotation, _) => {
                true
            }
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
        if self.is_angle(k) { thermokin_io::units::degrees(v) } else { v }
    }

    /// Parameter `k` from report units to internal units (the inverse of [`Effect::to_report_units`]).
    pub fn from_report_units(&self, k: usize, v: f64) -> f64 {
        if self.is_angle(k) { thermokin_io::units::radians(v) } else { v }
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
fn six_at(theta: &[f64], o: usize) -> ErrorParams {
    ErrorParams::from_array([theta[o], theta[o + 1], theta[o + 2], theta[o + 3], theta[o + 4], theta[o + 5]])
}

/// The chain of one parameter vector, kept across the measurements of one evaluation, with its joint
/// rows' errors before any drift (a drift row is rewritten from them per measurement).
pub(crate) struct ChainCache {
    chain: Chain,
    joint_err: Vec<ErrorParams>,
    /// Buffers reused across measurements: the joint values the chain sees, the chain's parameter
    /// Jacobian.
    q: Vec<f64>,
    pj: Matrix6xX<f64>,
    /// The chain rows this model's Jacobian reads ([`Model::parameter_rows`]).
    rows: ParameterRows,
    /// Per measurement: each drift's (effect index, factor, ∂factor/∂τ) and each drifting row's deviation.
    drift_scale: Vec<(usize, f64, f64)>,
    drift_rows: Vec<(usize, ErrorParams)>,
    /// `(sin, cos)` of the joint values the chain sees.
    sin_cos: Vec<(f64, f64)>,
}

/// Reference time of the linear drift: the parameters are the deviation at 180 minutes (section 4).
pub const LINEAR_DRIFT_REFERENCE_MIN: f64 = 180.0;
/// Largest time constant considered, minutes: beyond it the exponential is indistinguishable from the
/// linear drift over any warm-up a user measures.
const MAX_TAU_MIN: f64 = 1e4;
/// The time constants an exponential drift is evaluated and fitted in, minutes: from a thousandth of a
/// minute (a step) to [`MAX_TAU_MIN`].
pub(crate) const TAU_RANGE_MIN: (f64, f64) = (1e-3, MAX_TAU_MIN);
/// Initial time constant of an exponential drift, minutes.
const INITIAL_TAU_MIN: f64 = 60.0;

/// A model: a list of effects on top of a robot (its chain, known deviations included, and its link
/// masses), and the parameter vector's layout. Built by [`Model::new`], which checks every effect against
/// the robot; the layout is derived from the effects and cannot drift from them.
#[derive(Clone, Debug)]
pub struct Model {
    effects: Vec<Effect>,
    offsets: Vec<usize>,
    len: usize,
    registration: Isometry3<f64>,
}

impl Model {
    /// A model of `robot` with these effects (in parameter order).
    pub fn new(robot: &Robot, effects: Vec<Effect>) -> Result<Self, DiagnoseError> {
        let dof = robot.chain().dof();
        let mut offsets = Vec::with_capacity(effects.len());
        let mut len = 0;
        for e in &effects {
            e.validate(dof)?;
            offsets.push(len);
            len += e.len();
        }
        Ok(Self { effects, offsets, len, registration: Isometry3::identity() })
    }

    /// The same model with the tracker registration starting at `registration` (identity: the base frame).
    pub fn with_registration(mut self, registration: Isometry3<f64>) -> Self {
        self.registration = registration;
        self
    }

    /// The effects, in parameter order.
    pub fn effects(&self) -> &[Effect] {
        &self.effects
    }

    /// The first parameter of each effect.
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// The number of parameters.
    pub fn len(&self) -> usize {
        self.len
    }

    /// `true` when the model has no parameter.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether the model estimates a tracker registration.
    pub fn has_registration(&self) -> bool {
        self.effects.contains(&Effect::Registration)
    }

    /// The initial parameter vector (zeros, τ at its starting value).
    pub fn initial(&self) -> Vec<f64> {
        let mut theta = vec![0.0; self.len];
        for (e, &o) in self.effects.iter().zip(&self.offsets) {
            if let Effect::ThermalDrift(_, DriftShape::Exponential) = e {
                theta[o + 6] = INITIAL_TAU_MIN;
            }
        }
        theta
    }

    /// The columns that are time constants (an exponential drift's τ, minutes), with the range a fit
    /// keeps them in: the identification moves their rate `1/τ` rather than τ ([`crate::fit`]).
    pub(crate) fn time_constants(&self) -> Vec<usize> {
        self.effects
            .iter()
            .zip(&self.offsets)
            .filter(|(e, _)| matches!(e, Effect::ThermalDrift(_, DriftShape::Exponential)))
            .map(|(_, &o)| o + 6)
            .collect()
    }

    /// Names of all parameters.
    pub fn parameter_names(&self) -> Vec<String> {
        self.effects.iter().flat_map(Effect::parameter_names).collect()
    }

    /// The drift factor `s = f(t) / f(180)` of a shape at one measurement (`f` the law of the deform
    /// profile, [`DriftShape::profile`]) and `ds/dτ` for the exponential — zero where τ is held at a
    /// bound of [`TAU_RANGE_MIN`], as `s` is.
    fn drift_factor(shape: DriftShape, m: &Measurement, temp_rise: f64, tau: f64) -> (f64, f64) {
        let held = !(TAU_RANGE_MIN.0 < tau && tau < TAU_RANGE_MIN.1);
        let tau = tau.clamp(TAU_RANGE_MIN.0, TAU_RANGE_MIN.1);
        let Some(profile) = shape.profile(tau) else { return (temp_rise, 0.0) };
        let f = |t: f64| profile.time_factor(t).unwrap_or(0.0);
        let (ft, fr) = (f(m.time_min), f(LINEAR_DRIFT_REFERENCE_MIN));
        let ds = match shape {
            DriftShape::Exponential => {
                let df = |t: f64| profile.time_factor_dtau(t).unwrap_or(0.0);
                if held { 0.0 } else { (df(m.time_min) * fr - ft * df(LINEAR_DRIFT_REFERENCE_MIN)) / (fr * fr) }
            }
            _ => 0.0,
        };
        (ft / fr, ds)
    }

    /// The robot's chain with this model's static effects at `theta` — base frame and registration (as
    /// the base row: FK then gives the measurement frame), tool point, joint offsets, link deviations —
    /// and the effects a robot file cannot hold because they depend on the pose's load or on time
    /// (gravity compliance, thermal drift), which are left out.
    pub fn calibrated_chain(&self, robot: &Robot, theta: &[f64]) -> Result<(Chain, Vec<Effect>), DiagnoseError> {
        let (chain, _) = self.static_chain(robot, theta)?;
        let left_out = self.effects.iter().filter(|e| !e.is_static()).copied().collect();
        Ok((chain, left_out))
    }

    /// The identified robot with every effect of this model at `theta` — what a robot file carries and
    /// every command evaluates ([`RobotModel`]): the static effects in the chain
    /// ([`Model::calibrated_chain`]); gear-ratio, cyclic and compliance terms as joint corrections; each
    /// thermal drift as a drift row with its own law — linear and exponential as the deform profile whose
    /// factor at 180 minutes is 1 after dividing by `f(180)` ([`DriftShape::reference_factor`]), a
    /// temperature drift per kelvin of the joint's own sensor (or of the mean of all, as fitted), each
    /// against its reading at the earliest measurement of `data` (the fit's reference). Gravity keeps its
    /// direction in the robot's base frame while the registration turns the base row into the tracker's.
    ///
    /// Its forward model equals [`Model::predict`]'s at every measurement (a test checks it to 1e-9 mm).
    pub fn robot_model(&self, robot: &Robot, theta: &[f64], data: &Dataset) -> Result<RobotModel, DiagnoseError> {
        let (chain, _) = self.static_chain(robot, theta)?;
        let down = {
            let world_from_base_fitted = chain.base().pose().rotation;
            let world_from_base_given = robot.chain().base().pose().rotation;
            world_from_base_fitted * world_from_base_given.inverse() * -Vector3::z_axis()
        };
        let dof = robot.chain().dof();
        let mut joints = vec![JointCorrection::NONE; dof];
        let mut drift = Vec::new();
        let first = data.measurements.iter().min_by(|a, b| a.time_min.total_cmp(&b.time_min));
        for (e, &o) in self.effects.iter().zip(&self.offsets) {
            match *e {
                Effect::JointCompliance(j) => joints[j.index()].compliance_rad_per_nm += theta[o],
                Effect::JointScale(j) => joints[j.index()].scale += theta[o],
                Effect::Periodic(j) => {
                    for (c, t) in joints[j.index()].cyclic_rad.iter_mut().zip(&theta[o..o + 4]) {
                        *c += t;
                    }
                }
                Effect::ThermalDrift(j, shape) => {
                    let tau = theta.get(o + 6).copied().unwrap_or(0.0).clamp(TAU_RANGE_MIN.0, TAU_RANGE_MIN.1);
                    let at_reference = six_at(theta, o);
                    let law = match shape.profile(tau) {
                        Some(profile) => DriftLaw::Time(profile),
                        None => DriftLaw::PerKelvin { sensors: self.sensors_of(j.index(), data, first)? },
                    };
                    let deviation = at_reference.scaled(1.0 / shape.reference_factor(tau));
                    drift.push(DriftRow { row: Row::Joint(j.index()), deviation, law });
                }
                _ => {}
            }
        }
        let base = robot.with_chain(chain)?;
        Ok(RobotModel::new(base).with_gravity(down).with_joint_corrections(joints)?.with_drift(drift)?)
    }

    /// The sensors a temperature drift of joint `j` follows (its own, or all), named as in files
    /// (`temp_j2`), each with its reading at the earliest measurement.
    fn sensors_of(
        &self,
        j: usize,
        data: &Dataset,
        first: Option<&Measurement>,
    ) -> Result<Vec<(String, f64)>, DiagnoseError> {
        let dof = data.measurements.first().map_or(0, |m| m.q.len());
        let reading = |c: usize| first.and_then(|m| m.temps.get(c).copied());
        let own = data.temperature_names.iter().position(|n| sensor_joint(n, dof) == Some(j));
        let columns: Vec<usize> = match own {
            Some(c) => vec![c],
            None => (0..data.temperature_names.len()).collect(),
        };
        columns
            .into_iter()
            .map(|c| {
                let name = format!("temp_{}", data.temperature_names[c]);
                reading(c)
                    .map(|t| (name.clone(), t))
                    .ok_or(DiagnoseError::NoTemperatures { effect: format!("thermal_drift[{}] (temperature)", j + 1) })
            })
            .collect()
    }

    /// The chain with the static effects at `theta` (registered), and its joint rows' errors: the part
    /// of a prediction that is the same for every measurement.
    fn static_chain(&self, robot: &Robot, theta: &[f64]) -> Result<(Chain, Vec<ErrorParams>), DiagnoseError> {
        let chain = robot.chain();
        let mut base_err = chain.base().error;
        let mut tool_err = chain.tool().error;
        let mut joint_err: Vec<ErrorParams> = chain.joints().iter().map(|j| j.error).collect();
        let mut zeros: Vec<f64> = chain.joints().iter().map(|j| j.zero).collect();
        let six = |o: usize| six_at(theta, o);
        for (e, &o) in self.effects.iter().zip(&self.offsets) {
            match *e {
                Effect::Registration | Effect::BaseFrame => base_err = base_err.add(&six(o)),
                Effect::ToolPoint => tool_err.translation += Vector3::new(theta[o], theta[o + 1], theta[o + 2]),
                Effect::ToolRotation => tool_err.rotation += Vector3::new(theta[o], theta[o + 1], theta[o + 2]),
                Effect::ToolFrame => tool_err = tool_err.add(&six(o)),
                Effect::JointOffset(j) => zeros[j.index()] += theta[o],
                Effect::LinkDeviation(j) => joint_err[j.index()] = joint_err[j.index()].add(&six(o)),
                Effect::JointCompliance(_) | Effect::JointScale(_) | Effect::Periodic(_) | Effect::ThermalDrift(..) => {
                }
            }
        }
        let built = self.registered(chain.with_errors_and_zeros(base_err, &joint_err, tool_err, &zeros)?)?;
        Ok((built, joint_err))
    }

    /// `chain` with the registration's starting pose in its base row's nominal pose (its parameters are
    /// small corrections on top, in the row's error).
    fn registered(&self, chain: Chain) -> Result<Chain, DiagnoseError> {
        if self.registration == Isometry3::identity() {
            return Ok(chain);
        }
        let mut row = chain.base().clone();
        let nominal = self.registration * row.nominal();
        row.translation = nominal.translation.vector;
        row.rotation = nominal.rotation;
        Ok(chain.with_base(row)?)
    }

    /// The rows of the chain's parameter Jacobian this model's columns are read from in [`Model::predict`]:
    /// the base row for a registration or base frame, the tool row for the tool, a joint's error row for
    /// its link deviation or drift, its zero column for the joint-level effects.
    fn parameter_rows(&self, dof: usize) -> ParameterRows {
        let mut rows = ParameterRows::none(dof);
        for e in &self.effects {
            match *e {
                Effect::Registration | Effect::BaseFrame => rows.base = true,
                Effect::ToolPoint | Effect::ToolRotation | Effect::ToolFrame => rows.tool = true,
                Effect::LinkDeviation(j) | Effect::ThermalDrift(j, _) => rows.joints[j.index()] = true,
                Effect::JointOffset(j) | Effect::JointCompliance(j) | Effect::JointScale(j) | Effect::Periodic(j) => {
                    rows.zeros[j.index()] = true
                }
            }
        }
        rows
    }

    // Long on purpose (~145 lines): the identification's per-measurement hot path — every effect's
    // joint-value correction, drift row and Jacobian column in one pass over the effects, with the
    // cache's buffers borrowed once; split, it would pay the borrows and the effect dispatch per part.
    /// Predicted TCP position and rotation of one measurement and, if asked, the 6 × len Jacobian of the
    /// pose as twists in the measurement frame (rows 0–2 the position, 3–5 the rotation: a small turn
    /// `δφ` of the predicted rotation, `R ↦ exp(δφ)·R`).
    ///
    /// `cache` holds the chain of one parameter vector across the measurements of one evaluation: the
    /// static effects are built once; a thermal drift, which differs per measurement, rewrites only its
    /// own rows ([`Chain::set_joint_error`]).
    #[allow(clippy::too_many_arguments)] // one measurement's inputs, crate-internal hot path
    pub(crate) fn predict(
        &self,
        robot: &Robot,
        theta: &[f64],
        m: &Measurement,
        temp_rise: &[f64],
        torques: &[f64],
        q_sin_cos: Option<&[(f64, f64)]>,
        jacobian: Option<&mut Matrix6xX<f64>>,
        cache: &mut Option<ChainCache>,
    ) -> Result<(Vector3<f64>, Matrix3<f64>), DiagnoseError> {
        let chain = robot.chain();
        let six = |o: usize| six_at(theta, o);
        let cached = match cache {
            Some(c) => c,
            None => {
                let (chain, joint_err) = self.static_chain(robot, theta)?;
                let pj = Matrix6xX::zeros(chain.parameter_layout().len());
                let rows = self.parameter_rows(chain.dof());
                cache.insert(ChainCache {
                    chain,
                    joint_err,
                    q: Vec::with_capacity(m.q.len()),
                    pj,
                    rows,
                    drift_scale: Vec::new(),
                    drift_rows: Vec::new(),
                    sin_cos: Vec::with_capacity(m.q.len()),
                })
            }
        };
        // Per measurement: the joint values the joint-level effects move, and the drift rows.
        let mut q = std::mem::take(&mut cached.q);
        q.clear();
        q.extend_from_slice(&m.q);
        let mut drift_scale = std::mem::take(&mut cached.drift_scale);
        let mut drift_rows = std::mem::take(&mut cached.drift_rows);
        drift_scale.clear();
        drift_rows.clear();
        for (k, (e, &o)) in self.effects.iter().zip(&self.offsets).enumerate() {
            match *e {
                Effect::JointCompliance(j) => {
                    let j = j.index();
                    q[j] += theta[o] * torques[j];
                }
                Effect::JointScale(j) | Effect::Periodic(j) => {
                    let j = j.index();
                    q[j] += e.joint_basis(m.q[j]).as_slice().iter().zip(&theta[o..]).map(|(b, t)| b * t).sum::<f64>();
                }
                Effect::ThermalDrift(j, shape) => {
                    let j = j.index();
                    let tau = if shape == DriftShape::Exponential { theta[o + 6] } else { 0.0 };
                    let (s, ds) = Self::drift_factor(shape, m, temp_rise[j], tau);
                    match drift_rows.iter_mut().find(|(row, _)| *row == j) {
                        Some((_, d)) => *d = d.add(&six(o).scaled(s)),
                        None => drift_rows.push((j, six(o).scaled(s))),
                    }
                    drift_scale.push((k, s, ds));
                }
                _ => {}
            }
        }
        for &(j, d) in &drift_rows {
            let row = cached.joint_err[j].add(&d);
            cached.chain.set_joint_error(j, row)?;
        }
        cached.drift_rows = drift_rows;
        // The measured joints' sines, moved by angle addition where a joint-level effect moved the joint
        // (by a small angle: [`thermokin_chain::sin_cos`] takes it without a library sine).
        let sc = q_sin_cos.map(|given| {
            cached.sin_cos.clear();
            cached.sin_cos.extend(given.iter().zip(&q).zip(&m.q).map(|((&(s, c), &moved), &measured)| {
                let d = moved - measured;
                if d == 0.0 {
                    (s, c)
                } else {
                    let (sd, cd) = thermokin_chain::sin_cos(d);
                    (s * cd + c * sd, c * cd - s * sd)
                }
            }));
            &cached.sin_cos[..]
        });
        let registered = &cached.chain;
        let Some(jac) = jacobian else {
            let pose = match sc {
                Some(sc) => registered.tool_position_rotation_sin_cos(&q, sc),
                None => registered.tool_position_rotation(&q),
            };
            cached.q = q;
            cached.drift_scale = drift_scale;
            return Ok(pose?);
        };
        let pose = match sc {
            Some(sc) => registered.pose_and_parameter_jacobian_rows_sin_cos(&q, sc, &mut cached.pj, &cached.rows),
            None => registered.pose_and_parameter_jacobian_rows(&q, &mut cached.pj, &cached.rows),
        };
        cached.q = q;
        let pose = pose?;
        let pj = &cached.pj;
        let layout = registered.parameter_layout();
        jac.fill(0.0);
        let mut drift = drift_scale.iter();
        for (k, (e, &o)) in self.effects.iter().zip(&self.offsets).enumerate() {
            let mut copy = |dst: usize, src: usize, scale: f64| {
                for r in 0..6 {
                    jac[(r, dst)] = pj[(r, src)] * scale;
                }
            };
            match *e {
                Effect::Registration | Effect::BaseFrame => (0..6).for_each(|c| copy(o + c, layout.base() + c, 1.0)),
                Effect::ToolPoint => (0..3).for_each(|c| copy(o + c, layout.tool() + c, 1.0)),
                Effect::ToolRotation => (0..3).for_each(|c| copy(o + c, layout.tool() + 3 + c, 1.0)),
                Effect::ToolFrame => (0..6).for_each(|c| copy(o + c, layout.tool() + c, 1.0)),
                Effect::JointOffset(j) => copy(o, layout.zero(j.index()), 1.0),
                Effect::LinkDeviation(j) => (0..6).for_each(|c| copy(o + c, layout.joint(j.index()) + c, 1.0)),
                Effect::JointCompliance(j) => {
                    let j = j.index();
                    let scale = if chain.joints()[j].kind == JointKind::Revolute { torques[j] } else { 0.0 };
                    copy(o, layout.zero(j), scale);
                }
                Effect::JointScale(j) | Effect::Periodic(j) => {
                    // Δq enters exactly as a zero offset does: ∂p/∂θ_k = ∂p/∂zero · basis_k(q).
                    let j = j.index();
                    for (k, b) in e.joint_basis(m.q[j]).as_slice().iter().enumerate() {
                        copy(o + k, layout.zero(j), *b);
                    }
                }
                Effect::ThermalDrift(j, shape) => {
                    let j = j.index();
                    let &(_, s, ds) = drift.next().filter(|d| d.0 == k).unwrap_or(&(k, 0.0, 0.0));
                    (0..6).for_each(|c| copy(o + c, layout.joint(j) + c, s));
                    if shape == DriftShape::Exponential {
                        for r in 0..6 {
                            let mut v = 0.0;
                            for c in 0..6 {
                                v += pj[(r, layout.joint(j) + c)] * theta[o + c] * ds;
                            }
                            jac[(r, o + 6)] = v;
                        }
                    }
                }
            }
        }
        cached.drift_scale = drift_scale;
        Ok(pose)
    }
}

/// Gravity torque about each joint's axis at configuration `q`, N·m, from the link masses, gravity along
/// the chain's world −Z ([`thermokin_chain::gravity_torques`], the law a robot file's compliance is
/// evaluated with at use); zeros where FK fails (a wrong-length `q` is refused before any fit).
pub fn gravity_torques(chain: &Chain, masses: &[Option<LinkMass>], q: &[f64]) -> Vec<f64> {
    thermokin_chain::gravity_torques(chain, masses, q, &-Vector3::z_axis()).unwrap_or_else(|_| vec![0.0; chain.dof()])
}

/// The joint (0-based) a temperature column belongs to, from its name without the `temp_` prefix:
/// `j2`, `joint2`, `a2`, `axis2`, `motor2`, `m2`, `q2` or `2` (case and separators ignored: `J_2`, `Axis-2`)
/// name joint 2 of a robot with at least 2 joints. Other names (`ambient`, `base`) belong to no joint; a
/// joint's temperature drift follows its own column when it has one, the mean of all columns otherwise.
pub fn sensor_joint(name: &str, dof: usize) -> Option<usize> {
    let flat: String = name.chars().filter(char::is_ascii_alphanumeric).collect::<String>().to_ascii_lowercase();
    let digits_at = flat.find(|c: char| c.is_ascii_digit())?;
    let (prefix, number) = flat.split_at(digits_at);
    if !["", "j", "joint", "a", "axis", "m", "motor", "q"].contains(&prefix) {
        return None;
    }
    let n: usize = number.parse().ok()?;
    (1..=dof).contains(&n).then(|| n - 1)
}

/// What the residuals of one data set need beyond the parameters: gravity torques (one list per
/// measurement), the temperature rise each joint's drift follows, and whether orientations are fitted.
pub(crate) struct Pre {
    pub(crate) torques: Vec<Vec<f64>>,
    /// Per measurement, per joint: the rise of the joint's own sensor ([`sensor_joint`]) or, for a joint
    /// without one, the mean rise of all sensors, K.
    pub(crate) rise: Vec<Vec<f64>>,
    /// `Some(lever)` when measured orientations are fitted: a rotation error `δφ` (radians) counts as
    /// the displacement `lever · δφ` (mm) it causes at `lever` millimetres from the tool point.
    pub(crate) lever_mm: Option<f64>,
    /// Per measurement, the weights of its position rows in the fit, `σ̄ / σ` per axis from the
    /// tracker's stated standard deviations (`σ̄` their mean over the set, so that the weights average
    /// about 1 and residuals stay in millimetres); `None` when the set states none. Held-out errors are
    /// never weighted.
    pub(crate) weights: Option<Vec<Vector3<f64>>>,
    /// Per measurement, `(sin q_i, cos q_i)` of its joint values: computed once, every evaluation of
    /// every fit reads them ([`Chain::tool_position_rotation_sin_cos`]).
    pub(crate) sin_cos: Vec<Vec<(f64, f64)>>,
}

impl Pre {
    /// Residual rows per measurement: 3 (position) or 6 (position and weighted rotation).
    pub(crate) fn stride(&self) -> usize {
        if self.lever_mm.is_some() { 6 } else { 3 }
    }
}

/// [`Pre`] of `data`; orientations fitted when every measurement has one and `lever_mm > 0`.
pub(crate) fn prepare(robot: &Robot, data: &Dataset, lever_mm: f64) -> Pre {
    prepare_against(robot, data, data, lever_mm)
}

/// As [`prepare`], the temperature rise taken from the earliest measurement of `reference` (the data a
/// model was fitted on, when `data` is a test set scored with it); orientations are fitted only when
/// both carry them.
pub(crate) fn prepare_against(robot: &Robot, data: &Dataset, reference: &Dataset, lever_mm: f64) -> Pre {
    let torques = data.measurements.iter().map(|m| gravity_torques(robot.chain(), robot.masses(), &m.q)).collect();
    let first: Option<Vec<f64>> =
        reference.measurements.iter().min_by(|a, b| a.time_min.total_cmp(&b.time_min)).map(|m| m.temps.clone());
    let dof = robot.chain().dof();
    let own: Vec<Option<usize>> =
        (0..dof).map(|j| data.temperature_names.iter().position(|n| sensor_joint(n, dof) == Some(j))).collect();
    let rise = data
        .measurements
        .iter()
        .map(|m| match &first {
            Some(t0) if !m.temps.is_empty() => {
                let mean = m.temps.iter().zip(t0).map(|(a, b)| a - b).sum::<f64>() / m.temps.len() as f64;
                own.iter().map(|c| c.and_then(|c| Some(m.temps.get(c)? - t0.get(c)?)).unwrap_or(mean)).collect()
            }
            _ => vec![0.0; dof],
        })
        .collect();
    let lever_mm = (lever_mm > 0.0 && data.has_orientation() && reference.has_orientation()).then_some(lever_mm);
    let weights = data.has_position_std().then(|| {
        let stds: Vec<Vector3<f64>> = data.measurements.iter().filter_map(|m| m.position_std_mm).collect();
        let mean = stds.iter().map(|v| v.sum()).sum::<f64>() / (3 * stds.len()) as f64;
        stds.iter().map(|v| v.map(|s| mean / s)).collect()
    });
    let sin_cos = data.measurements.iter().map(|m| m.q.iter().map(|q| q.sin_cos()).collect()).collect();
    Pre { torques, rise, lever_mm, weights, sin_cos }
}
