//! Criterion bench of a full diagnosis: 240 poses over 240 minutes, every candidate, 5-fold.
#![allow(missing_docs, clippy::unwrap_used)] // criterion_group! makes an undocumented fn; benches unwrap.

use criterion::{Criterion, criterion_group, criterion_main};
use thermokin_diagnose::{Config, DriftShape, Effect, HiddenEffect, JointIndex, SimulationConfig, diagnose, simulate};

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
}

criterion_group!(group, benches);
criterion_main!(group);
