//! Static compensation of programs too large to hold: targets read in chunks, each chunk solved on every
//! core, the compensated joints written as they come, the summary built in one pass — memory that of a
//! chunk, whatever the program's length.
//!
//! Unlike [`crate::compensate_static`], which chains the nominal program target to target (a program's
//! natural order, one branch throughout), every target here is solved on its own from
//! [`RunSettings::start`]: targets are independent, so a chunk runs in parallel and the output does not
//! depend on the chunk size or the number of threads (each target's restart generator is keyed by its
//! index in the file). For an arm with a closed form ([`ClosedForm`]) the nominal solution is the
//! exact branch inside the limits nearest to `start` — the same configuration for every target, chosen
//! without iterating — checked by the solver like any other answer; otherwise the solver runs from
//! `start`. The compensated solution is then solved on the deformed robot from the nominal one.

use std::io::{BufRead, Write};

use nalgebra::Isometry3;
use rayon::prelude::*;
use thermokin_chain::Chain;
use thermokin_deform::DeviationTable;
use thermokin_ik::{ClosedForm, Goal, Workspace, solve};
use thermokin_io::TargetReader;

use crate::CompensateError;
use crate::export::{write_joint_header, write_joint_row};
use crate::run::{RunSettings, Summary, SummaryBuilder, TargetResult, record};

/// Settings of a streamed run.
#[derive(Clone, Debug, PartialEq)]
pub struct StreamSettings {
    /// The run's settings (semantics, IK, the seed of every target).
    pub run: RunSettings,
    /// Targets per chunk (default 65,536). Two chunks are in memory at once — one solved, the next read —
    /// which with their results is some tens of MB: the process peaks at ~78 MiB whether it compensates
    /// 300,000 or 1,000,000 targets (`cargo bench -p thermokin-compensate --bench program`).
    pub chunk: usize,
    /// Failed targets named in the summary (the count is always exact; default 1,000).
    pub named_failures: usize,
}

impl StreamSettings {
    /// Default chunking around `run`.
    pub fn new(run: RunSettings) -> Self {
        Self { run, chunk: 1 << 16, named_failures: 1000 }
    }
}

/// Compensates every target of `targets` on the deformed robot, writing the joint CSV
/// (`time_min,label,A1..An,status`, degrees) to `out` as chunks complete; `progress` gets the number of
/// targets done after each chunk. Returns the summary over all targets.
///
/// ```
/// use std::io::Cursor;
/// use thermokin_compensate::{RunSettings, StreamSettings, compensate_static_stream};
/// use thermokin_deform::{DeviationTable, TableSemantics};
/// use thermokin_io::TargetReader;
///
/// let robot = thermokin_testdata::irb140_table9();
/// let table = DeviationTable::from_joint_rows(vec![thermokin_testdata::error_mm_deg([1.0; 6]); 6]);
/// let csv = ",X,Y,Z\nP1,641,21,473\nP2,536,235,281\n";
/// let mut targets = TargetReader::new("program.csv".as_ref(), Cursor::new(csv))?;
/// let start = [0.0, 20.0, 20.0, 0.0, -45.0, 0.0].map(f64::to_radians).to_vec();
/// let run = RunSettings {
///     semantics: TableSemantics::Canonical,
///     accumulation: Default::default(),
///     ik: thermokin_ik::Params::default(),
///     start,
/// };
/// let mut out = Vec::new();
/// let summary = compensate_static_stream(&robot, &table, &mut targets, &mut out, &StreamSettings::new(run), |_| {})?;
/// assert_eq!((summary.solves, summary.failures), (2, 0));
/// assert!(summary.max_position_error_mm < 1e-9);
/// assert_eq!(String::from_utf8(out)?.lines().count(), 3); // header + 2 rows
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn compensate_static_stream<R: BufRead + Send, W: Write>(
    chain: &Chain,
    table: &DeviationTable,
    targets: &mut TargetReader<R>,
    out: &mut W,
    settings: &StreamSettings,
    mut progress: impl FnMut(usize),
) -> Result<Summary, CompensateError> {
    let run = &settings.run;
    let deformed = table.apply(chain, &run.semantics)?;
    let kinds: Vec<_> = chain.joints().iter().map(|j| j.kind).collect();
    let mut summary = SummaryBuilder::new(false, settings.named_failures);
    write_joint_header(out, kinds.len()).map_err(|source| CompensateError::Write { source })?;
    let wrist = ClosedForm::detect(chain);
    let chunk_size = settings.chunk.max(1);
    let mut done = 0usize;
    let mut chunk = targets.next_chunk(chunk_size)?;
    while !chunk.is_empty() {
        // Read the next chunk while this one is solved: the reader is sequential, the solves parallel.
        let (rows, next) = rayon::join(
            || -> Result<Vec<TargetResult>, CompensateError> {
                chunk
                    .par_iter()
                    .enumerate()
                    .map_init(
                        || Workspace::new(chain.dof()),
                        |ws, (i, target)| {
                            let index = (done + i) as u64;
                            let goal = Goal::Pose(target.pose);
                            let seed = wrist.as_ref().and_then(|w| nearest_branch(chain, w, &target.pose, &run.start));
                            let nominal =
                                solve(chain, &goal, seed.as_deref().unwrap_or(&run.start), &run.ik, ws, index)?;
                            let solution = solve(&deformed, &goal, &nominal.q, &run.ik, ws, index)?;
                            record(&deformed, 0.0, target, &solution, &nominal.q)
                        },
                    )
                    .collect()
            },
            || targets.next_chunk(chunk_size),
        );
        let rows = rows?;
        for r in &rows {
            write_joint_row(out, &kinds, r).map_err(|source| CompensateError::Write { source })?;
            summary.add(r);
        }
        done += rows.len();
        progress(done);
        chunk = next?;
    }
    Ok(summary.finish())
}

/// The exact closed-form branch inside the limits nearest to `start` (∞-norm over joints, whole turns
/// moved toward `start` where the limits allow).
fn nearest_branch(chain: &Chain, wrist: &ClosedForm, pose: &Isometry3<f64>, start: &[f64]) -> Option<Vec<f64>> {
    let tau = std::f64::consts::TAU;
    wrist
        .branches(pose)
        .into_iter()
        .filter(|b| b.exact)
        .map(|b| {
            b.q.iter()
                .zip(start)
                .zip(chain.joints())
                .map(|((&v, &s), j)| {
                    let moved = v + ((s - v) / tau).round() * tau;
                    if j.limits.is_none_or(|l| l.contains(moved)) { moved } else { v }
                })
                .collect::<Vec<f64>>()
        })
        .filter(|q| chain.within_limits(q))
        .min_by(|a, b| distance(a, start).total_cmp(&distance(b, start)))
}

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}
