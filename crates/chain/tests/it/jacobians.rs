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

#[test]
fn small_angle_sines_are_the_library_ones_to_rounding() {
    // The Taylor branch (|x| ≤ 1e-2) against the library's sin and cos: within one rounding of the
    // result (2.3e-16 of cos ≈ 1; 2.3e-16 relative for sin).
    let mut x = -1e-2;
    while x <= 1e-2 {
        let (s, c) = thermokin_chain::sin_cos(x);
        assert!((s - x.sin()).abs() <= 2.3e-16 * x.abs().max(1e-300), "sin {x}: {s} vs {}", x.sin());
        assert!((c - x.cos()).abs() <= 2.3e-16, "cos {x}: {c} vs {}", x.cos());
        x += 1.37e-5;
    }
    // Beyond the branch, the library itself.
    assert_eq!(thermokin_chain::sin_cos(0.5), 0.5f64.sin_cos());
}

#[test]
fn the_identification_paths_equal_the_plain_ones() {
    // Given sines of the joint values (angle addition with the zero offsets) and a subset of the
    // parameter Jacobian's rows: equal to the plain FK and the full Jacobian to rounding (1e-12 of the
    // column scale), the columns not asked for left untouched.
    use thermokin_chain::ParameterRows;
    let mut r = rng(43);
    for chain in [irb140_like(&mut r, true), general_chain(&mut r)] {
        let dof = chain.dof();
        let layout = chain.parameter_layout();
        for trial in 0..10 {
            let q = random_q(&mut r, dof);
            let sc: Vec<(f64, f64)> = q.iter().map(|v| v.sin_cos()).collect();
            let (p, rot) = chain.tool_position_rotation(&q).unwrap();
            let (pf, rotf) = chain.tool_position_rotation_sin_cos(&q, &sc).unwrap();
            assert!((p - pf).norm() < 1e-9 && (rot - rotf).abs().max() < 1e-12);
            let full = chain.parameter_jacobian(&q).unwrap();
            let mut rows = ParameterRows::none(dof);
            rows.base = trial % 2 == 0;
            rows.tool = trial % 3 == 0;
            rows.joints[trial % dof] = true;
            rows.zeros[(trial + 1) % dof] = true;
            let sentinel = 12345.0;
            let mut some = Matrix6xX::from_element(layout.len(), sentinel);
            let (ps, _) = chain.pose_and_parameter_jacobian_rows_sin_cos(&q, &sc, &mut some, &rows).unwrap();
            assert!((ps - p).norm() < 1e-9);
            let asked = |c: usize| {
                (rows.base && c < 6)
                    || (rows.tool && (layout.tool()..layout.tool() + 6).contains(&c))
                    || (0..dof).any(|i| {
                        (rows.joints[i] && (layout.joint(i)..layout.joint(i) + 6).contains(&c))
                            || (rows.zeros[i] && c == layout.zero(i))
                    })
            };
            let scale = full.abs().max().max(1.0);
            for c in 0..layout.len() {
                if asked(c) {
                    let err = (some.column(c) - full.column(c)).abs().max();
                    assert!(err < 1e-12 * scale, "column {c}: {err:e}");
                } else {
                    assert!(some.column(c).iter().all(|&v| v == sentinel), "column {c} was written");
                }
            }
        }
        // Sines that are not those of one angle are refused.
        let q = random_q(&mut r, dof);
        let mut sc: Vec<(f64, f64)> = q.iter().map(|v| v.sin_cos()).collect();
        sc[0] = (0.5, 0.5);
        assert!(chain.tool_position_rotation_sin_cos(&q, &sc).is_err());
        assert!(chain.tool_position_rotation_sin_cos(&q, &sc[1..]).is_err());
    }
}
