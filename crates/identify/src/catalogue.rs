//! The catalogue of effects for a robot and a data set, and the blocks every model of a measurement setup
//! estimates without reporting them (the tracker registration, an unknown tool).

use serde::Serialize;
use thermokin_chain::{Dataset, JointKind, Robot};

use crate::effect::{DriftShape, Effect, JointIndex, SensorId};
use crate::error::IdentifyError;
use crate::terms::max_gravity_torques;

/// Whether gravity loads revolute joint `j` at some of the data's poses (a vertical axis it never does):
/// its gravity-load functions ([`thermokin_chain::gravity_load_basis_into`]) are not all zero there.
fn gravity_loads(robot: &Robot, data: &Dataset, j: JointIndex) -> bool {
    let chain = robot.chain();
    if thermokin_chain::gravity_load_basis_len(chain, j.index()) == 0 {
        return false;
    }
    let down = -nalgebra::Vector3::z_axis();
    let mut basis = Vec::new();
    data.measurements.iter().take(500).any(|m| {
        thermokin_chain::gravity_load_basis_into(chain, &m.q, None, &down, j.index(), &mut basis).is_ok()
            && basis.iter().any(|f| f.abs() > 1e-6)
    })
}

/// Whether the gravity moments across joint `j` (with the file's masses) change over the data's poses:
/// a lateral compliance there is a tilt that varies, which a fixed link deviation cannot take.
fn lateral_loads(robot: &Robot, data: &Dataset, j: JointIndex) -> bool {
    let down = -nalgebra::Vector3::z_axis();
    let mut moments = Vec::new();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for m in data.measurements.iter().take(500) {
        if thermokin_chain::lateral_gravity_moments_into(robot.chain(), robot.masses(), &m.q, None, &down, &mut moments)
            .is_err()
        {
            return false;
        }
        for k in 0..2 {
            lo[k] = lo[k].min(moments[j.index()][k]);
            hi[k] = hi[k].max(moments[j.index()][k]);
        }
    }
    // A moment that changes by less than a newton-metre over the data tilts nothing a tracker sees.
    (0..2).any(|k| hi[k] - lo[k] > 1.0)
}

/// Whether some lateral-load function of joint `j` ([`thermokin_chain::lateral_load_basis_into`])
/// varies over the data's poses: where none does, a lateral compliance is a constant tilt — a link
/// deviation's.
fn lateral_loads_vary(robot: &Robot, data: &Dataset, j: JointIndex) -> bool {
    let chain = robot.chain();
    let n = thermokin_chain::lateral_load_basis_len(chain, j.index());
    if n == 0 {
        return false;
    }
    let down = -nalgebra::Vector3::z_axis();
    let (mut lo, mut hi) = (vec![f64::INFINITY; n], vec![f64::NEG_INFINITY; n]);
    let mut basis = Vec::new();
    for m in data.measurements.iter().take(500) {
        if thermokin_chain::lateral_load_basis_into(chain, &m.q, None, &down, j.index(), &mut basis).is_err() {
            return false;
        }
        for (b, f) in basis.iter().enumerate() {
            lo[b] = lo[b].min(*f);
            hi[b] = hi[b].max(*f);
        }
    }
    // A function of unit size that moves by less than a thousandth over the data tilts nothing.
    lo.iter().zip(&hi).any(|(l, h)| h - l > 1e-3)
}

/// How many of the data's poses at `rows` joint `j` reached rising and falling
/// ([`thermokin_chain::Approach`], from the measuring order; both zero when the set has none): a backlash
/// is seen only between the two.
pub fn approach_counts(data: &Dataset, rows: impl IntoIterator<Item = usize>, j: usize) -> (usize, usize) {
    rows.into_iter().fold((0, 0), |(up, down), i| match data.approach_of(i, j) {
        thermokin_chain::Approach::Rising => (up + 1, down),
        thermokin_chain::Approach::Falling => (up, down + 1),
        thermokin_chain::Approach::Unknown => (up, down),
    })
}

/// The gravity compliance of joint `j` a model of these data can carry: with the file's masses where
/// the joint carries some ([`Effect::JointCompliance`]), with its loads lumped where the file has no
/// masses and gravity loads the joint in the data ([`Effect::LumpedCompliance`]); `None` otherwise.
/// `loaded` is [`max_gravity_torques`] of the robot (computed once by the caller).
pub fn gravity_compliance(robot: &Robot, data: &Dataset, j: JointIndex, loaded: &[f64]) -> Option<Effect> {
    if loaded.get(j.index()).is_some_and(|&t| t > 0.0) {
        Some(Effect::JointCompliance(j))
    } else if robot.masses().iter().all(Option::is_none) && gravity_loads(robot, data, j) {
        Effect::lumped_compliance(robot, j).ok()
    } else {
        None
    }
}

/// In which frame the measurements are.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum FrameMode {
    /// The robot's base frame: a base misalignment is a candidate effect.
    Base,
    /// A tracker frame: an unknown registration is always estimated and never reported.
    Tracker,
}

/// Whether the tool point is known.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum ToolMode {
    /// The robot description's tool: a tool error is a candidate effect.
    Known,
    /// Unknown: the tool point is always estimated and never reported.
    Unknown,
}

thermokin_chain::choices!(
    FrameMode,
    "measurement frame",
    [
        ("base", "the robot's base frame: a base misalignment is a candidate effect", FrameMode::Base),
        ("tracker", "a tracker's frame: the registration is always estimated", FrameMode::Tracker),
    ]
);

thermokin_chain::choices!(
    ToolMode,
    "tool",
    [
        ("known", "the robot description's tool: a tool error is a candidate effect", ToolMode::Known),
        ("unknown", "estimated with every model (a probe of unknown offset)", ToolMode::Unknown),
    ]
);

/// Which joints a lateral compliance (a row tilting under the gravity moment across its axis) is a
/// candidate of.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum Lateral {
    /// The default: a slide's — a column bending under what it carries — where the file's masses load it
    /// and the load changes over the data. A revolute joint's is not offered: with masses, offered to the
    /// real WAM it was chosen on the grid and made the random poses worse (2.29 → 2.80 mm); without, on
    /// the real Rokae's 30 poses it was chosen for wrist joints and the nested held-out mean rose (6-D:
    /// 0.1397 → 0.1494 mm).
    #[default]
    Slides,
    /// Every joint's: also each revolute joint's bearing (a humanoid's torso carrying its arm, a cobot's
    /// elastic joints), on the file's masses or, without masses, its loads lumped
    /// ([`Effect::LumpedLateralCompliance`]) — what the user knows of the robot's build.
    Joints,
}

thermokin_chain::choices!(
    Lateral,
    "lateral compliance",
    [
        ("slides", "a column's bending under what it carries (with the file's masses)", Lateral::Slides),
        (
            "joints",
            "every joint's bearing tilting under the moment across it too (loads lumped without masses; a logged branch's moment too)",
            Lateral::Joints
        ),
    ]
);

/// The settings of a measurement setup that decide which blocks are always estimated: the frame of the
/// measurements, whether the tool is known, and the weight of measured orientations; and which joints'
/// lateral compliance is a candidate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setup {
    /// The measurement frame.
    pub frame: FrameMode,
    /// The tool point.
    pub tool: ToolMode,
    /// The orientation lever, mm (0: orientations ignored).
    pub orientation_lever_mm: f64,
    /// Which joints' lateral compliance is a candidate ([`Lateral`]).
    pub lateral: Lateral,
}

impl Setup {
    /// The blocks every model estimates (never reported as causes): the tracker registration and an
    /// unknown tool point — with its rotation when the data carry orientations that are fitted.
    pub fn always_estimated(&self, data: &Dataset) -> Vec<Effect> {
        let mut effects = Vec::new();
        if self.frame == FrameMode::Tracker {
            effects.push(Effect::Registration);
        }
        if self.tool == ToolMode::Unknown {
            effects.push(Effect::ToolPoint);
            // An unknown 6-D probe: its rotation is as unknown as its point.
            if data.has_orientation() && self.orientation_lever_mm > 0.0 {
                effects.push(Effect::ToolRotation);
            }
        }
        effects
    }

    /// The catalogue's candidates for `robot` and `data`, in catalogue order: the base and tool frames
    /// where they are not always estimated; per joint its offset and link deviation, a gravity compliance
    /// where the joint carries mass, a coupling of two neighbouring joints' compliances where gravity loads
    /// both, a column's lateral compliance (every joint's with [`Lateral::Joints`]), a gear-ratio scale and
    /// a cyclic error of a revolute joint, a slide's scale and straightness, a backlash where the
    /// measuring order approaches the joint from both sides; a thermal drift (linear and exponential) when
    /// the data span time, one per kelvin when they carry temperatures; a row driven by each sensor
    /// column that varies.
    pub fn candidates(&self, robot: &Robot, data: &Dataset) -> Result<Vec<Effect>, IdentifyError> {
        let joints =
            (0..robot.chain().dof()).map(|j| JointIndex::of(robot, j)).collect::<Result<Vec<_>, IdentifyError>>()?;
        let mut c = Vec::new();
        if self.frame == FrameMode::Base {
            c.push(Effect::BaseFrame);
        }
        if self.tool == ToolMode::Known {
            c.push(Effect::ToolFrame);
        }
        c.extend(joints.iter().map(|&j| Effect::JointOffset(j)));
        c.extend(joints.iter().map(|&j| Effect::LinkDeviation(j)));
        let massless = robot.masses().iter().all(Option::is_none);
        for &j in &joints {
            let carries_mass = robot.masses().iter().skip(j.index()).any(Option::is_some);
            if carries_mass {
                c.push(Effect::JointCompliance(j));
            } else if massless && gravity_loads(robot, data, j) {
                // No masses in the file: the compliance with its loads lumped, identified from the data.
                c.push(Effect::lumped_compliance(robot, j)?);
            }
        }
        // A column's lateral compliance where the file's masses load a slide across its axis and the load
        // changes over the data — the column bending under the arm's moment, more at its top extensions —
        // or, without masses, where its lateral-load functions vary (its loads lumped). A revolute joint's
        // (a bearing tilting) where the user says the joints are elastic ([`Lateral`]): on the file's
        // masses, or without masses its loads lumped (a torso carrying an arm: the moments of unknown
        // masses are the lateral-load functions' sums, which a fixed link deviation cannot take where they
        // vary over the data).
        for &j in &joints {
            let slide = robot.chain().joints()[j.index()].kind == JointKind::Prismatic;
            if !slide && self.lateral == Lateral::Slides {
                continue;
            }
            if massless {
                if lateral_loads_vary(robot, data, j) {
                    c.push(Effect::lumped_lateral_compliance(robot, j)?);
                }
            } else if robot.masses().iter().skip(j.index()).any(Option::is_some) && lateral_loads(robot, data, j) {
                c.push(Effect::lateral_compliance(robot, j));
            }
        }
        // A compliance coupling of two neighbouring revolute joints that gravity both loads (a drive the
        // two share): a joint gravity never loads — a vertical first axis — has no torque to couple.
        if joints.len() > 1 && robot.masses().iter().any(Option::is_some) {
            let largest = max_gravity_torques(robot);
            let top = largest.iter().copied().fold(0.0, f64::max);
            for pair in joints.windows(2) {
                let revolute = pair.iter().all(|j| robot.chain().joints()[j.index()].kind == JointKind::Revolute);
                // Rounding leaves ~1e-15 of the largest torque on an axis gravity never loads.
                let loaded = pair.iter().all(|j| largest[j.index()] > 1e-6 * top);
                if revolute && loaded {
                    c.push(Effect::ComplianceCoupling(pair[0]));
                }
            }
        }
        // Scale and cyclic errors of revolute joints (a gear ratio, an encoder's eccentricity); the scale
        // of a slide (a lead screw's or a rack's error, growing with the extension).
        // A slide's guide: its carriage tilting and bowing as it travels (straightness).
        for &j in &joints {
            c.push(Effect::JointScale(j));
            if robot.chain().joints()[j.index()].kind == JointKind::Revolute {
                c.push(Effect::Periodic(j));
            } else {
                c.push(Effect::Straightness(j));
            }
        }
        // Backlash of a joint the measuring order shows reaching its poses from both sides.
        for &j in &joints {
            let (up, down) = approach_counts(data, 0..data.len(), j.index());
            if up > 0 && down > 0 {
                c.push(Effect::Backlash(j));
            }
        }
        if data.time_span() > 0.0 {
            for &j in &joints {
                c.push(Effect::ThermalDrift(j, DriftShape::Linear));
                c.push(Effect::ThermalDrift(j, DriftShape::Exponential));
            }
        }
        if !data.temperature_names.is_empty() {
            c.extend(joints.iter().map(|&j| Effect::ThermalDrift(j, DriftShape::Temperature)));
        }
        c.extend(sensor_candidates(robot, data, &joints, self.lateral));
        if !massless {
            under_the_whole_load(&mut c);
        }
        Ok(c)
    }
}

/// A logged branch that carries masses loads a joint below it by their torque: with the file's masses on
/// the chain too, its load is the joint's compliance under everything the joint carries
/// (`BranchAt::masses`, one compliance for the sum) and replaces, in `c`, the joint's own under the
/// chain's masses alone (across the axis: its lateral compliance) — the two would be one stiffness
/// fitted twice, their columns nearly alike.
fn under_the_whole_load(c: &mut Vec<Effect>) {
    let whole: Vec<(JointIndex, bool)> = c
        .iter()
        .filter_map(|e| match e {
            Effect::BranchLoad(j, _, at) if at.masses => Some((*j, at.lateral)),
            _ => None,
        })
        .collect();
    c.retain(|e| match e {
        Effect::JointCompliance(j) => !whole.contains(&(*j, false)),
        Effect::LateralCompliance(j, _) => !whole.contains(&(*j, true)),
        _ => true,
    });
}

/// The candidates of the set's sensor columns: a declared accelerometer's tilt turning the row of the
/// joint its link carries, with no gain to fit (a sensor on the last link carries no joint's row: nothing
/// of it); any other sensor column that varies driving any row (a column's tilt, a base's, a load's
/// bending).
fn sensor_candidates(robot: &Robot, data: &Dataset, joints: &[JointIndex], lateral: Lateral) -> Vec<Effect> {
    let mut c = Vec::new();
    let columns = |t: &thermokin_chain::TiltSensor| if t.below.is_some() { 6 } else { 3 };
    let declared = |k: usize| {
        data.tilt_sensors.iter().any(|t| (t.column..t.column + columns(t)).contains(&k))
            || data.branch_columns.iter().any(|b| b.holds(k))
    };
    // A branch the set logs loads every revolute joint below its link (a torso carrying the other arm) —
    // about its axis, and, with every joint's lateral compliance offered, across it.
    for b in &data.branch_columns {
        let (Some(branch), Some(first), Ok(index)) =
            (robot.branches().get(b.branch), SensorId::of(data, b.column), u8::try_from(b.branch))
        else {
            continue;
        };
        for &j in joints {
            let about = thermokin_chain::branch_load_basis_len(robot.chain(), branch, j.index());
            let across = thermokin_chain::branch_lateral_basis_len(robot.chain(), branch, j.index());
            let kinds = [(about, false), (if lateral == Lateral::Joints { across } else { 0 }, true)];
            for (n, lateral) in kinds {
                if let Ok(count) = u8::try_from(n).map_err(|_| ()).and_then(|n| if n > 0 { Ok(n) } else { Err(()) }) {
                    let masses = branch.carries_masses();
                    c.push(Effect::BranchLoad(
                        j,
                        first,
                        crate::effect::BranchAt { branch: index, count, lateral, masses },
                    ));
                }
            }
        }
    }
    for t in &data.tilt_sensors {
        let over = if t.below.is_some() { crate::effect::TiltOver::Below } else { crate::effect::TiltOver::Ground };
        if let (Ok(j), Some(sensor)) = (JointIndex::of(robot, t.link), SensorId::of(data, t.column)) {
            c.push(Effect::Tilt(j, sensor, over));
        }
    }
    for k in (0..data.sensor_names.len()).filter(|&k| !declared(k)) {
        let (lo, hi) = data
            .sensor_values
            .iter()
            .filter_map(|v| v.get(k))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| (l.min(v), h.max(v)));
        if let Some(sensor) = SensorId::of(data, k).filter(|_| hi > lo) {
            c.extend(joints.iter().map(|&j| Effect::SensorDrift(j, sensor)));
        }
    }
    c
}
