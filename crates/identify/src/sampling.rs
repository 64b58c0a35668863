//! Seeded random draws shared by everything that samples a robot: configurations within the joint
//! limits, and Gaussian noise.

use rand::Rng;
use thermokin_chain::Chain;

/// A configuration drawn uniformly within the joint limits, `margin` (a fraction of each joint's travel)
/// inside them on both sides — real calibration poses avoid the limits; within ±π, by the same margin, for
/// a joint without limits (a revolution covers every angle of a revolute joint).
pub fn random_configuration(chain: &Chain, margin: f64, rng: &mut impl Rng) -> Vec<f64> {
    chain
        .joints()
        .iter()
        .map(|j| {
            let (lo, hi) = j.limits.map_or((-std::f64::consts::PI, std::f64::consts::PI), |l| (l.lower, l.upper));
            let m = margin * (hi - lo);
            rng.random_range(lo + m..hi - m)
        })
        .collect()
}

/// A standard normal sample (Box–Muller), from `rng`.
pub fn normal(rng: &mut impl Rng) -> f64 {
    let u1: f64 = rng.random_range(f64::MIN_POSITIVE..1.0);
    let u2: f64 = rng.random_range(0.0..1.0);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}
