//! Criterion benches of the kinematic core: FK and pose + Jacobian of the IRB 140 with error parameters.
#![allow(missing_docs, clippy::unwrap_used)] // criterion_group! makes an undocumented fn; benches unwrap.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use thermokin_chain::{Chain, ErrorParams};

/// Table 9's IRB 140 with the case-study deviations (1 mm, 1° everywhere) on every joint, so that every
/// error rotation is really multiplied.
fn irb140_deformed() -> Chain {
    let nominal = thermokin_testdata::irb140_table9();
    let errors = vec![thermokin_testdata::error_mm_deg([1.0; 6]); 6];
    nominal.with_errors(ErrorParams::ZERO, &errors, ErrorParams::ZERO).expect("valid")
}

fn benches(c: &mut Criterion) {
    let chain = irb140_deformed();
    let q = [0.3, 0.4, 0.2, -0.5, -0.9, 0.7];
    c.bench_function("fk_irb140_deformed", |b| b.iter(|| chain.tool_position_rotation(black_box(&q))));
    c.bench_function("fk_irb140_deformed_isometry", |b| b.iter(|| chain.tool_pose(black_box(&q))));
    let mut cols = vec![[0.0; 6]; 6];
    c.bench_function("jacobian_irb140_deformed", |b| {
        b.iter(|| chain.pose_and_jacobian_into(black_box(&q), &mut cols).map(|_| ()))
    });
    c.bench_function("parameter_jacobian_irb140", |b| b.iter(|| chain.parameter_jacobian(black_box(&q))));
}

criterion_group! {
    name = group;
    config = Criterion::default().sample_size(50).measurement_time(std::time::Duration::from_secs(2)).warm_up_time(std::time::Duration::from_millis(500));
    targets = benches
}
criterion_main!(group);
