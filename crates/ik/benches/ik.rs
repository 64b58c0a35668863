//! Criterion benches of the IK solver on the bundled IRB 140 under the case-study deformation: near and
#![allow(missing_docs, clippy::unwrap_used)] // criterion_group! makes an undocumented fn; benches unwrap.
//! random seeds, the faer and nalgebra steps, and the paper's 10,050-target transient program.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::{Chain, xyz_rotation};
use thermokin_deform::{AfterStabilization, DeviationTable, TableSemantics, TimeProfile};
use thermokin_ik::{Backend, Goal, Params, RestartSeeds, Seeds, Workspace, solve, solve_batch};

fn root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn robot() -> Chain {
    thermokin_io::read_robot(&root().join("configs/irb140.toml")).expect("bundled robot").chain().clone()
}

fn table() -> DeviationTable {
    DeviationTable::from_joint_rows(vec![thermokin_testdata::error_mm_deg([1.0; 6]); 6])
}

fn cases(chain: &Chain, n: usize, spread: f64, seed: u64) -> Vec<(Goal, Vec<f64>)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let q: Vec<f64> =
                chain.joints().iter().map(|j| j.limits.map_or(0.0, |l| rng.random_range(l.lower..l.upper))).collect();
            let s: Vec<f64> = if spread.is_finite() {
                q.iter()
                    .zip(chain.joints())
                    .map(|(v, j)| j.limits.unwrap().clamp(v + rng.random_range(-spread..spread)))
                    .collect()
            } else {
                chain.joints().iter().map(|j| j.limits.map_or(0.0, |l| rng.random_range(l.lower..l.upper))).collect()
            };
            (Goal::Pose(chain.tool_pose(&q).unwrap()), s)
        })
        .collect()
}

fn benches(c: &mut Criterion) {
    let chain = table().apply(&robot(), &TableSemantics::Canonical).unwrap();
    let mut ws = Workspace::new(6);
    // The default step (fixed-size 6 × 6) and faer's dynamic one, which chains of other sizes use.
    for (name, backend) in [("ik_near_seed", Backend::NalgebraFixed6), ("ik_near_seed_faer", Backend::Faer)] {
        let near = cases(&chain, 1000, 0.25, 1);
        let params = Params { backend, ..Params::default() };
        let mut k = 0;
        c.bench_function(name, |b| {
            b.iter(|| {
                let (t, s) = &near[k % near.len()];
                k += 1;
                black_box(solve(&chain, t, s, &params, &mut ws, k as u64).unwrap())
            })
        });
    }
    let random = cases(&chain, 2000, f64::INFINITY, 2);
    let params = Params::default();
    let ok = random
        .iter()
        .enumerate()
        .filter(|(i, (t, s))| solve(&chain, t, s, &params, &mut ws, *i as u64).unwrap().converged())
        .count();
    let _ = std::fs::create_dir_all(root().join("target/criterion"));
    let _ = std::fs::write(
        root().join("target/criterion/ik_random_success.txt"),
        format!("{}\n", ok as f64 / random.len() as f64),
    );
    for (name, restart_seeds) in [
        ("ik_random_seed", RestartSeeds::BranchesThenRandom),
        ("ik_random_seed_random_restarts", RestartSeeds::RandomOnly),
    ] {
        let params = Params { restart_seeds, ..Params::default() };
        let mut k = 0;
        c.bench_function(name, |b| {
            b.iter(|| {
                let (t, s) = &random[k % random.len()];
                k += 1;
                black_box(solve(&chain, t, s, &params, &mut ws, k as u64).unwrap())
            })
        });
    }
    k_peers(c, &chain);

    // The paper's transient program: 50 targets of Table 12, 201 model states (minutes 0..=200), each
    // target seeded from its previous solution.
    let text = std::fs::read_to_string(root().join("fixtures/paper/table12-targets.csv")).unwrap();
    let targets: Vec<Goal> = text
        .lines()
        .filter(|l| l.starts_with('P'))
        .map(|l| {
            let v: Vec<f64> = l.split(',').skip(1).map(|x| x.parse().unwrap()).collect();
            let r = xyz_rotation(&Vector3::new(v[3], v[4], v[5]).map(f64::to_radians));
            Goal::Pose(nalgebra::Isometry3::from_parts(
                Vector3::new(v[0], v[1], v[2]).into(),
                nalgebra::UnitQuaternion::from_matrix(&r),
            ))
        })
        .collect();
    let nominal = robot();
    let start = [0.0, 20.0, 20.0, 0.0, -45.0, 0.0].map(f64::to_radians);
    let first = solve_batch(&nominal, &targets, Seeds::ChainPrevious(&start), &params).unwrap();
    let profile = TimeProfile::Linear { stabilization_min: 180.0, after: AfterStabilization::KeepGrowing };
    let states: Vec<Chain> = (0..=200)
        .map(|t| profile.table_at(&table(), t as f64).unwrap().apply(&nominal, &TableSemantics::Canonical).unwrap())
        .collect();
    let mut group = c.benchmark_group("program");
    group.sample_size(10);
    group.bench_function("transient_10050", |b| {
        b.iter(|| {
            let mut seeds: Vec<Vec<f64>> = first.iter().map(|s| s.q.clone()).collect();
            let mut solved = 0;
            for state in &states {
                let sols = solve_batch(state, &targets, Seeds::PerTarget(&seeds), &params).unwrap();
                solved += sols.len();
                for (s, x) in seeds.iter_mut().zip(&sols) {
                    s.clone_from(&x.q);
                }
            }
            assert_eq!(solved, 10_050);
        })
    });
    group.finish();
}

/// The `k` crate (an independent Rust kinematics library) on the same deformed robot — our chain exported
/// as URDF, which k reads — and the same configurations: FK, the 6 × 6 Jacobian, and its Jacobian IK from
/// a seed within 0.25 rad at its own default step (multiplier 0.5) to 1e-6 m and 1e-6 rad, 100 tries.
/// Its success rate is written beside the timings (`target/criterion/k_ik_near_success.txt`).
fn k_peers(c: &mut Criterion, chain: &Chain) {
    use k::InverseKinematicsSolver;
    let dir = root().join("target/criterion");
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join("irb140-case-study.urdf");
    std::fs::write(&path, thermokin_urdf::export_urdf(chain, "irb140_case_study")).unwrap();
    let tree = k::Chain::<f64>::from_urdf_file(&path).unwrap();
    let arm = k::SerialChain::from_end(tree.find_link("tool0").unwrap());
    let near = cases(chain, 1000, 0.25, 1);
    let configs: Vec<Vec<f64>> = near.iter().map(|(_, s)| s.clone()).collect();
    let mut k = 0;
    c.bench_function("k_fk", |b| {
        b.iter(|| {
            arm.set_joint_positions_unchecked(&configs[k % configs.len()]);
            k += 1;
            black_box(arm.end_transform())
        })
    });
    c.bench_function("k_jacobian", |b| {
        b.iter(|| {
            arm.set_joint_positions_unchecked(&configs[k % configs.len()]);
            k += 1;
            arm.update_transforms();
            black_box(k::jacobian(&arm))
        })
    });
    // Goals in k's units (metres) from our targets.
    let goals: Vec<k::Isometry3<f64>> = near
        .iter()
        .map(|(g, _)| {
            let Goal::Pose(p) = g else { unreachable!("the bench's goals are poses") };
            let t = p.translation.vector / 1000.0;
            let q = p.rotation.coords;
            k::Isometry3::from_parts(
                k::Translation3::new(t.x, t.y, t.z),
                k::UnitQuaternion::from_quaternion(k::nalgebra::Quaternion::new(q.w, q.x, q.y, q.z)),
            )
        })
        .collect();
    let solver = k::JacobianIkSolver::new(1e-6, 1e-6, 0.5, 100);
    let ok = configs
        .iter()
        .zip(&goals)
        .filter(|(s, g)| {
            arm.set_joint_positions_unchecked(s);
            solver.solve(&arm, g).is_ok()
        })
        .count();
    let _ = std::fs::write(dir.join("k_ik_near_success.txt"), format!("{}\n", ok as f64 / configs.len() as f64));
    c.bench_function("k_ik_near_seed", |b| {
        b.iter(|| {
            let i = k % configs.len();
            k += 1;
            arm.set_joint_positions_unchecked(&configs[i]);
            black_box(solver.solve(&arm, &goals[i]).is_ok())
        })
    });
}

criterion_group! {
    name = group;
    config = Criterion::default().sample_size(50).measurement_time(std::time::Duration::from_secs(3)).warm_up_time(std::time::Duration::from_millis(500));
    targets = benches
}
criterion_main!(group);
