//! Many targets: parallel (rayon) or chained through a program, deterministic on any number of threads.

use rayon::prelude::*;
use thermokin_chain::Chain;

use crate::IkError;
use crate::lm::Workspace;
use crate::params::{Goal, Params, Solution};
use crate::solve::solve;

/// Where the seeds of a batch come from.
#[derive(Clone, Copy, Debug)]
pub enum Seeds<'a> {
    /// Every target from the same seed (parallel).
    Same(&'a [f64]),
    /// One seed per target, e.g. the previous time step's solutions (parallel).
    PerTarget(&'a [Vec<f64>]),
    /// The first target from this seed, each next one from the previous solution (sequential: a program
    /// in the order the robot runs it).
    ChainPrevious(&'a [f64]),
}

/// Solves many targets. Parallel (rayon) unless chained; the output is the same with 1 or N threads,
/// because every target's restart generator depends only on `params.rng_seed` and its index.
pub fn solve_batch(
    chain: &Chain,
    targets: &[Goal],
    seeds: Seeds<'_>,
    params: &Params,
) -> Result<Vec<Solution>, IkError> {
    match seeds {
        Seeds::Same(seed) => targets
            .par_iter()
            .enumerate()
            .map_init(|| Workspace::new(chain.dof()), |ws, (i, t)| solve(chain, t, seed, params, ws, i as u64))
            .collect(),
        Seeds::PerTarget(per) => {
            if per.len() != targets.len() {
                return Err(IkError::SeedCount { seeds: per.len(), targets: targets.len() });
            }
            targets
                .par_iter()
                .zip(per)
                .enumerate()
                .map_init(|| Workspace::new(chain.dof()), |ws, (i, (t, s))| solve(chain, t, s, params, ws, i as u64))
                .collect()
        }
        Seeds::ChainPrevious(first) => {
            let mut ws = Workspace::new(chain.dof());
            let mut seed = first.to_vec();
            let mut out = Vec::with_capacity(targets.len());
            for (i, t) in targets.iter().enumerate() {
                let s = solve(chain, t, &seed, params, &mut ws, i as u64)?;
                if s.converged() {
                    seed.clone_from(&s.q);
                }
                out.push(s);
            }
            Ok(out)
        }
    }
}
