//! 10,000 seeded random reachable targets, nominal and under the case-study deformation; FK∘IK = id;
//! unreachable, singular and bad inputs; batch determinism.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::Chain;
use thermokin_deform::{DeviationTable, TableSemantics};
use thermokin_ik::{Goal, IkError, Params, Seeds, Status, Workspace, solve, solve_batch};
use thermokin_testdata::workspace;

fn irb140() -> Chain {
    thermokin_io::read_robot(&workspace("configs/irb140.toml")).expect("bundled robot").chain().clone()
}

fn deformed() -> Chain {
    // Tables 10–11: 1 mm and 1° on every axis of every joint.
    let table = DeviationTable::from_joint_rows(vec![thermokin_testdata::error_mm_deg([1.0; 6]); 6]);
    table.apply(&irb140(), &TableSemantics::Canonical).unwrap()
}

fn random_in_limits(chain: &Chain, rng: &mut ChaCha8Rng) -> Vec<f64> {
    chain.joints().iter().map(|j| j.limits.map_or(0.0, |l| rng.random_range(l.lower..l.upper))).collect()
}

/// (target, the q it came from)
fn reachable_targets(chain: &Chain, n: usize, seed: u64) -> Vec<(Goal, Vec<f64>)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let q = random_in_limits(chain, &mut rng);
            (Goal::Pose(chain.tool_pose(&q).unwrap()), q)
        })
        .collect()
}

/// FK of the solution against the target: the tolerances of a converged solve, checked independently.
fn check_fk(chain: &Chain, t: &Goal, q: &[f64]) {
    let Goal::Pose(goal) = t else { unreachable!() };
    let reached = chain.tool_pose(q).unwrap();
    let dp = (reached.translation.vector - goal.translation.vector).norm();
    let dr = reached.rotation.angle_to(&goal.rotation).to_degrees();
    assert!(dp <= 1e-9 && dr <= 1e-9, "FK(IK(x)) off by {dp:.3e} mm, {dr:.3e}°");
    assert!(chain.within_limits(q));
}

fn near_seed_case(chain: &Chain, seed: u64) {
    let params = Params::default();
    let targets = reachable_targets(chain, 10_000, seed);
    let mut rng = ChaCha8Rng::seed_from_u64(seed + 1);
    let seeds: Vec<Vec<f64>> = targets
        .iter()
        .map(|(_, q)| {
            let mut s: Vec<f64> = q.iter().map(|v| v + rng.random_range(-0.25..0.25)).collect();
            for (v, j) in s.iter_mut().zip(chain.joints()) {
                *v = j.limits.unwrap().clamp(*v);
            }
            s
        })
        .collect();
    let ts: Vec<Goal> = targets.iter().map(|(t, _)| *t).collect();
    let sols = solve_batch(chain, &ts, Seeds::PerTarget(&seeds), &params).unwrap();
    let failed: Vec<_> = sols
        .iter()
        .enumerate()
        .filter(|(_, s)| !s.converged())
        .map(|(i, s)| (i, s.status, s.position_error_mm))
        .collect();
    let restarted = sols.iter().filter(|s| s.restarts > 0).count();
    eprintln!("near seeds: {restarted} of 10,000 needed a restart");
    assert!(
        failed.is_empty(),
        "{} of 10,000 near-seed solves failed: {:?}",
        failed.len(),
        &failed[..failed.len().min(5)]
    );
    for (s, t) in sols.iter().zip(&ts) {
        check_fk(chain, t, &s.q);
    }
}

#[test]
fn near_seeds_converge_always_nominal() {
    near_seed_case(&irb140(), 10);
}

#[test]
fn near_seeds_converge_always_deformed() {
    near_seed_case(&deformed(), 20);
}

fn random_seed_case(chain: &Chain, seed: u64) {
    let params = Params::default();
    let targets = reachable_targets(chain, 10_000, seed);
    let ts: Vec<Goal> = targets.iter().map(|(t, _)| *t).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed + 7);
    let seeds: Vec<Vec<f64>> = (0..ts.len()).map(|_| random_in_limits(chain, &mut rng)).collect();
    let sols = solve_batch(chain, &ts, Seeds::PerTarget(&seeds), &params).unwrap();
    let ok = sols.iter().filter(|s| s.converged()).count();
    eprintln!("random seeds: {ok} of 10,000 converged");

    assert!(ok >= 9_990, "{ok} of 10,000");
    for (s, t) in sols.iter().zip(&ts).filter(|(s, _)| s.converged()) {
        check_fk(chain, t, &s.q);
    }
}

#[test]
fn random_seeds_with_restarts_nominal() {
    random_seed_case(&irb140(), 30);
}

#[test]
fn random_seeds_with_restarts_deformed() {
    random_seed_case(&deformed(), 40);
}

#[test]
fn far_target_is_unreachable_quickly() {
    let chain = irb140();
    let target = Goal::Pose(nalgebra::Isometry3::translation(5000.0, 0.0, 0.0));
    let mut ws = Workspace::new(6);
    let s = solve(&chain, &target, &[0.0; 6], &Params::default(), &mut ws, 0).unwrap();
    assert_eq!(s.status, Status::Unreachable);
    // "Quickly" is a property of the algorithm — no iteration and no restart at all, decided by the reach
    // bound before any solve — not a timing (speed lives in the benches).
    assert_eq!((s.iterations, s.restarts), (0, 0));
    // Inside the reach sphere but outside the joint limits' workspace: reported, not hung.
    let behind_and_low = Goal::Position(nalgebra::Vector3::new(-100.0, 0.0, -400.0));
    let s =
        solve(&chain, &behind_and_low, &[0.0; 6], &Params { restarts: 5, ..Params::default() }, &mut ws, 0).unwrap();
    assert!(matches!(s.status, Status::Unreachable | Status::JointLimit | Status::Singular), "{:?}", s.status);
}

#[test]
fn wrist_singular_targets_converge_or_report() {
    let chain = irb140();
    let mut rng = ChaCha8Rng::seed_from_u64(55);
    let mut ws = Workspace::new(6);
    let mut converged = 0;
    for _ in 0..200 {
        let mut q = random_in_limits(&chain, &mut rng);
        q[4] = 0.0; // joints 4 and 6 aligned: wrist singularity
        let target = Goal::Pose(chain.tool_pose(&q).unwrap());
        let seed: Vec<f64> = q.iter().map(|v| v + rng.random_range(-0.2..0.2)).collect();
        let s = solve(&chain, &target, &seed, &Params::default(), &mut ws, 0).unwrap();
        if s.converged() {
            check_fk(&chain, &target, &s.q);
            converged += 1;
        } else {
            assert!(matches!(s.status, Status::Singular | Status::Unreachable | Status::JointLimit));
        }
    }
    eprintln!("wrist-singular targets: {converged} of 200 converged");
    assert!(converged >= 190, "{converged}");
}

#[test]
fn position_only_targets() {
    let chain = irb140();
    let mut rng = ChaCha8Rng::seed_from_u64(66);
    let mut ws = Workspace::new(6);
    for _ in 0..500 {
        let q = random_in_limits(&chain, &mut rng);
        let p = chain.tool_pose(&q).unwrap().translation.vector;
        let s = solve(&chain, &Goal::Position(p), &[0.0; 6], &Params::default(), &mut ws, 0).unwrap();
        assert!(s.converged(), "{:?}", s.status);
        assert!((chain.tool_pose(&s.q).unwrap().translation.vector - p).norm() <= 1e-9);
    }
}

#[test]
fn batch_is_deterministic_across_thread_counts() {
    let chain = deformed();
    let targets: Vec<Goal> = reachable_targets(&chain, 500, 77).into_iter().map(|(t, _)| t).collect();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| solve_batch(&chain, &targets, Seeds::Same(&[0.0; 6]), &Params::default()).unwrap())
    };
    let one = run(1);
    // The same under load: two busy threads compete for the cores. With no wall clock in the solver (the
    // default `time_budget` is None) the answers cannot depend on how fast they are computed.
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let busy: Vec<_> = (0..2)
        .map(|_| {
            let stop = stop.clone();
            std::thread::spawn(move || {
                let mut x = 0u64;
                while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                    x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
                }
                x
            })
        })
        .collect();
    let four = run(4);
    let one_loaded = run(1);
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    for b in busy {
        b.join().unwrap();
    }
    // Bit-identical: the full solutions, not just their statuses.
    assert_eq!(one, four);
    assert_eq!(one, one_loaded);
    assert_eq!(Params::default().time_budget, None);
}

#[test]
fn chained_seeding_keeps_the_branch() {
    // A straight line of 100 targets walked with chained seeds: every solution stays within a small step
    // of the previous one (no branch flips).
    let chain = irb140();
    let q0 = [0.2, 0.3, 0.1, 0.4, -0.8, 0.3];
    let start = chain.tool_pose(&q0).unwrap();
    let targets: Vec<Goal> = (0..100)
        .map(|k| {
            let mut p = start;
            p.translation.vector.y += k as f64 * 2.0;
            Goal::Pose(p)
        })
        .collect();
    let params = Params { restarts: 0, max_distance_from_seed: Some(0.2), ..Params::default() };
    let sols = solve_batch(&chain, &targets, Seeds::ChainPrevious(&q0), &params).unwrap();
    assert!(sols.iter().all(|s| s.converged()));
    for w in sols.windows(2) {
        let step = w[0].q.iter().zip(&w[1].q).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(step < 0.05, "{step}");
    }
}

#[test]
fn bad_inputs_are_errors() {
    let chain = irb140();
    let mut ws = Workspace::new(6);
    let t = Goal::Position(nalgebra::Vector3::new(500.0, 0.0, 500.0));
    assert_eq!(
        solve(&chain, &t, &[0.0; 5], &Params::default(), &mut ws, 0),
        Err(IkError::SeedLength { expected: 6, got: 5 })
    );
    assert_eq!(
        solve(&chain, &t, &[0.0, 0.0, f64::NAN, 0.0, 0.0, 0.0], &Params::default(), &mut ws, 0),
        Err(IkError::SeedNotFinite { joint: 3 })
    );
    let nan = Goal::Position(nalgebra::Vector3::new(f64::NAN, 0.0, 0.0));
    assert!(matches!(
        solve(&chain, &nan, &[0.0; 6], &Params::default(), &mut ws, 3),
        Err(IkError::BadTarget { index: 3 })
    ));
    let p = Params { length_scale_mm: -1.0, ..Params::default() };
    assert_eq!(
        solve(&chain, &t, &[0.0; 6], &p, &mut ws, 0),
        Err(IkError::BadParams { field: "length_scale_mm", value: -1.0 })
    );
}
