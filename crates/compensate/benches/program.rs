//! A million-target static compensation, streamed: targets generated on the fly as CSV text (FK of
//! seeded configurations of the nominal IRB 140 away from its singularities), read by the targets
//! reader in chunks, solved on every core, the joint CSV written to a sink. Timed once per size (a
//! 10-second workload does not fit criterion's sampling); the process's peak resident memory is read
//! after each size to show that it does not grow with the number of targets. Written to
//! `target/criterion/program_stream.json` for `cargo xtask bench`.
#![allow(missing_docs, clippy::unwrap_used)] // a bench binary; it unwraps to fail.

use std::io::{BufReader, Read};
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::Chain;
use thermokin_compensate::{RunSettings, StreamSettings, compensate_static_stream};
use thermokin_deform::{DeviationTable, TableSemantics};
use thermokin_io::TargetReader;

/// CSV text of `n` targets, produced as it is read.
struct Targets {
    chain: Chain,
    rng: ChaCha8Rng,
    left: usize,
    line: Vec<u8>,
    at: usize,
}

impl Targets {
    fn new(chain: Chain, n: usize) -> Self {
        let line = b"label,X,Y,Z,QW,QX,QY,QZ\n".to_vec();
        Self { chain, rng: ChaCha8Rng::seed_from_u64(1_000_000), left: n, line, at: 0 }
    }
}

impl Read for Targets {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.at == self.line.len() {
            if self.left == 0 {
                return Ok(0);
            }
            self.left -= 1;
            let ranges =
                [(-120.0, 120.0), (-20.0, 50.0), (-60.0, 20.0), (-150.0, 150.0), (30.0, 100.0), (-300.0, 300.0)];
            let q: Vec<f64> =
                ranges.iter().map(|&(lo, hi): &(f64, f64)| self.rng.random_range(lo..hi).to_radians()).collect();
            let pose = self.chain.tool_pose(&q).unwrap();
            let (p, r) = (pose.translation.vector, pose.rotation);
            self.line =
                format!("T{},{},{},{},{},{},{},{}\n", self.left, p.x, p.y, p.z, r.w, r.i, r.j, r.k).into_bytes();
            self.at = 0;
        }
        let n = buf.len().min(self.line.len() - self.at);
        buf[..n].copy_from_slice(&self.line[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }
}

fn main() {
    // `cargo bench` passes `--bench`; anything else (e.g. `cargo test --benches`) runs a tiny size only.
    let full = std::env::args().any(|a| a == "--bench");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let chain = thermokin_io::read_robot(&root.join("configs/irb140.toml")).unwrap().chain().clone();
    let table = DeviationTable::from_joint_rows(vec![thermokin_testdata::error_mm_deg([1.0; 6]); 6]);
    let start = [0.0, 20.0, 20.0, 0.0, -45.0, 0.0].map(f64::to_radians).to_vec();
    let run = RunSettings {
        semantics: TableSemantics::Canonical,
        accumulation: Default::default(),
        ik: thermokin_ik::Params::default(),
        start,
    };
    let settings = StreamSettings::new(run);
    let sizes: &[usize] = if full { &[100_000, 300_000, 1_000_000] } else { &[1_000] };
    let mut results = serde_json::Map::new();
    for &n in sizes {
        let mut reader =
            TargetReader::new("generated.csv".as_ref(), BufReader::new(Targets::new(chain.clone(), n))).unwrap();
        let t0 = Instant::now();
        let summary =
            compensate_static_stream(&chain, &table, &mut reader, &mut std::io::sink(), &settings, |_| {}).unwrap();
        let seconds = t0.elapsed().as_secs_f64();
        let rss = thermokin_testdata::peak_rss_mib();
        println!(
            "program_stream {n} targets: {seconds:.3} s, {:.2} µs per target, {} failed, peak RSS {} MiB",
            seconds / n as f64 * 1e6,
            summary.failures,
            rss.map_or("n/a".into(), |m| format!("{m:.1}"))
        );
        results.insert(
            format!("{n}"),
            serde_json::json!({"seconds": seconds, "failures": summary.failures, "peak_rss_mib": rss}),
        );
    }
    if full {
        let dir = root.join("target/criterion");
        let _ = std::fs::create_dir_all(&dir);
        let _ = std::fs::write(dir.join("program_stream.json"), serde_json::Value::Object(results).to_string());
    }
}
