//! Closed-form branches: every branch is a solution (checked by the chain's own FK, not the product of
//! exponentials the branches come from), the configuration a pose was made from is among them, the
//! geometry is recognised where it exists and refused where it does not, and on a deformed robot the
//! branches make every random-seed solve succeed.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::Chain;
use thermokin_deform::{DeviationTable, TableSemantics};
use thermokin_ik::{ClosedForm, Family, Goal, Params, Workspace, solve};
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

fn urdf_chain(file: &str, tip: &str) -> Chain {
    let options = thermokin_io::RobotOptions { base: None, tip: Some(tip.into()) };
    thermokin_io::read_robot_with(&urdf(file), &options).unwrap().chain().clone()
}

/// Every exact branch reaches the pose (checked by the chain's own FK, not the product of exponentials
/// the branches come from) and the configuration the pose was made from is among them.
fn branches_are_solutions(name: &str, chain: &Chain, family: Family) -> usize {
    let closed = ClosedForm::detect(chain).unwrap_or_else(|| panic!("{name}: no closed form found"));
    assert_eq!(closed.family(), family, "{name}");
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut eight = 0;
    for k in 0..500 {
        let q = random_q(chain, &mut rng);
        let goal = chain.tool_pose(&q).unwrap();
        let all = closed.branches(&goal);
        assert!(all.len() <= 8, "{name} {k}: {} branches", all.len());
        let branches: Vec<_> = all.into_iter().filter(|b| b.exact).collect();
        eight += usize::from(branches.len() == 8);
        let reach = goal.translation.vector.norm().max(1.0);
        for b in &branches {
            let reached = chain.tool_pose(&b.q).unwrap();
            let dp = (reached.translation.vector - goal.translation.vector).norm();
            let dr = reached.rotation.angle_to(&goal.rotation);
            // Exact geometry: exact up to rounding (1e-12 of the reach, and of a radian).
            assert!(dp < 1e-12 * reach && dr < 1e-12, "{name} {k}: branch {b:?} misses by {dp:e} mm, {dr:e} rad");
        }
        let found = branches.iter().any(|b| b.q.iter().zip(&q).all(|(x, y)| same_angle(*x, *y)));
        assert!(found, "{name} {k}: {q:?} is not among {branches:?}");
    }
    eprintln!("{name}: {eight}/500 poses with all eight branches exact");
    assert!(eight > 0, "{name}: no pose with eight exact branches");
    eight
}

#[test]
fn every_branch_reaches_the_pose_and_one_is_the_configuration() {
    // A 6R arm of these families has up to 8 solutions (2 shoulders × 2 elbows × 2 wrists); some are out
    // of reach for many poses (the IRB 140's 70 mm shoulder offset puts the shoulder-back ones far away).
    branches_are_solutions("IRB 140 (Table 9)", &irb140(), Family::SphericalWrist);
    branches_are_solutions(
        "IRB 140 (ROS-Industrial URDF)",
        &urdf_chain("abb_irb140.urdf", "tool0"),
        Family::SphericalWrist,
    );
    branches_are_solutions("UR5", &urdf_chain("ur5.urdf", "tool0"), Family::ParallelTriple);
    branches_are_solutions("UR10", &urdf_chain("ur10.urdf", "tool0"), Family::ParallelTriple);
}

#[test]
fn the_geometry_is_refused_where_it_does_not_exist() {
    // Seven-joint arms.
    for (file, tip) in [("panda.urdf", "panda_hand_tcp"), ("xarm7.urdf", "link_eef")] {
        assert!(ClosedForm::detect(&urdf_chain(file, tip)).is_none(), "{file}");
    }
    // An offset wrist: the IRB 140 with joint 6 moved 50 mm off joint 4's axis — axes 4, 5, 6 no longer
    // meet, and 4 is not parallel to 2.
    let chain = irb140();
    let mut joints = chain.joints().to_vec();
    joints[5].offset.y += 50.0;
    let offset = Chain::new(chain.base().clone(), joints, chain.tool().clone()).unwrap();
    assert!(ClosedForm::detect(&offset).is_none());
}

#[test]
fn on_deformed_robots_random_seeds_always_succeed() {
    // Tables 10–11's case study: 1 mm and 1° on every axis of every row, read canonically — on the
    // IRB 140 and on a UR5.
    let table = DeviationTable::from_joint_rows(vec![thermokin_testdata::error_mm_deg([1.0; 6]); 6]);
    for (name, nominal, family) in [
        ("IRB 140", irb140(), Family::SphericalWrist),
        ("UR5", urdf_chain("ur5.urdf", "tool0"), Family::ParallelTriple),
    ] {
        let chain = table.apply(&nominal, &TableSemantics::Canonical).unwrap();
        assert_eq!(
            ClosedForm::detect(&chain).map(|c| c.family()),
            Some(family),
            "{name}: 1° tilts stay near the ideal geometry"
        );
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut ws = Workspace::new(6);
        let params = Params::default();
        let (mut ok, mut restarts) = (0, 0);
        let n = 300;
        for k in 0..n {
            // A reachable pose (FK of a configuration inside the limits) and an unrelated seed.
            let goal = chain.tool_pose(&random_q(&chain, &mut rng)).unwrap();
            let seed = random_q(&chain, &mut rng);
            let s = solve(&chain, &Goal::Pose(goal), &seed, &params, &mut ws, k).unwrap();
            restarts += s.restarts;
            if s.converged() {
                ok += 1;
                assert!(chain.within_limits(&s.q));
                let reached = chain.tool_pose(&s.q).unwrap();
                assert!((reached.translation.vector - goal.translation.vector).norm() < 1e-8);
            }
        }
        eprintln!("{name}: {ok}/{n} converged, {restarts} restarts in all");
        assert_eq!(ok, n, "{name}: {ok}/{n} random-seed solves converged");
    }
}
