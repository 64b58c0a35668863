//! DH / modified DH / extended conversions and the two error groupings give the same FK.

use crate::support::*;
use nalgebra::{Isometry3, Vector3};
use thermokin_chain::{Chain, ChainError, DhConvention, ErrorGrouping, FixedRow, Joint};

/// 1e-9 mm is the contract; the FK of a 6-link chain with ~1 m reach in f64 carries ~1e-12 mm of
/// rounding, so this leaves three orders of magnitude of margin and still catches any real mistake.
const MM: f64 = 1e-9;
const RAD: f64 = 1e-12;

fn assert_same_fk(
    name: &str,
    a: impl Fn(&[f64]) -> Isometry3<f64>,
    b: impl Fn(&[f64]) -> Isometry3<f64>,
    n: usize,
    seed: u64,
) {
    let mut rng = rng(seed);
    let mut worst = (0.0f64, 0.0f64);
    for _ in 0..1000 {
        let q = random_q(&mut rng, n);
        let (dp, dr) = pose_gap(&a(&q), &b(&q));
        worst = (worst.0.max(dp), worst.1.max(dr));
    }
    assert!(worst.0 < MM && worst.1 < RAD, "{name}: worst gap {:.3e} mm, {:.3e} rad", worst.0, worst.1);
}

#[test]
fn classic_dh_to_extended_is_exact() {
    for seed in 0..5 {
        let table = random_dh(&mut rng(100 + seed), DhConvention::Classic, 6);
        let chain = table.to_extended().expect("converts");
        assert_same_fk("dh", |q| table.tool_pose(q).unwrap(), |q| chain.tool_pose(q).unwrap(), 6, seed);
    }
}

#[test]
fn modified_dh_to_extended_is_exact() {
    for seed in 0..5 {
        let table = random_dh(&mut rng(200 + seed), DhConvention::Modified, 6);
        let chain = table.to_extended().expect("converts");
        assert_same_fk("mdh", |q| table.tool_pose(q).unwrap(), |q| chain.tool_pose(q).unwrap(), 6, seed);
    }
}

#[test]
fn extended_to_modified_dh_round_trip() {
    // The IRB 140 shape with error parameters on joints 2–6 and the tool: the axes are skew lines now, and
    // the modified-DH table must still reproduce the FK. Base row and joint 1 stay error-free: a tilted or
    // sideways-shifted first axis has no MDH table without a base transform (see the refusal test).
    let mut r = rng(7);
    let chain = irb140_like(&mut r, true);
    let mut joints = chain.joints().to_vec();
    joints[0].error = thermokin_chain::ErrorParams::ZERO;
    let chain = Chain::new(FixedRow::identity(), joints, chain.tool().clone()).unwrap();
    let table = chain.to_modified_dh().expect("an MDH table exists");
    assert_same_fk("ext->mdh", |q| chain.tool_pose(q).unwrap(), |q| table.tool_pose(q).unwrap(), 6, 8);
    let back = table.to_extended().unwrap();
    assert_same_fk("mdh->ext", |q| chain.tool_pose(q).unwrap(), |q| back.tool_pose(q).unwrap(), 6, 9);
}

#[test]
fn extended_to_modified_dh_of_a_general_chain_from_its_own_mdh() {
    for seed in 0..5 {
        let table = random_dh(&mut rng(300 + seed), DhConvention::Modified, 6);
        let table = thermokin_chain::DhTable { base: Isometry3::identity(), ..table };
        let chain = table.to_extended().unwrap();
        let again = chain.to_modified_dh().expect("exists by construction");
        assert_same_fk("mdh round trip", |q| table.tool_pose(q).unwrap(), |q| again.tool_pose(q).unwrap(), 6, seed);
    }
}

#[test]
fn extended_to_modified_dh_refuses_a_tilted_first_axis() {
    let joints = vec![
        Joint::revolute(
            "j1",
            Vector3::new(0.0, 0.0, 100.0),
            nalgebra::Unit::new_normalize(Vector3::new(1.0, 0.0, 1.0)),
        ),
        Joint::revolute("j2", Vector3::new(0.0, 0.0, 100.0), Vector3::y_axis()),
    ];
    let chain = Chain::new(FixedRow::identity(), joints, FixedRow::identity()).unwrap();
    match chain.to_modified_dh() {
        Err(ChainError::NoModifiedDh { joint: 1, reason }) => assert!(reason.contains("perpendicular"), "{reason}"),
        other => panic!("expected NoModifiedDh on joint 1, got {other:?}"),
    }
    // A first axis offset sideways along Y (the base X line misses it) is refused too.
    let joints = vec![Joint::revolute("j1", Vector3::new(0.0, 50.0, 100.0), Vector3::z_axis())];
    let chain = Chain::new(FixedRow::identity(), joints, FixedRow::identity()).unwrap();
    assert!(matches!(chain.to_modified_dh(), Err(ChainError::NoModifiedDh { joint: 1, .. })));
}

#[test]
fn paper_eq21_grouping_gives_the_same_fk() {
    let mut r = rng(11);
    let chain = irb140_like(&mut r, true);
    // Re-read every joint's parameters as eq. 21 would write them, then build the eq. 21 product by hand.
    let eq21: Vec<_> = chain
        .joints()
        .iter()
        .map(|j| j.error.regroup(ErrorGrouping::Canonical, ErrorGrouping::PaperEq21, &j.offset))
        .collect();
    let mut r2 = rng(12);
    for _ in 0..200 {
        let q = random_q(&mut r2, 6);
        let mut t = chain.base().pose();
        for ((j, e), &qi) in chain.joints().iter().zip(&eq21).zip(&q) {
            // T_C (eq. 21) = Trans(Δp) · Rx · Ry · Rz · Trans(p); then R_i (eq. 22).
            let tc = Isometry3::from_parts(
                e.translation.into(),
                nalgebra::UnitQuaternion::from_matrix(&e.rotation_matrix()),
            ) * Isometry3::translation(j.offset.x, j.offset.y, j.offset.z);
            t = t * tc * Isometry3::rotation(j.axis.into_inner() * qi);
        }
        t *= chain.tool().pose();
        let (dp, dr) = pose_gap(&t, &chain.tool_pose(&q).unwrap());
        assert!(dp < MM && dr < RAD, "{dp:.3e} mm {dr:.3e} rad");
        // And back: eq. 21 → canonical restores the parameters.
        for (j, e) in chain.joints().iter().zip(&eq21) {
            let back = e.regroup(ErrorGrouping::PaperEq21, ErrorGrouping::Canonical, &j.offset);
            assert!((back.translation - j.error.translation).norm() < 1e-12);
        }
    }
}

#[test]
fn general_axes_and_prismatic_joints_survive_dh_round_trip() {
    let mut r = rng(21);
    let chain = general_chain(&mut r).with_base(FixedRow::identity()).unwrap();
    // The first axis of a random chain is tilted: no MDH without a base transform. Put joint 1 on Z.
    let mut joints = chain.joints().to_vec();
    joints[0].axis = Vector3::z_axis();
    joints[0].offset = Vector3::new(0.0, 0.0, 50.0);
    joints[0].error = thermokin_chain::ErrorParams::ZERO;
    let chain = Chain::new(FixedRow::identity(), joints, chain.tool().clone()).unwrap();
    let table = chain.to_modified_dh().expect("exists");
    assert_same_fk("general", |q| chain.tool_pose(q).unwrap(), |q| table.tool_pose(q).unwrap(), 6, 22);
}

#[test]
fn bad_chains_are_errors_not_panics() {
    let nan = Joint::revolute("j", Vector3::new(f64::NAN, 0.0, 0.0), Vector3::z_axis());
    assert!(matches!(
        Chain::new(FixedRow::identity(), vec![nan], FixedRow::identity()),
        Err(ChainError::NonFinite { joint: 1, .. })
    ));
    let zero_axis = Joint {
        axis: nalgebra::Unit::new_unchecked(Vector3::zeros()),
        ..Joint::revolute("j", Vector3::zeros(), Vector3::z_axis())
    };
    assert!(matches!(
        Chain::new(FixedRow::identity(), vec![zero_axis], FixedRow::identity()),
        Err(ChainError::BadAxis { joint: 1 })
    ));
    let chain = irb140_like(&mut rng(1), false);
    assert!(matches!(chain.tool_pose(&[0.0; 5]), Err(ChainError::WrongJointCount { expected: 6, got: 5 })));
    assert!(matches!(
        chain.tool_pose(&[0.0, f64::INFINITY, 0.0, 0.0, 0.0, 0.0]),
        Err(ChainError::NonFiniteJoint { joint: 2 })
    ));
    let bad_limits = Joint::revolute("j", Vector3::zeros(), Vector3::z_axis()).with_limits(1.0, -1.0);
    assert!(matches!(
        Chain::new(FixedRow::identity(), vec![bad_limits], FixedRow::identity()),
        Err(ChainError::BadLimits { joint: 1, .. })
    ));
}
