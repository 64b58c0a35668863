//! A thermal drift driven by one joint's own temperature, while the other sensors follow other curves:
//! data made by a robot built on the chain whose joint-3 row deviates in proportion to joint 3's logged
//! rise (not by the diagnosis's model). The diagnosis must name the drift on joint 3 and follow that
//! joint's column (`temp_j3`), not the mean of all sensors.

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use thermokin_chain::ErrorParams;
use thermokin_chain::{Dataset, Measurement};
use thermokin_diagnose::{Config, diagnose};
use thermokin_testdata::{error_mm_deg, workspace};

use crate::tracker::{NOISE_MM, gauss, random_q};

/// Sensor curves over a 240-minute run, K above the start: joint 2 warms fast (τ = 30 min, +8 K), joint 3
/// only after 60 minutes and then linearly (+4 K at 240), the ambient barely (+0.5 K, linear).
fn temps(t: f64) -> [f64; 3] {
    [8.0 * (1.0 - (-t / 30.0).exp()), 4.0 * ((t - 60.0).max(0.0) / 180.0), 0.5 * t / 240.0]
}

fn measure(names: [&str; 3]) -> (thermokin_chain::Robot, Dataset) {
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let chain = robot.chain().clone();
    // Joint 3's row per kelvin of its own rise.
    let per_kelvin = error_mm_deg([0.12, 0.0, -0.08, 0.008, 0.0, 0.004]);
    let mut rng = ChaCha8Rng::seed_from_u64(81);
    let n = 200;
    let measurements = (0..n)
        .map(|k| {
            let t = 240.0 * k as f64 / (n - 1) as f64;
            let q = random_q(&chain, &mut rng);
            let rise = temps(t);
            let mut rows = vec![ErrorParams::ZERO; 6];
            rows[2] = per_kelvin.scaled(rise[1]);
            let zeros = vec![0.0; 6];
            let warm = chain.with_errors_and_zeros(ErrorParams::ZERO, &rows, ErrorParams::ZERO, &zeros).unwrap();
            let noise = Vector3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng)) * NOISE_MM;
            Measurement {
                time_min: t,
                position_mm: warm.tool_pose(&q).unwrap().translation.vector + noise,
                q,
                orientation: None,
                position_std_mm: None,
                temps: rise.iter().map(|r| 22.0 + r).collect(),
            }
        })
        .collect();
    (
        robot,
        Dataset {
            measurements,
            temperature_names: names.map(String::from).to_vec(),
            source_lines: Vec::new(),
            ..Default::default()
        },
    )
}

#[test]
fn a_drift_follows_its_own_joints_temperature() {
    let (robot, data) = measure(["j2", "j3", "ambient"]);
    let report = diagnose(&robot, &data, None, &Config::default()).unwrap();
    let labels: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    let nested = report.nested.as_ref().unwrap();
    eprintln!(
        "own columns: found {labels:?}; nested {:.4} → {:.4} mm; {:?}",
        nested.nominal.heldout_rms_mm, nested.selected.heldout_rms_mm, nested.selections
    );
    assert_eq!(labels, ["thermal_drift[3] (temperature)"]);
    let noise_rms = NOISE_MM * 3f64.sqrt();
    assert!(nested.nominal.heldout_rms_mm > 10.0 * noise_rms);
    assert!(nested.selected.heldout_rms_mm <= 1.5 * noise_rms, "{} mm", nested.selected.heldout_rms_mm);
}

#[test]
fn without_joint_names_the_mean_of_the_sensors_cannot_follow_it() {
    // The same data with sensors named for no joint: every drift follows the mean rise, whose curve is
    // not joint 3's — what remains is well above the noise. (This is the control that shows the test
    // above depends on the per-joint columns.)
    let (robot, data) = measure(["s1", "s2", "s3"]);
    let report = diagnose(&robot, &data, None, &Config::default()).unwrap();
    let nested = report.nested.as_ref().unwrap();
    let labels: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    eprintln!(
        "mean rise: found {labels:?}; nested {:.4} → {:.4} mm",
        nested.nominal.heldout_rms_mm, nested.selected.heldout_rms_mm
    );
    assert!(nested.selected.heldout_rms_mm > 1.5 * NOISE_MM * 3f64.sqrt(), "{} mm", nested.selected.heldout_rms_mm);
}

#[test]
fn sensor_names_map_to_joints() {
    use thermokin_identify::sensor_joint;
    for (name, joint) in [
        ("j3", Some(2)),
        ("Joint_3", Some(2)),
        ("A1", Some(0)),
        ("axis-6", Some(5)),
        ("motor2", Some(1)),
        ("4", Some(3)),
    ] {
        assert_eq!(sensor_joint(name, 6), joint, "{name}");
    }
    for name in ["ambient", "j7", "j0", "base", "cabinet2"] {
        assert_eq!(sensor_joint(name, 6), None, "{name}");
    }
}
