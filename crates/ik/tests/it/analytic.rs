//! Closed-form branches: every branch is a solution (checked by the chain's own FK, not the product of
//! exponentials the branches come from), the configuration a pose was made from is among them, the
//! geometry is recognised where it exists and refused where it does not, and on a deformed robot the
//! branches make every random-seed solve succeed.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::Chain;
use thermokin_deform::{DeviationTable, TableSemantics};
use thermokin_ik::{Goal, Params, SphericalWrist, Workspace, solve};
use thermokin_testdata::{urdf, workspace};

fn irb140() -> Chain {
    thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap().chain().clone()
}

fn random_q(chain: &Chain, rng: &mut ChaCha8Rng) -> Vec<f64> {
    chain.joints().iter().map(|j| j.limits.map_or(0.0, |l| rng.random_range(l.lower..l.upper))).collect()
}

/// Same angle up to whole turns.
fn same_angle(a: f64, b: f64) -> bool {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    d.min(std::f64::consts::TAU - d) < 1e-9
}

#[test]
fn every_branch_of_the_irb140_reaches_the_pose_and_one_is_the_configuration() {
    let chain = irb140();
    let wrist = SphericalWrist::detect(&chain).expect("the IRB 140 has a spherical wrist and parallel axes 2, 3");
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut eight = 0;
    for k in 0..500 {
        let q = random_q(&chain, &mut rng);
        let goal = chain.tool_pose(&q).unwrap();
        let all = wrist.branches(&goal);
        assert!(all.len() <= 8, "{k}: {} branches", all.len());
        let branches: Vec<_> = all.into_iter().filter(|b| b.exact).collect();
        eight += usize::from(branches.len() == 8);
        for b in &branches {
            let reached = chain.tool_pose(&b.q).unwrap();
            let dp = (reached.translation.vector - goal.translation.vector).norm();
            let dr = reached.rotation.angle_to(&goal.rotation);
            // Exact geometry: the closed form is exact up to rounding (a 600 mm arm, 1e-9 mm).
            assert!(dp < 1e-9 && dr < 1e-12, "{k}: branch {b:?} misses by {dp:e} mm, {dr:e} rad");
        }
        let found = branches.iter().any(|b| b.q.iter().zip(&q).all(|(x, y)| same_angle(*x, *y)));
        assert!(found, "{k}: {q:?} is not among {branches:?}");
    }
    // A 6R arm of this family has up to 8 solutions (2 shoulders × 2 elbows × 2 wrists); the shoulder
    // back is out of reach for many poses of the IRB 140 (its 70 mm shoulder offset).
    eprintln!("{eight}/500 poses with all eight branches exact");
    assert!(eight > 0, "no pose with eight exact branches");
}

#[test]
fn the_geometry_is_refused_where_it_does_not_exist() {
    for (file, tip) in [("ur5.urdf", "tool0"), ("ur10.urdf", "tool0"), ("panda.urdf", "panda_hand_tcp")] {
        let options = thermokin_io::RobotOptions { base: None, tip: Some(tip.into()) };
        let robot = thermokin_io::read_robot_with(&urdf(file), &options).unwrap();
        assert!(SphericalWrist::detect(robot.chain()).is_none(), "{file} taken for a spherical-wrist arm");
    }
    // The ROS-Industrial IRB 140 (another source of the same geometry) is recognised.
    let options = thermokin_io::RobotOptions { base: None, tip: Some("tool0".into()) };
    let abb = thermokin_io::read_robot_with(&urdf("abb_irb140.urdf"), &options).unwrap();
    assert!(SphericalWrist::detect(abb.chain()).is_some());
}

#[test]
fn on_a_deformed_irb140_random_seeds_always_succeed() {
    // Tables 10–11's case study: 1 mm and 1° on every axis of every row, read canonically.
    let table = DeviationTable::from_joint_rows(vec![thermokin_testdata::error_mm_deg([1.0; 6]); 6]);
    let chain = table.apply(&irb140(), &TableSemantics::Canonical).unwrap();
    assert!(SphericalWrist::detect(&chain).is_some(), "1° tilts stay near the ideal geometry");
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut ws = Workspace::new(6);
    let params = Params::default();
    let mut ok = 0;
    let n = 300;
    for k in 0..n {
        // A reachable pose (FK of a configuration inside the limits) and an unrelated seed.
        let goal = chain.tool_pose(&random_q(&chain, &mut rng)).unwrap();
        let seed = random_q(&chain, &mut rng);
        let s = solve(&chain, &Goal::Pose(goal), &seed, &params, &mut ws, k).unwrap();
        if s.converged() {
            ok += 1;
            assert!(chain.within_limits(&s.q));
            let reached = chain.tool_pose(&s.q).unwrap();
            assert!((reached.translation.vector - goal.translation.vector).norm() < 1e-8);
        }
    }
    assert_eq!(ok, n, "{ok}/{n} random-seed solves converged");
}
