//! A tracker session as it runs (issue #48): poses measured one after the other over a warm-up, with a
//! truth the diagnosis does not share — the independent tracker of `tracker.rs` — and what only the
//! order tells, or must not be mistaken for it.

use thermokin_chain::Dataset;
use thermokin_diagnose::{Config, Validation, diagnose};
use thermokin_testdata::workspace;

/// `n` poses of the independent tracker on a robot standing at `actual(commanded)`, measured one after
/// the other over `minutes` (evenly spaced, from 0).
fn session(
    n: usize,
    minutes: f64,
    seed: u64,
    actual: impl Fn(&[f64]) -> Vec<f64>,
) -> (thermokin_chain::Robot, Dataset) {
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let mut data = crate::tracker::measure(robot.chain(), n, seed, actual);
    for (i, m) in data.measurements.iter_mut().enumerate() {
        m.time_min = minutes * i as f64 / (n - 1) as f64;
    }
    (robot, data)
}

/// Two static zero offsets, measured over three hours: nothing drifts, so no time law may be named —
/// an exponential drift over before all but a pose or two (τ of a tenth of a minute) is a static row,
/// and the offsets are what is named (issue #48's kept-aside case: `thermal_drift[3] (exponential)`
/// with τ = 0.1 min, whose export then refused `fk` without `--time`).
#[test]
fn static_offsets_in_a_timed_session_are_named_as_offsets_not_as_a_drift() {
    let (robot, data) = session(300, 180.0, 4821, |q| {
        let mut a = q.to_vec();
        a[1] += 0.04f64.to_radians();
        a[2] -= 0.03f64.to_radians();
        a
    });
    let config = Config { validation: Validation::SelectionOnly, ..Config::default() };
    let report = diagnose(&robot, &data, None, &config).unwrap();
    let chosen: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    eprintln!("chose {chosen:?}");
    assert!(chosen.iter().all(|e| !e.starts_with("thermal_drift")), "{chosen:?}");
    // Joint 2's and joint 3's offsets, as offsets or within the rows that contain them.
    for joint in [2, 3] {
        let named = report.effects.iter().any(|e| {
            e.label == format!("joint_offset[{joint}]")
                || e.contains.iter().any(|c| *c == format!("joint_offset[{joint}]"))
        });
        assert!(named, "joint {joint}'s offset not named: {chosen:?}");
    }
    assert!(report.additive.last().unwrap().stats.heldout_rms_mm < 2.0 * crate::tracker::NOISE_MM * 3f64.sqrt());
}
