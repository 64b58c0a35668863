//! Gravity torques against the potential energy they derive from: the torque gravity exerts about joint
//! `j` is `∂/∂q_j Σ_l m_l g·c_l(q)` (`c_l` the centre of mass of link `l` in the base frame), checked by
//! central differences of the centres of mass from [`Chain::joint_frames`] — a path that shares nothing
//! with the torques' one-pass sum but the chain's own FK.

use crate::support::*;
use nalgebra::{Point3, Vector3};
use rand::Rng;
use thermokin_chain::{Chain, LinkMass, gravity_torques, gravity_torques_into};

/// `Σ_l m_l (g·c_l)` in kg·mm²/s² (the work gravity does from the base frame's origin), for `down`.
fn potential(chain: &Chain, masses: &[Option<LinkMass>], q: &[f64], down: &Vector3<f64>) -> f64 {
    let frames = chain.joint_frames(q).unwrap();
    masses
        .iter()
        .zip(&frames)
        .filter_map(|(m, f)| m.map(|m| m.mass_kg * 9.80665 * down.dot(&(f * Point3::from(m.com_mm)).coords)))
        .sum()
}

#[test]
fn gravity_torques_are_the_derivative_of_gravity_s_work() {
    let mut r = rng(47);
    for chain in [irb140_like(&mut r, true), general_chain(&mut r)] {
        let n = chain.dof();
        let masses: Vec<Option<LinkMass>> = (0..n)
            .map(|l| {
                (l != 1).then(|| LinkMass {
                    mass_kg: r.random_range(0.5..20.0),
                    com_mm: Vector3::new(
                        r.random_range(-200.0..200.0),
                        r.random_range(-50.0..50.0),
                        r.random_range(0.0..300.0),
                    ),
                })
            })
            .collect();
        let down = nalgebra::Unit::new_normalize(Vector3::new(0.1, -0.2, -1.0));
        for _ in 0..20 {
            let q = random_q(&mut r, n);
            let tau = gravity_torques(&chain, &masses, &q, &down).unwrap();
            // Central differences: h = 1e-6 rad on a work of ~1e6 kg·mm²/s² (N·mm), truncation ~h²·1e6,
            // rounding ~1e-16·1e6/1e-6 = 1e-4 N·mm: 1e-6 N·m of tolerance per N·m of scale is above both.
            let h = 1e-6;
            for j in 0..n {
                let (mut qp, mut qm) = (q.clone(), q.clone());
                qp[j] += h;
                qm[j] -= h;
                let fd_nmm =
                    (potential(&chain, &masses, &qp, &down) - potential(&chain, &masses, &qm, &down)) / (2.0 * h);
                // N·mm per radian is 1/1000 N·m; a slide's derivative per mm is its force in N.
                let fd = if chain.joints()[j].kind == thermokin_chain::JointKind::Revolute {
                    fd_nmm / 1000.0
                } else {
                    fd_nmm
                };
                let scale = tau.iter().map(|t| t.abs()).fold(1.0, f64::max);
                assert!((tau[j] - fd).abs() < 1e-6 * scale, "joint {}: {} vs finite differences {}", j + 1, tau[j], fd);
            }
            // With the caller's sines: the same torques to rounding, into a reused buffer.
            let sc: Vec<(f64, f64)> = q.iter().map(|x| x.sin_cos()).collect();
            let mut out = vec![99.0; 2];
            gravity_torques_into(&chain, &masses, &q, Some(&sc), &down, &mut out).unwrap();
            assert_eq!(out.len(), n);
            for j in 0..n {
                assert!(
                    (out[j] - tau[j]).abs() < 1e-9 * (1.0 + tau[j].abs()),
                    "joint {}: {} vs {}",
                    j + 1,
                    out[j],
                    tau[j]
                );
            }
        }
    }
}
