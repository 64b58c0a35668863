//! The geometric and parameter Jacobians against central finite differences.

use crate::support::*;
use nalgebra::{Isometry3, Matrix6xX, Vector6};
use thermokin_chain::{Chain, ErrorParams};

/// Twist that takes `a` to `b`, divided by nothing: (Δp, log(R_b R_aᵀ)).
fn delta(a: &Isometry3<f64>, b: &Isometry3<f64>) -> Vector6<f64> {
    let dp = b.translation.vector - a.translation.vector;
    let dr = (b.rotation * a.rotation.inverse()).scaled_axis();
    Vector6::new(dp.x, dp.y, dp.z, dr.x, dr.y, dr.z)
}

/// Central differences with step h: truncation error ~ h² · |third derivative| ≈ 1e-10 · 1000 mm, rounding
/// ~ 1e-16 · 1000 / 1e-5 = 1e-8; a relative tolerance of 1e-6 of the column scale is safely above both and
/// orders of magnitude below any wrong column (whose error is of the size of the column itself).
const H: f64 = 1e-5;

fn check(name: &str, analytic: &Matrix6xX<f64>, fd: &Matrix6xX<f64>) {
    let scale = analytic.abs().max().max(1.0);
    let err = (analytic - fd).abs().max();
    assert!(err < 1e-6 * scale, "{name}: max |analytic − FD| = {err:.3e} (scale {scale:.1})");
}

#[test]
fn geometric_jacobian_matches_finite_differences() {
    let mut r = rng(31);
    for chain in [irb140_like(&mut r, false), irb140_like(&mut r, true), general_chain(&mut r)] {
        for _ in 0..50 {
            let q = random_q(&mut r, chain.dof());
            let j = chain.jacobian(&q).unwrap();
            let mut fd = Matrix6xX::zeros(chain.dof());
            for i in 0..chain.dof() {
                let (mut qp, mut qm) = (q.clone(), q.clone());
                qp[i] += H;
                qm[i] -= H;
                let d = delta(&chain.tool_pose(&qm).unwrap(), &chain.tool_pose(&qp).unwrap()) / (2.0 * H);
                fd.set_column(i, &d);
            }
            check("geometric", &j, &fd);
        }
    }
}

fn perturbed(chain: &Chain, col: usize, h: f64) -> Chain {
    let layout = chain.parameter_layout();
    let n = chain.dof();
    let mut base = chain.base().error.as_array();
    let mut tool = chain.tool().error.as_array();
    let mut joints: Vec<[f64; 6]> = chain.joints().iter().map(|j| j.error.as_array()).collect();
    let mut zeros: Vec<f64> = chain.joints().iter().map(|j| j.zero).collect();
    if col < layout.joint(0) {
        base[col] += h;
    } else if col < layout.tool() {
        let k = col - layout.joint(0);
        joints[k / 6][k % 6] += h;
    } else if col < layout.zero(0) {
        tool[col - layout.tool()] += h;
    } else {
        zeros[col - layout.zero(0)] += h;
    }
    let errs: Vec<ErrorParams> = joints.into_iter().map(ErrorParams::from_array).collect();
    let c = chain.with_errors(ErrorParams::from_array(base), &errs, ErrorParams::from_array(tool)).unwrap();
    assert_eq!(c.dof(), n);
    c.with_zeros(&zeros).unwrap()
}

#[test]
fn parameter_jacobian_matches_finite_differences() {
    let mut r = rng(41);
    for chain in [irb140_like(&mut r, false), irb140_like(&mut r, true), general_chain(&mut r)] {
        for _ in 0..10 {
            let q = random_q(&mut r, chain.dof());
            let j = chain.parameter_jacobian(&q).unwrap();
            let cols = chain.parameter_layout().len();
            assert_eq!(j.ncols(), cols);
            let mut fd = Matrix6xX::zeros(cols);
            for c in 0..cols {
                let plus = perturbed(&chain, c, H).tool_pose(&q).unwrap();
                let minus = perturbed(&chain, c, -H).tool_pose(&q).unwrap();
                fd.set_column(c, &(delta(&minus, &plus) / (2.0 * H)));
            }
            check("parameter", &j, &fd);
        }
    }
}

#[test]
fn joint_frames_end_at_the_tool_pose() {
    let mut r = rng(51);
    let chain = irb140_like(&mut r, true);
    let q = random_q(&mut r, 6);
    let frames = chain.joint_frames(&q).unwrap();
    assert_eq!(frames.len(), 7);
    let (dp, dr) = pose_gap(frames.last().unwrap(), &chain.tool_pose(&q).unwrap());
    assert!(dp < 1e-12 && dr < 1e-12);
}

#[test]
fn the_fast_paths_equal_the_slow_ones() {
    // `set_joint_error` (one row rewritten in place) against a chain rebuilt from scratch, and
    // `pose_and_parameter_jacobian` against `tool_pose` and `parameter_jacobian` separately: bit for bit,
    // since the same operations run in the same order.
    let mut r = rng(37);
    for chain in [irb140_like(&mut r, true), general_chain(&mut r)] {
        let errors: Vec<ErrorParams> = chain.joints().iter().map(|j| j.error).collect();
        let zeros: Vec<f64> = chain.joints().iter().map(|j| j.zero).collect();
        let mut fast = chain.clone();
        for j in 0..chain.dof() {
            let e = ErrorParams::from_array([0.1 * j as f64, -0.2, 0.3, 1e-3, -2e-3, 3e-3 * j as f64]);
            fast.set_joint_error(j, e).unwrap();
            let mut slow_errors = errors.clone();
            slow_errors[..=j].iter_mut().enumerate().for_each(|(k, s)| {
                *s = ErrorParams::from_array([0.1 * k as f64, -0.2, 0.3, 1e-3, -2e-3, 3e-3 * k as f64])
            });
            let slow =
                chain.with_errors_and_zeros(chain.base().error, &slow_errors, chain.tool().error, &zeros).unwrap();
            for _ in 0..10 {
                let q = random_q(&mut r, chain.dof());
                assert_eq!(fast.tool_pose(&q).unwrap(), slow.tool_pose(&q).unwrap());
                let both = slow.pose_and_parameter_jacobian(&q).unwrap();
                let (p, rot) = slow.tool_position_rotation(&q).unwrap();
                assert_eq!((both.position, both.rotation), (p, rot));
                assert_eq!(both.jacobian, fast.parameter_jacobian(&q).unwrap());
            }
        }
        // Refused, and the chain unchanged: a joint it lacks, a non-finite error.
        let before = fast.clone();
        assert!(fast.set_joint_error(chain.dof(), ErrorParams::ZERO).is_err());
        assert!(fast.set_joint_error(0, ErrorParams::from_array([f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0])).is_err());
        assert_eq!(fast, before);
    }
}
