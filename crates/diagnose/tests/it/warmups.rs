//! Issue #58: a warm-up's rise is never traded for a static deviation. The kept-aside robot's kind — an
//! IRB 140 whose joint 2 is 0.05° off, its row rising exponentially (τ = 40 min) and joint 3's linearly,
//! 240 poses over 180 minutes, 0.005 mm of tracker noise — drawn with rows of random size and sign. On
//! three such draws (seeds 10, 31, 40 of twenty-one tried, 10–40; the other eighteen already closed),
//! the exponential drift of joint 2 was fitted before joint 2's static row joined, took that row's
//! static part itself with τ ≈ 1 min, and was refused for good as "over before the poses"; joint 2
//! then kept a straight line through its rise and the next day's poses were predicted 0.021–0.034 mm
//! RMS, 0.05–0.11 mm at worst. The truth is built on the chain, not by the diagnosis's model; the next
//! day's 60 poses are predicted at their own minutes by the identified robot.

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::{Chain, Dataset, Measurement, OperatingState};
use thermokin_diagnose::{Config, Validation, diagnose};
use thermokin_testdata::{WarmUpLaw, error_mm_deg, gauss, random_q, warmed_up, workspace};

/// The warm-up of draw `seed`: joint 2's row (up to 0.3 mm, 0.02°) rising with τ = 40 min, joint 3's
/// (up to 0.15 mm, 0.01°) linearly, joint 2's zero 0.05° off.
fn truth(chain: &Chain, seed: u64) -> impl Fn(f64) -> Chain {
    let mut rng = ChaCha8Rng::seed_from_u64(seed * 7 + 1);
    let mut r = |s: f64| rng.random_range(-s..s);
    let row2 = error_mm_deg([r(0.3), r(0.3), r(0.3), r(0.02), r(0.02), r(0.01)]);
    let row3 = error_mm_deg([r(0.15), r(0.15), r(0.15), r(0.01), r(0.01), r(0.01)]);
    let chain = chain.clone();
    move |t: f64| {
        warmed_up(&chain, 0.05, (row2, WarmUpLaw::Exponential { tau_min: 40.0 }), (row3, WarmUpLaw::Linear), t)
    }
}

/// 240 poses over 180 minutes, in time order, 0.005 mm of noise per axis.
fn day1(chain: &Chain, truth: &dyn Fn(f64) -> Chain, seed: u64) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let measurements = (0..240)
        .map(|k| {
            let t = 180.0 * k as f64 / 239.0;
            let q = random_q(chain, &mut rng);
            let noise = Vector3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng)) * 0.005;
            Measurement {
                time_min: t,
                position_mm: truth(t).tool_pose(&q).unwrap().translation.vector + noise,
                q,
                orientation: None,
                position_std_mm: None,
                temps: vec![],
            }
        })
        .collect();
    Dataset { measurements, ..Default::default() }
}

#[test]
fn a_rise_fitted_before_its_rows_static_part_is_kept() {
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let chain = robot.chain().clone();
    for seed in [10, 31, 40] {
        let truth = truth(&chain, seed);
        let data = day1(&chain, &truth, seed);
        let config = Config { noise_mm: Some(0.005), validation: Validation::SelectionOnly, ..Config::default() };
        let report = diagnose(&robot, &data, None, &config).unwrap();
        let labels: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
        // The next day: 60 fresh poses, each at its own minute.
        let mut rng = ChaCha8Rng::seed_from_u64(2202);
        let (mut squares, mut worst) = (0.0, 0.0f64);
        for _ in 0..60 {
            let q = random_q(&chain, &mut rng);
            let t: f64 = rng.random_range(0.0..180.0);
            let predicted = report.identified.tool_pose(&q, &OperatingState::at_time(t)).unwrap().translation.vector;
            let e = (truth(t).tool_pose(&q).unwrap().translation.vector - predicted).norm();
            squares += e * e;
            worst = worst.max(e);
        }
        let rms = (squares / 60.0).sqrt();
        eprintln!("seed {seed}: {labels:?}; next day {rms:.4} mm RMS, {worst:.4} mm max");
        assert!(labels.contains(&"thermal_drift[2] (exponential)"), "seed {seed}: {labels:?}");
        assert!(rms <= 0.02 && worst <= 0.05, "seed {seed}: {rms:.4} mm RMS, {worst:.4} mm max");
    }
}
