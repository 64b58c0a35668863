//! The robot as one value — its name, its chain and the description data carried beside the chain
//! (link masses for gravity, joint ratings for planners) — and a programmed target. Plain data: the
//! readers build them, every algorithm crate takes them; they live in the core so that readers sit below
//! the algorithms.

use nalgebra::{Isometry3, Matrix3, Unit, Vector3};

use crate::link_mass::{LinkMass, STANDARD_GRAVITY};
use crate::{Chain, ChainError, JointKind};

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

/// A robot: name, chain, and per joint the mass of the link it moves and its ratings. The per-joint
/// lists always have one entry per joint of the chain (checked on construction), so that a robot
/// cannot carry the masses of another.
///
/// ```
/// use nalgebra::Vector3;
/// use thermokin_chain::{Chain, FixedRow, Joint, LinkMass, Robot};
///
/// let chain = Chain::new(
///     FixedRow::identity(),
///     vec![Joint::revolute("A1", Vector3::zeros(), Vector3::z_axis())],
///     FixedRow::from_isometry(&nalgebra::Isometry3::translation(100.0, 0.0, 0.0)),
/// )?;
/// let robot = Robot::new("one-axis", chain)
///     .with_masses(vec![Some(LinkMass { mass_kg: 2.0, com_mm: Vector3::new(50.0, 0.0, 0.0) })])?;
/// assert_eq!(robot.masses()[0].unwrap().mass_kg, 2.0);
/// assert!(robot.clone().with_masses(vec![None, None]).is_err()); // one entry per joint
/// # Ok::<(), thermokin_chain::ChainError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    name: String,
    chain: Chain,
    masses: Vec<Option<LinkMass>>,
    ratings: Vec<JointRatings>,
    accelerometers: Vec<LinkSensor>,
    branches: Vec<crate::Branch>,
}

/// An accelerometer or inclinometer on one of a robot's links, as its robot file declares it: measurement
/// files then carry its columns `NAME_x`, `NAME_y`, `NAME_z`, which the diagnosis reads as the link's
/// tilt.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LinkSensor {
    /// Its name.
    pub name: String,
    /// The link it sits on: 0 the robot's base, `k` the link joint `k` moves.
    pub link: usize,
}

impl Robot {
    /// A robot with no masses and no ratings known.
    pub fn new(name: impl Into<String>, chain: Chain) -> Self {
        let n = chain.dof();
        Self {
            name: name.into(),
            chain,
            masses: vec![None; n],
            ratings: vec![JointRatings::default(); n],
            accelerometers: Vec::new(),
            branches: Vec::new(),
        }
    }

    /// The same robot with these link masses (one per joint).
    pub fn with_masses(mut self, masses: Vec<Option<LinkMass>>) -> Result<Self, ChainError> {
        check_len("masses", self.chain.dof(), masses.len())?;
        self.masses = masses;
        Ok(self)
    }

    /// The same robot with these accelerometers on its links ([`LinkSensor`]): each named, on link 0 to
    /// the joint count.
    pub fn with_accelerometers(mut self, sensors: Vec<LinkSensor>) -> Result<Self, ChainError> {
        let last = self.chain.dof();
        if let Some(bad) = sensors.iter().find(|s| s.link > last || s.name.trim().is_empty()) {
            return Err(ChainError::BadSensor { name: bad.name.clone(), link: bad.link, last });
        }
        self.accelerometers = sensors;
        Ok(self)
    }

    /// The accelerometers its file declares on its links.
    pub fn accelerometers(&self) -> &[LinkSensor] {
        &self.accelerometers
    }

    /// The same robot with these branches hanging from its links ([`crate::Branch`]): each named, on a
    /// link from 0 to the joint count, every joint name used once in the whole robot.
    pub fn with_branches(mut self, branches: Vec<crate::Branch>) -> Result<Self, ChainError> {
        crate::branches::check_branches(&self.chain, &branches)?;
        self.branches = branches;
        Ok(self)
    }

    /// The branches hanging from its links: the rest of its tree beside the measured chain.
    pub fn branches(&self) -> &[crate::Branch] {
        &self.branches
    }

    /// The same robot with these joint ratings (one per joint).
    pub fn with_ratings(mut self, ratings: Vec<JointRatings>) -> Result<Self, ChainError> {
        check_len("ratings", self.chain.dof(), ratings.len())?;
        self.ratings = ratings;
        Ok(self)
    }

    /// The same robot on another chain of as many joints — a deformed or calibrated one; masses and
    /// ratings are kept.
    pub fn with_chain(&self, chain: Chain) -> Result<Self, ChainError> {
        if chain.dof() != self.chain.dof() {
            return Err(ChainError::JointCountChanged { expected: self.chain.dof(), got: chain.dof() });
        }
        Ok(Self { chain, ..self.clone() })
    }

    /// The same robot under another name.
    pub fn renamed(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }

    /// The robot carrying `payload` on its flange (a probe, a gripper, a load), its centre in the last
    /// link's frame (the flange's same-orientation frame, mm): merged with that link's own mass as one
    /// body (masses added, centres weighted by mass). A non-positive or non-finite payload is refused.
    pub fn with_payload(mut self, payload: LinkMass) -> Result<Self, ChainError> {
        let ok = payload.mass_kg.is_finite() && payload.mass_kg > 0.0 && payload.com_mm.iter().all(|v| v.is_finite());
        let last = self.chain.dof().checked_sub(1);
        let (true, Some(last)) = (ok, last) else {
            return Err(ChainError::BadPayload { mass_kg: payload.mass_kg });
        };
        self.masses[last] = Some(match self.masses[last] {
            None => payload,
            Some(link) => link.combined_with(payload),
        });
        Ok(self)
    }

    /// Display name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The extended table.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// Per joint: the mass of the link it moves, when known.
    pub fn masses(&self) -> &[Option<LinkMass>] {
        &self.masses
    }

    /// Per joint: rated speed and effort (rad/s, N·m; mm/s, N for prismatic joints).
    pub fn ratings(&self) -> &[JointRatings] {
        &self.ratings
    }

    /// Gravity torque about each joint's axis at configuration `q`, N·m, from the link masses, gravity
    /// pointing along `down` in the chain's world frame (the frame its base row maps into; `−Z` for a
    /// floor-mounted robot whose base row is level):
    /// `τ_j = z_j · Σ_{l ≥ j} (c_l − o_j) × m_l g`, with `z_j` and `o_j` joint j's axis and origin and `c_l`
    /// link l's centre of mass, all in the world frame. A link without a mass contributes nothing. A
    /// prismatic joint's entry is the weight it carries along its axis, N.
    ///
    /// ```
    /// use nalgebra::{Vector3, Isometry3};
    /// use thermokin_chain::{Chain, FixedRow, Joint, LinkMass, Robot};
    ///
    /// // One horizontal Y axis carrying 2 kg at 500 mm along X: τ = 0.5 m · 2 kg · g about +Y.
    /// let chain = Chain::new(
    ///     FixedRow::identity(),
    ///     vec![Joint::revolute("A1", Vector3::zeros(), Vector3::y_axis())],
    ///     FixedRow::from_isometry(&Isometry3::identity()),
    /// )?;
    /// let robot = Robot::new("arm", chain)
    ///     .with_masses(vec![Some(LinkMass { mass_kg: 2.0, com_mm: Vector3::new(500.0, 0.0, 0.0) })])?;
    /// let tau = robot.gravity_torques(&[0.0], &-Vector3::z_axis())?;
    /// assert!((tau[0] - 0.5 * 2.0 * 9.80665).abs() < 1e-12);
    /// # Ok::<(), thermokin_chain::ChainError>(())
    /// ```
    pub fn gravity_torques(&self, q: &[f64], down: &Unit<Vector3<f64>>) -> Result<Vec<f64>, ChainError> {
        gravity_torques(&self.chain, &self.masses, q, down)
    }

    /// The robot's parts: name, chain, masses, ratings.
    pub fn into_parts(self) -> (String, Chain, Vec<Option<LinkMass>>, Vec<JointRatings>) {
        (self.name, self.chain, self.masses, self.ratings)
    }
}

/// [`Robot::gravity_torques`] of a chain and its link masses (one per joint; missing entries carry
/// nothing), without building a robot.
pub fn gravity_torques(
    chain: &Chain,
    masses: &[Option<LinkMass>],
    q: &[f64],
    down: &Unit<Vector3<f64>>,
) -> Result<Vec<f64>, ChainError> {
    let mut out = Vec::with_capacity(chain.dof());
    gravity_torques_into(chain, masses, q, None, down, &mut out)?;
    Ok(out)
}

/// [`gravity_torques`] into `out` (its length set to the joints'), with the caller's `(sin q_i, cos
/// q_i)` of the joint values when given (as [`Chain::tool_position_rotation_sin_cos`] takes them): the
/// identification's hot path, which evaluates the torques of every pose at every fit evaluation of a
/// model with a compliance, with no allocation and no sine evaluated.
///
/// The torque about a revolute joint `j` is `aⱼ · Σ_{l ≥ j} (cₗ − oⱼ) × mₗ g` (axis `aⱼ` and origin `oⱼ` of joint
/// `j`'s frame, `cₗ` the centre of mass of link `l` carrying `mₗ`), summed from the tip inwards as
/// `aⱼ · (Mⱼ − oⱼ × g Wⱼ)` with the suffix sums `Mⱼ = Σ_{l ≥ j} cₗ × mₗ g` and `Wⱼ = Σ_{l ≥ j} mₗ`: one
/// pass over the links; a prismatic joint's is the force along its axis, `aⱼ · g Wⱼ` (N) — each the
/// derivative of gravity's work by the joint's motion (a test compares both with finite differences).
pub fn gravity_torques_into(
    chain: &Chain,
    masses: &[Option<LinkMass>],
    q: &[f64],
    q_sin_cos: Option<&[(f64, f64)]>,
    down: &Unit<Vector3<f64>>,
    out: &mut Vec<f64>,
) -> Result<(), ChainError> {
    out.clear();
    out.resize(chain.dof(), 0.0);
    // Kept per joint: its axis in the base frame.
    let axis_of = |j: usize, _parent: &Matrix3<f64>, rot: &Matrix3<f64>| rot * chain.joints()[j].axis.into_inner();
    visit_carried_loads(chain, masses, q, q_sin_cos, down, axis_of, |j, axis, moment, weight| {
        out[j] = match chain.joints()[j].kind {
            JointKind::Revolute => crate::units::newton_metres(axis.dot(moment)),
            // A slide: the weight it carries along its axis (N), the derivative of gravity's work by its travel.
            JointKind::Prismatic => axis.dot(weight),
        };
    })
}

/// From the tip inwards, `visit(j, kept, moment, weight)` for every joint: what `keep` took of its frames
/// (`keep(j, parent, rotation)`: its parent's rotation — the frame its row's errors are in — and its own
/// after its motion), the moment of gravity about its origin of the links it carries (its own and beyond),
/// `Mⱼ − oⱼ × g Wⱼ` in the base frame, N·mm, and their weight `g Wⱼ`, N — the suffix sums
/// `Mⱼ = Σ_{l ≥ j} cₗ × mₗ g`, `Wⱼ = Σ_{l ≥ j} mₗ` in one pass, with no allocation up to 16 joints (each
/// caller keeps only what it reads: this is the identification's hot path). What the torques about the
/// axes ([`gravity_torques_into`]) and the moments across them ([`crate::lateral_gravity_moments_into`])
/// are read from.
pub(crate) fn visit_carried_loads<K: Copy + Default>(
    chain: &Chain,
    masses: &[Option<LinkMass>],
    q: &[f64],
    q_sin_cos: Option<&[(f64, f64)]>,
    down: &Unit<Vector3<f64>>,
    keep: impl Fn(usize, &Matrix3<f64>, &Matrix3<f64>) -> K,
    mut visit: impl FnMut(usize, &K, &Vector3<f64>, &Vector3<f64>),
) -> Result<(), ChainError> {
    const ON_STACK: usize = 16;
    let n = chain.dof();
    let weight = down.into_inner() * STANDARD_GRAVITY;
    let none = (K::default(), Vector3::zeros(), Vector3::zeros(), 0.0);
    let mut small = [none; ON_STACK];
    let mut large = Vec::new();
    let per_joint: &mut [(K, Vector3<f64>, Vector3<f64>, f64)] = if n <= ON_STACK {
        &mut small[..n]
    } else {
        large.resize(n, none);
        &mut large[..]
    };
    chain.visit_joint_frames(q, q_sin_cos, |i, parent, rot, origin| {
        let (moment, mass) = match masses.get(i).copied().flatten() {
            Some(m) => ((rot * m.com_mm + origin).cross(&(weight * m.mass_kg)), m.mass_kg),
            None => (Vector3::zeros(), 0.0),
        };
        per_joint[i] = (keep(i, parent, rot), *origin, moment, mass);
    })?;
    let (mut moment, mut mass) = (Vector3::zeros(), 0.0);
    for j in (0..n).rev() {
        let (kept, origin, m, w) = &per_joint[j];
        moment += m;
        mass += w;
        let carried = weight * mass;
        visit(j, kept, &(moment - origin.cross(&carried)), &carried);
    }
    Ok(())
}

fn check_len(field: &'static str, expected: usize, got: usize) -> Result<(), ChainError> {
    if expected == got { Ok(()) } else { Err(ChainError::DescriptionLength { field, expected, got }) }
}

/// The state a robot operates in, beyond its joint values: what its state-dependent corrections (thermal
/// drift, gravity compliance) are evaluated at. Plain data; every part is optional — an empty state is
/// the robot cold (time 0, no temperature rise) carrying only what its file says it carries.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OperatingState {
    /// Operating time since the cold start of a warm-up, minutes.
    pub time_min: Option<f64>,
    /// Sensor readings, °C, by sensor name (`temp_j2`, …: the names of the measurement files).
    pub temperatures_c: Vec<(String, f64)>,
    /// The payload on the flange (kg; centre in mm, in the flange's same-orientation frame), replacing the
    /// one the robot file carries.
    pub payload: Option<LinkMass>,
    /// The direction each joint last moved in before this pose (one per joint, what a backlash follows);
    /// empty when not given.
    pub approach: Vec<crate::Approach>,
}

impl OperatingState {
    /// The state at operating time `time_min`.
    pub fn at_time(time_min: f64) -> Self {
        Self { time_min: Some(time_min), ..Self::default() }
    }

    /// The reading of sensor `name`, °C.
    pub fn temperature(&self, name: &str) -> Option<f64> {
        self.temperatures_c.iter().find(|(n, _)| n == name).map(|&(_, t)| t)
    }

    /// `true` when nothing is given.
    pub fn is_empty(&self) -> bool {
        self.time_min.is_none() && self.temperatures_c.is_empty() && self.payload.is_none() && self.approach.is_empty()
    }
}

/// A programmed target: a label (`P1`, …), the TCP pose to reach in the base frame (mm) and the state the
/// robot is in when it reaches it (a time of the warm-up, sensor readings; empty when the file gives
/// none). What a targets file holds and what a compensation run solves for; `line` is where it was read,
/// when it was.
#[derive(Clone, Debug, PartialEq)]
pub struct Target {
    /// Label (`P1`, …).
    pub label: String,
    /// Programmed `base_from_tcp`, mm.
    pub pose: Isometry3<f64>,
    /// Line of the file it was read from, if any (for messages).
    pub line: Option<usize>,
    /// The operating state at this target (its `time_min` and `temp_*` columns).
    pub state: OperatingState,
}

impl Target {
    /// A target not read from a file, in no particular state.
    pub fn new(label: impl Into<String>, pose: Isometry3<f64>) -> Self {
        Self { label: label.into(), pose, line: None, state: OperatingState::default() }
    }

    /// The same target in `state`.
    pub fn in_state(mut self, state: OperatingState) -> Self {
        self.state = state;
        self
    }
}
