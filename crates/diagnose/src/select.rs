//! The selection, as phases over one state ([`Selection`]):
//!
//! 1. **candidates** — the catalogue for this robot and these data ([`candidates`]);
//! 2. **eligibility** — what the data cannot pin down is refused before anything is scored
//!    ([`crate::eligibility`]);
//! 3. **forward** — the candidate with the lowest held-out error joins while it beats the current
//!    model by more than the gate ([`significantly_better`], over blocks of neighbouring poses), the
//!    smallest block within [`Config::parsimony`] of the best gain preferred, its fitted values within
//!    the stated physical bounds ([`Plausibility`]) ([`forward`]);
//! 4. **backward** — every effect whose removal the gate does not reject leaves again, the least useful
//!    first ([`backward`]);
//! 5. **parsimony** — an exponential drift not better than its linear twin becomes linear; each block is
//!    replaced by the smallest combination of smaller catalogue blocks it contains (a link row by the
//!    offsets of two parallel joints) when that is not significantly worse ([`parsimony`]);
//! 6. **report** — the final model on all data, its tables and relations ([`report`]).

use rayon::prelude::*;
use serde::Serialize;
use thermokin_chain::Robot;
use thermokin_io::units;

use crate::eligibility::Refusal;
use crate::fit::{Fit, fit, observability, residuals};
use crate::ladder::{Config, FoldGrouping, FrameMode, ToolMode};
use crate::model::{DriftShape, Effect, JointIndex, Model};
use crate::report::{
    EffectReport, FittedFrames, Identifiability, ParameterValue, PoseReport, Report, Stats, TableRow, breakdown,
};
use crate::validation::{Ctx, Relation, significantly_better};
use crate::{Dataset, DiagnoseError};

/// Bounds beyond which a fitted value is not a property of a working robot but a fit running away
/// (trading against another block, or chasing a few poses): a candidate whose fitted parameters exceed
/// them on all data is refused as implausible, with the values. Industrial arms are built and
/// calibrated to tenths of a millimetre and hundredths of a degree; these bounds are ten to a hundred
/// times that, so that no real deviation is refused.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Plausibility {
    /// Largest translation of a joint row's deviation or drift, mm. Default 5.
    pub link_translation_mm: f64,
    /// Largest rotation of a joint row's deviation or drift, degrees. Default 1.
    pub link_rotation_deg: f64,
    /// Largest zero offset, degrees. Default 5.
    pub joint_offset_deg: f64,
    /// Largest gear-ratio error (dimensionless). Default 0.01 (1 %).
    pub joint_scale: f64,
    /// Largest amplitude of a cyclic encoder term, degrees. Default 1.
    pub periodic_deg: f64,
    /// Largest deflection of a compliance at the joint's largest gravity torque, degrees. Default 1.
    pub compliance_deflection_deg: f64,
}

impl Default for Plausibility {
    fn default() -> Self {
        Self {
            link_translation_mm: 5.0,
            link_rotation_deg: 1.0,
            joint_offset_deg: 5.0,
            joint_scale: 0.01,
            periodic_deg: 1.0,
            compliance_deflection_deg: 1.0,
        }
    }
}

/// The catalogue's candidates for this robot and data set, in catalogue order.
pub(crate) fn candidates(robot: &Robot, data: &Dataset, config: &Config) -> Result<Vec<Effect>, DiagnoseError> {
    let joints =
        (0..robot.chain().dof()).map(|j| JointIndex::of(robot, j)).collect::<Result<Vec<_>, DiagnoseError>>()?;
    let mut c = Vec::new();
    if config.frame == FrameMode::Base {
        c.push(Effect::BaseFrame);
    }
    if config.tool == ToolMode::Known {
        c.push(Effect::ToolFrame);
    }
    c.extend(joints.iter().map(|&j| Effect::JointOffset(j)));
    c.extend(joints.iter().map(|&j| Effect::LinkDeviation(j)));
    for &j in &joints {
        let carries_mass = robot.masses().iter().skip(j.index()).any(Option::is_some);
        if carries_mass {
            c.push(Effect::JointCompliance(j));
        }
    }
    // Scale and cyclic errors of revolute joints (a gear ratio, an encoder's eccentricity).
    for &j in &joints {
        if robot.chain().joints()[j.index()].kind == thermokin_chain::JointKind::Revolute {
            c.push(Effect::JointScale(j));
            c.push(Effect::Periodic(j));
        }
    }
    if data.time_span() > 0.0 {
        for &j in &joints {
            c.push(Effect::ThermalDrift(j, DriftShape::Linear));
            c.push(Effect::ThermalDrift(j, DriftShape::Exponential));
        }
    }
    if !data.temperature_names.is_empty() {
        c.extend(joints.iter().map(|&j| Effect::ThermalDrift(j, DriftShape::Temperature)));
    }
    Ok(c)
}

/// The blocks every model estimates (never reported as causes): the tracker registration and an unknown
/// tool point.
pub(crate) fn always_estimated(config: &Config, data: &Dataset) -> Vec<Effect> {
    let mut effects = Vec::new();
    if config.frame == FrameMode::Tracker {
        effects.push(Effect::Registration);
    }
    if config.tool == ToolMode::Unknown {
        effects.push(Effect::ToolPoint);
        // An unknown 6-D probe: its rotation is as unknown as its point.
        if data.has_orientation() && config.orientation_lever_mm > 0.0 {
            effects.push(Effect::ToolRotation);
        }
    }
    effects
}

/// A candidate scored on the selection's folds.
#[derive(Clone, Debug)]
struct Candidate {
    effect: Effect,
    /// Its parameters that are identifiable next to the model.
    new_free: usize,
    stats: Stats,
    /// Held-out errors in fold order (pairs with the current model's).
    errors: Vec<f64>,
    /// Why its values are beyond [`Plausibility`] in the fit of every fold, when they are: a fit running
    /// away (a block trading with the probe), refused when first scored rather than refitted every step.
    runaway: Option<String>,
}

/// Where the selection stands between phases.
pub(crate) struct Selection {
    /// The model: the always-estimated blocks first, then the chosen effects.
    pub(crate) effects: Vec<Effect>,
    /// How many of `effects` are always estimated.
    always: usize,
    /// The model's held-out statistics and errors on the selection's folds.
    current: Stats,
    errors: Vec<f64>,
    /// Held-out RMS before and after each chosen effect joined (by effect).
    steps: Vec<(Effect, f64, f64)>,
    additive: Vec<TableRow>,
    bic: Vec<f64>,
    /// The model's parameters fitted on all measurements (where the forward screen linearises).
    theta: Vec<f64>,

    /// Candidates that add nothing identifiable: (label, reason).
    skipped: Vec<(String, String)>,
    /// Candidates refused by eligibility or plausibility.
    refused: Vec<Refusal>,
}

impl Selection {
    fn accept(&mut self, c: &Candidate, bic: f64, theta: Vec<f64>, row: String) {
        self.theta = theta;
        self.steps.push((c.effect, self.current.heldout_rms_mm, c.stats.heldout_rms_mm));
        self.effects.push(c.effect);
        self.current = c.stats;
        self.errors = c.errors.clone();
        self.additive.push(TableRow { model: row, stats: c.stats });
        self.bic.push(bic);
    }

    /// Replaces the model by `effects` (scored `stats`, `errors`), saying why in the additive table.
    fn replace(&mut self, effects: Vec<Effect>, stats: Stats, errors: Vec<f64>, row: String) {
        self.effects = effects;
        self.current = stats;
        self.errors = errors;
        self.additive.push(TableRow { model: row, stats });
    }

    fn chosen(&self) -> &[Effect] {
        &self.effects[self.always..]
    }
}

/// The ladder on `data`: candidates chosen by cross-validation, the final model fitted on all of it. The
/// report's held-out figures here are the selection's own (optimistic) scores.
pub(crate) fn select(robot: &Robot, data: &Dataset, config: &Config) -> Result<(Report, Vec<Effect>), DiagnoseError> {
    let needed = 2 * config.folds.max(2);
    if data.len() < needed {
        return Err(DiagnoseError::TooFewMeasurements { count: data.len(), folds: config.folds, needed });
    }
    let ctx = Ctx::new(robot, data, config);
    let always = always_estimated(config, data);
    // 1–2. Candidates and eligibility.
    let catalogue = candidates(robot, data, config)?;
    let (eligible, refused) = crate::eligibility::check(&ctx, &always, &catalogue, &config.eligibility)?;
    let (nominal, nominal_errors) = ctx.heldout_errors(&always, &ctx.folds)?;
    let (_, nominal_fit) = ctx.full_fit(&always)?;
    let mut sel = Selection {
        effects: always.clone(),
        always: always.len(),
        current: nominal,
        errors: nominal_errors,
        steps: Vec::new(),
        additive: vec![TableRow { model: "nominal".into(), stats: nominal }],
        bic: vec![ctx.bic_of(&nominal_fit)],
        theta: nominal_fit.theta,
        skipped: Vec::new(),
        refused,
    };
    // 3–5.
    forward(&ctx, config, &mut sel, eligible.clone())?;
    backward(&ctx, config, &mut sel)?;
    parsimony(&ctx, config, &mut sel, &eligible)?;
    // 6.
    report(&ctx, config, sel, &catalogue)
}

/// Scores `c` added to `effects` on the selection's folds; `Err(reason)` when it adds nothing
/// identifiable (the reason names the block a parameter duplicates).
/// Every fold's fit starts cold, at the initial values: warm starts from the current model's fold fits
/// were tried (issue #23) and changed the UR10's choice (B 0.457 → 0.569 mm) while running slower —
/// nearly dependent parameters leave flat valleys where the stopping rule halts elsewhere.
fn score(
    ctx: &Ctx<'_>,
    effects: &[Effect],
    c: Effect,
    plausibility: &Plausibility,
) -> Result<Result<Candidate, String>, DiagnoseError> {
    let (new_free, fixed) = ctx.new_free(effects, c)?;
    if new_free == 0 {
        return Ok(Err(fixed.first().map_or_else(|| "adds nothing identifiable".to_string(), |f| f.reason.clone())));
    }
    let mut with = effects.to_vec();
    with.push(c);
    let (stats, errors, thetas) = ctx.heldout_fits(&with, &ctx.folds)?;
    let o: usize = effects.iter().map(Effect::len).sum();
    let reasons: Vec<Option<String>> = thetas
        .iter()
        .filter(|t| t.len() >= o + c.len())
        .map(|t| implausible_values(ctx, &t[o..o + c.len()], c, plausibility))
        .collect();
    let runaway = if !reasons.is_empty() && reasons.iter().all(Option::is_some) {
        reasons.into_iter().flatten().next().map(|r| format!("{r} in the fit of every fold"))
    } else {
        None
    };
    Ok(Ok(Candidate { effect: c, new_free, stats, errors, runaway }))
}

// Long on purpose (~130 lines): one forward step is screen → score → gate → parsimony → plausibility →
// information criterion over the same scored candidates; its order is the selection's rule, read in one
// place.
/// Phase 3: forward steps. Each round scores every remaining candidate (in parallel); an exponential
/// drift refines the linear one of its joint and is scored only where the linear drift already earns
/// half the best gain (it costs a model per measurement and a nonlinear τ).
fn forward(ctx: &Ctx<'_>, config: &Config, sel: &mut Selection, mut pool: Vec<Effect>) -> Result<(), DiagnoseError> {
    let gate = config.gate_standard_errors;
    while sel.chosen().len() < config.max_effects && !pool.is_empty() {
        let is_exp = |c: &Effect| matches!(c, Effect::ThermalDrift(_, DriftShape::Exponential));
        let linear: Vec<Effect> = pool.iter().copied().filter(|c| !is_exp(c)).collect();
        let effects = sel.effects.clone();
        // Score before you fit: the candidates ranked by a linearised step, the shortlist fitted in full.
        let runs_away = |c: Effect, v: &[f64]| implausible_values(ctx, v, c, &config.plausibility);
        let screened = crate::screen::shortlist(ctx, &effects, &sel.theta, &linear, config.screen, &runs_away)?;
        for (c, reason) in screened.runaway {
            sel.refused.push(Refusal {
                effect: c.label(),
                reason,
                remedy: "check the robot description (masses, link lengths) and the units of the data".into(),
            });
            pool.retain(|p| *p != c);
        }
        let first = screened.keep;
        let mut scored: Vec<(Effect, Result<Candidate, String>)> = first
            .par_iter()
            .map(|&c| Ok((c, score(ctx, &effects, c, &config.plausibility)?)))
            .collect::<Result<_, DiagnoseError>>()?;
        let gain = |s: &Result<Candidate, String>| {
            s.as_ref().ok().map(|s| sel.current.heldout_rms_mm - s.stats.heldout_rms_mm)
        };
        let best_gain = scored.iter().filter_map(|(_, s)| gain(s)).fold(0.0, f64::max);
        let linear_gain = |j: Option<JointIndex>| {
            scored
                .iter()
                .filter(|(c, _)| matches!(c, Effect::ThermalDrift(_, DriftShape::Linear)) && c.joint() == j)
                .filter_map(|(_, s)| gain(s))
                .fold(f64::NEG_INFINITY, f64::max)
        };
        let second: Vec<Effect> = pool
            .iter()
            .copied()
            .filter(|c| is_exp(c) && best_gain > 0.0 && linear_gain(c.joint()) >= 0.5 * best_gain)
            .collect();
        let more: Vec<(Effect, Result<Candidate, String>)> = second
            .par_iter()
            .map(|&c| Ok((c, score(ctx, &effects, c, &config.plausibility)?)))
            .collect::<Result<_, DiagnoseError>>()?;
        scored.extend(more);
        let mut still: Vec<Effect> = pool
            .iter()
            .copied()
            .filter(|c| (is_exp(c) && !second.contains(c)) || (!is_exp(c) && !first.contains(c)))
            .collect();
        let mut results: Vec<Candidate> = Vec::new();
        for (c, s) in scored {
            match s {
                Err(reason) => {
                    if c.is_reported() && !sel.skipped.iter().any(|(l, _)| *l == c.label()) {
                        sel.skipped.push((c.label(), reason));
                    }
                }
                Ok(s) => match &s.runaway {
                    Some(reason) => sel.refused.push(Refusal {
                        effect: c.label(),
                        reason: reason.clone(),
                        remedy: "check the robot description (masses, link lengths) and the units of the data".into(),
                    }),
                    None => {
                        still.push(c);
                        results.push(s);
                    }
                },
            }
        }
        pool = still;
        let Some(best) = results.iter().min_by(|a, b| a.stats.heldout_rms_mm.total_cmp(&b.stats.heldout_rms_mm)) else {
            break;
        };
        if !significantly_better(&sel.errors, &best.errors, gate, &ctx.blocks) {
            break;
        }
        let gain = sel.current.heldout_rms_mm - best.stats.heldout_rms_mm;
        // Parsimony within the step: the smallest block within `parsimony` of the best gain, itself
        // significant; ties between blocks of one size go to the conventional one (base_frame,
        // tool_frame, joint_offset), then the lowest error.
        let mut eligible: Vec<&Candidate> = results
            .iter()
            .filter(|r| sel.current.heldout_rms_mm - r.stats.heldout_rms_mm >= config.parsimony * gain)
            .filter(|r| significantly_better(&sel.errors, &r.errors, gate, &ctx.blocks))
            .collect();
        let conventional = |e: &Effect| matches!(e, Effect::BaseFrame | Effect::ToolFrame | Effect::JointOffset(_));
        eligible.sort_by(|a, b| {
            a.new_free
                .cmp(&b.new_free)
                .then(conventional(&b.effect).cmp(&conventional(&a.effect)))
                .then(a.stats.heldout_rms_mm.total_cmp(&b.stats.heldout_rms_mm))
        });
        let mut chosen = None;
        let mut forward_before: Option<f64> = None;
        for cand in eligible {
            let mut with = sel.effects.clone();
            with.push(cand.effect);
            if cand.effect.is_time_dependent() {
                // The current model's forward-chained error, once per step however many drifts are tried.
                let before = match forward_before {
                    Some(b) => b,
                    None => *forward_before.insert(ctx.heldout(&sel.effects, &ctx.forward)?.heldout_rms_mm),
                };
                let after = ctx.heldout(&with, &ctx.forward)?;
                if after.heldout_rms_mm >= before {
                    continue;
                }
            }
            // One fit on all data serves the plausibility bounds and the information criterion.
            let (model, full) = ctx.full_fit(&with)?;
            if let Some(reason) = implausible(ctx, &model, &full, cand.effect, &config.plausibility) {
                sel.refused.push(Refusal {
                    effect: cand.effect.label(),
                    reason,
                    remedy: "check the robot description (masses, link lengths) and the units of the data".into(),
                });
                pool.retain(|c| *c != cand.effect);
                continue;
            }
            let b = ctx.bic_of(&full);
            if b >= *sel.bic.last().unwrap_or(&f64::INFINITY) {
                continue;
            }
            chosen = Some((cand.clone(), b, full.theta));
            break;
        }
        let Some((c, b, theta)) = chosen else { break };
        sel.accept(&c, b, theta, format!("+ {}", c.effect.label()));
        pool.retain(|e| *e != c.effect);
    }
    Ok(())
}

/// Why the fitted values of `effect` (the last block of `model`, fitted `f` on all data) are beyond
/// [`Plausibility`]; `None` when they are within.
fn implausible(ctx: &Ctx<'_>, model: &Model, f: &Fit, effect: Effect, p: &Plausibility) -> Option<String> {
    let o = model.offsets()[model.offsets().len() - 1];
    implausible_values(ctx, &f.theta[o..o + effect.len()], effect, p)
}

/// [`implausible`] of an effect's fitted values `v` (internal units).
fn implausible_values(ctx: &Ctx<'_>, v: &[f64], effect: Effect, p: &Plausibility) -> Option<String> {
    let deg = units::degrees;
    let over = |what: &str, value: f64, bound: f64, unit: &str| {
        (value.abs() > bound)
            .then(|| format!("{what} fitted at {value:.4} {unit} (beyond the plausible {bound} {unit})"))
    };
    match effect {
        Effect::LinkDeviation(_) | Effect::ThermalDrift(..) => {
            let t = v[..3].iter().map(|x| x * x).sum::<f64>().sqrt();
            let r = deg(v[3..6].iter().map(|x| x * x).sum::<f64>().sqrt());
            over("its translation", t, p.link_translation_mm, "mm")
                .or_else(|| over("its rotation", r, p.link_rotation_deg, "°"))
        }
        Effect::JointOffset(_) => over("the offset", deg(v[0]), p.joint_offset_deg, "°"),
        Effect::JointScale(_) => over("the scale error", v[0], p.joint_scale, ""),
        Effect::Periodic(_) => {
            let a = v.iter().map(|x| deg(*x).abs()).fold(0.0, f64::max);
            over("a cyclic amplitude", a, p.periodic_deg, "°")
        }
        Effect::JointCompliance(j) => {
            let bound = crate::eligibility::torque_bound(ctx.robot, j.index());
            over("the deflection at the largest gravity torque", deg(v[0] * bound), p.compliance_deflection_deg, "°")
        }
        _ => None,
    }
}

/// Phase 4: backward elimination. While some chosen effect can leave without the gate rejecting the
/// smaller model (the full one is not significantly better held out), the one whose removal leaves the
/// lowest held-out error leaves. An effect chosen early as a stand-in for later ones goes here.
fn backward(ctx: &Ctx<'_>, config: &Config, sel: &mut Selection) -> Result<(), DiagnoseError> {
    loop {
        let without: Vec<(usize, Stats, Vec<f64>)> = (sel.always..sel.effects.len())
            .into_par_iter()
            .map(|k| {
                let rest: Vec<Effect> =
                    sel.effects.iter().enumerate().filter(|(i, _)| *i != k).map(|(_, e)| *e).collect();
                let (s, e) = ctx.heldout_errors(&rest, &ctx.folds)?;
                Ok((k, s, e))
            })
            .collect::<Result<_, DiagnoseError>>()?;
        let removable = without
            .into_iter()
            .filter(|(_, _, e)| !significantly_better(e, &sel.errors, config.gate_standard_errors, &ctx.blocks))
            .min_by(|a, b| a.1.heldout_rms_mm.total_cmp(&b.1.heldout_rms_mm));
        let Some((k, stats, errors)) = removable else { return Ok(()) };
        let gone = sel.effects[k];
        let mut rest = sel.effects.clone();
        rest.remove(k);
        let row = format!("− {} (backward: not significantly better with it)", gone.label());
        sel.replace(rest, stats, errors, row);
    }
}

/// Phase 5: parsimony. An exponential drift not significantly better than its linear twin becomes the
/// linear one; then each chosen block is replaced by the smallest combination (one or two) of eligible
/// smaller catalogue blocks its directions contain on the data (rank test) when the larger is not
/// significantly better held out — the same gate, the other way round. Two offsets of parallel joints
/// inside one link row come out as the two offsets.
fn parsimony(ctx: &Ctx<'_>, config: &Config, sel: &mut Selection, eligible: &[Effect]) -> Result<(), DiagnoseError> {
    let gate = config.gate_standard_errors;
    for k in sel.always..sel.effects.len() {
        if let Effect::ThermalDrift(j, DriftShape::Exponential) = sel.effects[k] {
            let mut swapped = sel.effects.clone();
            swapped[k] = Effect::ThermalDrift(j, DriftShape::Linear);
            let (stats, errors) = ctx.heldout_errors(&swapped, &ctx.folds)?;
            if !significantly_better(&errors, &sel.errors, gate, &ctx.blocks) {
                let row = format!("{} replaces the exponential (not significantly worse)", swapped[k].label());
                sel.replace(swapped, stats, errors, row);
            }
        }
    }
    let mut k = sel.always;
    while k < sel.effects.len() {
        let big = sel.effects[k];
        let mut smaller: Vec<Effect> = Vec::new();
        for &c in eligible.iter().filter(|c| c.len() < big.len() && !sel.effects.contains(c)) {
            if ctx.relations(c, &[big])?.iter().any(|(_, r)| *r == Relation::ContainedIn) {
                smaller.push(c);
            }
        }
        // Combinations of one or two smaller blocks with fewer parameters than the larger, each adding
        // something identifiable to the model without the larger block.
        let rest: Vec<Effect> = sel.effects.iter().enumerate().filter(|(i, _)| *i != k).map(|(_, e)| *e).collect();
        let mut combos: Vec<Vec<Effect>> = smaller.iter().map(|&c| vec![c]).collect();
        for (a, &x) in smaller.iter().enumerate() {
            for &y in &smaller[a + 1..] {
                if x.len() + y.len() < big.len() {
                    combos.push(vec![x, y]);
                }
            }
        }
        let mut best: Option<(usize, Vec<Effect>, Stats, Vec<f64>)> = None;
        for combo in combos {
            let mut with = rest.clone();
            let mut adds = true;
            for &c in &combo {
                adds &= ctx.new_free(&with, c)?.0 > 0;
                with.push(c);
            }
            if !adds {
                continue;
            }
            let (stats, errors) = ctx.heldout_errors(&with, &ctx.folds)?;
            if significantly_better(&errors, &sel.errors, gate, &ctx.blocks) {
                continue; // The larger block is significantly better.
            }
            let size: usize = combo.iter().map(Effect::len).sum();
            let better = match &best {
                None => true,
                Some((s, _, b, _)) => (size, stats.heldout_rms_mm) < (*s, b.heldout_rms_mm),
            };
            if better {
                best = Some((size, combo, stats, errors));
            }
        }
        match best {
            Some((size, combo, stats, errors)) => {
                let mut with = rest;
                with.splice(k..k, combo.iter().copied());
                let names: Vec<String> = combo.iter().map(Effect::label).collect();
                let row = format!(
                    "{} replaces {} (as good held out with {size} parameters instead of {})",
                    names.join(" + "),
                    big.label(),
                    big.len()
                );
                for (s, &c) in sel.steps.iter_mut().filter(|s| s.0 == big).zip(&combo) {
                    s.0 = c;
                }
                for &c in combo.iter().skip(1) {
                    sel.steps.push((c, f64::NAN, stats.heldout_rms_mm));
                }
                sel.replace(with, stats, errors, row);
                k += combo.len();
            }
            None => k += 1,
        }
    }
    Ok(())
}

/// Phase 6: the final model on all data and the report (the selection's own, optimistic scores).
fn report(
    ctx: &Ctx<'_>,
    config: &Config,
    sel: Selection,
    catalogue: &[Effect],
) -> Result<(Report, Vec<Effect>), DiagnoseError> {
    let (robot, data) = (ctx.robot, ctx.data);
    let effects = sel.effects.clone();
    let always = sel.always;
    let (model, final_fit) = ctx.full_fit(&effects)?;
    let all: Vec<usize> = (0..data.len()).collect();
    let (_, jac) = residuals(robot, &model, &final_fit.theta, data, &all, &ctx.pre, true)?;
    let observability = observability(&jac, &final_fit.free);
    let reported: Vec<usize> = (always..effects.len()).collect();
    let without: Vec<Stats> = reported
        .par_iter()
        .map(|&k| {
            let rest: Vec<Effect> = effects.iter().enumerate().filter(|(i, _)| *i != k).map(|(_, e)| *e).collect();
            ctx.heldout(&rest, &ctx.folds)
        })
        .collect::<Result<_, DiagnoseError>>()?;
    let leave_one_out = reported
        .iter()
        .zip(&without)
        .map(|(&k, s)| TableRow { model: format!("all − {}", effects[k].label()), stats: *s })
        .collect();
    let names = model.parameter_names();
    let mut reports: Vec<EffectReport> = reported
        .iter()
        .zip(&without)
        .map(|(&k, w)| -> Result<EffectReport, DiagnoseError> {
            let e = effects[k];
            let o = model.offsets()[k];
            let parameters = (0..e.len())
                .map(|p| {
                    let v = final_fit.theta[o + p];
                    let s = final_fit.std[o + p];
                    let fixed = final_fit.fixed.iter().find(|f| f.parameter == names[o + p]).map(|f| f.reason.clone());
                    let std = (fixed.is_none() && s.is_finite()).then(|| e.to_report_units(p, s).abs());
                    (names[o + p].clone(), ParameterValue { value: e.to_report_units(p, v), std, fixed })
                })
                .collect();
            let relations = ctx.relations(e, catalogue)?;
            let of = |kind: Relation| -> Vec<String> {
                relations.iter().filter(|(_, r)| *r == kind).map(|(b, _)| b.label()).collect()
            };
            let (before, after) = sel.steps.iter().find(|s| s.0 == e).map_or((f64::NAN, f64::NAN), |s| (s.1, s.2));
            Ok(EffectReport {
                effect: e.kind_name().to_string(),
                label: e.label(),
                joints: e.joint().map(|j| vec![j.number()]).unwrap_or_default(),
                heldout_rms_before_mm: before,
                heldout_rms_after_mm: after,
                heldout_rms_without_mm: w.heldout_rms_mm,
                parameters,
                equivalent: of(Relation::Equivalent),
                contained_in: of(Relation::ContainedIn),
                contains: of(Relation::Contains),
            })
        })
        .collect::<Result<Vec<_>, DiagnoseError>>()?;
    // Main cause first: the effect whose removal hurts most.
    reports.sort_by(|a, b| (b.heldout_rms_without_mm).total_cmp(&a.heldout_rms_without_mm));
    let nominal_model = ctx.model(&effects[..always], &all)?;
    let nominal_fit = fit(robot, &nominal_model, data, &all, &ctx.pre)?;
    let (calibrated, left_out) = model.calibrated_chain(robot, &final_fit.theta)?;
    let frames = FittedFrames {
        registration: model.has_registration().then(|| {
            let world_from_base = calibrated.base().pose();
            let t = world_from_base.translation.vector;
            let r = thermokin_chain::xyz_angles_for_output(world_from_base.rotation.to_rotation_matrix().matrix());
            PoseReport { position_mm: [t.x, t.y, t.z], xyz_euler_deg: units::degrees3([r.x, r.y, r.z]) }
        }),
        tool_point_mm: effects.contains(&Effect::ToolPoint).then(|| {
            let t = calibrated.tool().translation + calibrated.tool().error.translation;
            [t.x, t.y, t.z]
        }),
        tool_rotation_deg: effects.contains(&Effect::ToolRotation).then(|| {
            let r = calibrated.tool().error.rotation;
            units::degrees3([r.x, r.y, r.z])
        }),
    };
    // The identified robot carries every chosen effect: the model written is the model scored.
    let identified = model.robot_model(robot, &final_fit.theta, data)?;
    debug_assert!(left_out.iter().all(|e| !e.is_static()));
    // A claim checked, not assumed: the parameters reported and exported are a least-squares minimum only
    // if the final fit ended by its own test.
    let warnings = if final_fit.converged {
        Vec::new()
    } else {
        vec![format!(
            "the final model's fit stopped at its {}-iteration limit before converging: its parameters (and an exported robot) are not at the least-squares minimum",
            crate::fit::MAX_ITERATIONS
        )]
    };
    let report = Report {
        frames,
        warnings,
        verdict: String::new(),
        honest_end: None,
        nominal: sel.additive[0].stats,
        nested: None,
        holdout: None,
        calibrated,
        identified,
        validation: validation_label(data, config),
        orientation_lever_mm: ctx.pre.lever_mm,
        effects: reports,
        additive: sel.additive,
        leave_one_out,
        identifiability: Identifiability {
            observability,
            fixed: final_fit.fixed.clone(),
            skipped_candidates: sel.skipped,
            not_identifiable: sel.refused,
            correlated: final_fit.correlated.clone(),
        },
        residuals_before: breakdown(robot, data, &nominal_model, &nominal_fit.theta, &ctx.pre)?,
        residuals_after: breakdown(robot, data, &model, &final_fit.theta, &ctx.pre)?,
        bic: sel.bic,
    };
    Ok((report, effects))
}

/// Which grouping decided: said in every report.
fn validation_label(data: &Dataset, config: &Config) -> String {
    match config.folds_by {
        FoldGrouping::WorkspaceRegion => "leave one workspace region out (4 quadrants of reach × height)".to_string(),
        FoldGrouping::JointConfiguration => "leave one arm configuration out (elbow × wrist)".to_string(),
        _ if data.time_span() > 0.0 => format!(
            "{}-fold cross-validation, folds grouped in time (4 chunks per fold); time-dependent effects also forward-chained",
            config.folds
        ),
        FoldGrouping::Neighbourhood if data.len() >= 40 * config.folds.max(2) => format!(
            "{}-fold cross-validation by neighbourhood: {} blocks of neighbouring arm configurations (k-means in joint space), a test pose's block never in its training part; the gate's standard error over blocks",
            config.folds,
            4 * config.folds
        ),
        FoldGrouping::Time | FoldGrouping::Neighbourhood => {
            format!("{}-fold cross-validation (seeded shuffle of single poses)", config.folds)
        }
    }
}
