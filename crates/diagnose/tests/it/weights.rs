//! The tracker's per-point standard deviations as weights: a third of the points measured ten times
//! worse (farther from the tracker), each with its stated σ. Weighted least squares takes the offset from
//! the good points; unweighted, the bad ones blur it. Data made by the chain moved to the erroneous
//! joints, noise drawn per point from its own σ (not the diagnosis's model).

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use thermokin_chain::{Dataset, Measurement};
use thermokin_diagnose::{Config, Outliers, Validation, diagnose};
use thermokin_testdata::workspace;

use crate::tracker::{gauss, random_q};

fn data(stated: bool) -> (thermokin_chain::Robot, Dataset) {
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let chain = robot.chain().clone();
    let mut rng = ChaCha8Rng::seed_from_u64(111);
    let measurements = (0..150)
        .map(|k| {
            let q = random_q(&chain, &mut rng);
            let mut actual = q.clone();
            actual[1] += 0.05f64.to_radians();
            let sigma = if k % 3 == 0 { 0.05 } else { 0.005 };
            let noise = Vector3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng)) * sigma;
            Measurement {
                time_min: 0.0,
                position_mm: chain.tool_pose(&actual).unwrap().translation.vector + noise,
                q,
                orientation: None,
                position_std_mm: stated.then(|| Vector3::repeat(sigma)),
                temps: Vec::new(),
            }
        })
        .collect();
    (robot, Dataset { measurements, ..Dataset::default() })
}

#[test]
fn stated_standard_deviations_weight_the_fit() {
    // Every point kept: the comparison is of the fits' weighting. (The screen for gross errors is
    // checked below: with the σ stated it flags none of the noisy points; without, it flags them, ten
    // times the bulk's noise.)
    let config = Config { validation: Validation::SelectionOnly, outliers: Outliers::Keep, ..Config::default() };
    let offset = |stated: bool| {
        let (robot, data) = data(stated);
        let report = diagnose(&robot, &data, None, &config).unwrap();
        let e = report.effects.iter().find(|e| e.label == "joint_offset[2]").expect("joint_offset[2] found");
        let v = &e.parameters["joint_offset[2].offset_deg"];
        (v.value, v.std.unwrap())
    };
    let (weighted, weighted_sd) = offset(true);
    let (plain, plain_sd) = offset(false);
    eprintln!("weighted {weighted:.6} ± {weighted_sd:.6}°, unweighted {plain:.6} ± {plain_sd:.6}° (truth 0.05°)");
    // The good points carry ~0.7 of the weight with 1/10 of the noise: the weighted uncertainty is
    // about a quarter of the unweighted one (0.005/√0.7 against the blended 0.028 mm per axis).
    assert!(weighted_sd < 0.5 * plain_sd);
    assert!((weighted - 0.05).abs() < 3.0 * weighted_sd, "{weighted} ± {weighted_sd}");
}

#[test]
fn standard_deviations_round_trip_and_must_be_positive() {
    let (robot, data) = data(true);
    let kinds: Vec<_> = robot.chain().joints().iter().map(|j| j.kind).collect();
    let mut text = Vec::new();
    thermokin_io::write_measurements(&mut text, &data, &kinds).unwrap();
    let text = String::from_utf8(text).unwrap();
    let back = thermokin_io::parse_measurements(std::path::Path::new("m.csv"), &text, &kinds).unwrap();
    assert!(back.measurements.iter().zip(&data.measurements).all(|(a, b)| a.position_std_mm == b.position_std_mm));
    let bad = "q1,q2,q3,q4,q5,q6,x,y,z,std_x,std_y,std_z\n0,0,0,0,0,0,1,2,3,0.01,0,0.01\n";
    let err = thermokin_io::parse_measurements(std::path::Path::new("m.csv"), bad, &kinds).unwrap_err().to_string();
    assert!(err.contains("m.csv:2: std_y") && err.contains("positive"), "{err}");
}

#[test]
fn stated_standard_deviations_keep_noisy_points_from_being_flagged() {
    // The noisy third is measured as stated: judged against its own σ, none is a gross error. Without
    // the σ, the same points are ten times the bulk's noise, and the screen flags most of them.
    let config = Config { validation: Validation::SelectionOnly, ..Config::default() };
    let (robot, stated) = data(true);
    assert!(diagnose(&robot, &stated, None, &config).unwrap().outliers.is_empty());
    let (robot, unstated) = data(false);
    let flagged = diagnose(&robot, &unstated, None, &config).unwrap().outliers;
    assert!(flagged.iter().all(|o| (o.measurement - 1) % 3 == 0), "only the noisy points: {flagged:?}");
    assert!(flagged.len() > 25, "{} of the 50 noisy points", flagged.len());
}
