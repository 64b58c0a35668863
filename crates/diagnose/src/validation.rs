//! How held-out errors are obtained: folds grouped in time (or a seeded shuffle), forward-chained folds
//! for time-dependent effects, an explicit hold-out set; and the fits the ladder asks for.

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::Robot;

use rayon::prelude::*;

use crate::fit::{Fit, FixedParameter, fit, identifiable, initial_registration, norms, residuals};
use crate::model::{Effect, Model, Pre};
use crate::report::Stats;
use crate::{Dataset, DiagnoseError};

pub(crate) type Folds = Vec<(Vec<usize>, Vec<usize>)>;

/// Folds and the block each measurement belongs to: measurements of one block are never split between
/// a training and a test part, and the gate's standard error is taken over blocks
/// ([`significantly_better`]), because the residuals of neighbouring poses (in time, or in joint space)
/// are correlated and do not count as independent evidence.
pub(crate) struct Partition {
    pub(crate) folds: Folds,
    /// Block of each measurement (data order).
    pub(crate) block: Vec<usize>,
}

impl Partition {
    /// The block of each held-out error, in the order [`Ctx::heldout_errors`] returns them.
    pub(crate) fn test_blocks(&self) -> Vec<usize> {
        self.folds
            .iter()
            .filter(|(tr, te)| !tr.is_empty() && !te.is_empty())
            .flat_map(|(_, te)| te.iter().map(|&i| self.block[i]))
            .collect()
    }
}

/// Blocks of neighbouring arm configurations: k-means (k-means++ start, seeded, Lloyd iterations until
/// nothing moves or 50 rounds) on the joint values in radians (millimetres / 1000 for a prismatic joint, so
/// that a metre weighs like a radian). Returns the cluster of each measurement.
pub(crate) fn configuration_clusters(data: &Dataset, count: usize, seed: u64) -> Vec<usize> {
    let n = data.len();
    let count = count.clamp(1, n.max(1));
    let x: Vec<&[f64]> = data.measurements.iter().map(|m| m.q.as_slice()).collect();
    let d2 = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(u, v)| (u - v) * (u - v)).sum::<f64>();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xc1a5_7e25);
    let mut centres: Vec<Vec<f64>> = Vec::with_capacity(count);
    if n == 0 {
        return Vec::new();
    }
    centres.push(x[rng.random_range(0..n)].to_vec());
    let mut nearest: Vec<f64> = x.iter().map(|p| d2(p, &centres[0])).collect();
    while centres.len() < count {
        let total: f64 = nearest.iter().sum();
        let pick = if total > 0.0 {
            let mut t = rng.random_range(0.0..total);
            let mut chosen = n - 1;
            for (i, w) in nearest.iter().enumerate() {
                if t < *w {
                    chosen = i;
                    break;
                }
                t -= w;
            }
            chosen
        } else {
            rng.random_range(0..n)
        };
        centres.push(x[pick].to_vec());
        for (i, p) in x.iter().enumerate() {
            nearest[i] = nearest[i].min(d2(p, &centres[centres.len() - 1]));
        }
    }
    let mut label = vec![usize::MAX; n];
    for _ in 0..50 {
        let mut moved = false;
        for (i, p) in x.iter().enumerate() {
            let best =
                (0..centres.len()).min_by(|&a, &b| d2(p, &centres[a]).total_cmp(&d2(p, &centres[b]))).unwrap_or(0);
            if label[i] != best {
                label[i] = best;
                moved = true;
            }
        }
        if !moved {
            break;
        }
        for (c, centre) in centres.iter_mut().enumerate() {
            let members: Vec<&&[f64]> = x.iter().zip(&label).filter(|(_, l)| **l == c).map(|(p, _)| p).collect();
            if members.is_empty() {
                continue;
            }
            for (a, v) in centre.iter_mut().enumerate() {
                *v = members.iter().map(|p| p[a]).sum::<f64>() / members.len() as f64;
            }
        }
    }
    label
}

/// Folds grouped in time when the data span time — the time-ordered measurements cut into chunks, fold
/// `f` holding chunks `f, f + k, f + 2k, …` so that neighbours in time (which share a thermal state)
/// never sit on both sides, while every fold spans the whole run — and a seeded shuffle otherwise (each
/// measurement its own block).
pub(crate) fn kfold(data: &Dataset, k: usize, seed: u64) -> Partition {
    let n = data.len();
    let mut idx: Vec<usize> = (0..n).collect();
    if data.time_span() > 0.0 {
        idx.sort_by(|&a, &b| data.measurements[a].time_min.total_cmp(&data.measurements[b].time_min).then(a.cmp(&b)));
    } else {
        idx.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
    }
    let k = k.clamp(2, n.max(2));
    let timed = data.time_span() > 0.0;
    let chunks = if timed { (4 * k).min(n) } else { k };
    let chunk_of = |pos: usize| pos * chunks / n;
    let folds = (0..k)
        .map(|f| {
            let (test, train): (Vec<usize>, Vec<usize>) = (0..n).partition(|&pos| chunk_of(pos) % k == f);
            (train.iter().map(|&p| idx[p]).collect(), test.iter().map(|&p| idx[p]).collect())
        })
        .collect();
    let mut block: Vec<usize> = (0..n).collect();
    if timed {
        for (pos, &i) in idx.iter().enumerate() {
            block[i] = chunk_of(pos);
        }
    }
    Partition { folds, block }
}

/// Folds of neighbouring arm configurations, for data without time: `4k` blocks of neighbouring
/// configurations ([`configuration_clusters`]), fold `f` holding every `k`-th block in a seeded order —
/// a test pose's neighbourhood is never in its training part, while every fold spans the workspace.
pub(crate) fn neighbourhood_folds(data: &Dataset, k: usize, seed: u64) -> Partition {
    let n = data.len();
    let k = k.clamp(2, n.max(2));
    let blocks = (4 * k).min(n);
    let block = configuration_clusters(data, blocks, seed);
    let mut order: Vec<usize> = (0..blocks).collect();
    order.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
    let fold_of_block: Vec<usize> = {
        let mut f = vec![0; blocks];
        for (pos, &b) in order.iter().enumerate() {
            f[b] = pos % k;
        }
        f
    };
    let folds = (0..k).map(|f| (0..n).partition::<Vec<usize>, _>(|&i| fold_of_block[block[i]] != f)).collect();
    Partition { folds, block }
}

/// The folds `config` asks for: [`kfold`] by default, or one fold per workspace region or joint
/// configuration (leave one group out), so that an effect which only memorises a region or a branch
/// scores worse than one that transfers.
pub(crate) fn folds_for(data: &Dataset, k: usize, seed: u64, by: crate::FoldGrouping) -> Partition {
    let groups: Vec<usize> = match by {
        crate::FoldGrouping::Neighbourhood if data.time_span() > 0.0 => return kfold(data, k, seed),
        // Blocks of fewer than 10 poses are no neighbourhood (and too few per block for the block
        // standard error): a small set is shuffled pose by pose.
        crate::FoldGrouping::Neighbourhood if data.len() < 10 * 4 * k.max(2) => return kfold(data, k, seed),
        crate::FoldGrouping::Neighbourhood => return neighbourhood_folds(data, k, seed),
        crate::FoldGrouping::Time => return kfold(data, k, seed),
        crate::FoldGrouping::WorkspaceRegion => {
            // Reach (distance from the base's Z axis) and height against their medians: four quadrants.
            let reach: Vec<f64> = data.measurements.iter().map(|m| m.position_mm.xy().norm()).collect();
            let height: Vec<f64> = data.measurements.iter().map(|m| m.position_mm.z).collect();
            let (mr, mh) = (median(&reach), median(&height));
            (0..data.len()).map(|i| usize::from(reach[i] > mr) * 2 + usize::from(height[i] > mh)).collect()
        }
        crate::FoldGrouping::JointConfiguration => {
            // The arm's branch: the sign of each joint that decides one (elbow: joint 3 against its
            // median; wrist: joint 5's sign) — ABB's cfx bits for the arms of this project.
            let elbow: Vec<f64> = data.measurements.iter().map(|m| m.q.get(2).copied().unwrap_or(0.0)).collect();
            let me = median(&elbow);
            let wrist = |i: usize| data.measurements[i].q.get(4).is_some_and(|&v| v > 0.0);
            (0..data.len()).map(|i| usize::from(elbow[i] > me) * 2 + usize::from(wrist(i))).collect()
        }
    };
    let labels: std::collections::BTreeSet<usize> = groups.iter().copied().collect();
    let folds = labels
        .into_iter()
        .map(|g| {
            let (test, train): (Vec<usize>, Vec<usize>) = (0..data.len()).partition(|&i| groups[i] == g);
            (train, test)
        })
        .filter(|(train, test)| !train.is_empty() && !test.is_empty())
        .collect();
    // One group per fold: the gate counts measurements (four groups are too few blocks for an error).
    Partition { folds, block: (0..data.len()).collect() }
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s.get(s.len() / 2).copied().unwrap_or(0.0)
}

/// Forward-chained folds: train on the earliest blocks, test on the next one.
pub(crate) fn forward_chained(data: &Dataset, k: usize) -> Folds {
    let n = data.len();
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&a, &b| data.measurements[a].time_min.total_cmp(&data.measurements[b].time_min).then(a.cmp(&b)));
    let blocks = k + 1;
    (1..blocks)
        .map(|b| {
            let cut = b * n / blocks;
            let end = (b + 1) * n / blocks;
            (idx[..cut].to_vec(), idx[cut..end].to_vec())
        })
        .collect()
}

/// What every held-out evaluation of one diagnosis shares.
pub(crate) struct Ctx<'a> {
    pub(crate) robot: &'a Robot,
    pub(crate) data: &'a Dataset,
    pub(crate) pre: Pre,
    pub(crate) folds: Folds,
    /// The block of each held-out error of `folds`, in order (the gate's unit of evidence).
    pub(crate) blocks: Vec<usize>,
    pub(crate) forward: Folds,
}

/// What [`Ctx::heldout_fits`] returns.
pub(crate) type HeldoutFits = (Stats, Vec<f64>, Vec<Vec<f64>>);

impl<'a> Ctx<'a> {
    /// The folds and per-measurement quantities of `data`.
    pub(crate) fn new(robot: &'a Robot, data: &'a Dataset, config: &crate::Config) -> Self {
        let partition = folds_for(data, config.folds, config.seed, config.folds_by);
        let blocks = partition.test_blocks();
        Self {
            robot,
            data,
            pre: crate::model::prepare(robot, data, config.orientation_lever_mm),
            folds: partition.folds,
            blocks,
            forward: forward_chained(data, config.folds),
        }
    }

    /// The model of `effects`, its registration started from the measurements `rows` (Kabsch).
    pub(crate) fn model(&self, effects: &[Effect], rows: &[usize]) -> Result<Model, DiagnoseError> {
        let m = Model::new(self.robot, effects.to_vec())?;
        Ok(if m.has_registration() {
            let registration = initial_registration(self.robot, self.data, rows)?;
            m.with_registration(registration)
        } else {
            m
        })
    }

    /// Held-out statistics of a model by cross-validation on `folds`.
    pub(crate) fn heldout(&self, effects: &[Effect], folds: &Folds) -> Result<Stats, DiagnoseError> {
        Ok(self.heldout_errors(effects, folds)?.0)
    }

    /// Held-out statistics and every held-out error (3-D norm, mm, in fold order: the same order for any
    /// model on the same folds, so that two models' errors pair up measurement by measurement).
    pub(crate) fn heldout_errors(&self, effects: &[Effect], folds: &Folds) -> Result<(Stats, Vec<f64>), DiagnoseError> {
        let (stats, errors, _) = self.heldout_fits(effects, folds)?;
        Ok((stats, errors))
    }

    /// [`Ctx::heldout_errors`] with each fold's fitted parameters (empty for an empty fold): the
    /// statistics, the errors in fold order, the parameters per fold.
    pub(crate) fn heldout_fits(&self, effects: &[Effect], folds: &Folds) -> Result<HeldoutFits, DiagnoseError> {
        // Folds in parallel, their errors concatenated in fold order (the same on any thread count).
        let per_fold: Vec<(Vec<f64>, Vec<f64>)> = folds
            .par_iter()
            .map(|(train, test)| {
                if train.is_empty() || test.is_empty() {
                    return Ok((Vec::new(), Vec::new()));
                }
                let model = self.model(effects, train)?;
                let f = fit(self.robot, &model, self.data, train, &self.pre)?;
                let (r, _) = residuals(self.robot, &model, &f.theta, self.data, test, &self.pre, false)?;
                Ok((norms(&r, self.pre.stride()), f.theta))
            })
            .collect::<Result<_, DiagnoseError>>()?;
        let errors: Vec<f64> = per_fold.iter().flat_map(|(e, _)| e.iter().copied()).collect();
        let thetas = per_fold.into_iter().map(|(_, t)| t).collect();
        Ok((Stats::of(&errors), errors, thetas))
    }

    /// The parameters of `candidate` that stay identifiable next to `effects`, on all data.
    pub(crate) fn new_free(
        &self,
        effects: &[Effect],
        candidate: Effect,
    ) -> Result<(usize, Vec<FixedParameter>), DiagnoseError> {
        let mut all_effects = effects.to_vec();
        all_effects.push(candidate);
        let all: Vec<usize> = (0..self.data.len()).collect();
        let model = self.model(&all_effects, &all)?;
        let (_, jac) = residuals(self.robot, &model, &model.initial(), self.data, &all, &self.pre, true)?;
        let names = model.parameter_names();
        let (free, fixed) = identifiable(&jac, &names, &vec![true; model.len()]);
        let start = model.offsets()[model.offsets().len() - 1];
        let new = (start..model.len()).filter(|&c| free[c]).count();
        let fixed_new = fixed.into_iter().filter(|f| candidate.parameter_names().contains(&f.parameter)).collect();
        Ok((new, fixed_new))
    }

    pub(crate) fn full_fit(&self, effects: &[Effect]) -> Result<(Model, Fit), DiagnoseError> {
        let all: Vec<usize> = (0..self.data.len()).collect();
        let model = self.model(effects, &all)?;
        let f = fit(self.robot, &model, self.data, &all, &self.pre)?;
        Ok((model, f))
    }

    /// The Bayesian information criterion of a fit on all of the data.
    pub(crate) fn bic_of(&self, f: &Fit) -> f64 {
        let m = (self.data.len() * self.pre.stride()) as f64;
        let k = f.free.iter().filter(|&&x| x).count() as f64;
        m * (f.ssr / m).max(1e-300).ln() + k * m.ln()
    }
}

/// Whether model `b` has a lower held-out mean squared error than model `a`, by more than `z` standard
/// errors of the paired difference (errors `a[i]`, `b[i]` of the same measurement): the acceptance rule
/// of the ladder. With `z = 1` this is the one-standard-error rule: an improvement smaller than its own
/// uncertainty is not taken. The standard error is taken over blocks (`blocks[i]`, the block of error
/// `i`: a cluster-robust standard error of the mean, `√(B/(B−1) · Σ_b (D_b − n_b·d̄)²) / n`, `D_b` the
/// block's summed difference): neighbouring poses share their systematic residuals, so a gain that
/// holds in a few neighbourhoods only is not counted once per pose. With one measurement per block this
/// is the ordinary paired standard error.
pub(crate) fn significantly_better(a: &[f64], b: &[f64], z: f64, blocks: &[usize]) -> bool {
    let n = a.len().min(b.len());
    if n < 2 {
        return false;
    }
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x * x - y * y).collect();
    let mean = d.iter().sum::<f64>() / n as f64;
    let mut sums: std::collections::BTreeMap<usize, (f64, f64)> = std::collections::BTreeMap::new();
    for (i, v) in d.iter().enumerate() {
        let e = sums.entry(blocks.get(i).copied().unwrap_or(usize::MAX - i)).or_insert((0.0, 0.0));
        e.0 += v;
        e.1 += 1.0;
    }
    let count = sums.len();
    if count < 2 {
        return false;
    }
    let ss: f64 = sums.values().map(|(s, m)| (s - m * mean) * (s - m * mean)).sum();
    let var_of_mean = ss * count as f64 / (count - 1) as f64 / (n as f64 * n as f64);
    mean > z * var_of_mean.sqrt()
}

impl Ctx<'_> {
    /// How effect `e`'s parameter directions relate to each of `others` on these data: `Equivalent` when
    /// the two blocks' Jacobian columns span the same space, `ContainedIn` when `e`'s lie in the other's
    /// span (the other block can do all `e` does, and more), `Contains` the other way round, decided by rank with [`crate::fit`]'s
    /// tolerance: a direction within 1e-6 (relative) of a span belongs to it. Linearised at the nominal
    /// model (every parameter zero) over all measurements.
    pub(crate) fn relations(&self, e: Effect, others: &[Effect]) -> Result<Vec<(Effect, Relation)>, DiagnoseError> {
        let all: Vec<usize> = (0..self.data.len()).collect();
        let mut out = Vec::new();
        for &b in others {
            if b == e || b.is_reported() != e.is_reported() {
                continue;
            }
            let model = self.model(&[e, b], &all)?;
            let (_, jac) = residuals(self.robot, &model, &model.initial(), self.data, &all, &self.pre, true)?;
            let cols = |range: std::ops::Range<usize>| -> Vec<Vec<f64>> {
                range.map(|c| (0..jac.nrows()).map(|r| jac[(r, c)]).collect()).collect()
            };
            let (ce, cb) = (cols(0..e.len()), cols(e.len()..e.len() + b.len()));
            // A block that moves nothing on these data (gravity about a vertical axis) relates to nothing.
            let moves = |c: &[Vec<f64>]| c.iter().any(|v| v.iter().any(|x| x.abs() > 1e-12));
            if !moves(&ce) || !moves(&cb) {
                continue;
            }
            let e_in_b = within_span(&ce, &cb);
            let b_in_e = within_span(&cb, &ce);
            match (e_in_b, b_in_e) {
                (true, true) => out.push((b, Relation::Equivalent)),
                (true, false) => out.push((b, Relation::ContainedIn)),
                (false, true) => out.push((b, Relation::Contains)),
                _ => {}
            }
        }
        Ok(out)
    }
}

/// How one block's parameter directions relate to another's on the data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Relation {
    /// The same column space.
    Equivalent,
    /// Inside the other's column space.
    ContainedIn,
    /// The other's column space is inside this one's.
    Contains,
}

/// Whether every non-zero column of `a` lies in the span of `b` (Gram–Schmidt, twice, on unit columns).
fn within_span(a: &[Vec<f64>], b: &[Vec<f64>]) -> bool {
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut basis: Vec<Vec<f64>> = Vec::new();
    for col in b {
        let n0 = norm(col);
        if n0 < 1e-12 {
            continue;
        }
        let mut v: Vec<f64> = col.iter().map(|x| x / n0).collect();
        let n = crate::fit::project_out(&basis, &mut v);
        if n >= crate::fit::DEPENDENT {
            basis.push(v.iter().map(|x| x / n).collect());
        }
    }
    a.iter().all(|col| {
        let n0 = norm(col);
        if n0 < 1e-12 {
            return true;
        }
        let mut v: Vec<f64> = col.iter().map(|x| x / n0).collect();
        crate::fit::project_out(&basis, &mut v) < crate::fit::DEPENDENT
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use super::*;
    use crate::Measurement;

    fn at(q: &[f64]) -> Measurement {
        Measurement {
            time_min: 0.0,
            q: q.to_vec(),
            position_mm: nalgebra::Vector3::zeros(),
            orientation: None,
            position_std_mm: None,
            temps: Vec::new(),
        }
    }

    #[test]
    fn single_pose_blocks_give_the_paired_standard_error() {
        // a² − b² = 1 + (−1)^i · 0.5: mean 1, sample sd 0.5·√(n/(n−1)); 1 > z·SE for z up to ~ 2√n.
        let n = 16;
        let a: Vec<f64> = (0..n).map(|i| (2.0f64 + if i % 2 == 0 { 0.5 } else { -0.5 }).sqrt()).collect();
        let b = vec![1.0; n];
        let blocks: Vec<usize> = (0..n).collect();
        let se = 0.5 * (n as f64 / (n - 1) as f64).sqrt() / (n as f64).sqrt();
        assert!(significantly_better(&a, &b, 0.99 / se, &blocks));
        assert!(!significantly_better(&a, &b, 1.01 / se, &blocks));
    }

    #[test]
    fn a_gain_held_by_one_block_is_not_significant_over_blocks() {
        // Every pose of block 0 gains a lot, the others nothing: per pose the gain looks consistent
        // (one SE passes), over four blocks it is one block's luck (it does not).
        let a: Vec<f64> = (0..40).map(|i| if i < 10 { 2.0 } else { 1.0 }).collect();
        let b = vec![1.0; 40];
        let per_pose: Vec<usize> = (0..40).collect();
        let per_block: Vec<usize> = (0..40).map(|i| i / 10).collect();
        assert!(significantly_better(&a, &b, 1.0, &per_pose));
        assert!(!significantly_better(&a, &b, 2.0, &per_block));
        // Equal gains in every block stay significant.
        let even: Vec<f64> = (0..40).map(|i| if i % 10 < 5 { 2.0 } else { 1.5 }).collect();
        assert!(significantly_better(&even, &b, 2.0, &per_block));
    }

    #[test]
    fn clusters_hold_neighbouring_configurations() {
        // Two tight groups of configurations far apart: two clusters, each one group.
        let mut data = Dataset::default();
        for k in 0..20 {
            let d = 0.001 * k as f64;
            data.measurements.push(at(&[d, 0.0, 0.0]));
            data.measurements.push(at(&[2.0 + d, 1.0, -1.0]));
        }
        let label = configuration_clusters(&data, 2, 7);
        assert!((0..40).step_by(2).all(|i| label[i] == label[0]));
        assert!((1..40).step_by(2).all(|i| label[i] == label[1]));
        assert_ne!(label[0], label[1]);
    }

    #[test]
    fn neighbourhood_folds_never_split_a_block_and_test_every_pose_once() {
        let data = Dataset {
            measurements: (0..200)
                .map(|i| at(&[(i as f64 * 0.37).sin(), (i as f64 * 0.11).cos(), i as f64 * 0.01]))
                .collect(),
            temperature_names: Vec::new(),
        };
        let p = neighbourhood_folds(&data, 5, 3);
        let mut tested = vec![0; 200];
        for (train, test) in &p.folds {
            for &i in test {
                tested[i] += 1;
                assert!(train.iter().all(|&t| p.block[t] != p.block[i]), "block {} on both sides", p.block[i]);
            }
            assert_eq!(train.len() + test.len(), 200);
        }
        assert!(tested.iter().all(|&c| c == 1));
        assert_eq!(p.test_blocks().len(), 200);
    }
}
