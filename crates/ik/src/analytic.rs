//! Closed-form branches of six-joint arms — with a spherical wrist (the IRB 140 and most ABB, KUKA and
//! Fanuc arms) or with three parallel axes 2, 3, 4 (the UR family) — used as seeds: all (up to 8)
//! analytic solutions of the chain's *ideal* geometry, which the Levenberg–Marquardt loop then refines on
//! the actual (deformed) chain. The spherical case is derived below; the parallel one at
//! [`ClosedForm`]'s `parallel` step.
//!
//! # The math
//! Any serial chain is a product of exponentials (Brockett): with each joint's axis line `(a_i, p_i)` at
//! the zero configuration and `g₀` the TCP pose there, `g(q) = e₁(q₁) ⋯ e₆(q₆) g₀`, where
//! `e_i(x) = p_i + R(a_i, q_i)(x − p_i)`. The same-orientation table makes the lines direct to read: they
//! are the joint frames of `Chain::joint_frames(0)`. When axes 2 and 3 are parallel and axes 4, 5, 6 meet
//! in one point `c` (the wrist centre), the problem splits into Paden–Kahan subproblems:
//! - `e₄e₅e₆ c = c`, so the wrist centre obeys `e₁e₂e₃ c = w` with `w = g_t g₀⁻¹ c`;
//! - rotations about lines parallel to `a₂` keep the coordinate `a₂·x`: `a₂·e₁⁻¹(w) = a₂·c` gives `q₁`
//!   (two solutions: shoulder front and back);
//! - `e₂` keeps the distance to `p₂`: `|e₃ c − p₂| = |e₁⁻¹(w) − p₂|` gives `q₃` (elbow up and down), then
//!   `q₂` rotates `e₃ c − p₂` onto `e₁⁻¹(w) − p₂`;
//! - the wrist rotation `R₄R₅R₆ = (R₁R₂R₃)ᵀ R_t R₀ᵀ`: `a₄·R_w a₆ = a₄·R₅ a₆` gives `q₅` (wrist flip), and
//!   `q₄`, `q₆` each rotate one known vector onto another.
//!
//! Every equation of the form `x · R(k, θ) v = d` is `A cos θ + B sin θ = d − C` with
//! `A = x·v − (x·k)(k·v)`, `B = x·(k × v)`, `C = (x·k)(k·v)` (Rodrigues).
//!
//! A deformed chain is only near this geometry (its axes tilt by its error parameters): the branches are
//! computed on the ideal geometry closest to it (axis 3 made parallel to axis 2, the wrist centre the
//! point nearest to the three wrist axes), where an equation has no exact solution its nearest one is
//! taken, and the refinement does the rest. Chains near neither geometry (a seven-joint arm, prismatic
//! joints, an offset wrist) get no branches: the solver falls back to its restarts.

use std::f64::consts::{PI, TAU};

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Unit, Vector3};
use thermokin_chain::{Chain, JointKind};

/// Largest angle (rad) between axes 2 and 3 still treated as parallel: 5°, far above any calibration or
/// thermal error (the paper's case study tilts each row by 1° per axis) and far below the 90° of an arm
/// whose axes are not parallel by design.
const PARALLEL_TOL: f64 = 0.087;
/// Largest distance (mm) of a wrist axis from the wrist centre still treated as a spherical wrist: 5 mm,
/// above the millimetre errors of a deformed model, below the ~100 mm wrist offsets of the UR family.
const WRIST_TOL_MM: f64 = 5.0;
/// Axes whose directions are closer than this (|cos| above it) cannot carry a subproblem.
const DISTINCT_COS: f64 = 0.999;

/// One closed-form solution: the six joint values of one branch (one root of each of the `q₁`, `q₃` and
/// `q₅` equations). Which configuration it is in a controller's terms (ABB's confdata, KUKA's Status) is
/// read from the joint values, not from the order of the roots.
#[derive(Clone, Debug, PartialEq)]
pub struct Branch {
    /// Joint values, radians, each in (−π, π].
    pub q: [f64; 6],
    /// Every equation on the way had an exact solution: on the ideal geometry this branch reaches the
    /// pose. `false` when one was out of range (the pose is out of this branch's reach, e.g. behind the
    /// shoulder) and its nearest solution was taken.
    pub exact: bool,
}

/// Which closed form an arm's geometry allows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// Axes 2 ∥ 3 and axes 4, 5, 6 through one point (the IRB 140, most ABB, KUKA, Fanuc arms).
    SphericalWrist,
    /// Axes 2 ∥ 3 ∥ 4 and axes 5, 6 meeting (the UR family).
    ParallelTriple,
}

/// The zero-configuration geometry of an arm whose closed form exists: its axis lines, the point its
/// last joints leave fixed (the wrist centre, or where axes 5 and 6 meet), the TCP pose at zero.
#[derive(Clone, Debug)]
pub struct ClosedForm {
    family: Family,
    axes: [Vector3<f64>; 6],
    points: [Vector3<f64>; 6],
    /// `sᵢ` with `aᵢ = sᵢ a₂` for the axes made parallel to axis 2 (the others 1).
    senses: [f64; 6],
    centre: Vector3<f64>,
    tcp_at_zero: Isometry3<f64>,
}

impl ClosedForm {
    /// The ideal geometry nearest to `chain`, or `None` when the chain is not a six-revolute-joint arm of
    /// a [`Family`] (axes within 5° of parallel, wrist axes within 5 mm of their common point).
    pub fn detect(chain: &Chain) -> Option<Self> {
        if chain.dof() != 6 || chain.joints().iter().any(|j| j.kind != JointKind::Revolute) {
            return None;
        }
        let zero = [0.0; 6];
        let frames = chain.joint_frames(&zero).ok()?;
        let tcp_at_zero = chain.tool_pose(&zero).ok()?;
        let mut axes = [Vector3::zeros(); 6];
        let mut points = [Vector3::zeros(); 6];
        for (i, (f, j)) in frames.iter().zip(chain.joints()).enumerate() {
            axes[i] = f.rotation * j.axis.into_inner();
            points[i] = f.translation.vector;
        }
        let parallel_to_2 = |k: usize| axes[1].dot(&axes[k]).abs() >= PARALLEL_TOL.cos();
        let distinct = |a: usize, b: usize| axes[a].dot(&axes[b]).abs() <= DISTINCT_COS;
        // Axes 2 and 3 parallel (either sense); axis 1 not parallel to them.
        if !parallel_to_2(2) || !distinct(0, 1) {
            return None;
        }
        let meeting = |ks: &[usize]| -> Option<Vector3<f64>> {
            let lines: Vec<_> = ks.iter().map(|&k| (points[k], axes[k])).collect();
            let c = nearest_point(&lines)?;
            let on_all = ks.iter().all(|&k| {
                let off = c - points[k];
                (off - axes[k] * axes[k].dot(&off)).norm() <= WRIST_TOL_MM
            });
            on_all.then_some(c)
        };
        let mut senses = [1.0; 6];
        let mut make_parallel = |axes: &mut [Vector3<f64>; 6], k: usize| {
            senses[k] = axes[1].dot(&axes[k]).signum();
            axes[k] = axes[1] * senses[k];
        };
        let (family, centre) = if distinct(3, 4) && distinct(5, 4) && !parallel_to_2(3) {
            (Family::SphericalWrist, meeting(&[3, 4, 5])?)
        } else if parallel_to_2(3) && distinct(4, 1) && distinct(5, 4) {
            (Family::ParallelTriple, meeting(&[4, 5])?)
        } else {
            return None;
        };
        make_parallel(&mut axes, 2);
        if family == Family::ParallelTriple {
            make_parallel(&mut axes, 3);
        }
        Some(Self { family, axes, points, senses, centre, tcp_at_zero })
    }

    /// The geometry found.
    pub fn family(&self) -> Family {
        self.family
    }

    /// Every closed-form solution for the TCP pose `goal` (up to 8), in branch order. Where the ideal
    /// geometry has no exact solution (a target just out of reach, or a deformed chain), the nearest one.
    pub fn branches(&self, goal: &Isometry3<f64>) -> Vec<Branch> {
        let (a, p, c) = (&self.axes, &self.points, self.centre);
        let w = (goal * self.tcp_at_zero.inverse() * Point3::from(c)).coords;
        // q₁ (both families): rotations about lines parallel to a₂ keep a₂·x, and the last joints keep c:
        // a₂ · (p₁ + R(a₁, −q₁)(w − p₁)) = a₂ · c.
        let (q1s, exact1) = solve_projection(&a[1], &a[0], &(w - p[0]), a[1].dot(&(c - p[0])));
        let mut out = Vec::with_capacity(8);
        for &t1 in &q1s {
            match self.family {
                Family::SphericalWrist => self.spherical(goal, -t1, w, exact1, &mut out),
                Family::ParallelTriple => self.parallel(goal, -t1, exact1, &mut out),
            }
        }
        out
    }

    /// `q₂ … q₆` of a spherical-wrist arm for one `q₁` (see the module documentation).
    fn spherical(&self, goal: &Isometry3<f64>, q1: f64, w: Vector3<f64>, exact1: bool, out: &mut Vec<Branch>) {
        let (a, p, c) = (&self.axes, &self.points, self.centre);
        let rt = goal.rotation.to_rotation_matrix();
        let r0 = self.tcp_at_zero.rotation.to_rotation_matrix();
        let r1 = rot(&a[0], q1);
        let w1 = p[0] + r1.transpose() * (w - p[0]);
        // q₃: |(p₃ − p₂) + R(a₃, q₃)(c − p₃)|² = |w₁ − p₂|².
        let (l, u) = (p[2] - p[1], c - p[2]);
        let target = ((w1 - p[1]).norm_squared() - l.norm_squared() - u.norm_squared()) / 2.0;
        let (q3s, exact3) = solve_projection(&l, &a[2], &u, target);
        for &q3 in &q3s {
            let r3 = rot(&a[2], q3);
            let y = l + r3 * u;
            let q2 = rotation_onto(&a[1], &y, &(w1 - p[1]));
            let r123 = r1 * rot(&a[1], q2) * r3;
            let rw = r123.transpose() * rt.matrix() * r0.matrix().transpose();
            let (x, k, v) = (&a[3], &a[4], &a[5]);
            let (q5s, exact5) = solve_projection(x, k, v, x.dot(&(rw * v)));
            for &q5 in &q5s {
                let r5 = rot(k, q5);
                let q4 = rotation_onto(x, &(r5 * v), &(rw * v));
                let q6 = -rotation_onto(v, &(r5.transpose() * x), &(rw.transpose() * x));
                out.push(Branch { q: [q1, q2, q3, q4, q5, q6].map(wrap), exact: exact1 && exact3 && exact5 });
            }
        }
    }

    /// `q₂ … q₆` of an arm with axes 2 ∥ 3 ∥ 4 and axes 5, 6 meeting in `c`, for one `q₁`: the rotation
    /// `M = R₁ᵀ R_t R₀ᵀ = R₂₃₄ R₅ R₆`, where `R₂₃₄` keeps `a₂`, gives `q₅` from `a₂·M a₆ = a₂·R₅ a₆` and
    /// `q₆` from `R₆ᵀR₅ᵀ a₂ = Mᵀ a₂`; then axis 4's point `p₄` (which `e₄` keeps) must reach
    /// `e₁⁻¹ g g₀⁻¹ e₆⁻¹ e₅⁻¹ p₄`: the planar two-link problem of the spherical case for `q₂`, `q₃`, and
    /// `q₄` closes the angle of `R₂₃₄`.
    fn parallel(&self, goal: &Isometry3<f64>, q1: f64, exact1: bool, out: &mut Vec<Branch>) {
        let (a, p, s) = (&self.axes, &self.points, &self.senses);
        let rt = goal.rotation.to_rotation_matrix();
        let r0 = self.tcp_at_zero.rotation.to_rotation_matrix();
        let r1 = rot(&a[0], q1);
        let m = r1.transpose() * rt.matrix() * r0.matrix().transpose();
        let (q5s, exact5) = solve_projection(&a[1], &a[4], &a[5], a[1].dot(&(m * a[5])));
        for &q5 in &q5s {
            let r5 = rot(&a[4], q5);
            let q6 = -rotation_onto(&a[5], &(r5.transpose() * a[1]), &(m.transpose() * a[1]));
            let r6 = rot(&a[5], q6);
            let r234 = m * r6.transpose() * r5.transpose();
            let across = a[1].cross(&a[0]).normalize();
            let angle234 = rotation_onto(&a[1], &across, &(r234 * across));
            // Where axis 4's point must go, seen from after joint 1.
            let x5 = p[4] + r5.transpose() * (p[3] - p[4]);
            let x6 = p[5] + r6.transpose() * (x5 - p[5]);
            let w4 = (goal * self.tcp_at_zero.inverse() * Point3::from(x6)).coords;
            let w41 = p[0] + r1.transpose() * (w4 - p[0]);
            let (l, u) = (p[2] - p[1], p[3] - p[2]);
            let target = ((w41 - p[1]).norm_squared() - l.norm_squared() - u.norm_squared()) / 2.0;
            let (q3s, exact3) = solve_projection(&l, &a[2], &u, target);
            for &q3 in &q3s {
                let y = l + rot(&a[2], q3) * u;
                let q2 = rotation_onto(&a[1], &y, &(w41 - p[1]));
                // R₂₃₄ turns about a₂ by q₂ + s₃q₃ + s₄q₄.
                let q4 = s[3] * (angle234 - q2 - s[2] * q3);
                out.push(Branch { q: [q1, q2, q3, q4, q5, q6].map(wrap), exact: exact1 && exact3 && exact5 });
            }
        }
    }
}

/// The rotation matrix `R(k, θ)` about the unit axis `k`.
fn rot(k: &Vector3<f64>, theta: f64) -> Matrix3<f64> {
    *Rotation3::from_axis_angle(&Unit::new_unchecked(*k), theta).matrix()
}

/// Angle into (−π, π].
fn wrap(t: f64) -> f64 {
    let r = t.rem_euclid(TAU);
    if r > PI { r - TAU } else { r }
}

/// The angles θ with `x · R(k, θ) v = d` (Rodrigues: `A cos θ + B sin θ = d − C`) and whether they are
/// exact: two, or the one nearest when `|d − C|` exceeds the amplitude (not exact), or none when
/// `x · R v` does not depend on θ.
fn solve_projection(x: &Vector3<f64>, k: &Vector3<f64>, v: &Vector3<f64>, d: f64) -> (Vec<f64>, bool) {
    let (xk, kv) = (x.dot(k), k.dot(v));
    let a = x.dot(v) - xk * kv;
    let b = x.dot(&k.cross(v));
    let amplitude = a.hypot(b);
    if amplitude < 1e-12 * (x.norm() * v.norm()).max(1e-300) {
        return (Vec::new(), false);
    }
    let phase = b.atan2(a);
    let ratio = (d - xk * kv) / amplitude;
    // 1e-12 of the amplitude: rounding of a pose exactly on the boundary of the reach.
    let exact = ratio.abs() <= 1.0 + 1e-12;
    let spread = ratio.clamp(-1.0, 1.0).acos();
    (if spread == 0.0 { vec![phase] } else { vec![phase + spread, phase - spread] }, exact)
}

/// The angle θ that turns `v` onto `w` about `k` (Paden–Kahan subproblem 1, on the components
/// perpendicular to `k`); 0 when either has none (a singular configuration: any θ serves).
fn rotation_onto(k: &Vector3<f64>, v: &Vector3<f64>, w: &Vector3<f64>) -> f64 {
    let vp = v - k * k.dot(v);
    let wp = w - k * k.dot(w);
    if vp.norm_squared() < 1e-24 || wp.norm_squared() < 1e-24 {
        return 0.0;
    }
    k.dot(&vp.cross(&wp)).atan2(vp.dot(&wp))
}

/// The point nearest (least squares) to lines `(point, unit direction)`; `None` when they are parallel.
fn nearest_point(lines: &[(Vector3<f64>, Vector3<f64>)]) -> Option<Vector3<f64>> {
    let mut m = Matrix3::zeros();
    let mut rhs = Vector3::zeros();
    for (p, d) in lines {
        let proj = Matrix3::identity() - d * d.transpose();
        m += proj;
        rhs += proj * p;
    }
    m.try_inverse().map(|inv| inv * rhs)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn projection_equation_solutions_satisfy_it() {
        let x = Vector3::new(0.3, -0.5, 0.8);
        let k = Vector3::new(1.0, 2.0, -0.5).normalize();
        let v = Vector3::new(-0.2, 0.9, 0.4);
        for d in [-0.3, 0.0, 0.2] {
            let (angles, exact) = solve_projection(&x, &k, &v, d);
            assert!(exact);
            for t in angles {
                assert!((x.dot(&(rot(&k, t) * v)) - d).abs() < 1e-12, "{d} {t}");
            }
        }
    }

    #[test]
    fn rotation_onto_turns_one_vector_onto_the_other() {
        let k = Vector3::new(0.0, 0.6, 0.8);
        let v = Vector3::new(1.0, 0.2, -0.3);
        let w = rot(&k, 1.234) * v;
        assert!((rotation_onto(&k, &v, &w) - 1.234).abs() < 1e-12);
    }
}
