//! Measurement sets generated from hidden effects, to check that the diagnosis finds what it is not told.

use self::rand_distr_free::normal;
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use thermokin_chain::Robot;

use crate::model::{Effect, Model, prepare};
use crate::{Dataset, DiagnoseError, Measurement};

/// A hidden effect with its parameter values (internal units: mm, radians, minutes, rad per N·m).
#[derive(Clone, Debug, PartialEq)]
pub struct HiddenEffect {
    /// The effect.
    pub effect: Effect,
    /// Its parameters.
    pub values: Vec<f64>,
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
            return Err(DiagnoseError::ParameterCount {
                effect: h.effect.label(),
                expected: h.effect.len(),
                got: h.values.len(),
            });
        }
        theta[o..o + h.values.len()].copy_from_slice(&h.values);
    }
    let pre = prepare(robot, &data, 0.0);
    for (i, m) in data.measurements.iter_mut().enumerate() {
        let (p, rot) = model.predict(robot, &theta, m, &pre.rise[i], &pre.torques[i], None, None, &mut None)?;
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
    Ok(data)
}

/// A tiny standard-normal sampler (Box–Muller), to avoid a dependency for one function.
mod rand_distr_free {
    use rand::Rng;
    pub fn normal(rng: &mut impl Rng) -> f64 {
        let u1: f64 = rng.random_range(f64::MIN_POSITIVE..1.0);
        let u2: f64 = rng.random_range(0.0..1.0);
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}
