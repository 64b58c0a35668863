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
//! **Several steps** (a tracker knocked twice, a stand that settles and is then bumped): binary
//! segmentation. Once a step is kept, each stretch of the order between the steps found is scanned the
//! same way, with a frame of its own; the likeliest split of any stretch is kept when its gain beats the
//! same test, `σ̂` and `κ` taken once every stretch — that split's two included — has its own frame fitted,
//! the Bonferroni count that stretch's splits. The scan stops at the first split that does not. Each step
//! found is a candidate; whether it is a cause is then the selection's question, held out.

use nalgebra::{Matrix3, Matrix6, SMatrix, Vector3, Vector6};
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
    let stride = scorer.terms.stride();
    // Per pose in the order of measuring: its residual, JᵀJ and Jᵀr of the step's six columns
    // (positions only).
    let poses: Vec<Pose> = order
        .iter()
        .map(|&i| {
            let residual = Vector3::new(r[stride * i], r[stride * i + 1], r[stride * i + 2]);
            let point = data.measurements[i].position_mm - residual;
            let mut j = SMatrix::<f64, 3, 6>::zeros();
            j.fixed_view_mut::<3, 3>(0, 0).copy_from(&Matrix3::identity());
            j.fixed_view_mut::<3, 3>(0, 3).copy_from(&-point.cross_matrix());
            Pose { residual, point, jtj: j.transpose() * j, jtr: j.transpose() * residual }
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
    jtj: Matrix6<f64>,
    jtr: Vector6<f64>,
}

/// The stretches `[lo, hi)` of `n` poses between the `cuts` (sorted).
fn stretches(cuts: &[usize], n: usize) -> Vec<(usize, usize)> {
    let bounds: Vec<usize> = std::iter::once(0).chain(cuts.iter().copied()).chain(std::iter::once(n)).collect();
    bounds.windows(2).map(|w| (w[0], w[1])).collect()
}

/// The split of one stretch with the largest gain of a step (a second frame for its later part beside
/// the frame all of it shares): `(gain, place in the stretch, splits scanned)`; `None` where no split
/// leaves [`MIN_SIDE`] poses on each side.
fn best_split(poses: &[Pose], at: &[Option<StepAt>]) -> Option<(f64, usize, usize)> {
    let n = poses.len();
    let (a_all, b_all) = poses.iter().fold((Matrix6::zeros(), Vector6::zeros()), |(a, b), p| (a + p.jtj, b + p.jtr));
    let a_inv = a_all.try_inverse()?;
    let (mut a_k, mut b_k) = (Matrix6::zeros(), Vector6::zeros());
    let mut best: Option<(f64, usize)> = None;
    let mut splits = 0usize;
    // From the last pose back: after k poses the running sums hold poses k.. of the stretch.
    for k in (1..n).rev() {
        a_k += poses[k].jtj;
        b_k += poses[k].jtr;
        if k < MIN_SIDE || n - k < MIN_SIDE || at[k].is_none() {
            continue;
        }
        splits += 1;
        let c = b_k - a_k * a_inv * b_all;
        let s = a_k - a_k * a_inv * a_k;
        let Some(gain) = s.try_inverse().map(|si| (c.transpose() * si * c)[0]) else { continue };
        if best.is_none_or(|(g, _)| gain > g) {
            best = Some((gain, k));
        }
    }
    best.map(|(g, k)| (g, k, splits))
}

/// The residuals once each stretch between `cuts` has its own frame fitted (a registration and the steps
/// that shift it: the same least squares), in the order of measuring; `None` where a stretch's frame is
/// not determined.
fn left_after(poses: &[Pose], cuts: &[usize]) -> Option<Vec<Vector3<f64>>> {
    let mut left = Vec::with_capacity(poses.len());
    for (lo, hi) in stretches(cuts, poses.len()) {
        let part = &poses[lo..hi];
        let (a, b) = part.iter().fold((Matrix6::zeros(), Vector6::zeros()), |(a, b), p| (a + p.jtj, b + p.jtr));
        let shift = a.try_inverse()? * b;
        let (t, w) = (shift.fixed_rows::<3>(0).into_owned(), shift.fixed_rows::<3>(3).into_owned());
        left.extend(part.iter().map(|p| p.residual - (t - p.point.cross(&w))));
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
