//! What the residuals of one data set need beyond the parameters, computed once per data set: each
//! pose's gravity torques, the temperature rise each joint's drift follows, the weights of the tracker's
//! stated standard deviations, the joints' sines.

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use thermokin_chain::{Chain, Dataset, LinkMass, Robot};

use crate::sampling::random_configuration;

/// Gravity torque about each joint's axis at configuration `q`, N·m, from the link masses, gravity along
/// the chain's world −Z ([`thermokin_chain::gravity_torques`], the law a robot file's compliance is
/// evaluated with at use); zeros where FK fails (a wrong-length `q` is refused before any fit).
pub fn gravity_torques(chain: &Chain, masses: &[Option<LinkMass>], q: &[f64]) -> Vec<f64> {
    thermokin_chain::gravity_torques(chain, masses, q, &-Vector3::z_axis()).unwrap_or_else(|_| vec![0.0; chain.dof()])
}

/// The largest gravity torque about each joint over its robot's joint space (2,000 seeded configurations
/// within the limits, ±π without — [`random_configuration`] with no margin), N·m: the scale a
/// compliance's deflection and a torque span are judged against. Zero for a joint gravity never loads
/// (a vertical first axis) or for a robot without masses.
pub fn max_gravity_torques(robot: &Robot) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(0x7a0e);
    let mut largest = vec![0.0f64; robot.chain().dof()];
    for _ in 0..2000 {
        let q = random_configuration(robot.chain(), 0.0, &mut rng);
        for (l, t) in largest.iter_mut().zip(gravity_torques(robot.chain(), robot.masses(), &q)) {
            *l = l.max(t.abs());
        }
    }
    largest
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
pub struct PoseTerms {
    /// Per measurement, the gravity torque about each joint, N·m ([`gravity_torques`]).
    pub torques: Vec<Vec<f64>>,
    /// Per measurement, per joint: the rise of the joint's own sensor ([`sensor_joint`]) or, for a joint
    /// without one, the mean rise of all sensors, K.
    pub rise: Vec<Vec<f64>>,
    /// `Some(lever)` when measured orientations are fitted: a rotation error `δφ` (radians) counts as
    /// the displacement `lever · δφ` (mm) it causes at `lever` millimetres from the tool point.
    pub lever_mm: Option<f64>,
    /// Per measurement, the weights of its position rows in the fit, `σ̄ / σ` per axis from the
    /// tracker's stated standard deviations (`σ̄` their mean over the set, so that the weights average
    /// about 1 and residuals stay in millimetres); `None` when the set states none. Held-out errors are
    /// never weighted.
    pub(crate) weights: Option<Vec<Vector3<f64>>>,
    /// Per measurement, `(sin q_i, cos q_i)` of its joint values: computed once, every evaluation of
    /// every fit reads them ([`Chain::tool_position_rotation_sin_cos`]).
    pub(crate) sin_cos: Vec<Vec<(f64, f64)>>,
    /// Per measurement, its line in the measurements file (where a step of the measurement frame at a
    /// line puts it: [`crate::StepAt`]).
    pub(crate) lines: Vec<Option<usize>>,
    /// Every measurement in the frame the training measurements ended in — after every step of it —
    /// whatever its time or line: a test set measured in another file ([`PoseTerms::in_latest_frame`]).
    pub(crate) latest_frame: bool,
}

impl PoseTerms {
    /// Whether the fit weights the position rows by the tracker's stated standard deviations.
    pub fn is_weighted(&self) -> bool {
        self.weights.is_some()
    }

    /// Residual rows per measurement: 3 (position) or 6 (position and weighted rotation).
    pub fn stride(&self) -> usize {
        if self.lever_mm.is_some() { 6 } else { 3 }
    }
}

impl PoseTerms {
    /// The terms of `data`; orientations fitted when every measurement has one and `lever_mm > 0`.
    pub fn of(robot: &Robot, data: &Dataset, lever_mm: f64) -> Self {
        Self::against(robot, data, data, lever_mm)
    }

    /// As [`PoseTerms::of`], the temperature rise taken from the earliest measurement of `reference` (the
    /// data a model was fitted on, when `data` is a test set scored with it); orientations are fitted only
    /// when both carry them.
    pub fn against(robot: &Robot, data: &Dataset, reference: &Dataset, lever_mm: f64) -> Self {
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
        let lines = (0..data.len()).map(|i| data.line_of(i)).collect();
        Self { torques, rise, lever_mm, weights, sin_cos, lines, latest_frame: false }
    }

    /// The same terms with every measurement in the frame the training measurements ended in, after every
    /// step of it ([`crate::Effect::FrameStep`]: a knocked tracker stays where it was knocked): how a model
    /// is used after its training session, as exported — on a hold-out file, whose times and lines are
    /// its own.
    pub fn in_latest_frame(mut self) -> Self {
        self.latest_frame = true;
        self
    }
}
