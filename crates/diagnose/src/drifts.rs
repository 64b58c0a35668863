//! Where a thermal drift differs from what would replace it. An exponential law `1 − e^(−t/τ)` rises
//! over its first time constants and then rests on its plateau; a static deviation is its average, a
//! linear law its chord. Over a session that is mostly plateau, the three predict alike at most poses,
//! and a gate over the whole session — one paired difference per block of time — can find the drift
//! "not significantly better" although every block of its first minutes says otherwise. Those minutes
//! are what a compensation is for: a warm-up's robot is used while it rises. So a drift is judged
//! twice — over the session, and over the minutes in which it rises (its first three time constants,
//! 95 % of the drift) — and a smaller law replaces it only where it predicts as well in both
//! ([`keeps_its_law`]). A drift over before the poses begin (τ of a tenth of a minute) rises within one
//! block of time, where the gate cannot show anything: it still becomes the static deviation it is.

use thermokin_identify::{DriftShape, Effect, Model};

use crate::config::Config;
use crate::error::DiagnoseError;
use crate::scoring::{Scorer, significantly_better};

/// The time constants an exponential drift rises over: 95 % of `1 − e^(−t/τ)` is reached at `3τ`.
const RISING_TIME_CONSTANTS: f64 = 3.0;

/// The minutes (from the first measurement) over which the exponential drift at `k` of `effects` rises,
/// its time constant read from the model fitted on all measurements; `None` for any other effect, or
/// where they cover the whole session (the session's own gate already judges them).
pub(crate) fn rising_minutes(
    scorer: &Scorer<'_>,
    effects: &[Effect],
    k: usize,
) -> Result<Option<(f64, f64)>, DiagnoseError> {
    if !matches!(effects.get(k), Some(Effect::ThermalDrift(_, DriftShape::Exponential))) {
        return Ok(None);
    }
    let (model, fit) = scorer.full_fit(effects)?;
    Ok(rising_in_fit(scorer, &model, &fit.theta, k))
}

/// [`rising_minutes`] of the exponential drift at `k` of `model`, whose parameters fitted on all
/// measurements are `theta`.
pub(crate) fn rising_in_fit(scorer: &Scorer<'_>, model: &Model, theta: &[f64], k: usize) -> Option<(f64, f64)> {
    let times = scorer.data.measurements.iter().map(|m| m.time_min);
    let first = times.clone().fold(f64::INFINITY, f64::min);
    let last = times.fold(f64::NEG_INFINITY, f64::max);
    let tau = theta[model.offsets()[k] + 6];
    let end = first + RISING_TIME_CONSTANTS * tau;
    (tau.is_finite() && tau > 0.0 && end < last).then_some((first, end))
}

/// Whether the model with the drift (held-out errors `with`, on the selection's folds) is significantly
/// better than the one without it (`without`) — over the whole session, or over the minutes
/// `rising` in which it rises: the gate over the blocks of time that hold those poses. Where they lie in
/// fewer than two blocks the gate cannot tell, and the session decides alone.
pub(crate) fn keeps_its_law(
    scorer: &Scorer<'_>,
    config: &Config,
    without: &[f64],
    with: &[f64],
    rising: Option<(f64, f64)>,
) -> bool {
    let z = config.gate_standard_errors;
    if significantly_better(without, with, z, &scorer.blocks) {
        return true;
    }
    let Some((from, to)) = rising else { return false };
    let inside: Vec<bool> = scorer
        .folds
        .iter()
        .filter(|(train, test)| !train.is_empty() && !test.is_empty())
        .flat_map(|(_, test)| test.iter().map(|&i| scorer.data.measurements[i].time_min))
        .map(|t| (from..=to).contains(&t))
        .collect();
    if inside.len() != with.len() || inside.len() != without.len() {
        return false;
    }
    let pick = |v: &[f64]| -> Vec<f64> { v.iter().zip(&inside).filter(|(_, i)| **i).map(|(x, _)| *x).collect() };
    let blocks: Vec<usize> = scorer.blocks.iter().zip(&inside).filter(|(_, i)| **i).map(|(b, _)| *b).collect();
    significantly_better(&pick(without), &pick(with), z, &blocks)
}
