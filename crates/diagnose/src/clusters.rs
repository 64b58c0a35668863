//! Flagged poses that gather are not gross errors: before the screen ([`crate::outliers`]) calls a pose a
//! gross error, it asks whether the flagged poses cluster — in a span of time (or of consecutive lines
//! where the user says the file lists the poses as measured), in one
//! part of a joint's range (a column's top extensions), in one range of a sensor column, or in one
//! neighbourhood of arm configurations. A tracker's beam breaks fall anywhere; a tracker bumped at one
//! pose, a compliance that grows at one end of a joint's range, a column that tilts at its top extension
//! put their departures together. Such a block is a systematic effect: its poses are kept, the report
//! says where it lies and by how much its poses depart, and, after the selection, whether the chosen
//! effects explain them. The flags left are asked one thing more ([`moved_joints`]): whether each
//! departure, wherever the pose lies, is a motion of one joint alone — a play read without the order it
//! was approached in — which no tracker glitch's direction follows.
//!
//! **The test: a scan statistic with a Bonferroni bound.** Along each ordering of the poses (time or lines,
//! each joint's value, each sensor column), the flagged poses sit at ranks `r₁ < … < r_K` among the `N`
//! poses. For every pair of flagged ranks `r_a ≤ r_b` the interval between them holds `n = r_b − r_a + 1`
//! poses, `k = b − a + 1` of them flagged; were the `K` flags independent of where a pose lies (each pose
//! flagged with the chance `K / N`), `k` or more of `n` would be flagged with the binomial upper tail
//! `P(X ≥ k)`. The smallest tail over the `K(K − 1)/2` intervals of every ordering, times their number and
//! the number of orderings, bounds the chance that independent gross errors gather so anywhere; below the
//! screen's [`crate::FALSE_ALARM`], with at least [`MIN_BLOCK`] flags, the interval's flags are a block.
//! Neighbourhoods of arm configurations (the folds' k-means blocks, a partition, not an interval) are
//! scanned the same way, one tail per block. Blocks are taken one at a time, the most significant first,
//! and the scan repeated on the flags left, up to [`MAX_BLOCKS`].
//!
//! Why a bound and not a permutation test: it costs `K²` tails per ordering (each summed over a few terms),
//! needs no random draws, and is conservative — a block it calls is one; one it misses stays flagged and
//! listed, as before. On the real UR10 series C with 1 % of its poses displaced at random by 2–10 mm, no
//! block is called and every displaced pose stays a gross error (tested).

use thermokin_chain::{Dataset, MeasuringOrder, Robot, units};

use crate::config::Config;
use crate::folds::configuration_clusters;
use crate::report::{Along, Cluster};
use crate::stats::FALSE_ALARM;
use crate::stats::span;

/// The fewest flagged poses that make a block: three departures in a row are still a plausible run of
/// beam breaks on a busy tracker line; four at one place are told apart from them by the test above.
pub const MIN_BLOCK: usize = 4;

/// Blocks looked for at most (each found one is taken out before the next scan).
const MAX_BLOCKS: usize = 3;

/// One ordering of the poses: what it is, and each pose's value along it.
struct Ordering {
    along: Along,
    values: Vec<f64>,
}

/// The orderings the scan looks along: the order of measuring where the poses have one — their times,
/// or their lines where the user says the file lists them as measured (`by`; a file's lines are no order
/// otherwise) — each joint's value, each sensor column that varies.
fn orderings(robot: &Robot, data: &Dataset, by: MeasuringOrder) -> Vec<Ordering> {
    let n = data.len();
    let mut out = Vec::new();
    if data.time_span() > 0.0 {
        out.push(Ordering { along: Along::Time, values: data.measurements.iter().map(|m| m.time_min).collect() });
    } else if by == MeasuringOrder::File {
        out.push(Ordering {
            along: Along::Lines,
            values: (0..n).map(|i| data.line_of(i).unwrap_or(i + 1) as f64).collect(),
        });
    }
    for (j, joint) in robot.chain().joints().iter().enumerate() {
        let values = data.measurements.iter().map(|m| units::joint_value_out(joint.kind, m.q[j])).collect();
        out.push(Ordering {
            along: Along::Joint { joint: j + 1, prismatic: joint.kind == thermokin_chain::JointKind::Prismatic },
            values,
        });
    }
    for (s, name) in data.temperature_names.iter().enumerate() {
        let values: Vec<f64> = data.measurements.iter().map(|m| m.temps.get(s).copied().unwrap_or(f64::NAN)).collect();
        let (lo, hi) = span(values.iter().copied());
        if values.iter().all(|v| v.is_finite()) && hi > lo {
            out.push(Ordering { along: Along::Sensor { column: name.clone() }, values });
        }
    }
    out
}

/// `ln m!` for `m = 0..=n`.
fn ln_factorials(n: usize) -> Vec<f64> {
    std::iter::once(0.0)
        .chain((1..=n).scan(0.0, |acc, i| {
            *acc += (i as f64).ln();
            Some(*acc)
        }))
        .collect()
}

/// `P(X ≥ k)` for `X ~ Binomial(n, p)`, with `ln m!` tabulated (`ln_fact`, at least `n + 1` long); 1 where
/// `k` is not above the mean (no gathering to speak of). Summed from `k` up until the terms no longer
/// count (they fall geometrically beyond the mean).
fn binomial_upper_tail(n: usize, k: usize, p: f64, ln_fact: &[f64]) -> f64 {
    if k == 0 || p >= 1.0 || (k as f64) <= n as f64 * p {
        return 1.0;
    }
    if p <= 0.0 {
        return 0.0;
    }
    let (lp, lq) = (p.ln(), (1.0 - p).ln());
    let mut sum = 0.0;
    for i in k..=n {
        let term = (ln_fact[n] - ln_fact[i] - ln_fact[n - i] + i as f64 * lp + (n - i) as f64 * lq).exp();
        sum += term;
        if term < 1e-17 * sum {
            break;
        }
    }
    sum.min(1.0)
}

/// The most gathered interval of `flagged` (pose indices, sorted) along `values`: its chance (the
/// binomial tail, uncorrected) and its flagged poses; `None` with fewer than [`MIN_BLOCK`] flags.
fn scan(values: &[f64], flagged: &[usize], ln_fact: &[f64]) -> Option<(f64, Vec<usize>)> {
    let n = values.len();
    let k_all = flagged.len();
    if k_all < MIN_BLOCK {
        return None;
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]).then(a.cmp(&b)));
    let mut rank = vec![0; n];
    for (r, &i) in order.iter().enumerate() {
        rank[i] = r;
    }
    let mut ranks: Vec<(usize, usize)> = flagged.iter().map(|&i| (rank[i], i)).collect();
    ranks.sort_unstable();
    let p = k_all as f64 / n as f64;
    let mut best: Option<(f64, usize, usize)> = None;
    for a in 0..k_all {
        for b in a + MIN_BLOCK - 1..k_all {
            let inside = ranks[b].0 - ranks[a].0 + 1;
            let tail = binomial_upper_tail(inside, b - a + 1, p, ln_fact);
            if best.is_none_or(|(t, _, _)| tail < t) {
                best = Some((tail, a, b));
            }
        }
    }
    let (tail, a, b) = best?;
    let mut members: Vec<usize> = ranks[a..=b].iter().map(|&(_, i)| i).collect();
    members.sort_unstable();
    Some((tail, members))
}

/// The most gathered neighbourhood of arm configurations (a k-means block of the joint values, as the
/// folds use, at least ten poses each): its chance (uncorrected), its flagged poses, and the number of
/// blocks compared.
fn scan_configurations(
    data: &Dataset,
    flagged: &[usize],
    config: &Config,
    ln_fact: &[f64],
) -> Option<(f64, Vec<usize>, usize)> {
    let n = data.len();
    let count = (4 * config.folds).min(n / 10).max(1);
    if flagged.len() < MIN_BLOCK || count < 2 {
        return None;
    }
    let blocks = configuration_clusters(data, count, config.seed);
    let p = flagged.len() as f64 / n as f64;
    (0..count)
        .map(|b| {
            let members = blocks.iter().filter(|&&c| c == b).count();
            let inside: Vec<usize> = flagged.iter().copied().filter(|&i| blocks[i] == b).collect();
            (binomial_upper_tail(members, inside.len(), p, ln_fact), inside)
        })
        .filter(|(_, inside)| inside.len() >= MIN_BLOCK)
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(tail, inside)| (tail, inside, count))
}

/// The blocks among the `flagged` poses (sorted indices into `data`; `residual_mm` the screen's residual
/// of every pose), and the flags left once their poses are kept.
pub(crate) fn blocks(
    robot: &Robot,
    data: &Dataset,
    flagged: &[usize],
    residual_mm: &[f64],
    config: &Config,
) -> (Vec<Cluster>, Vec<usize>) {
    let orderings = orderings(robot, data, config.order);
    let ln_fact = ln_factorials(data.len());
    let mut left = flagged.to_vec();
    let mut found = Vec::new();
    while found.len() < MAX_BLOCKS && left.len() >= MIN_BLOCK {
        let pairs = (left.len() * (left.len() - 1) / 2) as f64;
        let mut best: Option<(f64, Along, Vec<usize>)> = None;
        for o in &orderings {
            if let Some((tail, members)) = scan(&o.values, &left, &ln_fact)
                && best.as_ref().is_none_or(|(t, _, _)| tail * pairs < *t)
            {
                best = Some((tail * pairs, o.along.clone(), members));
            }
        }
        if let Some((tail, members, count)) = scan_configurations(data, &left, config, &ln_fact)
            && best.as_ref().is_none_or(|(t, _, _)| tail * (count as f64) < *t)
        {
            best = Some((tail * count as f64, Along::Configurations, members));
        }
        // Every ordering (and the neighbourhoods) looked along counts once more.
        let Some((chance, along, members)) = best.map(|(c, a, m)| (c * (orderings.len() + 1) as f64, a, m)) else {
            break;
        };
        if chance >= FALSE_ALARM {
            break;
        }
        found.push(describe(robot, data, along, &members, residual_mm, chance.min(1.0)));
        left.retain(|i| members.binary_search(i).is_err());
    }
    (found, left)
}

/// The flagged poses among `left` whose departures are each a motion of one joint, and the flags left.
///
/// **The test.** A pose's residual `r` (its position rows, `stride` rows per pose in `residual`) and
/// the motion `u` of joint `k` at that pose (`motions[k]`, the residual rows' change per unit of the
/// joint): were the departure a gross error of no particular direction, `|cos ∠(r, u)|` would be uniform
/// on [0, 1] (in three dimensions the cosine of a uniformly random direction with a fixed one is
/// uniform), so `pᵢ = 1 − |cos|` is a p-value of the pose lying along the joint's motion. Sorted, the
/// `m` smallest of `K` are all below `p₍ₘ₎` with the binomial tail `P(X ≥ m)`, `X ~ Binomial(K, p₍ₘ₎)`;
/// the smallest tail over `m ≥` [`MIN_BLOCK`], times the `m` tried and the joints, bounds the chance
/// that independent gross errors line up so. Below [`FALSE_ALARM`] those `m` poses are a block: a joint
/// standing off by its own amount at each — its play read without the order it was approached in, a
/// slipping joint or encoder — and kept. Each pose's amount is its least-squares motion `u·r / u·u`
/// (degrees, or mm for a slide): the block's range.
pub(crate) fn moved_joints(
    robot: &Robot,
    data: &Dataset,
    left: &[usize],
    residual: &[f64],
    stride: usize,
    motions: &[Vec<f64>],
    residual_mm: &[f64],
) -> (Vec<Cluster>, Vec<usize>) {
    let k_all = left.len();
    if k_all < MIN_BLOCK {
        return (Vec::new(), left.to_vec());
    }
    let ln_fact = ln_factorials(k_all);
    let dof = robot.chain().dof();
    let along = |k: usize, i: usize| {
        let r = &residual[i * stride..i * stride + 3];
        let u = &motions[k][i * stride..i * stride + 3];
        let (ru, uu, rr): (f64, f64, f64) =
            (0..3).fold((0.0, 0.0, 0.0), |(a, b, c), x| (a + r[x] * u[x], b + u[x] * u[x], c + r[x] * r[x]));
        let p = if uu > 0.0 && rr > 0.0 { 1.0 - (ru.abs() / (uu * rr).sqrt()).min(1.0) } else { 1.0 };
        (p, if uu > 0.0 { ru / uu } else { 0.0 })
    };
    let mut best: Option<(f64, usize, Vec<usize>)> = None;
    for k in 0..dof {
        let mut ps: Vec<(f64, usize)> = left.iter().map(|&i| (along(k, i).0, i)).collect();
        ps.sort_by(|a, b| a.0.total_cmp(&b.0));
        for m in MIN_BLOCK..=k_all {
            let tail = binomial_upper_tail(k_all, m, ps[m - 1].0, &ln_fact) * (k_all * dof) as f64;
            if best.as_ref().is_none_or(|(t, _, _)| tail < *t) {
                let mut members: Vec<usize> = ps[..m].iter().map(|&(_, i)| i).collect();
                members.sort_unstable();
                best = Some((tail, k, members));
            }
        }
    }
    let Some((chance, k, members)) = best.filter(|(chance, _, _)| *chance < FALSE_ALARM) else {
        return (Vec::new(), left.to_vec());
    };
    let joint = &robot.chain().joints()[k];
    let prismatic = joint.kind == thermokin_chain::JointKind::Prismatic;
    let mut cluster =
        describe(robot, data, Along::JointMotion { joint: k + 1, prismatic }, &members, residual_mm, chance);
    cluster.range = {
        let amounts = members.iter().map(|&i| units::joint_value_out(joint.kind, along(k, i).1));
        let (lo, hi) = span(amounts);
        [lo, hi]
    };
    let rest = left.iter().copied().filter(|i| members.binary_search(i).is_err()).collect();
    (vec![cluster], rest)
}

/// A block as the report states it: where it lies along what it gathers on, which poses, how far off.
fn describe(
    robot: &Robot,
    data: &Dataset,
    along: Along,
    members: &[usize],
    residual_mm: &[f64],
    chance: f64,
) -> Cluster {
    let joint_ranges = (0..robot.chain().dof())
        .map(|j| {
            let kind = robot.chain().joints()[j].kind;
            let (lo, hi) = span(members.iter().map(|&i| units::joint_value_out(kind, data.measurements[i].q[j])));
            [lo, hi]
        })
        .collect();
    let value = |i: usize| match &along {
        Along::Lines | Along::Configurations | Along::JointMotion { .. } => data.line_of(i).unwrap_or(i + 1) as f64,
        Along::Time => data.measurements[i].time_min,
        Along::Joint { joint, .. } => {
            let j = joint - 1;
            units::joint_value_out(robot.chain().joints()[j].kind, data.measurements[i].q[j])
        }
        Along::Sensor { column } => {
            let s = data.temperature_names.iter().position(|n| n == column).unwrap_or(0);
            data.measurements[i].temps.get(s).copied().unwrap_or(f64::NAN)
        }
    };
    let (lo, hi) = span(members.iter().map(|&i| value(i)));
    let (r_lo, r_hi) = span(members.iter().map(|&i| residual_mm[i]));
    Cluster {
        along,
        range: [lo, hi],
        joint_ranges,
        kept: members.len(),
        measurements: members.iter().map(|&i| i + 1).collect(),
        lines: members.iter().map(|&i| data.line_of(i)).collect(),
        residual_mm: [r_lo, r_hi],
        chance,
        after_mm: None,
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use super::*;

    #[test]
    fn the_binomial_tail_is_the_sum_of_its_terms() {
        // P(X ≥ 3) for n = 5, p = 0.1: 10·0.001·0.81 + 5·0.0001·0.9 + 0.00001 = 0.00856.
        let ln_fact = ln_factorials(10);
        let tail = binomial_upper_tail(5, 3, 0.1, &ln_fact);
        assert!((tail - 0.00856).abs() < 1e-12, "{tail}");
        // At or below the mean: nothing gathered.
        assert_eq!(binomial_upper_tail(10, 1, 0.1, &ln_fact), 1.0);
    }

    #[test]
    fn a_run_of_flags_is_found_and_scattered_flags_are_not() {
        let n = 300;
        let ln_fact = ln_factorials(n);
        let values: Vec<f64> = (0..n).map(|i| i as f64).collect();
        // Twelve flags in a row at 200–211 among 300.
        let run: Vec<usize> = (200..212).collect();
        let (tail, members) = scan(&values, &run, &ln_fact).unwrap();
        assert_eq!(members, run);
        assert!(tail * 66.0 < 1e-10, "{tail}");
        // Twelve flags every 25th pose: the best interval is no more gathered than chance.
        let spread: Vec<usize> = (0..12).map(|k| 7 + 25 * k).collect();
        let (tail, _) = scan(&values, &spread, &ln_fact).unwrap();
        assert!(tail * 66.0 > FALSE_ALARM, "{tail}");
    }
}
