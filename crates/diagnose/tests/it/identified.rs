//! Every catalogue effect reaches the robot file: for each, data made here by a robot built on the chain
//! (its rows, zeros, joint values and drift set by hand — not by the diagnosis's model), the diagnosis run
//! on one set, its identified robot written as TOML and read back, and that file's forward model — at each
//! fresh measurement's time and temperatures — scored on fresh poses it never saw. The fresh error must
//! match the report's held-out error (within 35 %, the bound of `export.rs`) and sit at the noise (within
//! 1.5 × its RMS): both bounds stated before any run.

use nalgebra::{Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::{Chain, ErrorParams, LinkMass, OperatingState};
use thermokin_chain::{Dataset, Measurement, Robot};
use thermokin_diagnose::{Config, Validation, diagnose};
use thermokin_testdata::{error_mm_deg, workspace};

use crate::tracker::{NOISE_MM, gauss, random_q};

fn nominal() -> Robot {
    thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap()
}

/// Sensor readings at minute `t` of a 240-minute warm-up, °C: joint 2's motor fast (τ = 30 min, +8 K),
/// joint 3's slowly and late (+4 K from minute 60).
fn temps(t: f64) -> [f64; 2] {
    [22.0 + 8.0 * (1.0 - (-t / 30.0).exp()), 21.0 + 4.0 * ((t - 60.0).max(0.0) / 180.0)]
}

/// The true robot at commanded `q` and minute `t`: the chain's rows, zeros and joint values as the case
/// sets them.
struct Truth {
    base: ErrorParams,
    tool: ErrorParams,
    zeros: [f64; 6],
    rows: Box<dyn Fn(f64) -> Vec<ErrorParams>>,
    joints: Box<dyn Fn(&Chain, &[f64]) -> Vec<f64>>,
}

impl Truth {
    fn still() -> Self {
        Self {
            base: ErrorParams::ZERO,
            tool: ErrorParams::ZERO,
            zeros: [0.0; 6],
            rows: Box::new(|_| vec![ErrorParams::ZERO; 6]),
            joints: Box::new(|_, q| q.to_vec()),
        }
    }

    fn position(&self, chain: &Chain, q: &[f64], t: f64) -> Vector3<f64> {
        let warm = chain.with_errors_and_zeros(self.base, &(self.rows)(t), self.tool, &self.zeros).unwrap();
        warm.tool_pose(&(self.joints)(chain, q)).unwrap().translation.vector
    }
}

/// `n` poses at random minutes of the warm-up, measured with [`NOISE_MM`] per axis, with the two sensors.
fn sample(chain: &Chain, truth: &Truth, n: usize, seed: u64) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut measurements: Vec<Measurement> = (0..n)
        .map(|_| {
            let t: f64 = rng.random_range(0.0..240.0);
            let q = random_q(chain, &mut rng);
            let noise = Vector3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng)) * NOISE_MM;
            Measurement {
                time_min: t,
                position_mm: truth.position(chain, &q, t) + noise,
                q,
                orientation: None,
                position_std_mm: None,
                temps: temps(t).to_vec(),
            }
        })
        .collect();
    measurements.sort_by(|a, b| a.time_min.total_cmp(&b.time_min));
    Dataset {
        measurements,
        temperature_names: vec!["j2".into(), "j3".into()],
        source_lines: Vec::new(),
        ..Default::default()
    }
}

/// Gravity torque about joint 2, N·m, from the link masses (gravity along −Z), computed here.
fn torque_2(chain: &Chain, masses: &[Option<LinkMass>], q: &[f64]) -> f64 {
    let frames = chain.joint_frames(q).unwrap();
    let axis = frames[1].rotation * chain.joints()[1].axis.into_inner();
    let origin = frames[1].translation.vector;
    let moment: Vector3<f64> = (1..6)
        .filter_map(|l| masses[l].map(|m| (m.mass_kg, (frames[l] * Point3::from(m.com_mm)).coords)))
        .map(|(m, c)| (c - origin).cross(&Vector3::new(0.0, 0.0, -9.80665 * m)))
        .sum();
    axis.dot(&moment) / 1000.0
}

/// Diagnoses 200 poses, writes the identified robot, reads it back, scores it on 200 fresh poses.
fn check(truth: Truth, expect: &str) {
    let robot = nominal();
    let train = sample(robot.chain(), &truth, 200, 301);
    let fresh = sample(robot.chain(), &truth, 200, 302);
    let config = Config { validation: Validation::SelectionOnly, ..Config::default() };
    let report = diagnose(&robot, &train, None, &config).unwrap();
    let labels: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    let text = thermokin_io::robot_model_to_toml(&report.identified);
    let file = thermokin_io::parse_robot_model_toml("identified.toml".as_ref(), &text).unwrap();
    let state = |m: &Measurement| OperatingState {
        time_min: Some(m.time_min),
        temperatures_c: vec![("temp_j2".into(), m.temps[0]), ("temp_j3".into(), m.temps[1])],
        ..OperatingState::default()
    };
    let sum: f64 = fresh
        .measurements
        .iter()
        .map(|m| (file.tool_pose(&m.q, &state(m)).unwrap().translation.vector - m.position_mm).norm_squared())
        .sum();
    let on_fresh = (sum / fresh.len() as f64).sqrt();
    let heldout = report.additive.last().unwrap().stats.heldout_rms_mm;
    let nominal_rms = report.additive[0].stats.heldout_rms_mm;
    let noise_rms = NOISE_MM * 3f64.sqrt();
    eprintln!(
        "{expect}: {labels:?}; nominal {nominal_rms:.4}, held-out {heldout:.4}, exported file on fresh poses {on_fresh:.4} mm"
    );
    assert!(labels.iter().any(|l| l.starts_with(expect)), "{expect} not named: {labels:?}");
    assert!(nominal_rms > 10.0 * noise_rms, "the hidden effect must matter: {nominal_rms}");
    assert!(on_fresh <= 1.5 * noise_rms, "{on_fresh} mm on fresh poses (noise {noise_rms})");
    assert!((on_fresh / heldout - 1.0).abs() < 0.35, "fresh {on_fresh} vs held-out {heldout}");
}

#[test]
fn base_frame_reaches_the_file() {
    check(Truth { base: error_mm_deg([0.5, -0.3, 0.4, 0.02, -0.01, 0.015]), ..Truth::still() }, "base_frame");
}

#[test]
fn tool_frame_reaches_the_file() {
    check(Truth { tool: error_mm_deg([0.3, -0.2, 0.25, 0.0, 0.0, 0.0]), ..Truth::still() }, "tool_frame");
}

#[test]
fn joint_offset_reaches_the_file() {
    let mut zeros = [0.0; 6];
    zeros[4] = 0.3f64.to_radians(); // 65 mm from the TCP: 0.34 mm, well above 10 × the noise
    check(Truth { zeros, ..Truth::still() }, "joint_offset");
}

#[test]
fn link_deviation_reaches_the_file() {
    let row = error_mm_deg([0.3, -0.2, 0.25, 0.02, 0.0, 0.015]);
    let rows = move |_: f64| {
        let mut r = vec![ErrorParams::ZERO; 6];
        r[2] = row;
        r
    };
    check(Truth { rows: Box::new(rows), ..Truth::still() }, "link_deviation[3]");
}

#[test]
fn joint_compliance_reaches_the_file() {
    let masses = nominal().masses().to_vec();
    let joints = move |chain: &Chain, q: &[f64]| {
        let mut a = q.to_vec();
        a[1] += 0.002f64.to_radians() * torque_2(chain, &masses, q);
        a
    };
    check(Truth { joints: Box::new(joints), ..Truth::still() }, "joint_compliance[2]");
}

#[test]
fn joint_scale_reaches_the_file() {
    let joints = |_: &Chain, q: &[f64]| {
        let mut a = q.to_vec();
        a[1] *= 1.0 + 5e-4;
        a
    };
    check(Truth { joints: Box::new(joints), ..Truth::still() }, "joint_scale[2]");
}

#[test]
fn periodic_reaches_the_file() {
    let joints = |_: &Chain, q: &[f64]| {
        let mut a = q.to_vec();
        a[2] += 0.03f64.to_radians() * (q[2] + 40f64.to_radians()).sin() + 0.01f64.to_radians() * (2.0 * q[2]).cos();
        a
    };
    check(Truth { joints: Box::new(joints), ..Truth::still() }, "periodic[3]");
}

#[test]
fn linear_thermal_drift_reaches_the_file() {
    let row = error_mm_deg([0.25, -0.1, 0.3, 0.01, 0.02, 0.005]);
    let rows = move |t: f64| {
        let mut r = vec![ErrorParams::ZERO; 6];
        r[2] = row.scaled(t / 180.0);
        r
    };
    check(Truth { rows: Box::new(rows), ..Truth::still() }, "thermal_drift[3] (linear)");
}

#[test]
fn exponential_thermal_drift_reaches_the_file() {
    let row = error_mm_deg([0.25, -0.1, 0.3, 0.01, 0.02, 0.005]);
    let rows = move |t: f64| {
        let mut r = vec![ErrorParams::ZERO; 6];
        r[1] = row.scaled(1.0 - (-t / 35.0).exp());
        r
    };
    check(Truth { rows: Box::new(rows), ..Truth::still() }, "thermal_drift[2] (exponential)");
}

#[test]
fn temperature_thermal_drift_reaches_the_file() {
    // Joint 3's row per kelvin of its own sensor (late and slow: neither time law follows it).
    let row = error_mm_deg([0.12, 0.0, -0.08, 0.008, 0.0, 0.004]);
    let rows = move |t: f64| {
        let mut r = vec![ErrorParams::ZERO; 6];
        r[2] = row.scaled(temps(t)[1] - 21.0);
        r
    };
    check(Truth { rows: Box::new(rows), ..Truth::still() }, "thermal_drift[3] (temperature)");
}
