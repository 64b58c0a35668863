//! The planner's speed: 60 poses out of 3,000 sampled candidates of the IRB 140 (the goal: ≤ 2 s
//! on 2 cores), and the growth with the candidates (1,500, 3,000, 6,000: no faster than linear).
#![allow(missing_docs, clippy::unwrap_used)] // criterion_group! makes an undocumented fn; benches unwrap.

use criterion::{Criterion, criterion_group, criterion_main};
use thermokin_identify::{FrameMode, ToolMode};
use thermokin_planner::{Candidates, Params, Poses, plan};

fn bench(c: &mut Criterion) {
    let robot = thermokin_io::read_robot(&thermokin_testdata::workspace("configs/irb140.toml")).unwrap();
    let params =
        Params { poses: Poses::Exactly(60), frame: FrameMode::Tracker, tool: ToolMode::Unknown, ..Params::default() };
    let mut group = c.benchmark_group("plan");
    group.sample_size(10);
    for n in [1500, 3000, 6000] {
        let pool = Candidates::sampled(&robot, n, 1, None).unwrap();
        group.bench_function(format!("60_of_{n}"), |b| b.iter(|| plan(&robot, &pool, &[], &params).unwrap()));
    }
    group.finish();
    if let Some(mib) = thermokin_testdata::peak_rss_mib() {
        eprintln!("plan: peak memory {mib:.0} MiB");
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
