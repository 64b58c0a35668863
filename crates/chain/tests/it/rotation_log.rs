//! The rotation log and the quaternion angle against nalgebra's axis-angle constructor (an independent
//! implementation): relative rotations swept over [0, π], exactly π about every principal axis included,
//! and the last degrees before π where the old skew-part formula lost the axis.

use std::f64::consts::PI;

use nalgebra::{Rotation3, Unit, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::{rotation_angle, rotation_log};

/// Principal axes, their negatives, diagonals and seeded random unit axes.
fn axes() -> Vec<Unit<Vector3<f64>>> {
    let mut out: Vec<Unit<Vector3<f64>>> = vec![
        Vector3::x_axis(),
        Vector3::y_axis(),
        Vector3::z_axis(),
        -Vector3::x_axis(),
        -Vector3::y_axis(),
        -Vector3::z_axis(),
        Unit::new_normalize(Vector3::new(1.0, 1.0, 0.0)),
        Unit::new_normalize(Vector3::new(1.0, 1.0, 1.0)),
        Unit::new_normalize(Vector3::new(0.0, -1.0, 1.0)),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(0x5033);
    for _ in 0..40 {
        let v = Vector3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        out.push(Unit::new_normalize(v));
    }
    out
}

/// Angles over [0, π]: a uniform sweep, the small end, and the approach to π, π itself included.
fn angles() -> Vec<f64> {
    let mut out: Vec<f64> = (0..=180).map(|k| PI * k as f64 / 180.0).collect();
    out.extend([1e-15, 1e-12, 1e-9, 1e-6]);
    out.extend([PI - 1e-3, PI - 1e-6, PI - 1e-9, PI - 1e-12, PI]);
    out
}

/// Equal as rotations: at exactly π the vectors θu and −θu are the same rotation.
fn same_rotation_vector(got: &Vector3<f64>, want: &Vector3<f64>, angle: f64) -> f64 {
    let direct = (got - want).norm();
    if (angle - PI).abs() < 1e-6 {
        // Near π a rotation vector and its antipode differ by ~2π; compare as rotations.
        let a = Rotation3::new(*got);
        let b = Rotation3::new(*want);
        return direct.min(a.angle_to(&b));
    }
    direct
}

#[test]
fn log_matches_axis_angle_over_the_whole_range() {
    let mut worst = 0.0_f64;
    for axis in axes() {
        for &angle in &angles() {
            let r = Rotation3::from_axis_angle(&axis, angle);
            let w = rotation_log(r.matrix());
            // Tolerance: the matrix entries carry ~1e-16 rounding; the log's angle and axis inherit a few
            // ulps of it (1e-15 rad), also next to π, where the symmetric part still has norm ≥ 3/2.
            let err = same_rotation_vector(&w, &(axis.into_inner() * angle), angle);
            worst = worst.max(err);
            assert!(err < 1e-13, "axis {:?}, angle {angle}: log {w:?}, error {err:e}", axis.into_inner());
            // exp(log R) = R (nalgebra's exponential map, independent of the log), entry by entry:
            // `angle_to` (an acos) would only resolve ~1e-8 rad.
            let back = Rotation3::new(w);
            assert!((back.matrix() - r.matrix()).norm() < 1e-13, "exp(log R) ≠ R at angle {angle}");
        }
    }
    assert!(worst < 1e-13);
}

#[test]
fn half_turn_about_every_axis_is_pi_not_zero() {
    // The old path (`Rotation3::scaled_axis`) returned the zero vector here: a tool 180° from its target
    // read as on target.
    for axis in axes() {
        let r = Rotation3::from_axis_angle(&axis, PI);
        let w = rotation_log(r.matrix());
        assert!((w.norm() - PI).abs() < 1e-14, "axis {:?}: |log| = {}", axis.into_inner(), w.norm());
        assert!(w.normalize().dot(&axis).abs() > 1.0 - 1e-14);
    }
}

#[test]
fn quaternion_angle_matches_over_the_whole_range() {
    let start = UnitQuaternion::from_euler_angles(0.3, -1.1, 2.0);
    for axis in axes() {
        for &angle in &angles() {
            let b = start * UnitQuaternion::from_axis_angle(&axis, angle);
            let got = rotation_angle(&start, &b);
            // Relative accuracy near 0 (atan2 of the imaginary part) and ~1e-15 absolute elsewhere.
            assert!((got - angle).abs() <= 1e-14 + 1e-12 * angle, "axis {:?}, angle {angle}: {got}", axis.into_inner());
        }
    }
}
