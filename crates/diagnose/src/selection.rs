//! Where the selection stands between its phases ([`Selection`]), and a candidate scored against it.

use std::sync::Arc;

use thermokin_identify::{Effect, GiveUp, MAX_ITERATIONS};

use crate::config::Plausibility;
use crate::error::DiagnoseError;
use crate::plausibility::{Implausible, Judged, Trade, implausible};
use crate::report::{Refusal, Skipped, TableRow};
use crate::scoring::{Addition, HeldOut, Scorer};
use crate::stats::Stats;

/// A candidate scored on the selection's folds.
#[derive(Clone, Debug)]
pub(crate) struct Candidate {
    pub(crate) effect: Effect,
    /// Its parameters that are identifiable next to the model.
    pub(crate) new_free: usize,
    pub(crate) stats: Stats,
    /// Held-out errors in fold order (pairs with the current model's).
    pub(crate) errors: Vec<f64>,
    /// Its values beyond [`Plausibility`] in the fit of every fold, when they are: a fit running away (a
    /// block trading with the probe), refused when first scored rather than refitted every step.
    pub(crate) runaway: Option<Implausible>,
    /// Its fit stopped at the iteration limit in every fold, still moving: refused when first scored
    /// ([`unsettled`]).
    pub(crate) unsettled: bool,
    /// Where it runs beyond its size: what the first fold's fit traded it with.
    pub(crate) trade: Option<Trade>,
    /// For a runaway: the fold whose fit its refusal quotes (the first holding its values) — a fit the
    /// bounds may have stopped, run to its end only if the refusal is reported ([`requote`]).
    pub(crate) quoted_fold: Option<usize>,
}

/// A refusal whose value comes from a fold fit the plausibility bounds may have stopped
/// ([`GIVE_UP_AFTER`]): the model it was scored in and the fold, to run that fit to its end should the
/// refusal be reported ([`requote`]).
#[derive(Clone, Debug)]
pub(crate) struct StoppedQuote {
    /// The refusal as made.
    pub(crate) refusal: Refusal,
    /// The model the candidate was scored in, the candidate last.
    pub(crate) with: Vec<Effect>,
    /// The selection's fold whose fit the refusal quotes.
    pub(crate) fold: usize,
}

/// What scoring a candidate found.
pub(crate) enum Scored {
    /// Scored on the folds.
    Candidate(Box<Candidate>),
    /// It adds nothing identifiable to the model (the reason names the block a parameter duplicates).
    AddsNothing(String),
    /// Not fitted: its forecast on every fold is beyond the plausible, why ([`crate::linearised`]).
    /// With what the forecast traded a value beyond its size, where it did.
    ForecastBeyond(Implausible, Option<Trade>),
}

/// An effect's step in the additive table: the selection's held-out RMS before and after it joined
/// (`before` none for an effect that joined as part of a replacement, beside the block it replaced).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Step {
    pub(crate) effect: Effect,
    pub(crate) before_mm: Option<f64>,
    pub(crate) after_mm: f64,
    /// The phase it joined in.
    pub(crate) joined: Joined,
}

/// The phase an effect joined the model in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Joined {
    /// A forward step, passing the gate on its own.
    Forward,
    /// Parsimony: beside others, in the place of a larger block that contains it.
    Replacing { larger: Effect },
    /// The completion for use, with the other rows it completed.
    Completion,
}

impl Joined {
    /// How it joined, in words, for the report.
    pub(crate) fn describe(self) -> String {
        match self {
            Joined::Forward => "forward step".into(),
            Joined::Replacing { larger } => format!("replacing {}", larger.label()),
            Joined::Completion => "completion for use".into(),
        }
    }
}

/// Where the selection stands between phases.
pub(crate) struct Selection {
    /// The model: the always-estimated blocks first, then the chosen effects.
    pub(crate) effects: Vec<Effect>,
    /// How many of `effects` are always estimated.
    pub(crate) always: usize,
    /// The model's held-out statistics and errors on the selection's folds.
    pub(crate) current: Stats,
    pub(crate) errors: Vec<f64>,
    /// Held-out RMS before and after each chosen effect joined.
    pub(crate) steps: Vec<Step>,
    pub(crate) additive: Vec<TableRow>,
    pub(crate) bic: Vec<f64>,
    /// The model's parameters fitted on all measurements (where the forward screen linearises).
    pub(crate) theta: Vec<f64>,
    /// Candidates that add nothing identifiable.
    pub(crate) skipped: Vec<Skipped>,
    /// Candidates refused by eligibility or plausibility.
    pub(crate) refused: Vec<Refusal>,
    /// The refusals that quote a fold fit the bounds may have stopped ([`requote`]).
    pub(crate) stopped_quotes: Vec<StoppedQuote>,
    /// The prior's strength the model is fitted with (rows of data per parameter; 0: none —
    /// [`crate::shrinkage`]).
    pub(crate) shrinkage: f64,
    /// The completed model the completion judged and did not take (the selected one was significantly
    /// better on the selection's folds): the fallback where the nested validation cannot tell the two
    /// apart.
    pub(crate) fallback: Option<Completed>,
}

/// A completed model ([`crate::completion`]): the chosen effects and the rows that join them, the prior's
/// strength, its held-out statistics and errors on the selection's folds.
#[derive(Clone, Debug)]
pub(crate) struct Completed {
    pub(crate) effects: Vec<Effect>,
    pub(crate) lambda: f64,
    pub(crate) stats: Stats,
    pub(crate) errors: Vec<f64>,
    pub(crate) rows: Vec<Effect>,
}

impl Selection {
    /// `c` joins the model (fitted `theta` on all data, information criterion `bic`), a row of the
    /// additive table saying so.
    pub(crate) fn accept(&mut self, c: &Candidate, bic: f64, theta: Vec<f64>, row: String) {
        self.theta = theta;
        self.steps.push(Step {
            effect: c.effect,
            before_mm: Some(self.current.heldout_rms_mm),
            after_mm: c.stats.heldout_rms_mm,
            joined: Joined::Forward,
        });
        self.effects.push(c.effect);
        self.current = c.stats;
        self.errors = c.errors.clone();
        self.additive.push(TableRow { model: row, stats: c.stats });
        self.bic.push(bic);
    }

    /// Replaces the model by `effects` (scored `stats`, `errors` by least squares: a prior, if any, is
    /// set after), saying why in the additive table.
    pub(crate) fn replace(&mut self, effects: Vec<Effect>, stats: Stats, errors: Vec<f64>, row: String) {
        self.effects = effects;
        self.shrinkage = 0.0;
        self.current = stats;
        self.errors = errors;
        self.additive.push(TableRow { model: row, stats });
    }

    /// The chosen effects (after the always-estimated blocks).
    pub(crate) fn chosen(&self) -> &[Effect] {
        &self.effects[self.always..]
    }

    /// Records that `c` adds nothing identifiable, once per candidate.
    pub(crate) fn skip(&mut self, c: Effect, reason: String) {
        if c.is_reported() && !self.skipped.iter().any(|s| s.effect == c.label()) {
            self.skipped.push(Skipped { effect: c.label(), reason });
        }
    }
}

/// The accepted steps of a candidate's fold fit before its values beyond the plausibility bounds stop it
/// ([`score`]). Measured (issue #49) over the diagnosis test suite and the real UR10 (2,876 fold fits
/// whose values passed a bound at some step): the 83 that came back within the bounds by the end had
/// passed them at their first or second step (a cold start's first steps overshoot while the frames
/// settle); of the ~1,000 that passed at the third step or later, none came back — a candidate trading
/// with another block (the UR10's `link_deviation[6]` against the probe) walks out along a flat valley,
/// 20 to 70 steps in, until the iteration limit. Five leaves a margin of three steps. Surveyed again under
/// Nielsen's damping (issue #60; UR10 C + B, the WAM grid → random, Rokae 6-D: ~1,250 watched fits run to
/// their end under each rule): none came back within its bounds after passing them. A fit stopped here
/// has not reached its end: a refusal quotes the fit run to its end ([`requote`]).
pub(crate) const GIVE_UP_AFTER: usize = 5;

/// Scores `c` added to `effects` on the selection's folds.
/// Every fold's fit starts cold, at the initial values: warm starts from the current model's fold fits
/// were tried (issue #23) and changed the UR10's choice (B 0.457 → 0.569 mm) while running slower —
/// nearly dependent parameters leave flat valleys where the stopping rule halts elsewhere.
pub(crate) fn score(
    scorer: &Scorer<'_>,
    effects: &[Effect],
    c: Effect,
    plausibility: &Plausibility,
) -> Result<Scored, DiagnoseError> {
    let addition = scorer.new_free(effects, c)?;
    if addition.new_free == 0 {
        return Ok(Scored::AddsNothing(nothing_added(&addition)));
    }
    let mut with = effects.to_vec();
    with.push(c);
    let o: usize = effects.iter().map(Effect::len).sum();
    let values = move |t: &[f64]| t.len() >= o + c.len();
    // A fold's fit stops once the candidate's values are beyond the bounds (from its `GIVE_UP_AFTER`-th
    // step on): it is refused where every fold's fit ends there, and where one does not, the stopped
    // folds are fitted to the end.
    let bounds = (scorer.scale.clone(), *plausibility);
    let give_up = GiveUp {
        after_steps: GIVE_UP_AFTER,
        test: Arc::new(move |_, t: &[f64]| {
            values(t) && implausible(&bounds.0, &t[o..o + c.len()], c, &bounds.1).is_some()
        }),
    };
    let (mut held, _) = scorer.heldout_fits_unless(&with, &scorer.folds, &give_up)?;
    let (mut runaway, mut trade) = runaway_and_trade(scorer, &with, &held, plausibility)?;
    if trade.as_ref().is_some_and(Trade::stands) {
        // The fits stopped at a value the poses show, traded with no block: fitted to their end, and
        // judged there.
        held = scorer.heldout_fits(&with, &scorer.folds)?;
        (runaway, trade) = runaway_and_trade(scorer, &with, &held, plausibility)?;
        if trade.as_ref().is_some_and(Trade::stands) {
            runaway = None;
        }
    }
    let unsettled = held.thetas.iter().zip(&held.settled).filter(|(t, _)| !t.is_empty()).all(|(_, s)| !s);
    let (runaway, quoted_fold) = runaway.map_or((None, None), |(r, fold)| (Some(r), Some(fold)));
    Ok(Scored::Candidate(Box::new(Candidate {
        effect: c,
        new_free: addition.new_free,
        stats: held.stats,
        errors: held.errors,
        runaway,
        unsettled,
        trade,
        quoted_fold,
    })))
}

/// A candidate's value beyond the bounds in every fold's fit, and the first fold whose fit holds it.
type Runaway = (Implausible, usize);

/// The candidate's (the last of `with`) value beyond the bounds in every fold's fit of `held`, if it is,
/// with the first fold whose fit reached one (the fit a refusal quotes), and, for a value beyond its
/// size, what it traded with in that fit.
fn runaway_and_trade(
    scorer: &Scorer<'_>,
    with: &[Effect],
    held: &HeldOut,
    plausibility: &Plausibility,
) -> Result<(Option<Runaway>, Option<Trade>), DiagnoseError> {
    let Some((&c, effects)) = with.split_last() else { return Ok((None, None)) };
    let o: usize = effects.iter().map(Effect::len).sum();
    let values = |t: &[f64]| t.len() >= o + c.len();
    let reasons: Vec<Option<Implausible>> = held
        .thetas
        .iter()
        .filter(|t| values(t))
        .map(|t| implausible(&scorer.scale, &t[o..o + c.len()], c, plausibility))
        .collect();
    let first = held.thetas.iter().position(|t| values(t));
    let runaway = match first {
        Some(fold) if reasons.iter().all(Option::is_some) => reasons.into_iter().flatten().next().map(|r| (r, fold)),
        _ => None,
    };
    let traded_in = runaway.as_ref().filter(|(r, _)| r.excess().is_some()).and_then(|&(_, f)| {
        let (train, _) = scorer.folds.get(f)?;
        Some((train, held.thetas.get(f)?))
    });
    let trade = match traded_in {
        Some((train, theta)) => {
            let model = scorer.model(with, train)?;
            scorer.traded_with(&model, theta, train, with.len() - 1)?
        }
        None => None,
    };
    Ok((runaway, trade))
}

/// The reported refusals that quote a fold fit the plausibility bounds may have stopped, each quoting
/// that fit run to its end instead: a fit stopped at its [`GIVE_UP_AFTER`]-th step holds the value it
/// had reached by then, which says where it was walking, not where it ends (a 40 mm row stopped at 33 mm
/// under a damping that lowers slowly). Run once, for the report, and only for the refusals it holds: a
/// runaway's fit walks to the iteration limit, which is why scoring stops it. The decision stands — the
/// stop rule was surveyed with every watched fit run to its end and none came back within its bounds;
/// should one, its refusal keeps the stopped value.
pub(crate) fn requote(
    scorer: &Scorer<'_>,
    sel: &mut Selection,
    plausibility: &Plausibility,
) -> Result<(), DiagnoseError> {
    let quotes = std::mem::take(&mut sel.stopped_quotes);
    for r in sel.refused.iter_mut() {
        let Some(q) = quotes.iter().rev().find(|q| q.refusal.effect == r.effect) else { continue };
        let (Some((&c, effects)), Some((train, _))) = (q.with.split_last(), scorer.folds.get(q.fold)) else {
            continue;
        };
        if q.refusal != *r {
            continue;
        }
        let o: usize = effects.iter().map(Effect::len).sum();
        let (model, fit) = scorer.fit_shrunk(&q.with, train, 0.0)?;
        let Some(why) = fit.theta.get(o..o + c.len()).and_then(|v| implausible(&scorer.scale, v, c, plausibility))
        else {
            continue;
        };
        let trade = match why.excess() {
            Some(_) => scorer.traded_with(&model, &fit.theta, train, q.with.len() - 1)?,
            None => None,
        };
        *r = why.refused_trading(c, Judged::FittedOnEveryFold, trade.as_ref());
    }
    Ok(())
}

/// Why a candidate with no identifiable parameter beside the model adds nothing: the block its first
/// parameter duplicates.
fn nothing_added(addition: &Addition) -> String {
    addition.fixed.first().map_or_else(|| "adds nothing identifiable".to_string(), |f| f.reason.clone())
}

/// Why `c` adds nothing identifiable beside `effects`, when it does not: what [`score`] finds before
/// any fit, for a candidate the round does not fit ([`crate::linearised`]).
pub(crate) fn adds_nothing(
    scorer: &Scorer<'_>,
    effects: &[Effect],
    c: Effect,
) -> Result<Option<String>, DiagnoseError> {
    let addition = scorer.new_free(effects, c)?;
    Ok((addition.new_free == 0).then(|| nothing_added(&addition)))
}

/// `effects` without its `k`-th (the model a removal step scores).
pub(crate) fn without(effects: &[Effect], k: usize) -> Vec<Effect> {
    effects.iter().enumerate().filter(|(i, _)| *i != k).map(|(_, e)| *e).collect()
}

/// The refusal of a candidate whose fit does not settle beside the model: in every fold it stopped at the
/// iteration limit with each step still moving its parameters by more than a tenth of their standard
/// deviations — a direction the poses barely determine, walked along (the real UR10's wrist row against
/// the probe on the 11,911 poses of series A: within its plausible bounds after a hundred steps, in
/// every fold of every forward step, never settling, never chosen — issue #49). Its held-out score is
/// that of wherever the limit stopped it, which says nothing of the effect; it would be scored so again
/// at every step.
pub(crate) fn unsettled(effect: Effect) -> Refusal {
    Refusal {
        effect: effect.label(),
        reason: format!(
            "its fit does not settle beside the model: in the fit of every fold it still moved by more than a tenth of its standard deviations per step at the {MAX_ITERATIONS}-iteration limit — a direction these poses barely determine, traded with another block"
        ),
        remedy: "measure poses that move it apart from the blocks it trades with (other configurations of the joints around it), or leave it to the completion, which fits it beside the whole geometry with a prior".into(),
    }
}
