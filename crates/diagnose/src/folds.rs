//! How poses are split into folds: grouped in time (or a seeded shuffle), blocks of neighbouring arm
//! configurations, leave-one-region-out, and forward-chained folds for time-dependent effects.

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::Dataset;

use crate::config::{Config, FoldGrouping};
use crate::regions::{arm_branches, workspace_quadrants};

/// Folds as `(training, test)` index lists.
pub(crate) type Folds = Vec<(Vec<usize>, Vec<usize>)>;

/// Folds and the block each measurement belongs to: measurements of one block are never split between
/// a training and a test part, and the gate's standard error is taken over blocks
/// ([`crate::scoring::significantly_better`]), because the residuals of neighbouring poses (in time, or in joint space)
/// are correlated and do not count as independent evidence.
pub(crate) struct Partition {
    pub(crate) folds: Folds,
    /// Block of each measurement (data order).
    pub(crate) block: Vec<usize>,
}

impl Partition {
    /// The block of each held-out error, in the order [`crate::scoring::Scorer::heldout_errors`] returns them.
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
    let chunks = if timed { (BLOCKS_PER_FOLD * k).min(n) } else { k };
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
    let blocks = (BLOCKS_PER_FOLD * k).min(n);
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

/// Poses per block of neighbouring configurations below which a set is shuffled pose by pose instead:
/// blocks of fewer are no neighbourhood, and too few per block for the block standard error.
const POSES_PER_BLOCK: usize = 10;
/// Blocks of neighbouring configurations per fold.
const BLOCKS_PER_FOLD: usize = 4;

/// Whether `poses` static poses are enough for `k` folds of neighbourhood blocks ([`neighbourhood_folds`]):
/// [`BLOCKS_PER_FOLD`] blocks per fold of at least [`POSES_PER_BLOCK`] poses. The one rule the folds and
/// the report's description of them follow.
pub(crate) fn by_neighbourhood(poses: usize, k: usize) -> bool {
    poses >= POSES_PER_BLOCK * BLOCKS_PER_FOLD * k.max(2)
}

/// The folds `config` asks for: [`kfold`] by default, or one fold per workspace region or joint
/// configuration (leave one group out), so that an effect which only memorises a region or a branch
/// scores worse than one that transfers.
pub(crate) fn folds_for(data: &Dataset, k: usize, seed: u64, by: FoldGrouping) -> Partition {
    let groups: Vec<usize> = match by {
        FoldGrouping::Neighbourhood if data.time_span() > 0.0 => return kfold(data, k, seed),
        FoldGrouping::Neighbourhood if !by_neighbourhood(data.len(), k) => return kfold(data, k, seed),
        FoldGrouping::Neighbourhood => return neighbourhood_folds(data, k, seed),
        FoldGrouping::Time => return kfold(data, k, seed),
        FoldGrouping::WorkspaceRegion => workspace_quadrants(data),
        FoldGrouping::JointConfiguration => arm_branches(data),
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

/// How the folds `config` asks for group these data, in words: said in every report.
pub(crate) fn describe(data: &Dataset, config: &Config) -> String {
    let k = config.folds;
    match config.folds_by {
        FoldGrouping::WorkspaceRegion => "leave one workspace region out (4 quadrants of reach × height)".to_string(),
        FoldGrouping::JointConfiguration => "leave one arm configuration out (elbow × wrist)".to_string(),
        _ if data.time_span() > 0.0 => format!(
            "{k}-fold cross-validation, folds grouped in time ({BLOCKS_PER_FOLD} chunks per fold); time-dependent effects also forward-chained"
        ),
        FoldGrouping::Neighbourhood if by_neighbourhood(data.len(), k) => format!(
            "{k}-fold cross-validation by neighbourhood: {} blocks of neighbouring arm configurations (k-means in joint space), a test pose's block never in its training part; the gate's standard error over blocks",
            BLOCKS_PER_FOLD * k
        ),
        FoldGrouping::Time | FoldGrouping::Neighbourhood => {
            format!("{k}-fold cross-validation (seeded shuffle of single poses)")
        }
    }
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

/// One fold that extrapolates along a joint: the poses on one side of the joint's median fitted, those on
/// the other side scored ([`joint_halves`]).
pub(crate) struct Half {
    /// The joint (0-based).
    pub(crate) joint: usize,
    /// Its median over the data (radians, or metres for a prismatic joint): the poses at or above it
    /// form the upper half.
    pub(crate) median: f64,
    /// Whether the lower half is the one scored.
    pub(crate) lower_scored: bool,
    /// The fitted poses.
    pub(crate) train: Vec<usize>,
    /// The scored poses.
    pub(crate) test: Vec<usize>,
}

/// For every joint the data move, two folds: its lower half (below the median) fitted and the upper half
/// scored, and the other way round. Unlike the selection's folds, whose test poses sit among training
/// poses, every test pose here lies beyond the fitted poses' range of one joint — as the arm's other
/// configurations lie beyond the measured ones when a calibration is used.
pub(crate) fn joint_halves(data: &Dataset) -> Vec<Half> {
    let dof = data.measurements.first().map_or(0, |m| m.q.len());
    let mut halves = Vec::new();
    for joint in 0..dof {
        let mut q: Vec<f64> = data.measurements.iter().map(|m| m.q[joint]).collect();
        q.sort_by(f64::total_cmp);
        let Some(&median) = q.get(q.len() / 2) else { continue };
        let (lower, upper): (Vec<usize>, Vec<usize>) =
            (0..data.len()).partition(|&i| data.measurements[i].q[joint] < median);
        if lower.is_empty() || upper.is_empty() {
            continue;
        }
        halves.push(Half { joint, median, lower_scored: false, train: lower.clone(), test: upper.clone() });
        halves.push(Half { joint, median, lower_scored: true, train: upper, test: lower });
    }
    halves
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use super::*;
    use thermokin_chain::Measurement;

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
            source_lines: Vec::new(),
            ..Default::default()
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

    #[test]
    fn every_scored_half_lies_beyond_the_fitted_one_along_its_joint() {
        let data = Dataset {
            measurements: (0..101).map(|i| at(&[(i as f64 * 0.37).sin(), (i as f64 * 0.11).cos(), 0.5])).collect(),
            ..Dataset::default()
        };
        let halves = joint_halves(&data);
        // Joint 3 never moves: no split along it; joints 1 and 2 each give two folds.
        assert_eq!(
            halves.iter().map(|h| (h.joint, h.lower_scored)).collect::<Vec<_>>(),
            [(0, false), (0, true), (1, false), (1, true)]
        );
        for h in &halves {
            assert_eq!(h.train.len() + h.test.len(), data.len());
            let q = |i: &usize| data.measurements[*i].q[h.joint];
            let (train_lo, train_hi) =
                (h.train.iter().map(q).fold(f64::MAX, f64::min), h.train.iter().map(q).fold(f64::MIN, f64::max));
            let (test_lo, test_hi) =
                (h.test.iter().map(q).fold(f64::MAX, f64::min), h.test.iter().map(q).fold(f64::MIN, f64::max));
            assert!(
                if h.lower_scored { test_hi < train_lo } else { test_lo > train_hi },
                "{test_lo}..{test_hi} vs {train_lo}..{train_hi}"
            );
        }
    }

    /// The real week (UR10 series A: 11,911 poses over 4.7 days, `time_min`): its folds are what the
    /// report and docs/diagnosis.md say — 5 folds of 4 chunks each, 20 chunks of ~596 poses in time order
    /// (about 5.6 hours each), fold `f` holding chunks `f, f + 5, f + 10, f + 15`: every fold spans the
    /// week, no chunk is split between a training and a test part, each pose is tested once — and the
    /// nested validation's outer folds are the same time chunks (a seed does not move time).
    #[test]
    fn the_real_week_is_folded_in_chunks_of_time() {
        let robot = thermokin_io::read_robot_with(
            &thermokin_testdata::urdf("ur10.urdf"),
            &thermokin_io::RobotOptions { base: None, tip: Some("tool0".into()) },
        )
        .unwrap();
        let kinds: Vec<_> = robot.chain().joints().iter().map(|j| j.kind).collect();
        let path = thermokin_testdata::workspace("fixtures/real/ur10-ipa/series_A.csv");
        let data = thermokin_io::read_measurements(&path, &kinds).unwrap();
        assert_eq!(data.len(), 11_911);
        let config = Config::default();
        assert_eq!(
            describe(&data, &config),
            "5-fold cross-validation, folds grouped in time (4 chunks per fold); time-dependent effects also forward-chained"
        );
        let p = folds_for(&data, config.folds, config.seed, config.folds_by);
        assert_eq!(p.folds.len(), 5);
        let t = |i: usize| data.measurements[i].time_min;
        // 20 chunks, each a contiguous span of time, in order.
        let chunks = p.block.iter().copied().max().unwrap() + 1;
        assert_eq!(chunks, 20);
        let span = |c: usize| {
            let times: Vec<f64> = (0..data.len()).filter(|&i| p.block[i] == c).map(t).collect();
            (
                times.len(),
                times.iter().copied().fold(f64::MAX, f64::min),
                times.iter().copied().fold(f64::MIN, f64::max),
            )
        };
        let spans: Vec<(usize, f64, f64)> = (0..chunks).map(span).collect();
        for w in spans.windows(2) {
            assert!(w[0].2 <= w[1].1, "chunks overlap in time: {:?} {:?}", w[0], w[1]);
        }
        assert!(spans.iter().all(|s| (595..=596).contains(&s.0)), "{spans:?}");
        let hours = |s: &(usize, f64, f64)| (s.2 - s.1) / 60.0;
        assert!(
            spans.iter().all(|s| hours(s) > 1.0 && hours(s) < 24.0),
            "{:?}",
            spans.iter().map(hours).collect::<Vec<_>>()
        );
        let mut tested = vec![0; data.len()];
        for (f, (train, test)) in p.folds.iter().enumerate() {
            let held: std::collections::BTreeSet<usize> = test.iter().map(|&i| p.block[i]).collect();
            assert_eq!(held.into_iter().collect::<Vec<_>>(), vec![f, f + 5, f + 10, f + 15]);
            assert!(train.iter().all(|&i| p.block[i] % 5 != f));
            test.iter().for_each(|&i| tested[i] += 1);
        }
        assert!(tested.iter().all(|&c| c == 1));
        // The nested validation's outer folds (their own seed): the same chunks of time.
        let outer = crate::validation::nested_folds(&data, &config, 5);
        assert_eq!(outer, p.folds);
    }
}
