//! The robot as a calibration identifies it: its chain (geometry, zero offsets, link errors) and the
//! corrections that depend on the joint values or on the operating state — gear-ratio and cyclic errors of
//! the joint variables, gravity compliance, thermal drift of rows each with its own law. What a robot file
//! carries ([`RobotModel`]) and every command evaluates at an [`OperatingState`].
//!
//! The forward model, in the order it is evaluated:
//!
//! 1. the joint values the chain sees: `q_j = c_j + Δq_j(c)` for the commanded values `c`, with
//!    `Δq_j = s_j c_j + a₁ sin c_j + b₁ cos c_j + a₂ sin 2c_j + b₂ cos 2c_j + k_j τ_j(c)` — a gear-ratio
//!    error `s`, the encoder's once- and twice-per-revolution error, and the compliance `k` (rad/(N·m))
//!    under the gravity torque `τ_j` of the link masses and the payload at the commanded configuration;
//! 2. the chain in force: the chain's own error parameters plus, for each drift row, its deviation times
//!    its law's factor at the state — a [`TimeProfile`]'s `f(t)` (the paper's table grown with operating
//!    time, section 4) or the mean temperature rise of named sensors over their reference (per kelvin) —
//!    and, for a joint with a lateral compliance, its row tilted (and a slide's shifted) by the gravity
//!    moments across the joint at the commanded configuration ([`lateral_row_error`],
//!    [`thermokin_chain::lateral_gravity_moments_into`]);
//! 3. eq. 22 of that chain at `q`.
//!
//! The authors' case studies — one deviation table, one profile for every row — are the special case
//! [`RobotModel::with_table`]: the chain in force is `profile.table_at(table, t)` applied canonically.
//!
//! Inverse kinematics solves step 3 for `q` on the chain in force, and [`RobotModel::commanded_for`]
//! inverts step 1 (a fixed point: the corrections' derivative is far below 1), so that a program carries
//! the values to command.

use nalgebra::{Isometry3, Unit, Vector3};
use thermokin_chain::{Chain, ErrorParams, JointKind, LinkMass, OperatingState, Robot};

use crate::{AfterStabilization, DeformError, DeviationTable, Row, StateError, TableSemantics, TimeProfile};

/// Joint-variable corrections of one joint, beyond the zero offset the chain holds: `Δq = s·q + a₁ sin q
/// + b₁ cos q + a₂ sin 2q + b₂ cos 2q + k·τ` (radians; mm for a prismatic joint's scale), and a coupling
/// with the next joint: `c·τ_next` on this joint, `c·τ_this` on the next ([`RobotModel::joint_values`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointCorrection {
    /// Gear-ratio (scale) error `s`, dimensionless.
    pub scale: f64,
    /// Cyclic encoder error `[a₁, b₁, a₂, b₂]`, radians (revolute joints only).
    pub cyclic_rad: [f64; 4],
    /// Gravity compliance `k`, radians per N·m (revolute joints only).
    pub compliance_rad_per_nm: f64,
    /// The coupling `c` of this joint's compliance with the next joint's, radians per N·m: this joint
    /// moves by `c · τ_next` and the next by `c · τ_this` (a drive the two share; revolute joints only,
    /// zero on the last joint).
    pub coupling_rad_per_nm: f64,
    /// Lateral compliance `[c₁, c₂, c′₁, c′₂, s₁, s₂]` under the gravity moments `Mₖ` across the joint
    /// ([`lateral_row_error`]): its row tilts by `cₖ Mₖ` (rad per N·m); a slide's also as a beam of its
    /// extension's length, `c′ₖ` (rad per N·m per mm), and shifts by `sₖ Mₖ` (mm per N·m) — `c′` and `s`
    /// zero for a revolute joint.
    pub lateral: [f64; 6],
    /// Straightness of a slide's guide `[κ₁, κ₂, ρ, σ₁, σ₂]` ([`straightness_row_error`]): its row tilts by
    /// `κₖ d` about the two directions across its axis and rolls by `ρ d` about it (rad per mm of extension
    /// `d`), and its carriage bows across by `σₖ d²` (per mm) — zero for a revolute joint.
    pub straightness: [f64; 5],
    /// Backlash `b`, radians (mm for a slide): the joint sits `b · s` from its commanded value, `s` = ±1
    /// the direction it last moved in ([`thermokin_chain::Approach`]) — half the play between its gears'
    /// flanks; negative when the joint trails its motion (a link behind a motor-side encoder). Needs the
    /// direction in the operating state.
    pub backlash: f64,
}

impl JointCorrection {
    /// No correction.
    pub const NONE: JointCorrection = JointCorrection {
        scale: 0.0,
        cyclic_rad: [0.0; 4],
        compliance_rad_per_nm: 0.0,
        coupling_rad_per_nm: 0.0,
        lateral: [0.0; 6],
        straightness: [0.0; 5],
        backlash: 0.0,
    };

    /// `true` when every coefficient is zero.
    pub fn is_none(&self) -> bool {
        *self == Self::NONE
    }

    /// `true` when the correction moves the joint's value (anything but a lateral compliance or a slide's
    /// straightness, which tilt its row).
    pub fn moves_joint(&self) -> bool {
        JointCorrection { lateral: [0.0; 6], straightness: [0.0; 5], ..*self } != Self::NONE
    }

    /// `true` when the joint's row changes with the configuration (a lateral compliance, a slide's
    /// straightness).
    pub fn bends(&self) -> bool {
        self.lateral != [0.0; 6] || self.straightness != [0.0; 5]
    }

    /// `Δq` at commanded value `q` under gravity torque `torque_nm`.
    pub fn delta(&self, q: f64, torque_nm: f64) -> f64 {
        let [a1, b1, a2, b2] = self.cyclic_rad;
        let cyclic = if self.cyclic_rad == [0.0; 4] {
            0.0
        } else {
            a1 * q.sin() + b1 * q.cos() + a2 * (2.0 * q).sin() + b2 * (2.0 * q).cos()
        };
        self.scale * q + cyclic + self.compliance_rad_per_nm * torque_nm
    }
}

/// The error a lateral compliance adds to a joint's row (eq. 19's angles and the row's translation, in
/// its parent's frame) under the gravity moments `[M₁, M₂]` across it (N·m) along its two lateral
/// `directions` `eₖ` ([`thermokin_chain::lateral_directions`]), `axis` its unit axis, `d` a slide's
/// extension (mm), `c` the coefficients `[c₁, c₂, c′₁, c′₂, s₁, s₂]` (missing ones zero: a revolute
/// joint's two):
///
/// `Δθ = Σₖ (cₖ + c′ₖ d) Mₖ eₖ`, `Δp = Σₖ (sₖ − c′ₖ d²/2) Mₖ (eₖ × a)`.
///
/// The row sits at the slide's foot, before its travel: `c′` is a beam of the extension's length under
/// the moment at its tip — curvature `c′M`, so the tip turns by `c′Md` and moves across by `c′Md²/2`:
/// the row's turn at the foot moves it by `c′Md²`, its shift takes `c′Md²/2` back — and `c`, `s` a
/// compliant foot (a mount, the column's fixed part) turning and shifting in proportion to the moment.
/// For a revolute joint the first term alone: a bearing tilting under the arm's moment.
pub fn lateral_row_error(
    c: &[f64],
    directions: &[Vector3<f64>; 2],
    axis: &Vector3<f64>,
    moments: [f64; 2],
    d: f64,
) -> ErrorParams {
    let at = |i: usize| c.get(i).copied().unwrap_or(0.0);
    let (mut rotation, mut translation) = (Vector3::zeros(), Vector3::zeros());
    for k in 0..2 {
        rotation += directions[k] * ((at(k) + at(2 + k) * d) * moments[k]);
        translation += directions[k].cross(axis) * ((at(4 + k) - 0.5 * at(2 + k) * d * d) * moments[k]);
    }
    ErrorParams::new(translation, rotation)
}

/// The load of one of the robot's branches ([`thermokin_chain::Branch`]) on joint `joint`'s gravity
/// compliance: `Δq_joint += Σ θ_b g_b(q, q_branch)` over the functions of
/// [`thermokin_chain::branch_load_basis_into`] at the commanded joints and the branch's joint values —
/// read from the operating state by the branch joints' names (degrees; mm for a slide), as a
/// measurement file logs them. Known without masses, the weights lump the joint's stiffness with the
/// branch links' unknown first moments (radians); when the branch carries masses
/// ([`thermokin_chain::Branch::carries_masses`]) the one function is the torque (N·m) of everything the
/// joint carries — the chain's links with the model's masses and payload, and the branch's
/// ([`thermokin_chain::branch_load_functions_into`]) — and the weight the joint's compliance (radians per N·m);
/// across the axis, one per lateral direction.
#[derive(Clone, Debug, PartialEq)]
pub struct BranchLoad {
    /// The loaded joint, 0-based.
    pub joint: usize,
    /// The branch's name.
    pub branch: String,
    /// The weights, radians (radians per N·m for a branch that carries masses).
    pub weights: Vec<f64>,
    /// Whether the load tilts the joint's row across its axis — a bearing under the branch's moment:
    /// [`lumped_lateral_row_error`]'s one set over [`thermokin_chain::branch_lateral_basis_into`]'s
    /// functions — rather than turning the joint about it.
    pub lateral: bool,
}

/// The joint values of `branch` in `state`: each joint's reading by its name (or `temp_NAME`), converted
/// by [`thermokin_chain::Branch::joint_value`]; an error naming the first missing.
fn branch_joint_values(branch: &thermokin_chain::Branch, state: &OperatingState) -> Result<Vec<f64>, DeformError> {
    branch
        .joints
        .iter()
        .enumerate()
        .map(|(i, j)| {
            let reading = state.temperature(&j.name).or_else(|| state.temperature(&format!("temp_{}", j.name)));
            reading.map(|r| branch.joint_value(i, r)).ok_or_else(|| DeformError::MissingState {
                needed: format!(
                    "the position of joint `{}` of branch `{}` (degrees; mm for a slide)",
                    j.name, branch.name
                ),
                why: "what hangs from that branch loads the joints below it".into(),
            })
        })
        .collect()
}

/// Per joint of `chain` (one entry each) none, or as many finite weights as `expected` gives the joint
/// (`thermokin_chain::gravity_load_basis_len` or `lateral_load_basis_len`, zero where it takes none): a
/// compliance known without masses, `kind` `"gravity"` or `"lateral"`.
fn check_load_weights(
    chain: &Chain,
    loads: &[Vec<f64>],
    expected: fn(&Chain, usize) -> usize,
    kind: &str,
) -> Result<(), DeformError> {
    if loads.len() != chain.dof() {
        return Err(DeformError::RowCount { rows: loads.len(), joints: chain.dof() });
    }
    for (j, l) in loads.iter().enumerate().filter(|(_, l)| !l.is_empty()) {
        let expected = expected(chain, j);
        let bad = |message: String| Err(DeformError::BadCorrection { joint: j + 1, message });
        if expected == 0 {
            return bad(format!("a {kind} compliance without masses is for a revolute joint"));
        }
        if l.len() != expected {
            return bad(format!("{} {kind}-load weights for the {expected} this joint's arm takes", l.len()));
        }
        if l.iter().any(|v| !v.is_finite()) {
            return bad(format!("every {kind}-load weight must be finite"));
        }
    }
    Ok(())
}

/// The tilts `[φ₁, φ₂]` of a lateral compliance known without masses: the weights times the functions of
/// [`thermokin_chain::lateral_load_basis_into`], the first half of each about the first direction.
pub fn lumped_tilts(basis: &[f64], weights: &[f64]) -> [f64; 2] {
    let half = basis.len() / 2;
    let dot = |k: usize| basis[k * half..(k + 1) * half].iter().zip(&weights[k * half..]).map(|(f, w)| f * w).sum();
    [dot(0), dot(1)]
}

/// How many weights a lateral compliance known without masses takes on joint `joint` (0-based): the
/// functions of [`thermokin_chain::lateral_load_basis_len`] once for a revolute joint (its bearing's
/// tilt), three times for a slide (a column's foot tilting, its beam bending over the extension, its
/// foot shifting: the three coefficients of [`lateral_row_error`], each lumped with the unknown moments);
/// zero past the chain.
pub fn lumped_lateral_weights_len(chain: &Chain, joint: usize) -> usize {
    let n = thermokin_chain::lateral_load_basis_len(chain, joint);
    match chain.joints().get(joint).map(|j| j.kind) {
        Some(JointKind::Prismatic) => 3 * n,
        _ => n,
    }
}

/// The error a lateral compliance known without masses adds to its joint's row at joint value `d` (a
/// slide's extension, mm): [`lateral_row_error`] at unit moments with its coefficients the weights' sums
/// over `basis` ([`thermokin_chain::lateral_load_basis_into`] at the pose) — `[c₁M₁, c₂M₂]` from the first
/// set of weights (a revolute joint's only one), `[c′₁M₁, c′₂M₂]` from a slide's second and
/// `[s₁M₁, s₂M₂]` from its third ([`lumped_lateral_weights_len`]): each product of a compliance and the
/// moment is linear in lumped weights, as [`thermokin_chain::lateral_load_basis_into`]'s span holds the
/// moments of any masses.
pub fn lumped_lateral_row_error(
    basis: &[f64],
    weights: &[f64],
    directions: &[Vector3<f64>; 2],
    axis: &Vector3<f64>,
    d: f64,
) -> ErrorParams {
    let n = basis.len();
    let set = |s: usize| weights.get(s * n..(s + 1) * n).map_or([0.0; 2], |w| lumped_tilts(basis, w));
    let [tilt, bend, shift] = [set(0), set(1), set(2)];
    lateral_row_error(&[tilt[0], tilt[1], bend[0], bend[1], shift[0], shift[1]], directions, axis, [1.0; 2], d)
}

/// [`lumped_lateral_row_error`] of joint `joint` of `chain`, along its lateral directions
/// ([`thermokin_chain::lateral_directions`]; none past the chain: no error) and axis, at its value `d`.
pub fn lumped_lateral_row_on(chain: &Chain, joint: usize, basis: &[f64], weights: &[f64], d: f64) -> ErrorParams {
    let (Some(directions), Some(j)) = (thermokin_chain::lateral_directions(chain, joint), chain.joints().get(joint))
    else {
        return ErrorParams::ZERO;
    };
    lumped_lateral_row_error(basis, weights, &directions, &j.axis.into_inner(), d)
}

/// The error a slide's straightness adds to its row (eq. 19's angles and the row's translation, in its
/// parent's frame) at extension `d` (mm), `directions` `eₖ` its two lateral directions
/// ([`thermokin_chain::lateral_directions`]), `axis` its unit axis `a`, `c = [κ₁, κ₂, ρ, σ₁, σ₂]`:
///
/// `Δθ = d (κ₁ e₁ + κ₂ e₂ + ρ a)`, `Δp = d² (σ₁ (e₁ × a) + σ₂ (e₂ × a))`.
///
/// The first-order terms of a linear axis' error motions (ISO 230-1: its pitch, yaw and roll growing
/// with the travel, its straightness bowing with its square) that the row's fixed geometry cannot take:
/// an angle or a shift proportional to `d` is an axis pointing another way — a link deviation. A carriage
/// on a guide bent to curvature `κ` turns by `κ d` and bows by `−κ d²/2` across: `σ = −κ/2`.
pub fn straightness_row_error(
    c: &[f64; 5],
    directions: &[Vector3<f64>; 2],
    axis: &Vector3<f64>,
    d: f64,
) -> ErrorParams {
    let rotation = (directions[0] * c[0] + directions[1] * c[1] + axis * c[2]) * d;
    let translation = (directions[0].cross(axis) * c[3] + directions[1].cross(axis) * c[4]) * (d * d);
    ErrorParams::new(translation, rotation)
}

/// How much of a drift row's deviation is in force in a given state.
#[derive(Clone, Debug, PartialEq)]
pub enum DriftLaw {
    /// The row is a deviation-table row grown by this profile's factor `f(t)` at operating time `t`
    /// (linear with or without plateau, exponential, cubic — [`TimeProfile::time_factor`]).
    Time(TimeProfile),
    /// The row is a deviation per kelvin of the mean rise of these sensors over their reference readings:
    /// `(name, reference °C)`. One sensor: the joint's own; several: their mean (how the diagnosis reads
    /// a joint without a sensor of its own).
    PerKelvin {
        /// `(sensor name, reference temperature °C)`.
        sensors: Vec<(String, f64)>,
    },
    /// The row turns with the tilt an accelerometer measures ([`thermokin_chain::TiltSensor::tilt`]): the
    /// factor is component `component` (0 x, 1 y, 2 z, the sensor's axes) of the tilt its reading
    /// (columns `NAME_x`, `NAME_y`, `NAME_z`, any unit proportional to g) shows against `reference` —
    /// radians, no gain: the row's deviation is how that component turns it.
    Tilt {
        /// The sensor's name.
        sensor: String,
        /// Which component of its tilt: 0, 1, 2.
        component: usize,
        /// Its reference direction (unit), in its axes.
        reference: [f64; 3],
    },
}

/// The tilt of accelerometer `name` in `state` from `reference` (its readings `NAME_x`, `NAME_y`,
/// `NAME_z`, or with the `temp_` prefix the command line adds).
fn measured_tilt(
    state: &OperatingState,
    name: &str,
    reference: [f64; 3],
    row: Row,
) -> Result<Vector3<f64>, DeformError> {
    let mut reading = [0.0; 3];
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let column = format!("{name}_{axis}");
        reading[k] =
            state.temperature(&column).or_else(|| state.temperature(&format!("temp_{column}"))).ok_or_else(|| {
                DeformError::MissingState {
                    needed: format!("the reading of accelerometer `{name}` (`{name}_x`, `{name}_y`, `{name}_z`)"),
                    why: format!("{} turns with the tilt it measures", row_name(row)),
                }
            })?;
    }
    thermokin_chain::TiltSensor::tilt(reading, reference).ok_or_else(|| DeformError::MissingState {
        needed: format!("a finite, non-zero reading of accelerometer `{name}`"),
        why: format!("got {reading:?}"),
    })
}

impl DriftLaw {
    /// A short description for messages: `exponential (τ = 45 min)`, `per kelvin of temp_j2`.
    pub fn describe(&self) -> String {
        match self {
            DriftLaw::Time(TimeProfile::Static) => "static".into(),
            DriftLaw::Time(TimeProfile::Linear { stabilization_min, after: AfterStabilization::Plateau }) => {
                format!("linear, full after {stabilization_min:.1} min")
            }
            DriftLaw::Time(TimeProfile::Linear { stabilization_min, after: AfterStabilization::KeepGrowing }) => {
                format!("linear, its deviation reached at {stabilization_min:.1} min and growing on")
            }
            DriftLaw::Time(TimeProfile::Exponential { tau_min }) => format!("exponential (τ = {tau_min:.1} min)"),
            DriftLaw::Time(TimeProfile::Cubic { .. }) => "cubic in time".into(),
            DriftLaw::Time(TimeProfile::Temperature { .. }) => "a temperature log".into(),
            DriftLaw::PerKelvin { sensors } => {
                let names: Vec<&str> = sensors.iter().map(|(n, _)| n.as_str()).collect();
                format!("per kelvin of {}", names.join(" + "))
            }
            DriftLaw::Tilt { sensor, component, .. } => {
                let axis = ["x", "y", "z"].get(*component).copied().unwrap_or("?");
                format!("with the tilt accelerometer {sensor} measures about its {axis}")
            }
        }
    }

    /// The factor in force at `state`; an error naming what the state lacks.
    pub fn factor(&self, state: &OperatingState, row: Row) -> Result<f64, DeformError> {
        match self {
            // A static row is in force at every time: no time needed.
            DriftLaw::Time(TimeProfile::Static) => Ok(1.0),
            DriftLaw::Time(profile) => {
                let t = state.time_min.ok_or_else(|| DeformError::MissingState {
                    needed: "an operating time (minutes)".into(),
                    why: format!(
                        "{} drifts with operating time, {}; give the time (0 is the cold robot)",
                        row_name(row),
                        self.describe()
                    ),
                })?;
                if !(t.is_finite() && t >= 0.0) {
                    return Err(DeformError::BadTime { time_min: t, reason: "time must be finite and ≥ 0".into() });
                }
                profile.time_factor(t).ok_or_else(|| DeformError::BadProfile {
                    field: "law",
                    message: "a drift row's time law cannot be a temperature log; use a per-kelvin law".into(),
                })
            }
            DriftLaw::PerKelvin { sensors } => {
                let mut rise = 0.0;
                for (name, reference) in sensors {
                    // A sensor that is not a temperature (an accelerometer's column, named as its file
                    // names it) is given at run time as the command lines give readings: `temp_` + name.
                    let given = state.temperature(name).or_else(|| state.temperature(&format!("temp_{name}")));
                    let now = given.ok_or_else(|| DeformError::MissingState {
                        needed: format!("the reading of sensor `{name}` (°C)"),
                        why: format!("{} drifts {}", row_name(row), self.describe()),
                    })?;
                    if !now.is_finite() {
                        return Err(DeformError::MissingState {
                            needed: format!("a finite reading of sensor `{name}`"),
                            why: format!("got {now}"),
                        });
                    }
                    rise += now - reference;
                }
                Ok(rise / sensors.len() as f64)
            }
            DriftLaw::Tilt { sensor, component, reference } => {
                Ok(measured_tilt(state, sensor, *reference, row)?.get(*component).copied().unwrap_or(0.0))
            }
        }
    }
}

/// A row of the table that drifts: its deviation (at factor 1, or per kelvin) and its law.
#[derive(Clone, Debug, PartialEq)]
pub struct DriftRow {
    /// Base, joint (0-based) or tool row.
    pub row: Row,
    /// The six error parameters at factor 1 (mm, radians).
    pub deviation: ErrorParams,
    /// How much of it is in force.
    pub law: DriftLaw,
}

/// `joint 2's row`, `the base row`.
fn row_name(row: Row) -> String {
    match row {
        Row::Base => "the base row".into(),
        Row::Joint(j) => format!("joint {}'s row", j + 1),
        Row::Tool => "the tool row".into(),
    }
}

/// The largest `|Δq(c) − Δq(c′)| / |c − c′|` for which [`RobotModel::commanded_for`]'s fixed point is
/// trusted; beyond it (a correction of the order of the joint motion itself) the model is refused.
pub const MAX_CORRECTION_SLOPE: f64 = 0.1;
/// Iterations of the fixed point: each gains a factor of at least 1/[`MAX_CORRECTION_SLOPE`]; in practice
/// (slopes ~1e-3) three or four reach machine precision.
const MAX_FIXED_POINT_ITERATIONS: usize = 60;
/// Agreement sought for the inverted joint values, radians (mm): 1e-14 rad moves a point 10 m away by
/// 1e-10 mm, a tenth of the IK's 1e-9 mm tolerance, so inverting adds nothing measurable to a compensated
/// pose; a few ulps of a joint value of 2π (~9e-16 each).
const INVERSION_TARGET: f64 = 1e-14;
/// Agreement accepted when rounding stops the fixed point short of [`INVERSION_TARGET`].
const INVERSION_TOLERANCE: f64 = 1e-12;

/// A robot with every correction a calibration identified: see the module documentation for the law.
/// Built from a [`Robot`] (a model with no corrections is the robot itself), checked on construction.
///
/// ```
/// use thermokin_chain::{OperatingState, Robot};
/// use thermokin_deform::{JointCorrection, RobotModel};
///
/// let robot = Robot::new("IRB 140", thermokin_testdata::irb140_table9());
/// // Joint 1's gear ratio 0.1 % long.
/// let mut corrections = vec![JointCorrection::NONE; 6];
/// corrections[0].scale = 1e-3;
/// let model = RobotModel::new(robot).with_joint_corrections(corrections)?;
/// let commanded = [0.5, 0.1, 0.2, 0.0, 0.3, 0.0];
/// let state = OperatingState::default();
/// let seen = model.joint_values(&commanded, &state)?;
/// assert!((seen[0] - 0.5 * 1.001).abs() < 1e-15);
/// // The values to command for the joint values the chain must take:
/// let back = model.commanded_for(&seen, &state)?;
/// assert!((back[0] - 0.5).abs() < 1e-12);
/// # Ok::<(), thermokin_deform::DeformError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct RobotModel {
    robot: Robot,
    joints: Vec<JointCorrection>,
    /// Per joint: the weights of a gravity compliance known without masses (empty when none).
    gravity_loads: Vec<Vec<f64>>,
    /// Per joint: the weights of a lateral compliance known without masses (empty when none).
    lateral_loads: Vec<Vec<f64>>,
    /// The loads of the robot's branches on its joints' compliance ([`BranchLoad`]).
    branch_loads: Vec<BranchLoad>,
    drift: Vec<DriftRow>,
    payload: Option<LinkMass>,
    down: Unit<Vector3<f64>>,
}

impl RobotModel {
    /// The robot with no corrections, no payload, gravity along its world −Z.
    pub fn new(robot: Robot) -> Self {
        let n = robot.chain().dof();
        Self {
            robot,
            joints: vec![JointCorrection::NONE; n],
            gravity_loads: vec![Vec::new(); n],
            lateral_loads: vec![Vec::new(); n],
            branch_loads: Vec::new(),
            drift: Vec::new(),
            payload: None,
            down: -Vector3::z_axis(),
        }
    }

    /// The same model with these joint corrections (one per joint; finite; cyclic terms and compliance on
    /// revolute joints only).
    pub fn with_joint_corrections(mut self, joints: Vec<JointCorrection>) -> Result<Self, DeformError> {
        let chain = self.robot.chain();
        if joints.len() != chain.dof() {
            return Err(DeformError::RowCount { rows: joints.len(), joints: chain.dof() });
        }
        for (j, (c, joint)) in joints.iter().zip(chain.joints()).enumerate() {
            let bad = |message: String| Err(DeformError::BadCorrection { joint: j + 1, message });
            let all = [c.scale, c.compliance_rad_per_nm, c.coupling_rad_per_nm, c.backlash]
                .into_iter()
                .chain(c.cyclic_rad)
                .chain(c.lateral)
                .chain(c.straightness);
            if all.clone().any(|v| !v.is_finite()) {
                return bad("every coefficient must be finite".into());
            }
            if joint.kind == JointKind::Prismatic
                && (c.cyclic_rad != [0.0; 4] || c.compliance_rad_per_nm != 0.0 || c.coupling_rad_per_nm != 0.0)
            {
                return bad("cyclic terms and gravity compliance are for revolute joints".into());
            }
            if joint.kind == JointKind::Revolute && c.lateral[2..] != [0.0; 4] {
                return bad("a lateral compliance's extension and shift terms are a slide's".into());
            }
            if joint.kind == JointKind::Revolute && c.straightness != [0.0; 5] {
                return bad("straightness is a slide's guide".into());
            }
            if c.coupling_rad_per_nm != 0.0
                && chain.joints().get(j + 1).is_none_or(|next| next.kind != JointKind::Revolute)
            {
                return bad("a compliance coupling is with the next joint, which must be revolute".into());
            }
            if c.scale.abs() + c.cyclic_rad.iter().map(|a| a.abs() * 2.0).sum::<f64>() > MAX_CORRECTION_SLOPE {
                return bad(format!(
                    "the scale and cyclic terms change the joint value by more than {} % of its motion: not a correction",
                    MAX_CORRECTION_SLOPE * 100.0
                ));
            }
        }
        self.joints = joints;
        Ok(self)
    }

    /// The same model with a gravity compliance known without masses on some joints: per joint (one entry
    /// each) none, or the weights `θ` of `Δq = Σ θ_b f_b(q)` (radians; radians per mm for a term of a
    /// slide it carries) over the functions of [`thermokin_chain::gravity_load_basis_into`] at the
    /// commanded joint values — the joint's stiffness lumped with the unknown first moments of the links
    /// it carries, as calibrated (a payload given at use does not change them).
    pub fn with_gravity_loads(mut self, loads: Vec<Vec<f64>>) -> Result<Self, DeformError> {
        check_load_weights(self.robot.chain(), &loads, thermokin_chain::gravity_load_basis_len, "gravity")?;
        self.gravity_loads = loads;
        Ok(self)
    }

    /// The same model with a lateral compliance known without masses on some joints: per joint (one entry
    /// each) none, or the weights `θ` of its row's tilts `φₖ = Σ θₖ,b fₖ,b(q)` about its two lateral
    /// directions (radians; radians per mm for a term of a slide it carries) over the functions of
    /// [`thermokin_chain::lateral_load_basis_into`] at the commanded joint values (the first half about
    /// the first direction) — the bearing's compliance lumped with the unknown first moments of the links
    /// it carries, as calibrated; for a slide three such sets, its foot's tilt, its bending and its foot's
    /// shift ([`lumped_lateral_row_error`], [`lumped_lateral_weights_len`]).
    pub fn with_lateral_loads(mut self, loads: Vec<Vec<f64>>) -> Result<Self, DeformError> {
        check_load_weights(self.robot.chain(), &loads, lumped_lateral_weights_len, "lateral")?;
        self.lateral_loads = loads;
        Ok(self)
    }

    /// The same model with the loads of its robot's branches on some joints' gravity compliance
    /// ([`BranchLoad`]): each on a revolute joint below the branch's link, with as many finite weights as
    /// [`thermokin_chain::branch_load_basis_len`] gives.
    pub fn with_branch_loads(mut self, loads: Vec<BranchLoad>) -> Result<Self, DeformError> {
        let chain = self.robot.chain();
        for l in &loads {
            let bad = |message: String| Err(DeformError::BadCorrection { joint: l.joint + 1, message });
            let Some(branch) = self.robot.branches().iter().find(|b| b.name == l.branch) else {
                let known: Vec<&str> = self.robot.branches().iter().map(|b| b.name.as_str()).collect();
                return bad(format!("the robot has no branch `{}` (its branches: {})", l.branch, known.join(", ")));
            };
            let expected = if l.lateral {
                thermokin_chain::branch_lateral_basis_len(chain, branch, l.joint)
            } else {
                thermokin_chain::branch_load_basis_len(chain, branch, l.joint)
            };
            if expected == 0 {
                return bad(format!(
                    "branch `{}` loads only the revolute joints below its link {}",
                    l.branch, branch.link
                ));
            }
            if l.weights.len() != expected || l.weights.iter().any(|w| !w.is_finite()) {
                return bad(format!(
                    "{} branch-load weights of `{}` for the {expected} finite ones it takes",
                    l.weights.len(),
                    l.branch
                ));
            }
        }
        self.branch_loads = loads;
        Ok(self)
    }

    /// The loads of the robot's branches on its joints' compliance: [`RobotModel::with_branch_loads`].
    pub fn branch_loads(&self) -> &[BranchLoad] {
        &self.branch_loads
    }

    /// The same model with these drift rows (any number per row; their deviations add).
    pub fn with_drift(mut self, drift: Vec<DriftRow>) -> Result<Self, DeformError> {
        let dof = self.robot.chain().dof();
        for d in &drift {
            if let Row::Joint(j) = d.row
                && j >= dof
            {
                return Err(DeformError::RowCount { rows: j + 1, joints: dof });
            }
            if !d.deviation.is_finite() {
                return Err(DeformError::BadProfile {
                    field: "deviation",
                    message: format!("{}: every deviation must be finite", row_name(d.row)),
                });
            }
            match &d.law {
                DriftLaw::Time(TimeProfile::Temperature { .. }) => {
                    return Err(DeformError::BadProfile {
                        field: "law",
                        message: format!(
                            "{}: a per-row law is a time profile or per kelvin of named sensors",
                            row_name(d.row)
                        ),
                    });
                }
                DriftLaw::Time(p) => p.validate(dof)?,
                DriftLaw::Tilt { sensor, component, reference } => {
                    if sensor.is_empty() || *component > 2 || (Vector3::from(*reference).norm() - 1.0).abs() > 1e-6 {
                        return Err(DeformError::BadProfile {
                            field: "tilt",
                            message: format!(
                                "{}: a tilt law names its sensor, a component 0–2 and unit reference directions",
                                row_name(d.row)
                            ),
                        });
                    }
                }
                DriftLaw::PerKelvin { sensors } => {
                    if sensors.is_empty() || sensors.iter().any(|(n, t)| n.is_empty() || !t.is_finite()) {
                        return Err(DeformError::BadProfile {
                            field: "sensors",
                            message: format!(
                                "{}: a per-kelvin law names at least one sensor, each with a finite reference temperature",
                                row_name(d.row)
                            ),
                        });
                    }
                }
            }
        }
        self.drift = drift;
        Ok(self)
    }

    /// The authors' case: every row of `table` drifting with the one `profile` (a time profile). The chain
    /// in force at time `t` is the table at `t` applied canonically to the robot's chain.
    pub fn with_table(self, table: &DeviationTable, profile: &TimeProfile) -> Result<Self, DeformError> {
        if table.dof() != self.robot.chain().dof() {
            return Err(DeformError::RowCount { rows: table.dof(), joints: self.robot.chain().dof() });
        }
        let rows = std::iter::once((Row::Base, table.base))
            .chain(table.joints.iter().enumerate().map(|(j, e)| (Row::Joint(j), *e)))
            .chain(std::iter::once((Row::Tool, table.tool)))
            .filter(|(_, e)| !e.is_zero())
            .map(|(row, deviation)| DriftRow { row, deviation, law: DriftLaw::Time(profile.clone()) });
        let mut drift = self.drift.clone();
        drift.extend(rows);
        self.with_drift(drift)
    }

    /// The same model carrying `payload` by default (the one it was calibrated with); a state's payload
    /// replaces it.
    pub fn with_payload(mut self, payload: Option<LinkMass>) -> Result<Self, DeformError> {
        if let Some(p) = payload {
            // The robot checks mass and centre.
            self.robot.clone().with_payload(p)?;
        }
        self.payload = payload;
        Ok(self)
    }

    /// The same model with gravity along `down` in the chain's world frame (−Z for a level floor mount;
    /// a tracker-registered base row turns it).
    pub fn with_gravity(mut self, down: Unit<Vector3<f64>>) -> Self {
        self.down = down;
        self
    }

    /// The same corrections on another robot of as many joints (a renamed robot, another tool or base
    /// row, a chain deformed by a further table).
    pub fn with_robot(mut self, robot: Robot) -> Result<Self, DeformError> {
        let expected = self.robot.chain().dof();
        if robot.chain().dof() != expected {
            return Err(DeformError::RowCount { rows: robot.chain().dof(), joints: expected });
        }
        self.robot = robot;
        Ok(self)
    }

    /// The robot (its chain: geometry, zero offsets, link errors — the model cold, unloaded).
    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    /// The joint corrections, one per joint.
    pub fn joint_corrections(&self) -> &[JointCorrection] {
        &self.joints
    }

    /// Per joint, the weights of a gravity compliance known without masses (empty when none):
    /// [`RobotModel::with_gravity_loads`].
    pub fn gravity_loads(&self) -> &[Vec<f64>] {
        &self.gravity_loads
    }

    /// Per joint, the weights of a lateral compliance known without masses (empty when none):
    /// [`RobotModel::with_lateral_loads`].
    pub fn lateral_loads(&self) -> &[Vec<f64>] {
        &self.lateral_loads
    }

    /// `true` when the joint values the chain sees differ from the commanded ones (a gear ratio, a cyclic
    /// error, a compliance with or without masses).
    pub fn corrects_joints(&self) -> bool {
        self.joints.iter().any(JointCorrection::moves_joint)
            || self.gravity_loads.iter().any(|l| !l.is_empty())
            || self.branch_loads.iter().any(|l| !l.lateral)
    }

    /// `true` when some joint has a backlash: its value then depends on the direction it last moved in
    /// ([`OperatingState::approach`]).
    pub fn has_backlash(&self) -> bool {
        self.joints.iter().any(|c| c.backlash != 0.0)
    }

    /// `true` when some joint's row tilts with the configuration (a lateral compliance, a slide's
    /// straightness): the chain in force then depends on the joint values ([`RobotModel::chain_at_joints`]).
    pub fn bends(&self) -> bool {
        self.joints.iter().any(JointCorrection::bends)
            || self.lateral_loads.iter().any(|l| !l.is_empty())
            || self.branch_loads.iter().any(|l| l.lateral)
    }

    /// The drift rows.
    pub fn drift(&self) -> &[DriftRow] {
        &self.drift
    }

    /// The payload carried by default.
    pub fn payload(&self) -> Option<LinkMass> {
        self.payload
    }

    /// Gravity's direction in the chain's world frame.
    pub fn gravity(&self) -> Unit<Vector3<f64>> {
        self.down
    }

    /// `true` when the model is its robot's chain alone: no joint correction and no drift.
    pub fn is_plain(&self) -> bool {
        self.drift.is_empty() && !self.corrects_joints() && !self.bends()
    }

    /// `true` for the robot as designed: plain ([`RobotModel::is_plain`]) with no error parameter and no
    /// zero offset in its chain — nothing a compensation could correct.
    pub fn is_nominal(&self) -> bool {
        let chain = self.robot.chain();
        self.is_plain()
            && chain.base().error.is_zero()
            && chain.tool().error.is_zero()
            && chain.joints().iter().all(|j| j.error.is_zero() && j.zero == 0.0)
    }

    /// The robot as described, refused when it carries identified corrections (a diagnosis or a
    /// simulation starts from the geometry alone).
    pub fn require_plain(&self) -> Result<&Robot, DeformError> {
        if self.is_plain() {
            Ok(&self.robot)
        } else {
            Err(DeformError::CarriesCorrections { corrections: self.beyond_urdf() })
        }
    }

    /// Checks a state against what the robot can use: a time only when a row drifts with time (or
    /// `with_table`: a table is given to grow with it), sensor readings only of sensors some row follows,
    /// a profile only with a table.
    pub fn check_state(&self, state: &OperatingState, with_table: bool, with_profile: bool) -> Result<(), DeformError> {
        let (time, sensors) = self.needs();
        let refuse = |e| Err(DeformError::State(e));
        if with_profile && !with_table {
            return refuse(StateError::ProfileWithoutTable);
        }
        if state.time_min.is_some() && !time && !with_table {
            return refuse(StateError::TimeWithoutDrift);
        }
        // A sensor that is not a temperature is named as its file names it (`acc_col_x`); the command
        // line and targets files give every reading with the `temp_` prefix: either spelling reads it.
        let reads = |given: &str| sensors.iter().any(|s| given == s || given.strip_prefix("temp_") == Some(s.as_str()));
        if let Some((unknown, _)) = state.temperatures_c.iter().find(|(n, _)| !reads(n)) {
            return refuse(StateError::UnknownSensor { name: unknown.clone(), known: sensors });
        }
        let joints = self.robot.chain().dof();
        match state.approach.len() {
            0 => {}
            _ if !self.has_backlash() => return refuse(StateError::ApproachWithoutBacklash),
            given if given != joints => return refuse(StateError::ApproachCount { given, joints }),
            _ => {}
        }
        Ok(())
    }

    /// Whether any row drifts with operating time; the sensors some row's drift reads.
    pub fn needs(&self) -> (bool, Vec<String>) {
        let time = self.drift.iter().any(|d| matches!(&d.law, DriftLaw::Time(p) if *p != TimeProfile::Static));
        let mut sensors: Vec<String> = Vec::new();
        for d in &self.drift {
            let mut names: Vec<String> = Vec::new();
            match &d.law {
                DriftLaw::PerKelvin { sensors: s } => names.extend(s.iter().map(|(n, _)| n.clone())),
                DriftLaw::Tilt { sensor, .. } => names.extend(["x", "y", "z"].map(|a| format!("{sensor}_{a}"))),
                DriftLaw::Time(_) => {}
            }
            for n in names {
                if !sensors.contains(&n) {
                    sensors.push(n);
                }
            }
        }
        for l in &self.branch_loads {
            let joints = self.robot.branches().iter().filter(|b| b.name == l.branch).flat_map(|b| &b.joints);
            for j in joints {
                if !sensors.contains(&j.name) {
                    sensors.push(j.name.clone());
                }
            }
        }
        (time, sensors)
    }

    /// What a URDF file cannot hold, one line per item (URDF has geometry and zero offsets only).
    pub fn beyond_urdf(&self) -> Vec<String> {
        let names: Vec<&str> = self.robot.chain().joints().iter().map(|j| j.name.as_str()).collect();
        let mut out = Vec::new();
        for (j, c) in self.joints.iter().enumerate() {
            if c.scale != 0.0 {
                out.push(format!("joint {} ({}): gear-ratio error {:.6e}", j + 1, names[j], c.scale));
            }
            if c.cyclic_rad != [0.0; 4] {
                out.push(format!("joint {} ({}): cyclic encoder error", j + 1, names[j]));
            }
            if c.compliance_rad_per_nm != 0.0 {
                out.push(format!("joint {} ({}): gravity compliance", j + 1, names[j]));
            }
            if c.coupling_rad_per_nm != 0.0 {
                out.push(format!("joints {} and {}: compliance coupling", j + 1, j + 2));
            }
            if !self.gravity_loads[j].is_empty() {
                out.push(format!("joint {} ({}): gravity compliance without masses", j + 1, names[j]));
            }
            for l in self.branch_loads.iter().filter(|l| l.joint == j) {
                let on = if l.lateral { "lateral compliance" } else { "compliance" };
                out.push(format!("joint {} ({}): the load of branch `{}` on its {on}", j + 1, names[j], l.branch));
            }
            if c.lateral != [0.0; 6] {
                out.push(format!("joint {} ({}): lateral compliance", j + 1, names[j]));
            }
            if !self.lateral_loads[j].is_empty() {
                out.push(format!("joint {} ({}): lateral compliance without masses", j + 1, names[j]));
            }
            if c.straightness != [0.0; 5] {
                out.push(format!("joint {} ({}): straightness of its guide", j + 1, names[j]));
            }
            if c.backlash != 0.0 {
                out.push(format!("joint {} ({}): backlash (needs the direction it last moved in)", j + 1, names[j]));
            }
        }
        for d in &self.drift {
            out.push(format!("{}: thermal drift, {}", row_name(d.row), d.law.describe()));
        }
        out
    }

    /// The deviation in force at `state`: each drift row times its law's factor, summed per row.
    pub fn drift_at(&self, state: &OperatingState) -> Result<DeviationTable, DeformError> {
        let mut table = DeviationTable::zeros(self.robot.chain().dof());
        for d in &self.drift {
            let add = d.deviation.scaled(d.law.factor(state, d.row)?);
            match d.row {
                Row::Base => table.base = table.base.add(&add),
                Row::Joint(j) => table.joints[j] = table.joints[j].add(&add),
                Row::Tool => table.tool = table.tool.add(&add),
            }
        }
        Ok(table)
    }

    /// The chain in force at `state`: the robot's chain with the drift in force added to its rows.
    pub fn chain_at(&self, state: &OperatingState) -> Result<Chain, DeformError> {
        if self.drift.is_empty() {
            return Ok(self.robot.chain().clone());
        }
        self.drift_at(state)?.apply(self.robot.chain(), &TableSemantics::Canonical)
    }

    /// The chain in force at `state` when `commanded` is commanded: [`RobotModel::chain_at`] with each
    /// lateral compliance's tilt at the configuration added to its row (step 2 of the law). The same chain
    /// as `chain_at` for a model that does not bend.
    pub fn chain_at_joints(&self, state: &OperatingState, commanded: &[f64]) -> Result<Chain, DeformError> {
        let mut chain = self.chain_at(state)?;
        if !self.bends() {
            return Ok(chain);
        }
        let mut moments = Vec::new();
        if self.joints.iter().any(|c| c.lateral != [0.0; 6]) {
            let masses = self.masses_in(state);
            thermokin_chain::lateral_gravity_moments_into(
                self.robot.chain(),
                &masses,
                commanded,
                None,
                &self.down,
                &mut moments,
            )?;
        }
        for (j, c) in self.joints.iter().enumerate().filter(|(_, c)| c.bends()) {
            let Some(directions) = thermokin_chain::lateral_directions(self.robot.chain(), j) else { continue };
            let axis = self.robot.chain().joints()[j].axis.into_inner();
            let moments = moments.get(j).copied().unwrap_or([0.0; 2]);
            let bend = lateral_row_error(&c.lateral, &directions, &axis, moments, commanded[j])
                .add(&straightness_row_error(&c.straightness, &directions, &axis, commanded[j]));
            let row = chain.joints()[j].error.add(&bend);
            chain.set_joint_error(j, row)?;
        }
        let mut basis = Vec::new();
        for (j, weights) in self.lateral_loads.iter().enumerate().filter(|(_, l)| !l.is_empty()) {
            let plain = self.robot.chain();
            thermokin_chain::lateral_load_basis_into(plain, commanded, None, &self.down, j, &mut basis)?;
            let bend = lumped_lateral_row_on(plain, j, &basis, weights, commanded[j]);
            let row = chain.joints()[j].error.add(&bend);
            chain.set_joint_error(j, row)?;
        }
        for l in self.branch_loads.iter().filter(|l| l.lateral) {
            let Some(branch) = self.robot.branches().iter().find(|b| b.name == l.branch) else { continue };
            let branch_q = branch_joint_values(branch, state)?;
            let plain = self.robot.chain();
            let (j, down) = (l.joint, &self.down);
            let (masses, joints) = (self.masses_in(state), (commanded, branch_q.as_slice()));
            thermokin_chain::branch_load_functions_into(plain, &masses, branch, joints, down, (j, true), &mut basis)?;
            let bend = lumped_lateral_row_on(plain, j, &basis, &l.weights, commanded[j]);
            let row = chain.joints()[j].error.add(&bend);
            chain.set_joint_error(j, row)?;
        }
        Ok(chain)
    }

    /// The link masses with the state's payload (or the model's) merged into the last link's, as
    /// [`Robot::with_payload`] merges them, without copying the chain.
    fn masses_in(&self, state: &OperatingState) -> std::borrow::Cow<'_, [Option<LinkMass>]> {
        let Some(payload) = state.payload.or(self.payload) else {
            return std::borrow::Cow::Borrowed(self.robot.masses());
        };
        let mut masses = self.robot.masses().to_vec();
        if let Some(last) = masses.last_mut() {
            *last = Some(last.map_or(payload, |link| link.combined_with(payload)));
        }
        std::borrow::Cow::Owned(masses)
    }

    /// Gravity torques at commanded `q` with the state's payload (or the model's) on the last link, N·m
    /// (this runs at every step of every inversion).
    fn torques(&self, q: &[f64], state: &OperatingState) -> Result<Vec<f64>, DeformError> {
        Ok(thermokin_chain::gravity_torques(self.robot.chain(), &self.masses_in(state), q, &self.down)?)
    }

    /// The joint values the chain sees when `commanded` is commanded in `state` (step 1 of the law).
    pub fn joint_values(&self, commanded: &[f64], state: &OperatingState) -> Result<Vec<f64>, DeformError> {
        self.robot.chain().check_joint_count(commanded)?;
        if !self.corrects_joints() {
            return Ok(commanded.to_vec());
        }
        let torques = if self.joints.iter().any(|c| c.compliance_rad_per_nm != 0.0 || c.coupling_rad_per_nm != 0.0) {
            self.torques(commanded, state)?
        } else {
            vec![0.0; commanded.len()]
        };
        let mut actual: Vec<f64> =
            commanded.iter().zip(&self.joints).zip(&torques).map(|((&c, k), &t)| c + k.delta(c, t)).collect();
        // A coupling moves both joints of its pair, each by the other's torque.
        for (j, k) in self.joints.iter().enumerate().filter(|(_, k)| k.coupling_rad_per_nm != 0.0) {
            actual[j] += k.coupling_rad_per_nm * torques[j + 1];
            actual[j + 1] += k.coupling_rad_per_nm * torques[j];
        }
        if let Some(j) = self.joints.iter().position(|k| k.backlash != 0.0) {
            if state.approach.len() != commanded.len() {
                return Err(DeformError::MissingState {
                    needed: format!(
                        "the direction each of the {} joints last moved in (+, - or ?: the state's approach, --approach on the command line)",
                        commanded.len()
                    ),
                    why: format!(
                        "joint {}'s backlash puts it on one flank or the other by the direction it came from ({} given)",
                        j + 1,
                        state.approach.len()
                    ),
                });
            }
            for ((a, k), s) in actual.iter_mut().zip(&self.joints).zip(&state.approach) {
                *a += k.backlash * s.sign();
            }
        }
        let mut basis = Vec::new();
        for (j, weights) in self.gravity_loads.iter().enumerate().filter(|(_, l)| !l.is_empty()) {
            let chain = self.robot.chain();
            thermokin_chain::gravity_load_basis_into(chain, commanded, None, &self.down, j, &mut basis)?;
            actual[j] += basis.iter().zip(weights).map(|(f, w)| f * w).sum::<f64>();
        }
        for l in self.branch_loads.iter().filter(|l| !l.lateral) {
            let branch = self.robot.branches().iter().find(|b| b.name == l.branch);
            let Some(branch) = branch else { continue };
            let branch_q = branch_joint_values(branch, state)?;
            let chain = self.robot.chain();
            let (masses, joints) = (self.masses_in(state), (commanded, branch_q.as_slice()));
            let at = (l.joint, false);
            thermokin_chain::branch_load_functions_into(chain, &masses, branch, joints, &self.down, at, &mut basis)?;
            actual[l.joint] += basis.iter().zip(&l.weights).map(|(f, w)| f * w).sum::<f64>();
        }
        Ok(actual)
    }

    /// The commanded values that make the chain see `actual` in `state`: the inverse of
    /// [`RobotModel::joint_values`], by the fixed point `c ← actual − Δq(c)` (a contraction: the
    /// corrections' slope is checked below [`MAX_CORRECTION_SLOPE`] for scale and cyclic terms, and a
    /// compliance's is its angle per N·m times the torque's change per radian, ~1e-4). Verified: an error
    /// unless `joint_values` of the answer is `actual` to 1e-12 (1e-14 sought).
    pub fn commanded_for(&self, actual: &[f64], state: &OperatingState) -> Result<Vec<f64>, DeformError> {
        let mut c = actual.to_vec();
        if !self.corrects_joints() {
            self.robot.chain().check_joint_count(actual)?;
            return Ok(c);
        }
        let mut best = (f64::INFINITY, c.clone());
        for _ in 0..MAX_FIXED_POINT_ITERATIONS {
            let seen = self.joint_values(&c, state)?;
            let gap = seen.iter().zip(actual).map(|(s, a)| (s - a).abs()).fold(0.0, f64::max);
            if gap < best.0 {
                best = (gap, c.clone());
            }
            if gap <= INVERSION_TARGET {
                break;
            }
            for ((ci, s), a) in c.iter_mut().zip(&seen).zip(actual) {
                *ci += a - s;
            }
        }
        let (gap, c) = best;
        if gap <= INVERSION_TOLERANCE { Ok(c) } else { Err(DeformError::NotInvertible { gap }) }
    }

    /// `base_from_tcp` when `commanded` is commanded in `state`: steps 1–3 of the law.
    pub fn tool_pose(&self, commanded: &[f64], state: &OperatingState) -> Result<Isometry3<f64>, DeformError> {
        let q = self.joint_values(commanded, state)?;
        Ok(self.chain_at_joints(state, commanded)?.tool_pose(&q)?)
    }
}
