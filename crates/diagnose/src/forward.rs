//! Phase 3 of the selection: forward steps. Each round ranks the remaining candidates by a linearised
//! step ([`crate::screen`]), scores a shortlist in full (in parallel), and the candidate with the lowest
//! held-out error joins while it beats the current model by more than the gate — the smallest block
//! within [`Config::parsimony`] of the best gain preferred, its fitted values within the physical bounds,
//! its information criterion lower.

use rayon::prelude::*;
use thermokin_identify::{DriftShape, Effect, JointIndex};

use crate::config::{Config, Fitted};
use crate::drifts::{keeps_its_law, rising_in_fit};
use crate::error::DiagnoseError;
use crate::plausibility::{Implausible, Judged, Trade, implausible};
use crate::scoring::{Scorer, significantly_better};
use crate::selection::{Candidate, Scored, Selection, StoppedQuote, adds_nothing, score, unsettled};

fn is_exponential(c: &Effect) -> bool {
    matches!(c, Effect::ThermalDrift(_, DriftShape::Exponential))
}

/// Forward steps until no candidate passes the gate, the pool is empty or [`Config::max_effects`] are
/// chosen. An exponential drift refines the linear one of its joint and is scored only where the linear
/// drift already earns half the best gain (it costs a model per measurement and a nonlinear τ).
pub(crate) fn forward(
    scorer: &Scorer<'_>,
    config: &Config,
    sel: &mut Selection,
    mut pool: Vec<Effect>,
) -> Result<(), DiagnoseError> {
    // Candidates refused for their size in the model of their refusal: out of the pool until another
    // effect joins and a linearised step puts them within bounds (`refuse`, `wake`).
    let mut resting = Vec::new();
    while sel.chosen().len() < config.max_effects && !pool.is_empty() {
        let (mut results, mut deferred) = score_round(scorer, config, sel, &mut pool, &mut resting)?;
        // The best candidate that passes every check joins. Where every block within parsimony of the
        // best gain was a drift that forward chaining rejects (a later drift fitted on early minutes
        // that still lack an earlier one), the next best are tried: on a warm-up rising over its first
        // minutes, a slow row's drift ranks first and cannot carry forward until the fast one joined.
        // The candidates the forecast left out (their gain short of the parsimony's reach) join those
        // next best once the ones tried are set aside: they are fitted then.
        let chosen = loop {
            let best = results.iter().min_by(|a, b| a.stats.heldout_rms_mm.total_cmp(&b.stats.heldout_rms_mm)).cloned();
            let passing = best
                .filter(|b| significantly_better(&sel.errors, &b.errors, config.gate_standard_errors, &scorer.blocks));
            let Some(best) = passing else { break None };
            match choose(scorer, config, sel, &results, &best, &mut pool, &mut resting)? {
                Choice::Joins(c, b, theta) => break Some((*c, b, theta)),
                Choice::OnlyNotForward(tried) => {
                    results.retain(|r| !tried.contains(&r.effect));
                    let later = std::mem::take(&mut deferred);
                    if !later.is_empty() {
                        let mut fitted = score_listed(scorer, config, sel, &later, &mut pool, &mut resting)?;
                        results.append(&mut fitted);
                    }
                }
                Choice::None => break None,
            }
        };
        let Some((c, b, theta)) = chosen else { break };
        sel.accept(&c, b, theta, format!("+ {}", c.effect.label()));
        pool.retain(|e| *e != c.effect);
        refine_to_exponential(scorer, config, sel, &mut pool)?;
        wake(scorer, config, sel, &mut pool, &mut resting)?;
    }
    Ok(())
}

/// The linear drift that has just joined gives its place to its exponential twin where the exponential
/// is significantly better held out — over the session, or over the minutes in which it rises
/// ([`crate::drifts`]) — with plausible values. A round scores the exponential only where the linear
/// drift earns half the best gain; once the linear one has joined, the twin is not scored again, and a
/// warm-up whose joint rises over forty minutes would keep a straight line through it.
fn refine_to_exponential(
    scorer: &Scorer<'_>,
    config: &Config,
    sel: &mut Selection,
    pool: &mut Vec<Effect>,
) -> Result<(), DiagnoseError> {
    let Some((&linear, before)) = sel.effects.split_last() else { return Ok(()) };
    let Effect::ThermalDrift(j, DriftShape::Linear) = linear else { return Ok(()) };
    let twin = Effect::ThermalDrift(j, DriftShape::Exponential);
    if !pool.contains(&twin) {
        return Ok(());
    }
    let k = before.len();
    let mut swapped = sel.effects.clone();
    swapped[k] = twin;
    let (stats, errors) = scorer.heldout_errors(&swapped, &scorer.folds)?;
    // One fit on all data serves the minutes it rises in, its plausibility and the information criterion.
    let (model, full) = scorer.full_fit(&swapped)?;
    let rising = rising_in_fit(scorer, &model, &full.theta, k);
    if !keeps_its_law(scorer, config, &sel.errors, &errors, rising) {
        return Ok(());
    }
    let o = model.offsets()[k];
    if implausible(&scorer.scale, &full.theta[o..o + twin.len()], twin, &config.plausibility).is_some() {
        return Ok(());
    }
    for s in sel.steps.iter_mut().filter(|s| s.effect == linear) {
        s.effect = twin;
    }
    let bic = scorer.bic_of(&full);
    let row = format!("{} replaces the linear (significantly better held out)", twin.label());
    sel.replace(swapped, stats, errors, row);
    sel.theta = full.theta;
    if let Some(last) = sel.bic.last_mut() {
        *last = bic;
    }
    pool.retain(|e| *e != twin);
    Ok(())
}

/// Refuses candidate `c` for `why`, judged as `judged`: its refusal replaces an earlier one of the same
/// effect. A value beyond its size bound is a fit of this model — where the model still lacks the rows
/// it trades with, a candidate absorbs their errors (on an elastic arm whose geometry is millimetres off,
/// a compliance fitted before the rows bends by degrees) — so it rests (`resting`) and may return once
/// other effects have joined ([`wake`]); so does an exponential drift over before the poses in a model
/// without its row's static deviation ([`holds_static_row`]); a refusal in kind (a joint rising under its
/// load, a drift over before the poses beside its row, a slope no joint correction has) is final.
fn refuse(
    sel: &mut Selection,
    c: Effect,
    (why, trade): (&Implausible, Option<&Trade>),
    judged: Judged,
    resting: &mut Vec<Effect>,
) {
    let refusal = why.refused_trading(c, judged, trade);
    sel.refused.retain(|r| r.effect != refusal.effect);
    sel.refused.push(refusal);
    let stands_in_for_its_row = matches!(why, Implausible::Instant { .. }) && !holds_static_row(&sel.effects, c);
    if why.excess().is_some() || stands_in_for_its_row {
        resting.push(c);
    }
}

/// Whether `effects` hold a static deviation of the row a drift `c` moves (its joint's offset or link
/// deviation). Without one, an exponential drift fitted where the row is off takes the static part
/// itself, its time constant collapsing to a fraction of a minute (a law "over before the poses"): a
/// refusal of that fit says nothing of the drift once the row is in the model ([`wake`]).
fn holds_static_row(effects: &[Effect], c: Effect) -> bool {
    let Effect::ThermalDrift(j, _) = c else { return false };
    effects.contains(&Effect::LinkDeviation(j)) || effects.contains(&Effect::JointOffset(j))
}

/// After an effect joined: the resting candidates whose values one linearised step on all data puts
/// within their bounds in the model as it now stands return to the pool, to be fitted in full again
/// ([`crate::screen::linearised_values`]); the others rest — a fit runs to about the values that step
/// points at, so fitting them again would refuse them again at the cost of a fit per fold (on the UR10,
/// `link_deviation[6]` trading with the probe at 27 mm, every round).
fn wake(
    scorer: &Scorer<'_>,
    config: &Config,
    sel: &Selection,
    pool: &mut Vec<Effect>,
    resting: &mut Vec<Effect>,
) -> Result<(), DiagnoseError> {
    if resting.is_empty() {
        return Ok(());
    }
    // A drift refused as over before the poses, where the model lacked its row: back once the row joined.
    let (back, sized): (Vec<Effect>, Vec<Effect>) =
        resting.drain(..).partition(|&c| is_exponential(&c) && holds_static_row(&sel.effects, c));
    pool.extend(back);
    let values = crate::screen::linearised_values(scorer, &sel.effects, &sel.theta, &sized)?;
    let mut still = Vec::new();
    for (c, v) in sized.into_iter().zip(values) {
        match implausible(&scorer.scale, &v, c, &config.plausibility) {
            Some(_) => still.push(c),
            None => pool.push(c),
        }
    }
    *resting = still;
    Ok(())
}

/// One round's scored candidates: the screen's shortlist of the linear candidates (those of them a
/// forecast from the current model's fold fits puts out of reach deferred, [`crate::linearised`]), then
/// the exponential drifts whose linear twin earns half the best gain. Candidates every fold finds
/// implausible are refused and leave the pool (for their size, to rest: `refuse`); those that add
/// nothing identifiable are recorded as skipped; the pool keeps the others, the deferred ones too.
fn score_round(
    scorer: &Scorer<'_>,
    config: &Config,
    sel: &mut Selection,
    pool: &mut Vec<Effect>,
    resting: &mut Vec<Effect>,
) -> Result<(Vec<Candidate>, Vec<Effect>), DiagnoseError> {
    let linear: Vec<Effect> = pool.iter().copied().filter(|c| !is_exponential(c)).collect();
    let effects = sel.effects.clone();
    // Score before you fit: the candidates ranked by a linearised step, the shortlist fitted in full.
    let shortlisted = crate::screen::shortlist(scorer, &effects, &sel.theta, &linear, config.screen)?;
    let forecasts = match config.screen.fitted {
        Fitted::InReach => crate::linearised::forecasts(scorer, &effects, &shortlisted)?,
        Fitted::Every => None,
    };
    let score_all = |list: &[Effect]| score_each(scorer, config, &effects, list);
    let current = sel.current.heldout_rms_mm;
    let (mut scored, first, deferred, forecast_gain) = match &forecasts {
        Some(f) => {
            let passing = crate::linearised::passing(f, &sel.errors, config.gate_standard_errors, &scorer.blocks);
            // The best forecast fitted first; its fitted gain sets which others are within reach. One the
            // fit refuses (beyond the plausible on every fold, never settling) cannot be the step's choice
            // and sets nothing: the next best is fitted, until one stands (an elastic torso's own lateral
            // compliance, refused as traded with its bend, had set a reach that left out the link row the
            // step then lacked, and the selection stopped a step short).
            let mut scored = Vec::new();
            let mut reference = 0.0;
            for lead in &passing {
                let lead_scored = score_all(&[lead.effect])?;
                let stands = match lead_scored.first() {
                    Some((_, Scored::Candidate(c))) if c.runaway.is_none() && !c.unsettled => {
                        reference = current - c.stats.heldout_rms_mm;
                        true
                    }
                    _ => false,
                };
                scored.extend(lead_scored);
                if stands {
                    break;
                }
            }
            let reach = crate::linearised::in_reach(&passing, current, reference, config.parsimony);
            let rest: Vec<Effect> = reach.iter().copied().filter(|c| !scored.iter().any(|(s, _)| s == c)).collect();
            scored.extend(score_all(&rest)?);
            let first: Vec<Effect> = scored.iter().map(|(c, _)| *c).collect();
            let deferred: Vec<Effect> = shortlisted.iter().copied().filter(|c| !first.contains(c)).collect();
            let gains: Vec<(Effect, f64)> = f.iter().map(|f| (f.effect, current - f.stats.heldout_rms_mm)).collect();
            (scored, first, deferred, gains)
        }
        None => (score_all(&shortlisted)?, shortlisted.clone(), Vec::new(), Vec::new()),
    };
    let gain = |s: &Scored| match s {
        Scored::Candidate(s) => Some(sel.current.heldout_rms_mm - s.stats.heldout_rms_mm),
        Scored::AddsNothing(_) | Scored::ForecastBeyond(..) => None,
    };
    // A deferred linear drift's gain is its forecast's.
    let gains: Vec<(Effect, f64)> = scored
        .iter()
        .filter_map(|(c, s)| gain(s).map(|g| (*c, g)))
        .chain(forecast_gain.iter().copied().filter(|(c, _)| deferred.contains(c)))
        .collect();
    let best_gain = gains.iter().map(|(_, g)| *g).fold(0.0, f64::max);
    let linear_gain = |j: Option<JointIndex>| {
        gains
            .iter()
            .filter(|(c, _)| matches!(c, Effect::ThermalDrift(_, DriftShape::Linear)) && c.joint() == j)
            .map(|(_, g)| *g)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let second: Vec<Effect> = pool
        .iter()
        .copied()
        .filter(|c| is_exponential(c) && best_gain > 0.0 && linear_gain(c.joint()) >= 0.5 * best_gain)
        .collect();
    scored.extend(score_all(&second)?);
    let mut still: Vec<Effect> = pool
        .iter()
        .copied()
        .filter(|c| (is_exponential(c) && !second.contains(c)) || (!is_exponential(c) && !first.contains(c)))
        .collect();
    let later = judge_deferred(scorer, config, sel, forecasts.as_deref(), deferred, &mut scored, &mut still)?;
    let rank = |c: &Effect| shortlisted.iter().position(|s| s == c).unwrap_or(usize::MAX);
    scored.sort_by_key(|(c, _)| rank(c));
    let results = keep_scored(sel, scored, &mut still, resting);
    *pool = still;
    Ok((results, later))
}

/// The deferred candidates judged as a fit would judge them before any gain counts: one that adds
/// nothing identifiable is said so and leaves the pool, as when fitted; one beyond the plausible in kind
/// in every fold's forecast is refused as one beyond it in every fold's fit, said as forecast (one beyond
/// its size only where the forecast traded the value with another block, [`forecast_trade`]);
/// one plausible there lifts an earlier refusal for its size, as a fitted one does. Their verdicts join
/// `scored` (the round orders them by the shortlist), they leave `still` where they leave the pool; the
/// others are returned, deferred still.
fn judge_deferred(
    scorer: &Scorer<'_>,
    config: &Config,
    sel: &mut Selection,
    forecasts: Option<&[crate::linearised::Forecast]>,
    deferred: Vec<Effect>,
    scored: &mut Vec<(Effect, Scored)>,
    still: &mut Vec<Effect>,
) -> Result<Vec<Effect>, DiagnoseError> {
    let effects = sel.effects.clone();
    let mut later = Vec::with_capacity(deferred.len());
    for c in deferred {
        if let Some(reason) = adds_nothing(scorer, &effects, c)? {
            still.retain(|e| *e != c);
            scored.push((c, Scored::AddsNothing(reason)));
        } else if let Some((why, forecast)) = forecast_runaway(scorer, config, forecasts, c) {
            // Beyond its size, the value may be the poses' own (`Trade::stands`): told at the forecast as a
            // fit's is told at the fit; it then stays deferred, as a plausible one.
            let trade = match why.excess() {
                Some(_) => forecast_trade(scorer, &effects, forecast)?,
                None => None,
            };
            if trade.as_ref().is_some_and(Trade::stands) {
                later.push(c);
            } else {
                still.retain(|e| *e != c);
                scored.push((c, Scored::ForecastBeyond(why, trade)));
            }
        } else {
            sel.refused.retain(|r| r.effect != c.label());
            later.push(c);
        }
    }
    Ok(later)
}

/// What the forecast `f` of a candidate traded its value with, in the first fold it has values on: the
/// current model at that fold's fit, the candidate at its forecast values ([`Scorer::traded_with`]).
fn forecast_trade(
    scorer: &Scorer<'_>,
    effects: &[Effect],
    f: &crate::linearised::Forecast,
) -> Result<Option<Trade>, DiagnoseError> {
    let Some(fits) = scorer.kept_fold_fits(effects) else { return Ok(None) };
    let mut with = effects.to_vec();
    with.push(f.effect);
    let folds = scorer.folds.iter().zip(fits.iter()).zip(&f.values);
    for (((train, _), (theta, ..)), values) in folds {
        if theta.is_empty() || values.len() != f.effect.len() {
            continue;
        }
        let model = scorer.model(&with, train)?;
        let mut at = model.initial();
        at[..theta.len()].copy_from_slice(theta);
        let o = model.offsets()[effects.len()];
        at[o..o + values.len()].copy_from_slice(values);
        return scorer.traded_with(&model, &at, train, effects.len());
    }
    Ok(None)
}

/// Why the forecast of candidate `c` is beyond the plausible in every fold, where it is, and the forecast.
fn forecast_runaway<'f>(
    scorer: &Scorer<'_>,
    config: &Config,
    forecasts: Option<&'f [crate::linearised::Forecast]>,
    c: Effect,
) -> Option<(Implausible, &'f crate::linearised::Forecast)> {
    let f = forecasts?.iter().find(|f| f.effect == c)?;
    let reasons: Vec<Option<Implausible>> =
        f.values.iter().map(|v| implausible(&scorer.scale, v, c, &config.plausibility)).collect();
    if reasons.is_empty() || reasons.iter().any(Option::is_none) {
        return None;
    }
    reasons.into_iter().flatten().next().map(|why| (why, f))
}

/// Each candidate of `list` beside `effects`, scored on the selection's folds (in parallel).
fn score_each(
    scorer: &Scorer<'_>,
    config: &Config,
    effects: &[Effect],
    list: &[Effect],
) -> Result<Vec<(Effect, Scored)>, DiagnoseError> {
    list.par_iter().map(|&c| Ok((c, score(scorer, effects, c, &config.plausibility)?))).collect()
}

/// The deferred candidates `list` scored in full (a round whose best were drifts that forward chaining
/// turned down: the next best are tried, the deferred ones among them).
fn score_listed(
    scorer: &Scorer<'_>,
    config: &Config,
    sel: &mut Selection,
    list: &[Effect],
    pool: &mut Vec<Effect>,
    resting: &mut Vec<Effect>,
) -> Result<Vec<Candidate>, DiagnoseError> {
    let scored = score_each(scorer, config, &sel.effects, list)?;
    let mut still: Vec<Effect> = pool.iter().copied().filter(|c| !list.contains(c)).collect();
    let results = keep_scored(sel, scored, &mut still, resting);
    *pool = still;
    Ok(results)
}

/// What scoring found, recorded: a candidate that adds nothing is skipped, one implausible on every fold
/// refused (or resting), one that never settles refused; the others return to the pool (`still`) and
/// are the round's results.
fn keep_scored(
    sel: &mut Selection,
    scored: Vec<(Effect, Scored)>,
    still: &mut Vec<Effect>,
    resting: &mut Vec<Effect>,
) -> Vec<Candidate> {
    let mut results = Vec::new();
    for (c, s) in scored {
        match s {
            Scored::AddsNothing(reason) => sel.skip(c, reason),
            Scored::ForecastBeyond(why, trade) => {
                refuse(sel, c, (&why, trade.as_ref()), Judged::ForecastOnEveryFold, resting)
            }
            Scored::Candidate(s) => match &s.runaway {
                Some(why) => {
                    refuse(sel, c, (why, s.trade.as_ref()), Judged::FittedOnEveryFold, resting);
                    if let (Some(fold), Some(refusal)) = (s.quoted_fold, sel.refused.last()) {
                        let mut with = sel.effects.clone();
                        with.push(c);
                        sel.stopped_quotes.push(StoppedQuote { refusal: refusal.clone(), with, fold });
                    }
                }
                None if s.unsettled => sel.refused.push(unsettled(c)),
                None => {
                    // Plausible in this model: an earlier refusal for its size no longer holds.
                    sel.refused.retain(|r| r.effect != c.label());
                    still.push(c);
                    results.push(*s);
                }
            },
        }
    }
    results
}

/// The candidate that joins, with its information criterion and its parameters fitted on all data.
/// Parsimony within the step: the smallest block within `parsimony` of the best gain, itself
/// significant; ties between blocks of one size go to the conventional one (base_frame, tool_frame,
/// joint_offset), then the lowest error. A time-dependent candidate must also lower the forward-chained
/// error; one whose values fitted on all data are implausible is refused (and leaves the pool, for its
/// size to rest: `refuse`); the information criterion must fall.
fn choose(
    scorer: &Scorer<'_>,
    config: &Config,
    sel: &mut Selection,
    results: &[Candidate],
    best: &Candidate,
    pool: &mut Vec<Effect>,
    resting: &mut Vec<Effect>,
) -> Result<Choice, DiagnoseError> {
    let gate = config.gate_standard_errors;
    let gain = sel.current.heldout_rms_mm - best.stats.heldout_rms_mm;
    let mut eligible: Vec<&Candidate> = results
        .iter()
        .filter(|r| sel.current.heldout_rms_mm - r.stats.heldout_rms_mm >= config.parsimony * gain)
        .filter(|r| significantly_better(&sel.errors, &r.errors, gate, &scorer.blocks))
        .collect();
    let conventional = |e: &Effect| matches!(e, Effect::BaseFrame | Effect::ToolFrame | Effect::JointOffset(_));
    eligible.sort_by(|a, b| {
        a.new_free
            .cmp(&b.new_free)
            .then(conventional(&b.effect).cmp(&conventional(&a.effect)))
            .then(a.stats.heldout_rms_mm.total_cmp(&b.stats.heldout_rms_mm))
    });
    let mut forward_before: Option<f64> = None;
    let tried: Vec<Effect> = eligible.iter().map(|c| c.effect).collect();
    let mut not_forward = Vec::new();
    for cand in eligible {
        let mut with = sel.effects.clone();
        with.push(cand.effect);
        if cand.effect.is_time_dependent() {
            // The current model's forward-chained error, once per step however many drifts are tried.
            let before = match forward_before {
                Some(b) => b,
                None => *forward_before.insert(scorer.heldout(&sel.effects, &scorer.forward)?.heldout_rms_mm),
            };
            let after = scorer.heldout(&with, &scorer.forward)?;
            if after.heldout_rms_mm >= before {
                not_forward.push(cand.effect);
                continue;
            }
        }
        // One fit on all data serves the plausibility bounds and the information criterion.
        let (model, full) = scorer.full_fit(&with)?;
        let o = model.offsets()[model.offsets().len() - 1];
        let values = &full.theta[o..o + cand.effect.len()];
        if let Some(why) = implausible(&scorer.scale, values, cand.effect, &config.plausibility) {
            let trade = match why.excess() {
                Some(_) => scorer.traded_with(&model, &full.theta, &scorer.all(), model.effects().len() - 1)?,
                None => None,
            };
            if !trade.as_ref().is_some_and(Trade::stands) {
                refuse(sel, cand.effect, (&why, trade.as_ref()), Judged::Fitted, resting);
                pool.retain(|c| *c != cand.effect);
                continue;
            }
        }
        let b = scorer.bic_of(&full);
        if b >= *sel.bic.last().unwrap_or(&f64::INFINITY) {
            continue;
        }
        return Ok(Choice::Joins(Box::new(cand.clone()), b, full.theta));
    }
    Ok(if !tried.is_empty() && tried.iter().all(|e| not_forward.contains(e)) {
        Choice::OnlyNotForward(tried)
    } else {
        Choice::None
    })
}

/// What [`choose`] found.
enum Choice {
    /// This candidate joins, with its information criterion and its parameters fitted on all data.
    Joins(Box<Candidate>, f64, Vec<f64>),
    /// Every candidate it tried (these) was a drift whose forward-chained error rose.
    OnlyNotForward(Vec<Effect>),
    /// None joins.
    None,
}
