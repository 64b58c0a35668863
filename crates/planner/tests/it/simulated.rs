//! A hidden effect that random poses of the same count miss is found from the planned ones, and planning
//! after a refusal unlocks the refused effect. The robot measured is `thermokin-deform`'s robot model with
//! a cyclic encoder error on joint 4 — not the planner's model — plus seeded tracker noise.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::{Dataset, Measurement, OperatingState, Robot, units};
use thermokin_deform::{JointCorrection, RobotModel};
use thermokin_diagnose::{Config, Validation, diagnose};
use thermokin_planner::{Candidates, Criterion, Params, Poses, plan};

/// The IRB 140 and a pool where joint 4 barely turns: 98 % of the candidates within ±10° of zero, the rest
/// anywhere in its travel (a cell where wrist turns are the exception).
fn setup() -> (Robot, Vec<Vec<f64>>) {
    let robot = thermokin_io::read_robot(&thermokin_testdata::workspace("configs/irb140.toml")).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(404);
    let pool = (0..1500)
        .map(|k| {
            let mut q = thermokin_testdata::random_q(robot.chain(), &mut rng);
            if k % 50 != 0 {
                q[3] = units::radians(rng.random_range(-10.0..10.0));
            }
            q
        })
        .collect();
    (robot, pool)
}

/// The poses measured on the robot with a once- and twice-per-revolution error of joint 4 (0.1° and 0.05°).
fn measure(robot: &Robot, poses: &[Vec<f64>], seed: u64) -> Dataset {
    let mut corrections = vec![JointCorrection::NONE; 6];
    corrections[3].cyclic_rad = [units::radians(0.1), 0.0, 0.0, units::radians(0.05)];
    let truth = RobotModel::new(robot.clone()).with_joint_corrections(corrections).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let measurements = poses
        .iter()
        .map(|q| {
            let p = truth.tool_pose(q, &OperatingState::default()).unwrap().translation.vector;
            let noise = nalgebra::Vector3::from_fn(|_, _| 0.01 * thermokin_testdata::gauss(&mut rng));
            Measurement {
                time_min: 0.0,
                q: q.clone(),
                position_mm: p + noise,
                orientation: None,
                position_std_mm: None,
                temps: vec![],
            }
        })
        .collect();
    Dataset { measurements, ..Dataset::default() }
}

fn found(robot: &Robot, data: &Dataset) -> (bool, bool) {
    let config = Config { validation: Validation::SelectionOnly, noise_mm: Some(0.01), ..Config::default() };
    let report = diagnose(robot, data, None, &config).unwrap();
    let labels: Vec<&str> = report.effects.iter().chain(&report.completed).map(|e| e.label.as_str()).collect();
    eprintln!("{} poses: {labels:?}", data.len());
    let chosen = labels.contains(&"periodic[4]");
    let refused = report.identifiability.not_identifiable.iter().any(|r| r.effect == "periodic[4]");
    (chosen, refused)
}

#[test]
fn a_cyclic_error_random_poses_miss_is_found_from_the_planned_ones() {
    let (robot, pool) = setup();
    let candidates = Candidates::new(&robot, pool.clone(), vec![]).unwrap();
    // Planned for the parameters: where the robot works (the candidates) joint 4 barely turns, and a plan
    // for prediction there spends no pose on its cyclic error — which matters little there.
    let params = Params { poses: Poses::Exactly(30), criterion: Criterion::Parameters, ..Params::default() };
    let p = plan(&robot, &candidates, &[], &params).unwrap();
    let planned: Vec<Vec<f64>> = p.poses.iter().map(|x| x.joints_rad.clone()).collect();
    let (chosen, _) = found(&robot, &measure(&robot, &planned, 1));
    assert!(chosen, "the planned poses should reveal periodic[4]");
    // Three random draws of 30 from the same pool: none finds it.
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    for draw in 0..3 {
        let rows = rand::seq::index::sample(&mut rng, pool.len(), 30).into_vec();
        let random: Vec<Vec<f64>> = rows.iter().map(|&i| pool[i].clone()).collect();
        let (chosen, _) = found(&robot, &measure(&robot, &random, 2 + draw));
        assert!(!chosen, "random draw {draw} found periodic[4]");
    }
}

#[test]
fn planning_after_a_refusal_unlocks_the_refused_effect() {
    let (robot, pool) = setup();
    // Thirty poses measured where joint 4 barely turns: the cyclic error is refused for coverage.
    let measured: Vec<Vec<f64>> = pool.iter().filter(|q| q[3].abs() < units::radians(10.0)).take(30).cloned().collect();
    let (chosen, refused) = found(&robot, &measure(&robot, &measured, 3));
    assert!(!chosen && refused, "chosen {chosen}, refused {refused}");
    let candidates = Candidates::new(&robot, pool, vec![]).unwrap();
    let p = plan(&robot, &candidates, &measured, &Params { poses: Poses::Exactly(20), ..Params::default() }).unwrap();
    assert!(p.poses.iter().any(|x| x.helps.iter().any(|h| h == "periodic[4]")), "no pose helps periodic[4]");
    let mut all = measured.clone();
    all.extend(p.poses.iter().map(|x| x.joints_rad.clone()));
    let (chosen, refused) = found(&robot, &measure(&robot, &all, 3));
    assert!(chosen && !refused, "chosen {chosen}, refused {refused}");
}
