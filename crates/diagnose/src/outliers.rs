//! Gross errors: measurements a tracker got wrong (a beam break, a probe knocked in its nest), found
//! before anything is chosen and kept out of every fit and figure unless [`Outliers::Keep`].
//!
//! **The rule: flag and refit.** A flexible screening model — the registration and tool freedoms the
//! diagnosis always estimates, every joint row and every joint's gravity compliance (and, for a
//! warm-up, every row's exponential and temperature drift), unidentifiable
//! parameters fixed as in any fit — is fitted to all measurements; the residual scale σ̂ per axis is
//! taken robustly from its residual components (`1.4826 · median |r|`: a tenth of the poses displaced
//! by metres moves it by a few percent); a measurement whose residual norm exceeds
//! `σ̂ · √(χ²_k quantile at 1 − α/n)` is flagged (`k` residual rows per pose, `n` poses, `α` =
//! [`FALSE_ALARM`](crate::FALSE_ALARM): with Gaussian residuals at the scale σ̂, a clean set of any size has a 1 % chance
//! of one false flag); the model is refitted without the flagged poses and the test repeated until the
//! flags stop changing. Why this and not a redescending loss inside every fit: the selection, its folds
//! and the nested validation then all work on one set of poses that no fold can be fooled by, and the
//! report can name each excluded pose by its line.
//!
//! The stated noise never lowers the threshold below what the model's own residuals show: on real data
//! the model's error (tenths of a millimetre) dwarfs a tracker's noise (hundredths), and a threshold of
//! five noise sigmas would flag every pose. Where the data are too few for the screening model to leave
//! residual freedom ([`MIN_REDUNDANCY`]), the same model screens with a prior toward the nominal robot that
//! brings its effective parameters within that freedom (`screening_model`); only where even the blocks
//! always estimated would not leave it do they screen alone. The report says which. The residual scale is
//! taken over the fit's own degrees of freedom (`σ̂ / √(1 − p/m)`, `p` its effective parameters on `m`
//! rows), so that a model's freedom does not lower the threshold on few poses.
//!
//! Measured on small clean real sets (ten seeded draws each, 2026-11-25): the WAM's 60 grid poses flagged
//! 59 of 600 with the frame alone screening, none now; its 30, 25 of 300 and 7 now (poses where its
//! nominal error reaches 16 mm: not met, docs/diagnosis.md); the UR10's 30 and 60 of series C none and one
//! of 600 (line 1049, whose residual in the whole series stays under that screen's threshold).
//!
//! Measured on the real UR10 series C (2,773 poses) with 1 % of its poses displaced by 2–10 mm (seeded):
//! every displaced pose flagged, 2 clean ones (residuals 1.39 and 1.53 mm against a scale of 0.26 mm).

use faer::Mat;
use faer::linalg::solvers::Solve;
use thermokin_chain::{Dataset, Robot};
use thermokin_identify::{
    DriftShape, Effect, JointIndex, Model, PoseTerms, Prior, Settle, Start, fit_from, identifiable, initial_frames,
    norms, residuals, residuals_and_jacobian,
};

use crate::clusters::{blocks, moved_joints};
use crate::config::{Config, Outliers};
use crate::error::DiagnoseError;
use crate::report::{Outlier, OutlierScreen, ScaleSource, ScreenCompliance, ScreenModel};
use crate::scoring::prior;
use crate::stats::{FALSE_ALARM, chi_square_upper_quantile};

/// The fewest residual rows per free parameter of the screening model for its residuals to show the
/// noise and not the fit's own freedom (a model that can bend to every pose hides the pose that is off);
/// below, the always-estimated blocks screen alone.
pub const MIN_REDUNDANCY: usize = 4;

/// Flag-and-refit rounds at most; each one fits the screening model once.
const ROUNDS: usize = 6;

/// The screening fit's stop ([`Settle::Residuals`]): a step predicted to gain less than this
/// fraction of the cost ends it — the residual rows would move by a thousandth of their scale in RMS,
/// where the threshold flags at several times that scale. The fit's parameters are never reported; only
/// its residuals are used, and the parameters' own rule (a tenth of their σ, which shrinks as `1/√n`)
/// had the screen of a simulated week of 100,000 poses creep 25 steps where 6 leave its residuals as
/// they are (issue #60: 21.5 s of the week's 281, 19.5× the 12,000-pose week's screen). It stops a
/// fit earlier only above about 10,000 residual rows (below, the parameters' rule already stops there)
/// and never under a strong prior (few poses: such a fit settles in a few steps anyway).
const RESIDUALS_SETTLED: f64 = 1e-6;

/// The screen's result: the measurements kept (0-based indices, in order) and what the report says.
pub(crate) struct Screened {
    pub(crate) kept: Vec<usize>,
    pub(crate) outliers: Vec<Outlier>,
    pub(crate) screen: OutlierScreen,
}

/// Screens `data` for gross errors ([module documentation](self)).
pub(crate) fn screen(robot: &Robot, data: &Dataset, config: &Config) -> Result<Screened, DiagnoseError> {
    let terms = PoseTerms::of(robot, data, config.orientation_lever_mm);
    let stride = terms.stride();
    let all: Vec<usize> = (0..data.len()).collect();
    let (full, compliance_left_out) = screening_effects(robot, data, config, stride);
    let (effects, which, shrinkage) = screening_model(robot, data, config, &terms, full)?;
    let threshold_sigmas = chi_square_upper_quantile(stride, FALSE_ALARM / data.len().max(1) as f64).sqrt();
    let mut kept = all.clone();
    let mut last = (0.0, ScaleSource::Residuals, vec![0.0; data.len()]);
    let mut fitted: Option<(Model, Vec<f64>, Vec<f64>)> = None;
    for _ in 0..ROUNDS {
        let model = Model::new(robot, effects.clone())?.with_start(initial_frames(robot, data, &kept, &effects)?);
        let mut start = Start::new(model.initial(), vec![true; model.len()]);
        start.prior = shrinkage.clone();
        start.settle = Settle::Residuals { relative_gain: RESIDUALS_SETTLED };
        let f = fit_from(robot, &model, data, &kept, &terms, &start)?;
        let raw_r = residuals(robot, &model, &f.theta, data, &all, &terms)?;
        let raw = norms(&raw_r, stride);
        let r = standardised(data, raw_r.clone(), stride);
        let norm = norms(&r, stride);
        // Over every measurement, flagged ones included: the median's breakdown point (half the data)
        // keeps gross errors from inflating it, and a scale over the kept ones alone would shrink with
        // every round and flag ever more.
        // The residuals of a fit with `p` (effective) parameters on `m` rows spread by `√(1 − p/m)` of the
        // noise (the textbook `m − p` of a residual variance): undone, so that a model's own freedom does
        // not lower the threshold on few poses.
        let parameters = match which {
            ScreenModel::ShrunkGeometry { effective_parameters, .. } => effective_parameters,
            _ => f.free.iter().filter(|&&x| x).count() as f64,
        };
        let rows = (kept.len() * stride) as f64;
        let scale = robust_scale(r.iter().copied()) / (1.0 - parameters / rows).max(f64::EPSILON).sqrt();
        let (scale, from) = match config.noise_mm {
            Some(noise) if noise > scale => (noise, ScaleSource::StatedNoise),
            _ => (scale, ScaleSource::Residuals),
        };
        let limit = threshold_sigmas * scale;
        let mut next: Vec<usize> = all.iter().copied().filter(|&i| norm[i] <= limit).collect();
        if 2 * next.len() < all.len() {
            // Most measurements beyond the threshold: the screening model does not describe these data
            // (a wrong convention, wrong units) — nothing here is a gross error among good poses.
            next = all.clone();
        }
        let settled = next == kept;
        last = (scale, from, raw);
        fitted = Some((model, f.theta, raw_r));
        kept = next;
        if settled {
            break;
        }
    }
    // The screening model is the largest fitted (125 columns for a UR10's rows and compliances): its
    // Jacobian, kept by this thread for its next fit, would stay resident through every later phase
    // (300 MB on a week of 100,000 poses), where the models are half its width and the diagnosing
    // thread, outside the pool, fits little.
    thermokin_identify::release_scratch();
    let (scale_mm, scale_from, raw) = last;
    let threshold_mm = threshold_sigmas * scale_mm;
    // Flags that gather are a systematic effect, not gross errors: their poses are kept.
    let flagged: Vec<usize> = (0..data.len()).filter(|&i| kept.binary_search(&i).is_err()).collect();
    let (mut clusters, isolated) = blocks(robot, data, &flagged, &raw, config);
    // Flags left whose departures are each a motion of one joint (a joint standing off by its own amount
    // at each pose, as a play read without the order it was approached in) are kept too.
    let isolated = match &fitted {
        Some((model, theta, raw_r)) if isolated.len() >= crate::clusters::MIN_BLOCK => {
            let motions = joint_motions(robot, data, model, theta, config)?;
            let (found, left) = moved_joints(robot, data, &isolated, raw_r, stride, &motions, &raw);
            clusters.extend(found);
            left
        }
        _ => isolated,
    };
    let kept: Vec<usize> = (0..data.len()).filter(|i| isolated.binary_search(i).is_err()).collect();
    let outliers =
        isolated.iter().map(|&i| Outlier { line: data.line_of(i), measurement: i + 1, residual_mm: raw[i] }).collect();
    let screen = OutlierScreen {
        model: which,
        compliance: screened_compliance(&effects, compliance_left_out),
        scale_mm,
        scale_from,
        threshold_mm,
        excluded: config.outliers == Outliers::Exclude,
        clusters,
    };
    let kept = if config.outliers == Outliers::Exclude { kept } else { all };
    Ok(Screened { kept, outliers, screen })
}

/// Per pose, per joint, how the residual rows of `model` at `theta` move when the joint moves by one
/// radian (one millimetre for a slide): central differences of the commanded value, the poses' terms
/// recomputed — the joint's motion at the tool point in the measurement frame, the model's deflections
/// and all.
fn joint_motions(
    robot: &Robot,
    data: &Dataset,
    model: &Model,
    theta: &[f64],
    config: &Config,
) -> Result<Vec<Vec<f64>>, DiagnoseError> {
    let all: Vec<usize> = (0..data.len()).collect();
    let moved = |j: usize, h: f64| -> Result<Vec<f64>, DiagnoseError> {
        let mut shifted = data.clone();
        shifted.measurements.iter_mut().for_each(|m| m.q[j] += h);
        let terms = PoseTerms::of(robot, &shifted, config.orientation_lever_mm);
        Ok(residuals(robot, model, theta, &shifted, &all, &terms)?)
    };
    (0..robot.chain().dof())
        .map(|j| {
            // A thousandth of a radian (or millimetre): the tool moves by ~1 mm, far above the rounding
            // of positions of ~1 m, and the motion's curvature over it is ~1e-3 of the motion.
            let h = 1e-3;
            let (up, down) = (moved(j, h)?, moved(j, -h)?);
            Ok(up.iter().zip(&down).map(|(a, b)| (a - b) / (2.0 * h)).collect())
        })
        .collect()
}

/// Which gravity compliance the screening model `effects` holds ([`ScreenCompliance`]); `left_out`:
/// whether one without masses was left out of it for the poses' number ([`screening_effects`]).
fn screened_compliance(effects: &[Effect], left_out: bool) -> ScreenCompliance {
    if effects.iter().any(|e| matches!(e, Effect::JointCompliance(_) | Effect::LateralCompliance(..))) {
        ScreenCompliance::FileMasses
    } else if effects.iter().any(|e| matches!(e, Effect::LumpedCompliance(..) | Effect::LumpedLateralCompliance(..))) {
        ScreenCompliance::Lumped
    } else if left_out {
        ScreenCompliance::TooFewPoses
    } else {
        ScreenCompliance::NotLoaded
    }
}

/// The screening model's effects for this robot and these data: the always-estimated blocks, every
/// joint row, every slide's scale and straightness and every loaded joint's compliance (and, for a
/// warm-up, every row's drifts); and whether a compliance without masses was left out of them for the
/// poses' number.
fn screening_effects(robot: &Robot, data: &Dataset, config: &Config, stride: usize) -> (Vec<Effect>, bool) {
    let mut effects = config.setup().always_estimated(data);
    let spans_time = data.time_span() > 0.0;
    let mut lumped = Vec::new();
    let loaded = thermokin_identify::max_gravity_torques(robot);
    for j in (0..robot.chain().dof()).filter_map(|j| JointIndex::of(robot, j).ok()) {
        effects.push(Effect::LinkDeviation(j));
        // A slide's scale and its guide's straightness: its row's constant deviation cannot take an
        // error growing with the extension, whose top poses would stand out as gross errors.
        if robot.chain().joints()[j.index()].kind == thermokin_chain::JointKind::Prismatic {
            effects.push(Effect::JointScale(j));
            effects.push(Effect::Straightness(j));
            // A column bending under what it carries, more at its top extensions: its tilt, on the
            // file's masses or, without them, its loads lumped.
            if robot.masses().iter().skip(j.index()).any(Option::is_some) {
                lumped.push(Effect::lateral_compliance(robot, j));
            } else if robot.masses().iter().all(Option::is_none) {
                lumped.extend(Effect::lumped_lateral_compliance(robot, j).ok());
            }
        }
        // A backlash: the poses reached from its less usual side are no gross errors.
        let (up, down) = thermokin_identify::approach_counts(data, 0..data.len(), j.index());
        if up.min(down) >= crate::eligibility::MIN_POSES_EACH_SIDE {
            lumped.push(Effect::Backlash(j));
        }
        match thermokin_identify::gravity_compliance(robot, data, j, &loaded) {
            Some(e @ Effect::LumpedCompliance(..)) => lumped.push(e),
            other => effects.extend(other),
        }
        if spans_time {
            // A warm-up: each row may drift (in time, and with its logged temperature), so that a drift's
            // late poses are not mistaken for gross errors.
            effects.push(Effect::ThermalDrift(j, DriftShape::Exponential));
            if !data.temperature_names.is_empty() {
                effects.push(Effect::ThermalDrift(j, DriftShape::Temperature));
            }
        }
    }
    // Every row following each sensor column (a tilt the column's accelerometer reads moves the poses
    // it reads high, which are no gross errors).
    for k in 0..data.sensor_names.len() {
        let (lo, hi) = crate::stats::span(data.sensor_values.iter().filter_map(|v| v.get(k).copied()));
        if let Some(sensor) = thermokin_identify::SensorId::of(data, k).filter(|_| hi > lo) {
            let rows = (0..robot.chain().dof()).filter_map(|j| JointIndex::of(robot, j).ok());
            lumped.extend(rows.map(|j| Effect::SensorDrift(j, sensor)));
        }
    }
    // A compliance without masses (up to two weights per link carried), the backlashes and the sensors'
    // rows screen where the rows hold [`MIN_REDUNDANCY`] per parameter with them; on fewer they would only
    // make the screen shrink the rows that explain a small set's millimetres, and hide the pose that is
    // off.
    let parameters: usize = effects.iter().chain(&lumped).map(Effect::len).sum();
    if data.len() * stride >= MIN_REDUNDANCY * parameters {
        effects.extend(lumped);
        return (effects, false);
    }
    let compliance_left_out =
        lumped.iter().any(|e| matches!(e, Effect::LumpedCompliance(..) | Effect::LumpedLateralCompliance(..)));
    (effects, compliance_left_out)
}

/// The screening model for these data ([`ScreenModel`]), from the effects `full` of
/// [`screening_effects`]: its effects and, where the data are too few for its identifiable parameters to
/// leave [`MIN_REDUNDANCY`] residual rows each, the prior toward the nominal robot that brings its
/// effective parameters within them.
///
/// **Effective parameters.** A fit with a Gaussian prior (weights `D`, [`crate::shrinkage`]'s at unit
/// strength times `λ`) bends to the data by `trace((JᵀJ + λD)⁻¹ JᵀJ)` degrees of freedom — the trace of
/// its hat matrix, the parameter count of least squares (`λ = 0`) and less as the prior pulls — `J` the
/// identifiable columns of the Jacobian at the nominal robot. The smallest `λ` of a doubling sequence
/// from 0.01 rows per parameter whose trace is within the rows' [`MIN_REDUNDANCY`] is taken: a model as
/// flexible as the redundancy rule allows, which explains a light arm's millimetres of systematic error
/// the frame alone leaves — the frame alone on thirty poses of the real WAM flagged one to four clean
/// poses in every draw. Where even the blocks always estimated (never shrunk) exceed the rows' share,
/// they screen alone.
fn screening_model(
    robot: &Robot,
    data: &Dataset,
    config: &Config,
    terms: &PoseTerms,
    full: Vec<Effect>,
) -> Result<(Vec<Effect>, ScreenModel, Option<Prior>), DiagnoseError> {
    let rows = data.len() * terms.stride();
    let parameters: usize = full.iter().map(Effect::len).sum();
    if rows >= MIN_REDUNDANCY * parameters {
        return Ok((full, ScreenModel::FullGeometry, None));
    }
    let always = config.setup().always_estimated(data);
    let all: Vec<usize> = (0..data.len()).collect();
    let model = Model::new(robot, full.clone())?.with_start(initial_frames(robot, data, &all, &full)?);
    let (_, jac) = residuals_and_jacobian(robot, &model, &model.initial(), data, &all, terms)?;
    let free: Vec<usize> = {
        let decided = identifiable(jac.as_ref(), &vec![true; model.len()]);
        (0..model.len()).filter(|&c| decided.free[c]).collect()
    };
    let squares: Vec<f64> = (0..model.len()).map(|c| jac.col(c).squared_norm_l2()).collect();
    let unit = prior(&model, (&squares, jac.nrows()), 1.0);
    let p = free.len();
    let gram = Mat::from_fn(p, p, |i, k| jac.col(free[i]).transpose() * jac.col(free[k]));
    let budget = rows as f64 / MIN_REDUNDANCY as f64;
    let effective = |lambda: f64| -> f64 {
        let mut m = gram.clone();
        for (i, &c) in free.iter().enumerate() {
            m[(i, i)] += lambda * unit.weight[c] * unit.weight[c];
        }
        let solved = m.partial_piv_lu().solve(&gram);
        (0..p).map(|i| solved[(i, i)]).sum()
    };
    // Its identifiable parameters may be within the budget where all of them are not: least squares.
    if p as f64 <= budget {
        return Ok((full, ScreenModel::FullGeometry, None));
    }
    let unshrunk = free.iter().filter(|&&c| unit.weight[c] == 0.0).count() as f64;
    if unshrunk > budget {
        return Ok((always, ScreenModel::FrameOnly, None));
    }
    let Some((lambda, effective_parameters)) = std::iter::successors(Some(0.01), |l| Some(l * 2.0))
        .take(64)
        .map(|l| (l, effective(l)))
        .find(|&(_, e)| e <= budget)
    else {
        return Ok((always, ScreenModel::FrameOnly, None));
    };
    let which = ScreenModel::ShrunkGeometry { effective_parameters, prior_rows: lambda };
    let mut weighted = unit;
    weighted.weight.iter_mut().for_each(|w| *w *= lambda.sqrt());
    Ok((full, which, Some(weighted)))
}

/// The residuals `r` (`stride` rows per measurement) with each position row divided by the tracker's
/// stated standard deviation over its mean (as the fit weighs them), when every measurement states one:
/// a pose measured ten times less precisely is judged against ten times the scale, not flagged for its
/// stated noise. Unchanged otherwise.
fn standardised(data: &Dataset, mut r: Vec<f64>, stride: usize) -> Vec<f64> {
    if !data.has_position_std() {
        return r;
    }
    let stds: Vec<nalgebra::Vector3<f64>> = data.measurements.iter().filter_map(|m| m.position_std_mm).collect();
    let mean = stds.iter().map(|s| s.sum()).sum::<f64>() / (3 * stds.len()) as f64;
    for (rows, s) in r.chunks_mut(stride).zip(&stds) {
        for a in 0..3 {
            rows[a] *= mean / s[a];
        }
    }
    r
}

/// The robust standard deviation of residual components: `1.4826 · median |r|` (the median absolute
/// deviation about zero — a fitted model's residuals have mean zero — scaled to σ for Gaussian ones).
fn robust_scale(components: impl Iterator<Item = f64>) -> f64 {
    let mut a: Vec<f64> = components.map(f64::abs).collect();
    if a.is_empty() {
        return 0.0;
    }
    let mid = a.len() / 2;
    let (_, median, _) = a.select_nth_unstable_by(mid, f64::total_cmp);
    1.4826 * *median
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_robust_scale_ignores_a_few_gross_values() {
        // ±1 alternating has median |r| = 1: σ̂ = 1.4826; ten values of 1e6 among a thousand move it not.
        let clean: Vec<f64> = (0..1000).map(|i| if i % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let mut dirty = clean.clone();
        dirty[..10].fill(1e6);
        assert_eq!(robust_scale(clean.into_iter()), 1.4826);
        assert_eq!(robust_scale(dirty.into_iter()), 1.4826);
    }
}
