//! Measurement sets generated from hidden effects, to check that the diagnosis finds what it is not told.

use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::{Dataset, Measurement, Robot};
use thermokin_identify::{DriftShape, Effect, IdentifyError, Model, PoseInputs, PoseTerms, Support, normal};

use crate::error::DiagnoseError;

/// A hidden effect with its parameter values (internal units: mm, radians, minutes, rad per N·m).
#[derive(Clone, Debug, PartialEq)]
pub struct HiddenEffect {
    /// The effect.
    pub effect: Effect,
    /// Its parameters.
    pub values: Vec<f64>,
}

impl HiddenEffect {
    /// The effect with values in report units (mm, degrees, minutes, degrees per N·m), converted to
    /// internal units. A tool-frame error given as a point only (three values) has no rotation.
    pub fn from_report_units(effect: Effect, mut values: Vec<f64>) -> Result<Self, DiagnoseError> {
        if effect == Effect::ToolFrame && values.len() == 3 {
            values.extend([0.0; 3]);
        }
        if values.len() != effect.len() {
            return Err(IdentifyError::ParameterCount {
                effect: effect.label(),
                expected: effect.len(),
                got: values.len(),
            }
            .into());
        }
        let values = values.iter().enumerate().map(|(k, &v)| effect.from_report_units(k, v)).collect();
        Ok(Self { effect, values })
    }

    /// Parses `KIND[:JOINT][=VALUES]` — the catalogue name ([`Effect::named`]), the joint numbered from 1,
    /// values in report units (comma-separated; [`HiddenEffect::from_report_units`]) — with a random
    /// effect of typical size drawn from `rng` when no values are given ([`HiddenEffect::typical`]). The
    /// one reading of an effect spec: `thermokin simulate --effect` and the Python `simulate(effects=…)`.
    ///
    /// ```
    /// use rand::SeedableRng;
    /// use thermokin_chain::{Chain, FixedRow, Joint, Robot};
    /// use thermokin_diagnose::HiddenEffect;
    ///
    /// let joints = (0..2).map(|i| Joint::revolute(format!("j{i}"), nalgebra::Vector3::z() * 100.0, nalgebra::Vector3::y_axis())).collect();
    /// let robot = Robot::new("two", Chain::new(FixedRow::identity(), joints, FixedRow::identity()).unwrap());
    /// let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    /// let h = HiddenEffect::parse("joint_offset:2=0.05", &robot, &mut rng).unwrap();
    /// assert_eq!(h.effect.label(), "joint_offset[2]");
    /// assert!((h.values[0] - 0.05f64.to_radians()).abs() < 1e-15);
    /// assert!(HiddenEffect::parse("joint_offset:0", &robot, &mut rng).is_err());
    /// ```
    pub fn parse(spec: &str, robot: &Robot, rng: &mut impl Rng) -> Result<Self, DiagnoseError> {
        let bad = |message: String| DiagnoseError::BadEffectSpec { spec: spec.to_string(), message };
        let (head, values) =
            match spec.split_once('=') {
                Some((h, v)) => {
                    let values =
                        v.split(',')
                            .enumerate()
                            .map(|(i, x)| {
                                x.trim().parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                                    bad(format!("value {} `{}` is not a finite number", i + 1, x.trim()))
                                })
                            })
                            .collect::<Result<Vec<_>, _>>()?;
                    (h, Some(values))
                }
                None => (spec, None),
            };
        let effect = Effect::parse(robot, head).map_err(|e| bad(e.to_string()))?;
        match values {
            Some(v) => Self::from_report_units(effect, v).map_err(|e| bad(e.to_string())),
            None => Ok(Self::typical(effect, rng)),
        }
    }

    /// The effect at a random size typical of a calibrated industrial arm, drawn from `rng`: a zero
    /// offset of 0.02–0.06° either way, a compliance of 5e-4–1.5e-3 °/N·m (a coupling of two: 3e-4–1e-3
    /// either way), a lateral compliance within ±8e-6 °/N·m (a slide's growth within ±8e-9 °/N·m per mm;
    /// without masses each weight within ±0.005°, a column's bend weights ±5e-6 °/mm and shift ±0.01 mm),
    /// a slide's straightness within ±2e-5 °/mm (bows within ±2e-7 per mm), a gear-ratio error of 2e-4–6e-4,
    /// cyclic amplitudes within ±0.03°, an exponential drift's τ of 30–90 min, translations within
    /// ±0.4 mm and rotations within ±0.02° otherwise.
    pub fn typical(effect: Effect, rng: &mut impl Rng) -> Self {
        let report_units: Vec<f64> = (0..effect.len())
            .map(|k| match (effect, k) {
                (Effect::JointOffset(_), _) => {
                    rng.random_range(0.02..0.06) * if rng.random_bool(0.5) { 1.0 } else { -1.0 }
                }
                (Effect::JointCompliance(_), _) => rng.random_range(5e-4..1.5e-3),
                (Effect::LumpedCompliance(..), _) => rng.random_range(-0.02..0.02),
                // A column's bend weights per mm (0.005° over a metre), its shift weights in mm.
                (Effect::LumpedLateralCompliance(_, n, Support::Column), k) if 3 * k >= 2 * n as usize => {
                    rng.random_range(-0.01..0.01)
                }
                (Effect::LumpedLateralCompliance(_, n, Support::Column), k) if 3 * k >= n as usize => {
                    rng.random_range(-5e-6..5e-6)
                }
                (Effect::LumpedLateralCompliance(..), _) => rng.random_range(-0.005..0.005),
                (Effect::ComplianceCoupling(_), _) => {
                    rng.random_range(3e-4..1e-3) * if rng.random_bool(0.5) { 1.0 } else { -1.0 }
                }
                (Effect::LateralCompliance(..), 0..=1) => rng.random_range(-8e-6..8e-6),
                (Effect::LateralCompliance(..), 2 | 3) => rng.random_range(-8e-9..8e-9),
                (Effect::LateralCompliance(..), _) => rng.random_range(-1e-4..1e-4),
                (Effect::Straightness(_), 0..=2) => rng.random_range(-2e-5..2e-5),
                (Effect::Straightness(_), _) => rng.random_range(-2e-7..2e-7),
                (Effect::JointScale(_), _) => rng.random_range(2e-4..6e-4),
                (Effect::Backlash(_), _) => rng.random_range(0.01..0.03),
                (Effect::Periodic(_), _) => rng.random_range(-0.03..0.03),
                (Effect::ThermalDrift(_, DriftShape::Exponential), 6) => rng.random_range(30.0..90.0),
                (_, 0..=2) => rng.random_range(-0.4..0.4),
                _ => rng.random_range(-0.02..0.02),
            })
            .collect();
        let values = report_units.iter().enumerate().map(|(k, &v)| effect.from_report_units(k, v)).collect();
        Self { effect, values }
    }
}

impl std::fmt::Display for HiddenEffect {
    /// `joint_offset[2]: 0.050000° (mm, degrees, minutes)`: the label and the values in report units (per
    /// N·m for a compliance; below 1e-3 with an exponent).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let shown: Vec<String> = self
            .values
            .iter()
            .enumerate()
            .map(|(k, &v)| {
                let shown = self.effect.to_report_units(k, v);
                // A compliance's per-N·m values are far below a millionth: shown with their exponent.
                let number =
                    if shown != 0.0 && shown.abs() < 1e-3 { format!("{shown:.4e}") } else { format!("{shown:.6}") };
                if self.effect.is_angle(k) { format!("{number}°") } else { number }
            })
            .collect();
        write!(f, "{}: {} (mm, degrees, minutes)", self.effect.label(), shown.join(", "))
    }
}

/// Settings of a simulated data set.
#[derive(Clone, Debug, PartialEq)]
pub struct SimulationConfig {
    /// Poses.
    pub poses: usize,
    /// Time span, minutes (poses spread evenly over it; 0 for a static set).
    pub minutes: f64,
    /// Standard deviation of the measurement noise per axis, mm.
    pub noise_mm: f64,
    /// Seed.
    pub seed: u64,
    /// Frame of the measurements: this registration applied to every position.
    pub registration: Isometry3<f64>,
    /// `Some(σ)`: every measurement carries the tool's orientation too (a 6-D probe), turned by a random
    /// rotation vector of σ radians per axis. `None`: positions only.
    pub orientation_noise_rad: Option<f64>,
}

impl SimulationConfig {
    /// The generator that draws hidden effects of typical size ([`HiddenEffect::parse`] without values)
    /// for this configuration: seeded from [`SimulationConfig::seed`], apart from the poses' and noise's
    /// generator, so that adding an effect does not move the poses.
    pub fn effect_rng(&self) -> ChaCha8Rng {
        ChaCha8Rng::seed_from_u64(self.seed ^ 0x5eed)
    }

    /// Checks every setting against its domain: at least one pose, a time span and noises ≥ 0 (a
    /// noise-free set is a valid simulation).
    pub fn validate(&self) -> Result<(), DiagnoseError> {
        let bad = |setting, value: f64, rule| Err(DiagnoseError::BadSetting { setting, value, rule });
        if self.poses == 0 {
            return bad("poses", 0.0, "must be at least 1");
        }
        if !(self.minutes.is_finite() && self.minutes >= 0.0) {
            return bad("minutes", self.minutes, "must be ≥ 0");
        }
        if !(self.noise_mm.is_finite() && self.noise_mm >= 0.0) {
            return bad("noise_mm", self.noise_mm, "must be ≥ 0");
        }
        if let Some(n) = self.orientation_noise_rad
            && !(n.is_finite() && n >= 0.0)
        {
            return bad("orientation_noise_rad", n, "must be ≥ 0");
        }
        Ok(())
    }
}

impl Default for SimulationConfig {
    fn default() -> Self {
        Self {
            poses: 240,
            minutes: 240.0,
            noise_mm: 0.005,
            seed: 1,
            registration: Isometry3::identity(),
            orientation_noise_rad: None,
        }
    }
}

/// Random poses within the joint limits (±π where a joint has none), measured on the robot with the
/// hidden effects, with Gaussian noise.
pub fn simulate(robot: &Robot, hidden: &[HiddenEffect], config: &SimulationConfig) -> Result<Dataset, DiagnoseError> {
    config.validate()?;
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    let mut data = Dataset::default();
    for k in 0..config.poses {
        let q: Vec<f64> = robot
            .chain()
            .joints()
            .iter()
            .map(|j| {
                let (lo, hi) = j.limits.map_or((-3.0, 3.0), |l| (l.lower, l.upper));
                // Stay 10 % inside the limits: real calibration poses avoid them.
                let m = 0.1 * (hi - lo);
                rng.random_range(lo + m..hi - m)
            })
            .collect();
        let time_min = if config.poses > 1 { config.minutes * k as f64 / (config.poses - 1) as f64 } else { 0.0 };
        data.measurements.push(Measurement {
            time_min,
            q,
            position_mm: Vector3::zeros(),
            orientation: None,
            position_std_mm: None,
            temps: Vec::new(),
        });
    }
    let effects: Vec<Effect> = hidden.iter().map(|h| h.effect).collect();
    let model = Model::new(robot, effects)?;
    let mut theta = model.initial();
    for (h, &o) in hidden.iter().zip(model.offsets()) {
        if h.values.len() != h.effect.len() {
            return Err(IdentifyError::ParameterCount {
                effect: h.effect.label(),
                expected: h.effect.len(),
                got: h.values.len(),
            }
            .into());
        }
        theta[o..o + h.values.len()].copy_from_slice(&h.values);
    }
    // The poses are measured in the order they are written (line 1 the header): each joint's approach
    // direction, which a backlash follows, from that order.
    data.source_lines = (0..data.len()).map(|k| k + 2).collect();
    let mut data = data.with_approach(thermokin_chain::MeasuringOrder::File);
    let approach = std::mem::take(&mut data.approach);
    let terms = PoseTerms::of(robot, &data, 0.0);
    for (i, m) in data.measurements.iter_mut().enumerate() {
        let inputs = PoseInputs { approach: &approach[i], ..PoseInputs::plain(&terms.rise[i]) };
        let (p, rot) = model.predict(robot, &theta, m, &inputs, None, &mut None)?;
        let noise = Vector3::new(normal(&mut rng), normal(&mut rng), normal(&mut rng)) * config.noise_mm;
        m.position_mm = (config.registration * nalgebra::Point3::from(p)).coords + noise;
        if let Some(sigma) = config.orientation_noise_rad {
            let turn = Vector3::new(normal(&mut rng), normal(&mut rng), normal(&mut rng)) * sigma;
            let measured = UnitQuaternion::from_scaled_axis(turn)
                * config.registration.rotation
                * UnitQuaternion::from_matrix(&rot);
            m.orientation = Some(measured);
        }
    }
    data.approach = approach;
    Ok(data)
}

/// The UR10 of the repository's fixtures (its URDF, flange `tool0`), for the crate's unit tests.
#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
pub(crate) fn test_ur10() -> Robot {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let text = std::fs::read_to_string(root.join("fixtures/urdf/ur10.urdf")).unwrap();
    let options = thermokin_urdf::ImportOptions { base: None, tip: Some("tool0".into()) };
    thermokin_urdf::import_urdf(&text, "ur10.urdf", &options).unwrap().robot
}
