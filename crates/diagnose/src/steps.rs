//! A step of the measurement frame — a tracker knocked mid-session, its stand settling, the robot's base
//! moved — found where the measurements have an order: their times, or their lines in the file where the
//! user says the file lists them as measured (`--order file`; a file's lines alone are no order). The step
//! becomes a candidate like any effect ([`Effect::FrameStep`]): fitted as the frame after it, scored on
//! the folds, kept only where it gains held out. A boundary between blocks of configurations measured one
//! after the other (a column's heights, a joint's range: the poses before and after it apart in some
//! joint's range) is never a candidate: a step there and an error of those configurations fit alike.
//!
//! **The scan.** A flexible static model — the blocks always estimated, every joint row, every loaded
//! joint's compliance — is fitted to the selection's measurements; whatever of the robot's geometry the
//! poses show it absorbs, so that what is left in the order of measuring is what no static robot does.
//! A step of the frame after the `k`-th pose of that order moves every later residual by `J_i δ`
//! (`J_i = [I | −[p_i]×]`, `δ` the step's translation and small rotation, `p_i` the predicted point), on
//! top of the registration that all poses share. With `A_k = Σ_{i ≥ k} J_iᵀJ_i`, `b_k = Σ_{i ≥ k} J_iᵀr_i`
//! over the later poses and `A`, `b` over all, the least-squares gain of the step is
//! `g_k = cᵀ (A_k − A_k A⁻¹ A_k)⁻¹ c` with `c = b_k − A_k A⁻¹ b` (the step's columns made orthogonal to
//! the registration's: the partitioned normal equations). Every split with [`MIN_SIDE`] poses on each
//! side is scanned by running sums (linear in the poses); the largest gain is a candidate when it exceeds
//! what noise gives the largest of all splits — `σ̂² · κ · χ²₆` at `1 − FALSE_ALARM / splits`, `σ̂` the
//! robust scale per axis of the residuals left once the step is fitted, `κ` how much more their means
//! over runs of consecutive poses vary than independent residuals' would (real residuals wander with the
//! configurations measured one after another: on the real UR10 series C, a step of 0.2 mm at line 711
//! passed the plain test and gained 0.001 mm held out).
//!
//! **A drift is no step.** A thermal drift the static model leaves is a trend of the residuals in time,
//! whose spread grows away from the session's middle; read as equally noisy residuals it gave dozens of
//! steps (41 at 3,000 simulated poses, 316 at 100,000). So each stretch's frame may drift steadily — the
//! nuisance is `[J_i | u_i J_i]`, `u_i` the pose's place in the stretch scaled to `[−1, 1]`, and the gain
//! above is taken with it (`A_k` is then `[S_k | T_k]`, the later poses' sums of `JᵀJ` and `u JᵀJ`) — and
//! each pose is weighted by the inverse of the residuals' variance about their mean over the poses around
//! it (a window of `max(25, √n)`), so that the test holds where their spread changes.
//!
//! **Several steps** (a tracker knocked twice, a stand that settles and is then bumped): binary
//! segmentation. Once a step is kept, each stretch of the order between the steps found is scanned the
//! same way, with a frame of its own; the likeliest split of any stretch is kept when its gain beats the
//! same test, `σ̂` and `κ` taken once every stretch — that split's two included — has its own frame fitted,
//! the Bonferroni count that stretch's splits. The scan stops at the first split that does not. Each step
//! found is a candidate; whether it is a cause is then the selection's question, held out.

use std::ops::AddAssign;

use nalgebra::{Matrix3, Matrix6, SMatrix, SVector, Vector3, Vector6};
use thermokin_chain::{Dataset, MeasuringOrder};
use thermokin_identify::{Effect, JointIndex, StepAt, residuals};

use crate::error::DiagnoseError;
use crate::scoring::Scorer;
use crate::stats::{FALSE_ALARM, chi_square_upper_quantile};

/// The fewest poses on either side of a step: twice its six parameters.
pub const MIN_SIDE: usize = 12;

/// The most poses the flexible static model is fitted on (evenly spread); its residuals are taken on all.
const FIT_POSES: usize = 2000;

/// The order the measurements were taken in, when they carry one: by time when they span time, else by
/// file line where the user says the file lists them as measured (`by`): a file's lines alone are no
/// order — a block of configurations (a column height, a joint's range) measured together is not a
/// moved tracker. The poses in that order, and per place `k` where a step before its pose is put (`None`
/// where the pose before it shares its time: no step between them).
fn order(data: &Dataset, by: MeasuringOrder) -> Option<(Vec<usize>, Vec<Option<StepAt>>)> {
    let n = data.len();
    let mut idx: Vec<usize> = (0..n).collect();
    if data.time_span() > 0.0 {
        let t = |i: usize| data.measurements[i].time_min;
        idx.sort_by(|&a, &b| t(a).total_cmp(&t(b)).then(a.cmp(&b)));
        // A step between two poses sits halfway between their times: a pose measured in between (in a
        // test fold) is put on the side it is nearer to.
        let at = (0..n)
            .map(|k| {
                let (before, after) = (t(idx[k.max(1) - 1]), t(idx[k]));
                (k > 0 && after > before).then(|| StepAt::time(0.5 * (before + after)))
            })
            .collect();
        return Some((idx, at));
    }
    if by != MeasuringOrder::File {
        return None;
    }
    let lines: Option<Vec<usize>> = (0..n).map(|i| data.line_of(i)).collect();
    let lines = lines?;
    idx.sort_by_key(|&i| lines[i]);
    let at = idx.iter().map(|&i| Some(StepAt::Line(lines[i]))).collect();
    Some((idx, at))
}

/// The steps of the measurement frame in the scorer's data that noise alone would not give, found one
/// after another (binary segmentation): the candidates [`Effect::FrameStep`], in the order of measuring
/// (none without an order, or with too few poses).
pub(crate) fn frame_steps(
    scorer: &Scorer<'_>,
    always: &[Effect],
    by: MeasuringOrder,
) -> Result<Vec<Effect>, DiagnoseError> {
    let data = scorer.data;
    let n = data.len();
    if n < 2 * MIN_SIDE {
        return Ok(Vec::new());
    }
    let Some((order, at)) = order(data, by) else { return Ok(Vec::new()) };
    let robot = scorer.robot;
    let mut flexible = always.to_vec();
    let loaded = thermokin_identify::max_gravity_torques(robot);
    for j in (0..robot.chain().dof()).filter_map(|j| JointIndex::of(robot, j).ok()) {
        flexible.push(Effect::LinkDeviation(j));
        if robot.chain().joints()[j.index()].kind == thermokin_chain::JointKind::Prismatic {
            flexible.push(Effect::JointScale(j));
        }
        flexible.extend(thermokin_identify::gravity_compliance(robot, data, j, &loaded));
    }
    // Its geometry pinned down by at most FIT_POSES poses spread evenly over the set (a week of poses
    // adds nothing to a static robot's rows but time), its residuals taken on every pose.
    let rows = scorer.all();
    let every = n.div_ceil(FIT_POSES);
    let fitted: Vec<usize> = rows.iter().copied().step_by(every).collect();
    let (model, fit) = scorer.fit_shrunk(&flexible, &fitted, 0.0)?;
    let r = residuals(robot, &model, &fit.theta, data, &rows, &scorer.terms)?;
    // Per pose in the order of measuring: its residual, JᵀJ and Jᵀr of the step's six columns
    // (positions only), each weighted by the inverse of the residuals' local variance around it — a drift
    // the static model leaves makes them larger far from the session's middle, and a test that takes them
    // as equally noisy reads that as steps.
    let stride = scorer.terms.stride();
    let raw: Vec<Vector3<f64>> =
        order.iter().map(|&i| Vector3::new(r[stride * i], r[stride * i + 1], r[stride * i + 2])).collect();
    let weights = local_precision(&raw);
    let timed = data.time_span() > 0.0;
    let poses: Vec<Pose> = order
        .iter()
        .enumerate()
        .map(|(rank, &i)| {
            let (residual, w) = (raw[rank], weights[rank]);
            let point = data.measurements[i].position_mm - residual;
            let mut j = SMatrix::<f64, 3, 6>::zeros();
            j.fixed_view_mut::<3, 3>(0, 0).copy_from(&Matrix3::identity());
            j.fixed_view_mut::<3, 3>(0, 3).copy_from(&-point.cross_matrix());
            // Its place in the order: its time where the set spans time, else its rank.
            let when = if timed { data.measurements[i].time_min } else { rank as f64 };
            let root = w.sqrt();
            Pose {
                residual: residual * root,
                point,
                when,
                root,
                jtj: j.transpose() * j * w,
                jtr: j.transpose() * residual * w,
            }
        })
        .collect();
    // The likeliest split of any stretch between the steps found so far, tested against the noise left
    // once the frame is fitted on every stretch, that split included; kept, and the scan goes on.
    let mut cuts: Vec<usize> = Vec::new();
    loop {
        let stretches = stretches(&cuts, n);
        let best = stretches
            .iter()
            .filter_map(|&(lo, hi)| {
                let open = splittable(data, &order[lo..hi], &at[lo..hi]);
                best_split(&poses[lo..hi], &open).map(|(g, k, splits)| (g, lo + k, splits))
            })
            .max_by(|a, b| a.0.total_cmp(&b.0));
        let Some((gain, k, splits)) = best else { break };
        let mut with = cuts.clone();
        with.push(k);
        with.sort_unstable();
        let Some(left) = left_after(&poses, &with) else { break };
        let sigma2 = robust_variance(left.iter().flat_map(|v| v.iter().copied()));
        let threshold =
            sigma2 * run_inflation(&left) * chi_square_upper_quantile(6, FALSE_ALARM / splits.max(1) as f64);
        if gain <= threshold {
            break;
        }
        cuts = with;
    }
    Ok(cuts.into_iter().filter_map(|k| at[k].map(Effect::FrameStep)).collect())
}

/// Per place of a stretch of the order of measuring (`rows`, with where a step before each would be put:
/// `at`), where a step may be put: not between two poses of one time, and not where the poses before and
/// after it are apart in some joint's range (all of one side below all of the other). There the session
/// measured one block of configurations and then another — a column's heights, a joint's range — and a
/// step of the frame and an error of those configurations fit alike: such a boundary is never said to
/// be a moved tracker (what those configurations do is the selection's question, by their effects).
fn splittable(data: &Dataset, rows: &[usize], at: &[Option<StepAt>]) -> Vec<Option<StepAt>> {
    let n = rows.len();
    let dof = data.measurements.first().map_or(0, |m| m.q.len());
    let q = |k: usize, j: usize| data.measurements[rows[k]].q[j];
    let mut open: Vec<Option<StepAt>> = at.to_vec();
    for j in 0..dof {
        // The range of joint j over the poses before place k, and over those from k on.
        let mut before = vec![(f64::INFINITY, f64::NEG_INFINITY); n + 1];
        for k in 0..n {
            before[k + 1] = (before[k].0.min(q(k, j)), before[k].1.max(q(k, j)));
        }
        let mut after = (f64::INFINITY, f64::NEG_INFINITY);
        for k in (1..n).rev() {
            after = (after.0.min(q(k, j)), after.1.max(q(k, j)));
            let (lo_b, hi_b) = before[k];
            if hi_b < after.0 || after.1 < lo_b {
                open[k] = None;
            }
        }
    }
    open
}

/// One pose of the scan, in the order of measuring: its residual under the flexible static model, its
/// predicted point, and the normal-equation terms of a shift of the frame (`J = [I | −[p]×]`).
struct Pose {
    residual: Vector3<f64>,
    point: Vector3<f64>,
    /// Its place in the order of measuring: its time, or its rank where the order is the file's.
    when: f64,
    /// The square root of its weight (`residual` is the weighted one).
    root: f64,
    jtj: Matrix6<f64>,
    jtr: Vector6<f64>,
}

/// The stretches `[lo, hi)` of `n` poses between the `cuts` (sorted).
fn stretches(cuts: &[usize], n: usize) -> Vec<(usize, usize)> {
    let bounds: Vec<usize> = std::iter::once(0).chain(cuts.iter().copied()).chain(std::iter::once(n)).collect();
    bounds.windows(2).map(|w| (w[0], w[1])).collect()
}

/// A stretch's frame and its trend: the normal equations of the twelve columns `[J_i | u_i J_i]` (`u_i` the
/// pose's place in the order, centred on the stretch and scaled to its span: the frame drifting
/// steadily) summed over `poses`, with each pose's `u_i`.
struct Drifting {
    a: SMatrix<f64, 12, 12>,
    b: SVector<f64, 12>,
    u: Vec<f64>,
}

impl Drifting {
    fn of(poses: &[Pose]) -> Self {
        let (lo, hi) =
            poses.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p.when), h.max(p.when)));
        let (mid, half) = (0.5 * (lo + hi), (0.5 * (hi - lo)).max(f64::MIN_POSITIVE));
        let u: Vec<f64> = poses.iter().map(|p| (p.when - mid) / half).collect();
        let (mut a, mut b) = (SMatrix::<f64, 12, 12>::zeros(), SVector::<f64, 12>::zeros());
        for (p, &u) in poses.iter().zip(&u) {
            let mut block = |r: usize, c: usize, f: f64| {
                a.fixed_view_mut::<6, 6>(r, c).add_assign(&(p.jtj * f));
            };
            block(0, 0, 1.0);
            block(0, 6, u);
            block(6, 0, u);
            block(6, 6, u * u);
            b.fixed_rows_mut::<6>(0).add_assign(&p.jtr);
            b.fixed_rows_mut::<6>(6).add_assign(&(p.jtr * u));
        }
        Self { a, b, u }
    }
}

/// The split of one stretch with the largest gain of a step (a second frame for its later part beside
/// the frame all of it shares, and that frame's steady drift over the stretch: a trend in time — a
/// thermal drift the static model leaves — is not read as steps): `(gain, place in the stretch, splits
/// scanned)`; `None` where no split leaves [`MIN_SIDE`] poses on each side. The partitioned normal
/// equations with the nuisance `N = [J | uJ]`: `g_k = cᵀ (S_k − A_k N⁻¹ A_kᵀ)⁻¹ c`, `c = b_k − A_k N⁻¹ b`,
/// `A_k = [S_k | T_k]` the later poses' sums of `JᵀJ` and `u JᵀJ` — running sums, linear in the poses.
fn best_split(poses: &[Pose], at: &[Option<StepAt>]) -> Option<(f64, usize, usize)> {
    let n = poses.len();
    let nuisance = Drifting::of(poses);
    let n_inv = nuisance.a.try_inverse()?;
    let n_inv_b = n_inv * nuisance.b;
    let (mut s_k, mut t_k, mut b_k) = (Matrix6::zeros(), Matrix6::zeros(), Vector6::zeros());
    let mut best: Option<(f64, usize)> = None;
    let mut splits = 0usize;
    // From the last pose back: after k poses the running sums hold poses k.. of the stretch.
    for k in (1..n).rev() {
        s_k += poses[k].jtj;
        t_k += poses[k].jtj * nuisance.u[k];
        b_k += poses[k].jtr;
        if k < MIN_SIDE || n - k < MIN_SIDE || at[k].is_none() {
            continue;
        }
        splits += 1;
        let mut a_k = SMatrix::<f64, 6, 12>::zeros();
        a_k.fixed_view_mut::<6, 6>(0, 0).copy_from(&s_k);
        a_k.fixed_view_mut::<6, 6>(0, 6).copy_from(&t_k);
        let c = b_k - a_k * n_inv_b;
        let s = s_k - a_k * n_inv * a_k.transpose();
        let Some(gain) = s.try_inverse().map(|si| (c.transpose() * si * c)[0]) else { continue };
        if best.is_none_or(|(g, _)| gain > g) {
            best = Some((gain, k));
        }
    }
    best.map(|(g, k)| (g, k, splits))
}

/// The residuals once each stretch between `cuts` has its own frame and its drift fitted (a registration
/// and the steps that shift it: the same least squares, [`Drifting`]), in the order of measuring; `None`
/// where a stretch's frame is not determined.
fn left_after(poses: &[Pose], cuts: &[usize]) -> Option<Vec<Vector3<f64>>> {
    let mut left = Vec::with_capacity(poses.len());
    for (lo, hi) in stretches(cuts, poses.len()) {
        let part = &poses[lo..hi];
        let nuisance = Drifting::of(part);
        let x = nuisance.a.try_inverse()? * nuisance.b;
        for (p, &u) in part.iter().zip(&nuisance.u) {
            let shift = x.fixed_rows::<6>(0) + x.fixed_rows::<6>(6) * u;
            let (t, w) = (shift.fixed_rows::<3>(0).into_owned(), shift.fixed_rows::<3>(3).into_owned());
            left.push(p.residual - (t - p.point.cross(&w)) * p.root);
        }
    }
    Some(left)
}

/// How much more the residuals' means over runs of consecutive poses vary than independent residuals'
/// would (at least 1): `B · Var(run means) / Var(residuals)`, runs of `B = max(10, √n)` poses, averaged
/// over the axes. Residuals that wander together in the order of measuring — an unmodelled error of the
/// configurations measured one after another, an air temperature that drifts — make any split of the
/// order look like a step by `√(inflation)` times more than noise does; the threshold takes it in. A
/// single step fitted away leaves runs that vary as noise does: about 1.
fn run_inflation(left: &[Vector3<f64>]) -> f64 {
    let n = left.len();
    let run = ((n as f64).sqrt() as usize).max(10);
    if n < 2 * run {
        return 1.0;
    }
    let means: Vec<Vector3<f64>> =
        left.chunks_exact(run).map(|c| c.iter().sum::<Vector3<f64>>() / run as f64).collect();
    let mean_all = left.iter().sum::<Vector3<f64>>() / n as f64;
    let (mut ratio, mut axes) = (0.0, 0);
    for a in 0..3 {
        let var = left.iter().map(|v| (v[a] - mean_all[a]).powi(2)).sum::<f64>() / (n - 1) as f64;
        let m_mean = means.iter().map(|m| m[a]).sum::<f64>() / means.len() as f64;
        let var_means = means.iter().map(|m| (m[a] - m_mean).powi(2)).sum::<f64>() / (means.len() - 1) as f64;
        if var > 0.0 {
            ratio += run as f64 * var_means / var;
            axes += 1;
        }
    }
    if axes == 0 { 1.0 } else { (ratio / axes as f64).max(1.0) }
}

/// Per pose, the inverse of the residuals' variance about their mean over the poses around it in the order
/// (a window of `max(25, √n)`), floored at a hundredth of the set's robust variance — the weights that
/// make a test of steps hold where the residuals' spread changes over the session.
fn local_precision(residuals: &[Vector3<f64>]) -> Vec<f64> {
    let n = residuals.len();
    let half = ((n as f64).sqrt() as usize).max(25) / 2;
    let floor = robust_variance(residuals.iter().flat_map(|v| v.iter().copied())) / 100.0;
    let (mut sum, mut sq) = (vec![Vector3::zeros(); n + 1], vec![0.0; n + 1]);
    for (k, r) in residuals.iter().enumerate() {
        sum[k + 1] = sum[k] + r;
        sq[k + 1] = sq[k] + r.norm_squared();
    }
    (0..n)
        .map(|k| {
            let (lo, hi) = (k.saturating_sub(half), (k + half + 1).min(n));
            let m = (hi - lo) as f64;
            let mean = (sum[hi] - sum[lo]) / m;
            let var = ((sq[hi] - sq[lo]) / m - mean.norm_squared()) / 3.0;
            1.0 / var.max(floor).max(f64::MIN_POSITIVE)
        })
        .collect()
}

/// `(1.4826 · median |r|)²`: the residual components' robust variance.
fn robust_variance(components: impl Iterator<Item = f64>) -> f64 {
    let mut a: Vec<f64> = components.map(f64::abs).collect();
    if a.is_empty() {
        return 0.0;
    }
    let mid = a.len() / 2;
    let (_, median, _) = a.select_nth_unstable_by(mid, f64::total_cmp);
    (1.4826 * *median).powi(2)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use super::*;
    use crate::{Config, HiddenEffect, SimulationConfig, simulate};

    /// A week of a UR10 whose joint 3 row drifts linearly in time (with a joint offset, a link deviation
    /// and a compliance: the bench's simulated week), no knock: no step of the frame is a candidate, at
    /// 3,000 poses as at 12,000. The static model's residuals grow with the drift away from the session's
    /// middle; tested as equally noisy, they gave 41 and 86 steps (316 at 100,000 poses).
    #[test]
    fn a_drift_is_not_read_as_steps_of_the_frame() {
        let robot = crate::simulate::test_ur10();
        let joint = |j| JointIndex::of(&robot, j).unwrap();
        let hidden = [
            HiddenEffect { effect: Effect::JointOffset(joint(1)), values: vec![0.03f64.to_radians()] },
            HiddenEffect {
                effect: Effect::LinkDeviation(joint(2)),
                values: vec![0.2, -0.1, 0.15, 0.01f64.to_radians(), 0.0, 0.005f64.to_radians()],
            },
            HiddenEffect { effect: Effect::JointCompliance(joint(1)), values: vec![0.0004f64.to_radians()] },
            HiddenEffect {
                effect: Effect::ThermalDrift(joint(2), thermokin_identify::DriftShape::Linear),
                values: vec![0.1, 0.05, -0.2, 0.0, 0.004f64.to_radians(), 0.0],
            },
        ];
        for poses in [3_000, 12_000] {
            let data = simulate(&robot, &hidden, &SimulationConfig { poses, ..SimulationConfig::default() }).unwrap();
            let config = Config::default();
            let scorer = Scorer::new(&robot, &data, &config);
            let steps = frame_steps(&scorer, &config.setup().always_estimated(&data), config.order).unwrap();
            assert!(steps.is_empty(), "{poses} poses: {:?}", steps.iter().map(Effect::label).collect::<Vec<_>>());
        }
    }
}
