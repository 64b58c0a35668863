//! Rotation logarithms and angles: the orientation errors every solver and report measures.
//!
//! Two independent metrics live here on purpose. [`rotation_log`] works on a rotation matrix and is what
//! the IK residual and the identification use; [`rotation_angle`] works on unit quaternions and is what a
//! result is checked with before it is called converged. A bug in one does not hide in the other.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// The rotation vector `θ·u` (axis times angle, θ ∈ [0, π]) of a rotation matrix: `R = exp([θu]×)`.
///
/// Exact through the whole range, π included:
/// - **θ < 120°** (`cos θ > −½`): the skew part `(R − Rᵀ)/2 = sin θ [u]×` gives `sin θ · u` at full relative
///   precision, and the angle is `atan2(sin θ, cos θ)`. (`acos((tr R − 1)/2)`, which nalgebra's
///   `scaled_axis` uses, resolves angles near 0 only to ~1e-8 rad, the square root of machine epsilon —
///   far above the 1.7e-11 rad (1e-9°) the IK must reach.)
/// - **θ ≥ 120°**: the skew part shrinks to zero at π, where nalgebra's `scaled_axis` returns the zero
///   vector — a half-turn error read as none. The symmetric part instead,
///   `(R + Rᵀ)/2 − cos θ · I = (1 − cos θ) u uᵀ` with `1 − cos θ ≥ 3/2`, gives `u` up to sign from its
///   largest column; the sign is taken from the skew part (any sign is right at exactly π, where `u` and
///   `−u` are the same rotation).
///
/// `r` must be a rotation matrix (orthonormal, det +1); the result is undefined otherwise.
///
/// ```
/// use nalgebra::{Rotation3, Vector3};
/// use thermokin_chain::rotation_log;
///
/// // A half turn about Z: the old `scaled_axis` path returned (0, 0, 0) here.
/// let half_turn = Rotation3::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI);
/// let w = rotation_log(half_turn.matrix());
/// assert!((w.norm() - std::f64::consts::PI).abs() < 1e-15);
/// assert!(w.x.abs() < 1e-15 && w.y.abs() < 1e-15);
/// ```
pub fn rotation_log(r: &Matrix3<f64>) -> Vector3<f64> {
    // sin θ · u from the skew-symmetric part.
    let s = Vector3::new(r[(2, 1)] - r[(1, 2)], r[(0, 2)] - r[(2, 0)], r[(1, 0)] - r[(0, 1)]) * 0.5;
    let sin = s.norm();
    let cos = ((r.trace() - 1.0) * 0.5).clamp(-1.0, 1.0);
    let angle = sin.atan2(cos);
    if cos > -0.5 {
        if sin < 1e-300 {
            return Vector3::zeros();
        }
        return s * (angle / sin);
    }
    // (1 − cos θ) u uᵀ from the symmetric part; its largest diagonal entry is ≥ (1 − cos θ)/3.
    let sym = (r + r.transpose()) * 0.5 - Matrix3::identity() * cos;
    let k = (0..3).max_by(|&a, &b| sym[(a, a)].total_cmp(&sym[(b, b)])).unwrap_or(0);
    let column = sym.column(k).into_owned();
    let mut u = column / column.norm();
    if u.dot(&s) < 0.0 {
        u = -u;
    }
    u * angle
}

/// The components `w, x, y, z` of a rotation's unit quaternion, with `w ≥ 0` (of the two quaternions that
/// describe it) and no negative zeros: the one form every writer prints.
pub fn quaternion_wxyz(rotation: &UnitQuaternion<f64>) -> [f64; 4] {
    let q = rotation.quaternion();
    let s = if q.w < 0.0 { -1.0 } else { 1.0 };
    [s * q.w + 0.0, s * q.i + 0.0, s * q.j + 0.0, s * q.k + 0.0]
}

/// The angle (radians, in [0, π]) of the rotation taking `a` to `b`: `2·atan2(|v|, |w|)` of the quaternion
/// `a⁻¹ b`.
///
/// Accurate to rounding at every angle (unlike `2·acos(w)`, which loses half the digits near 0). It shares
/// no code with [`rotation_log`]: the IK checks its convergence claim with it.
///
/// ```
/// use nalgebra::{UnitQuaternion, Vector3};
/// use thermokin_chain::rotation_angle;
///
/// let a = UnitQuaternion::from_euler_angles(0.1, 0.2, 0.3);
/// let b = a * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 1e-12);
/// // Rounding of the product is ~1e-16 rad, absolute: far below the 1e-8 rad that `2·acos(w)` resolves.
/// assert!((rotation_angle(&a, &b) - 1e-12).abs() < 1e-15);
/// ```
pub fn rotation_angle(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>) -> f64 {
    let rel = a.inverse() * b;
    2.0 * rel.imag().norm().atan2(rel.w.abs())
}
