//! A simulated laser tracker independent of the diagnosis's model: a robot built on the chain is moved to
//! the joint values an error produces and its TCP measured with Gaussian noise.

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::Chain;
use thermokin_chain::{Dataset, Measurement};
use thermokin_testdata::measured_point;

/// Noise per axis, mm.
pub const NOISE_MM: f64 = 0.005;

pub use thermokin_testdata::{gauss, random_q};

/// `n` poses 10 % inside the limits: the commanded joints are recorded, the robot stands at
/// `actual(commanded)`, its TCP is measured with [`NOISE_MM`] of Gaussian noise per axis (Box–Muller).
pub fn measure(chain: &Chain, n: usize, seed: u64, actual: impl Fn(&[f64]) -> Vec<f64>) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let measurements = (0..n)
        .map(|_| {
            let q = random_q(chain, &mut rng);
            let p = chain.tool_pose(&actual(&q)).unwrap().translation.vector;
            measured_point(q, p, NOISE_MM, &mut rng)
        })
        .collect();
    Dataset { measurements, ..Dataset::default() }
}

/// 200 poses as [`measure`] draws them with `seed`, on a robot whose joint 2 stands 0.1° off wherever
/// `on(commanded)` holds — an error of one arm configuration, which no catalogue effect describes.
pub fn joint_two_off_where(chain: &Chain, seed: u64, on: impl Fn(&[f64]) -> bool) -> Dataset {
    measure(chain, 200, seed, |q| {
        let mut a = q.to_vec();
        if on(q) {
            a[1] += 0.1f64.to_radians();
        }
        a
    })
}

/// The median elbow (joint 3) angle of the 200 poses [`measure`] draws with `seed`.
pub fn elbow_median(chain: &Chain, seed: u64) -> f64 {
    let mut elbow: Vec<f64> = measure(chain, 200, seed, <[f64]>::to_vec).measurements.iter().map(|m| m.q[2]).collect();
    elbow.sort_by(f64::total_cmp);
    elbow[elbow.len() / 2]
}

/// Orientation noise of [`measure_6d`], degrees per axis.
pub const ORIENTATION_NOISE_DEG: f64 = 0.002;

/// As [`measure`], with a 6-D probe: the robot stands at `actual(commanded)`, the probe sits at
/// `tool_from_probe` behind the chain's tool frame (its error: a point and a rotation), and the tracker
/// reports the probe's position ([`NOISE_MM`] per axis) and orientation (a random turn of
/// [`ORIENTATION_NOISE_DEG`] per axis).
pub fn measure_6d(
    chain: &Chain,
    n: usize,
    seed: u64,
    actual: impl Fn(&[f64]) -> Vec<f64>,
    tool_from_probe: nalgebra::Isometry3<f64>,
) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let measurements = (0..n)
        .map(|_| {
            let q = random_q(chain, &mut rng);
            let base_from_probe = chain.tool_pose(&actual(&q)).unwrap() * tool_from_probe;
            let noise = Vector3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng)) * NOISE_MM;
            let turn =
                Vector3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng)) * ORIENTATION_NOISE_DEG.to_radians();
            Measurement {
                time_min: 0.0,
                q,
                position_mm: base_from_probe.translation.vector + noise,
                orientation: Some(nalgebra::UnitQuaternion::from_scaled_axis(turn) * base_from_probe.rotation),
                position_std_mm: None,
                temps: Vec::new(),
            }
        })
        .collect();
    Dataset { measurements, ..Dataset::default() }
}

/// `n` poses as [`random_q`] draws them, but joint `joint` (0-based) kept between `lo_deg` and `hi_deg`
/// — a calibration set that covers a short arc of one joint; the robot stands at `actual(commanded)`,
/// measured without noise.
pub fn measure_short_arc(
    chain: &Chain,
    n: usize,
    seed: u64,
    (joint, lo_deg, hi_deg): (usize, f64, f64),
    actual: impl Fn(&[f64]) -> Vec<f64>,
) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let measurements = (0..n)
        .map(|_| {
            let mut q = random_q(chain, &mut rng);
            q[joint] = rng.random_range(lo_deg.to_radians()..hi_deg.to_radians());
            Measurement {
                time_min: 0.0,
                position_mm: chain.tool_pose(&actual(&q)).unwrap().translation.vector,
                q,
                orientation: None,
                position_std_mm: None,
                temps: Vec::new(),
            }
        })
        .collect();
    Dataset { measurements, ..Dataset::default() }
}

/// The robot the report exports, written as TOML (which must contain `written`) and read back, at each
/// pose of `other` with its sensor columns given as `fk --temperature` gives them (`temp_NAME=…`): its RMS
/// distance from where `other` measured is the report's as-exported hold-out figure (to 1e-6 mm). Returns
/// what the export says at the first pose without the columns.
pub fn export_given_the_columns(
    robot: &thermokin_chain::Robot,
    report: &thermokin_diagnose::Report,
    other: &Dataset,
    written: &str,
) -> String {
    let export = report.export_model(robot, None, "exported").unwrap();
    let text = thermokin_io::robot_model_to_toml(&export);
    assert!(text.contains(written), "{text}");
    let model = thermokin_io::parse_robot_model_toml("exported.toml".as_ref(), &text).unwrap();
    let mut sum = 0.0;
    for (m, readings) in other.measurements.iter().zip(&other.sensor_values) {
        let temperatures_c =
            other.sensor_names.iter().zip(readings).map(|(n, v)| (thermokin_io::sensor_name(n), *v)).collect();
        let state = thermokin_chain::OperatingState { temperatures_c, ..Default::default() };
        model.check_state(&state, false, false).unwrap();
        let p = model.tool_pose(&m.q, &state).unwrap().translation.vector;
        sum += (p - m.position_mm).norm_squared();
    }
    let rms = (sum / other.len() as f64).sqrt();
    let h = report.holdout.as_ref().unwrap();
    eprintln!(
        "the export given the columns: {rms:.4} mm RMS (the report: {:.4})",
        h.same_frame.selected.heldout_rms_mm
    );
    assert!((rms - h.same_frame.selected.heldout_rms_mm).abs() < 1e-6, "{rms}");
    model.tool_pose(&other.measurements[0].q, &Default::default()).unwrap_err().to_string()
}
