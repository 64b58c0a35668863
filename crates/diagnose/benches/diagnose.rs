//! Criterion bench of a full diagnosis (240 poses over 240 minutes, every candidate, 5-fold, nested
//! validation), and of the selection alone at 60 to 480 poses: how the cost grows with the poses.
#![allow(missing_docs, clippy::unwrap_used)] // criterion_group! makes an undocumented fn; benches unwrap.

use criterion::{Criterion, criterion_group, criterion_main};
use thermokin_diagnose::{Config, HiddenEffect, SimulationConfig, Validation, diagnose, simulate};
use thermokin_identify::{DriftShape, Effect, JointIndex};

fn benches(c: &mut Criterion) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let base = thermokin_io::read_robot(&root.join("configs/irb140.toml")).unwrap();
    let joint = |j| JointIndex::of(&base, j).unwrap();
    let hidden = [
        HiddenEffect { effect: Effect::JointOffset(joint(2)), values: vec![0.05f64.to_radians()] },
        HiddenEffect {
            effect: Effect::ThermalDrift(joint(1), DriftShape::Linear),
            values: vec![0.0, 0.0, -0.4, 0.0, 0.0, 0.0],
        },
    ];
    let data = simulate(&base, &hidden, &SimulationConfig::default()).unwrap();
    let mut group = c.benchmark_group("diagnose");
    group.sample_size(10);
    group
        .bench_function("diagnose_240_poses", |b| b.iter(|| diagnose(&base, &data, None, &Config::default()).unwrap()));
    group.finish();
    // The same effects at 60 … 480 poses over the same 240 minutes, the selection only (one 5-fold ladder):
    // linear cost means the 480-pose run takes 8× the 60-pose one.
    let mut scaling = c.benchmark_group("diagnose_scaling");
    scaling.sample_size(10);
    let selection = Config { validation: Validation::SelectionOnly, ..Config::default() };
    for poses in [60, 120, 240, 480] {
        let data = simulate(&base, &hidden, &SimulationConfig { poses, ..SimulationConfig::default() }).unwrap();
        scaling.bench_with_input(criterion::BenchmarkId::new("selection", poses), &data, |b, data| {
            b.iter(|| diagnose(&base, data, None, &selection).unwrap())
        });
    }
    scaling.finish();
}

criterion_group!(group, benches);
criterion_main!(group);
