//! The diagnosis: where the residuals lie, which effect explains them (a ladder of candidates judged on
//! held-out data), how far the gap shrinks (the additive and leave-one-out tables, in the DLR format).

use std::collections::BTreeMap;

use nalgebra::Isometry3;
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use crate::fit::{
    FixedParameter, Observability, fit, has_registration, identifiable, initial_registration, observability, residuals,
};
use crate::model::{Base, DriftShape, Effect, EffectKind, Model, prepare};
use crate::{Dataset, DiagnoseError};

/// In which frame the measurements are.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum FrameMode {
    /// The robot's base frame: a base misalignment is a candidate effect.
    Base,
    /// A tracker frame: an unknown registration is always estimated and never reported.
    Tracker,
}

/// Whether the tool point is known.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum ToolMode {
    /// The robot description's tool: a tool error is a candidate effect.
    Known,
    /// Unknown: the tool point is always estimated and never reported.
    Unknown,
}

/// Diagnosis settings.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Config {
    /// Cross-validation folds.
    pub folds: usize,
    /// Measurement frame.
    pub frame: FrameMode,
    /// Tool point.
    pub tool: ToolMode,
    /// A candidate must lower the held-out RMS by at least this fraction.
    pub min_improvement: f64,
    /// Among candidates within this fraction of the best improvement, the smallest block wins.
    pub parsimony: f64,
    /// Most effects added.
    pub max_effects: usize,
    /// Seed of the fold assignment.
    pub seed: u64,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            folds: 5,
            frame: FrameMode::Base,
            tool: ToolMode::Known,
            min_improvement: 0.02,
            parsimony: 0.9,
            max_effects: 8,
            seed: 0xd1a6,
        }
    }
}

/// Held-out error statistics of the 3-D position residual, mm.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Stats {
    /// Mean |e|.
    pub heldout_mean_mm: f64,
    /// RMS |e|.
    pub heldout_rms_mm: f64,
    /// Max |e|.
    pub heldout_max_mm: f64,
    /// Held-out residuals counted.
    pub heldout_count: usize,
}

impl Stats {
    fn of(norms: &[f64]) -> Stats {
        let n = norms.len().max(1) as f64;
        Stats {
            heldout_mean_mm: norms.iter().sum::<f64>() / n,
            heldout_rms_mm: (norms.iter().map(|x| x * x).sum::<f64>() / n).sqrt(),
            heldout_max_mm: norms.iter().copied().fold(0.0, f64::max),
            heldout_count: norms.len(),
        }
    }
}

/// A row of the additive or leave-one-out table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TableRow {
    /// The model of this row, e.g. `nominal + joint_offset[2]`.
    pub model: String,
    /// Its held-out errors.
    #[serde(flatten)]
    pub stats: Stats,
}

/// A fitted parameter in report units (mm, degrees, minutes, degrees per N·m).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ParameterValue {
    /// Value.
    pub value: f64,
    /// One standard deviation (NaN when fixed as unidentifiable).
    pub std: f64,
}

/// One effect of the final model.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EffectReport {
    /// The effect's kind name (`joint_offset`, …).
    pub effect: String,
    /// Label with joint and shape (`joint_offset[2]`).
    pub label: String,
    /// Joints, 1-based.
    pub joints: Vec<usize>,
    /// Held-out RMS before this effect was added, mm.
    pub heldout_rms_before_mm: f64,
    /// Held-out RMS after it was added, mm.
    pub heldout_rms_after_mm: f64,
    /// Held-out RMS of the final model without this effect, mm (the leave-one-out table).
    pub heldout_rms_without_mm: f64,
    /// Fitted parameters.
    pub parameters: BTreeMap<String, ParameterValue>,
    /// Blocks that span the same directions.
    pub equivalent: Vec<String>,
}

/// Identifiability of the final model.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Identifiability {
    /// Observability indices and condition number.
    pub observability: Option<Observability>,
    /// Parameters fixed as unidentifiable, with the reason.
    pub fixed: Vec<FixedParameter>,
    /// Candidates skipped because they add nothing identifiable to the model: (candidate, reason).
    pub skipped_candidates: Vec<(String, String)>,
}

/// Residual RMS broken down by groups of measurements, mm.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Breakdown {
    /// Per joint: RMS in the four quartiles of that joint's angle.
    pub by_joint: Vec<[f64; 4]>,
    /// Workspace: near-low, near-high, far-low, far-high (reach and height against their medians).
    pub by_workspace_region: [f64; 4],
    /// Joint space: elbow (joint 3 below/above its median) × wrist (joint 5 negative/positive).
    pub by_joint_space_region: [f64; 4],
    /// Time quartiles (empty without a time column).
    pub by_time: Vec<f64>,
    /// |residual| of every measurement, in file order (model fitted on all data), mm.
    pub per_measurement_mm: Vec<f64>,
}

/// The diagnosis.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// The nominal model (with the always-estimated blocks) on held-out data.
    pub nominal: Stats,
    /// How held-out errors were obtained.
    pub validation: String,
    /// Effects of the final model, main cause first.
    pub effects: Vec<EffectReport>,
    /// Held-out errors as effects are added, in the order chosen.
    pub additive: Vec<TableRow>,
    /// Held-out errors of the final model with each effect left out.
    pub leave_one_out: Vec<TableRow>,
    /// Observability and fixed parameters of the final model.
    pub identifiability: Identifiability,
    /// Where the nominal model's residuals lie.
    pub residuals_before: Breakdown,
    /// Where the final model's residuals lie.
    pub residuals_after: Breakdown,
    /// Bayesian information criterion of each model in the additive table (full-data fits).
    pub bic: Vec<f64>,
}

type Pre = (Vec<Vec<f64>>, Vec<f64>);
/// A scored candidate: the effect, its newly identifiable parameters, its held-out statistics.
type Scored = Result<Option<(Effect, usize, Stats)>, DiagnoseError>;
type Folds = Vec<(Vec<usize>, Vec<usize>)>;

/// Folds grouped in time when the data span time — the time-ordered measurements cut into chunks, fold
/// `f` holding chunks `f, f + k, f + 2k, …` so that neighbours in time (which share a thermal state)
/// never sit on both sides, while every fold spans the whole run — and a seeded shuffle otherwise.
fn kfold(data: &Dataset, k: usize, seed: u64) -> Folds {
    let n = data.len();
    let mut idx: Vec<usize> = (0..n).collect();
    if data.time_span() > 0.0 {
        idx.sort_by(|&a, &b| data.measurements[a].time_min.total_cmp(&data.measurements[b].time_min).then(a.cmp(&b)));
    } else {
        idx.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
    }
    let k = k.clamp(2, n.max(2));
    let chunks = if data.time_span() > 0.0 { (4 * k).min(n) } else { k };
    let chunk_of = |pos: usize| pos * chunks / n;
    (0..k)
        .map(|f| {
            let (test, train): (Vec<usize>, Vec<usize>) = (0..n).partition(|&pos| chunk_of(pos) % k == f);
            (train.iter().map(|&p| idx[p]).collect(), test.iter().map(|&p| idx[p]).collect())
        })
        .collect()
}

/// Forward-chained folds: train on the earliest blocks, test on the next one.
fn forward_chained(data: &Dataset, k: usize) -> Folds {
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

struct Ctx<'a> {
    base: &'a Base,
    data: &'a Dataset,
    pre: Pre,
    holdout: Option<(&'a Dataset, Pre)>,
    folds: Folds,
    forward: Folds,
}

impl Ctx<'_> {
    fn model(&self, effects: &[Effect], rows: &[usize]) -> Model {
        let mut m = Model::new(effects.to_vec(), Isometry3::identity());
        if has_registration(&m) {
            m.registration = initial_registration(self.base, self.data, rows);
        }
        m
    }

    /// Held-out statistics of a model: the hold-out set when given, else cross-validation on `folds`.
    fn heldout(&self, effects: &[Effect], folds: &Folds) -> Result<Stats, DiagnoseError> {
        let mut norms = Vec::new();
        if let Some((hold, hpre)) = &self.holdout {
            let all: Vec<usize> = (0..self.data.len()).collect();
            let model = self.model(effects, &all);
            let f = fit(self.base, &model, self.data, &all, &self.pre)?;
            let rows: Vec<usize> = (0..hold.len()).collect();
            let (r, _) = residuals(self.base, &model, &f.theta, hold, &rows, hpre, false)?;
            norms.extend(r.chunks(3).map(|c| (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()));
            return Ok(Stats::of(&norms));
        }
        for (train, test) in folds {
            if train.is_empty() || test.is_empty() {
                continue;
            }
            let model = self.model(effects, train);
            let f = fit(self.base, &model, self.data, train, &self.pre)?;
            let (r, _) = residuals(self.base, &model, &f.theta, self.data, test, &self.pre, false)?;
            norms.extend(r.chunks(3).map(|c| (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()));
        }
        Ok(Stats::of(&norms))
    }

    /// The parameters of `candidate` that stay identifiable next to `effects`, on all data.
    fn new_free(&self, effects: &[Effect], candidate: Effect) -> Result<(usize, Vec<FixedParameter>), DiagnoseError> {
        let mut all_effects = effects.to_vec();
        all_effects.push(candidate);
        let all: Vec<usize> = (0..self.data.len()).collect();
        let model = self.model(&all_effects, &all);
        let (_, jac) = residuals(self.base, &model, &model.initial(), self.data, &all, &self.pre, true)?;
        let names = model.parameter_names();
        let (free, fixed) = identifiable(&jac, &names, &vec![true; model.len]);
        let start = model.offsets[model.offsets.len() - 1];
        let new = (start..model.len).filter(|&c| free[c]).count();
        let fixed_new = fixed.into_iter().filter(|f| candidate.parameter_names().contains(&f.parameter)).collect();
        Ok((new, fixed_new))
    }

    fn full_fit(&self, effects: &[Effect]) -> Result<(Model, crate::fit::Fit), DiagnoseError> {
        let all: Vec<usize> = (0..self.data.len()).collect();
        let model = self.model(effects, &all);
        let f = fit(self.base, &model, self.data, &all, &self.pre)?;
        Ok((model, f))
    }

    fn bic(&self, effects: &[Effect]) -> Result<f64, DiagnoseError> {
        let (_, f) = self.full_fit(effects)?;
        let m = (self.data.len() * 3) as f64;
        let k = f.free.iter().filter(|&&x| x).count() as f64;
        Ok(m * (f.ssr / m).max(1e-300).ln() + k * m.ln())
    }
}

fn candidates(base: &Base, data: &Dataset, config: &Config) -> Vec<Effect> {
    let n = base.chain.dof();
    let mut c = Vec::new();
    if config.frame == FrameMode::Base {
        c.push(Effect::global(EffectKind::BaseFrame));
    }
    if config.tool == ToolMode::Known {
        c.push(Effect::global(EffectKind::ToolFrame));
    }
    for j in 0..n {
        c.push(Effect::at(EffectKind::JointOffset, j));
    }
    for j in 0..n {
        c.push(Effect::at(EffectKind::LinkDeviation, j));
    }
    for j in 0..n {
        let carries_mass = base.masses.iter().skip(j).any(Option::is_some);
        if carries_mass {
            c.push(Effect::at(EffectKind::JointCompliance, j));
        }
    }
    if data.time_span() > 0.0 {
        for j in 0..n {
            c.push(Effect::at(EffectKind::ThermalDrift(DriftShape::Linear), j));
            c.push(Effect::at(EffectKind::ThermalDrift(DriftShape::Exponential), j));
        }
    }
    if !data.temperature_names.is_empty() {
        for j in 0..n {
            c.push(Effect::at(EffectKind::ThermalDrift(DriftShape::Temperature), j));
        }
    }
    c
}

fn breakdown(base: &Base, data: &Dataset, model: &Model, theta: &[f64], pre: &Pre) -> Result<Breakdown, DiagnoseError> {
    let all: Vec<usize> = (0..data.len()).collect();
    let (r, _) = residuals(base, model, theta, data, &all, pre, false)?;
    let e: Vec<f64> = r.chunks(3).map(|c| c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).collect();
    let rms_of = |sel: &[usize]| -> f64 {
        if sel.is_empty() { f64::NAN } else { (sel.iter().map(|&i| e[i]).sum::<f64>() / sel.len() as f64).sqrt() }
    };
    let quartiles = |key: &dyn Fn(usize) -> f64| -> [f64; 4] {
        let mut idx = all.clone();
        idx.sort_by(|&a, &b| key(a).total_cmp(&key(b)));
        let n = idx.len();
        [0, 1, 2, 3].map(|k| rms_of(&idx[k * n / 4..(k + 1) * n / 4]))
    };
    let n = base.chain.dof();
    let by_joint = (0..n).map(|j| quartiles(&|i| data.measurements[i].q[j])).collect();
    let median = |v: &mut Vec<f64>| -> f64 {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(0.0)
    };
    let reach: Vec<f64> = data.measurements.iter().map(|m| m.position_mm.xy().norm()).collect();
    let height: Vec<f64> = data.measurements.iter().map(|m| m.position_mm.z).collect();
    let (mr, mh) = (median(&mut reach.clone()), median(&mut height.clone()));
    let region = |f: &dyn Fn(usize) -> usize| -> [f64; 4] {
        [0, 1, 2, 3].map(|k| rms_of(&all.iter().copied().filter(|&i| f(i) == k).collect::<Vec<_>>()))
    };
    let by_workspace_region = region(&|i| usize::from(reach[i] > mr) * 2 + usize::from(height[i] > mh));
    let elbow: Vec<f64> = data.measurements.iter().map(|m| m.q.get(2).copied().unwrap_or(0.0)).collect();
    let me = median(&mut elbow.clone());
    let by_joint_space_region = region(&|i| {
        usize::from(elbow[i] > me) * 2 + usize::from(data.measurements[i].q.get(4).copied().unwrap_or(0.0) > 0.0)
    });
    let by_time =
        if data.time_span() > 0.0 { quartiles(&|i| data.measurements[i].time_min).to_vec() } else { Vec::new() };
    let per_measurement_mm = e.iter().map(|x| x.sqrt()).collect();
    Ok(Breakdown { by_joint, by_workspace_region, by_joint_space_region, by_time, per_measurement_mm })
}

/// Runs the diagnosis of `data` against `base`. `holdout`, when given, replaces cross-validation.
///
/// ```
/// use thermokin_diagnose::{Base, Config, Effect, EffectKind, HiddenEffect, SimulationConfig, diagnose, simulate};
///
/// let chain = thermokin_testdata::irb140_table9();
/// let base = Base { chain, masses: vec![None; 6] };
/// // A hidden zero offset of +0.05° on joint 2 (index 1), measured with 5 µm noise.
/// let hidden = [HiddenEffect { effect: Effect::at(EffectKind::JointOffset, 1), values: vec![0.05f64.to_radians()] }];
/// let data = simulate(&base, &hidden, &SimulationConfig { poses: 120, ..SimulationConfig::default() }).unwrap();
/// let report = diagnose(&base, &data, None, &Config::default()).unwrap();
/// assert_eq!(report.effects[0].label, "joint_offset[2]");
/// ```
pub fn diagnose(
    base: &Base,
    data: &Dataset,
    holdout: Option<&Dataset>,
    config: &Config,
) -> Result<Report, DiagnoseError> {
    let n = base.chain.dof();
    if data.len() < 2 * config.folds.max(2) {
        return Err(DiagnoseError::Input(format!(
            "{} measurements are too few for {}-fold cross-validation",
            data.len(),
            config.folds
        )));
    }
    for (i, m) in data.measurements.iter().chain(holdout.iter().flat_map(|h| h.measurements.iter())).enumerate() {
        if m.q.len() != n {
            return Err(DiagnoseError::Input(format!(
                "measurement {}: {} joint values for {n} joints",
                i + 1,
                m.q.len()
            )));
        }
    }
    let ctx = Ctx {
        base,
        data,
        pre: prepare(base, data),
        holdout: holdout.map(|h| (h, prepare(base, h))),
        folds: kfold(data, config.folds, config.seed),
        forward: forward_chained(data, config.folds),
    };
    let validation = if holdout.is_some() {
        "explicit hold-out set (model fitted on all measurements)".to_string()
    } else if data.time_span() > 0.0 {
        format!(
            "{}-fold cross-validation, folds grouped in time; time-dependent effects also forward-chained",
            config.folds
        )
    } else {
        format!("{}-fold cross-validation (seeded shuffle)", config.folds)
    };
    let mut effects: Vec<Effect> = Vec::new();
    if config.frame == FrameMode::Tracker {
        effects.push(Effect::global(EffectKind::Registration));
    }
    if config.tool == ToolMode::Unknown {
        effects.push(Effect::global(EffectKind::ToolPoint));
    }
    let always = effects.len();
    let nominal = ctx.heldout(&effects, &ctx.folds)?;
    let mut current = nominal;
    let mut additive = vec![TableRow { model: "nominal".into(), stats: nominal }];
    let mut bic = vec![ctx.bic(&effects)?];
    let mut before_after: Vec<(f64, f64)> = Vec::new();
    let mut skipped: Vec<(String, String)> = Vec::new();
    let mut pool = candidates(base, data, config);
    while effects.len() - always < config.max_effects && !pool.is_empty() {
        // Identifiability gate, then held-out error of each remaining candidate (in parallel). An
        // exponential drift refines the linear one of its joint: it is scored only where the linear drift
        // already earns half the best gain (it costs a model per measurement and a nonlinear τ).
        let score = |c: &Effect| -> Scored {
            let (new, _) = ctx.new_free(&effects, *c)?;
            if new == 0 {
                return Ok(None);
            }
            let mut with = effects.clone();
            with.push(*c);
            Ok(Some((*c, new, ctx.heldout(&with, &ctx.folds)?)))
        };
        let is_exp = |c: &Effect| c.kind == EffectKind::ThermalDrift(DriftShape::Exponential);
        let first: Vec<Effect> = pool.iter().copied().filter(|c| !is_exp(c)).collect();
        let mut scored: Vec<(Effect, Scored)> = first.par_iter().map(|c| (*c, score(c))).collect();
        let best_gain = scored
            .iter()
            .filter_map(|(_, r)| {
                r.as_ref().ok().and_then(|o| o.as_ref()).map(|s| current.heldout_rms_mm - s.2.heldout_rms_mm)
            })
            .fold(0.0, f64::max);
        let linear_gain = |j: Option<usize>| {
            scored
                .iter()
                .filter(|(c, _)| c.kind == EffectKind::ThermalDrift(DriftShape::Linear) && c.joint == j)
                .filter_map(|(_, r)| {
                    r.as_ref().ok().and_then(|o| o.as_ref()).map(|s| current.heldout_rms_mm - s.2.heldout_rms_mm)
                })
                .fold(f64::NEG_INFINITY, f64::max)
        };
        let second: Vec<Effect> = pool
            .iter()
            .copied()
            .filter(|c| is_exp(c) && linear_gain(c.joint) >= 0.5 * best_gain && best_gain > 0.0)
            .collect();
        scored.extend(second.par_iter().map(|c| (*c, score(c))).collect::<Vec<_>>());
        let deferred: Vec<Effect> = pool.iter().copied().filter(|c| is_exp(c) && !second.contains(c)).collect();
        let mut results = Vec::new();
        let mut still = deferred;
        for (c, r) in &scored {
            match r.clone()? {
                None => {
                    let (_, fixed) = ctx.new_free(&effects, *c)?;
                    let reason =
                        fixed.first().map_or_else(|| "adds nothing identifiable".to_string(), |f| f.reason.clone());
                    if c.is_reported() {
                        skipped.push((c.label(), reason));
                    }
                }
                Some(s) => {
                    results.push(s);
                    still.push(*c);
                }
            }
        }
        pool = still;
        let Some(best) = results.iter().map(|r| r.2.heldout_rms_mm).min_by(f64::total_cmp) else { break };
        let gain = current.heldout_rms_mm - best;
        if gain < config.min_improvement * current.heldout_rms_mm {
            break;
        }
        // Parsimony: the smallest block within `parsimony` of the best gain; then the lowest error.
        let mut eligible: Vec<&(Effect, usize, Stats)> =
            results.iter().filter(|r| current.heldout_rms_mm - r.2.heldout_rms_mm >= config.parsimony * gain).collect();
        // Ties between blocks of one size go to the conventional one (base_frame, tool_frame,
        // joint_offset), which the report names; its equivalents are listed beside it.
        let conventional =
            |e: &Effect| matches!(e.kind, EffectKind::BaseFrame | EffectKind::ToolFrame | EffectKind::JointOffset);
        eligible.sort_by(|a, b| {
            a.1.cmp(&b.1)
                .then(conventional(&b.0).cmp(&conventional(&a.0)))
                .then(a.2.heldout_rms_mm.total_cmp(&b.2.heldout_rms_mm))
        });
        let mut chosen = None;
        for cand in eligible {
            let mut with = effects.clone();
            with.push(cand.0);
            if cand.0.is_time_dependent() && ctx.holdout.is_none() {
                let before = ctx.heldout(&effects, &ctx.forward)?;
                let after = ctx.heldout(&with, &ctx.forward)?;
                if after.heldout_rms_mm >= before.heldout_rms_mm {
                    continue;
                }
            }
            let b = ctx.bic(&with)?;
            if b >= *bic.last().unwrap_or(&f64::INFINITY) {
                continue;
            }
            chosen = Some((cand.0, cand.2, b));
            break;
        }
        let Some((effect, stats, b)) = chosen else { break };
        before_after.push((current.heldout_rms_mm, stats.heldout_rms_mm));
        effects.push(effect);
        pool.retain(|c| *c != effect);
        current = stats;
        additive.push(TableRow { model: format!("+ {}", effect.label()), stats });
        bic.push(b);
    }
    // An exponential drift whose linear twin does as well on held-out data (within the improvement gate)
    // is reported as the linear one: the smaller model.
    for k in always..effects.len() {
        if let (EffectKind::ThermalDrift(DriftShape::Exponential), Some(j)) = (effects[k].kind, effects[k].joint) {
            let mut swapped = effects.clone();
            swapped[k] = Effect::at(EffectKind::ThermalDrift(DriftShape::Linear), j);
            let s = ctx.heldout(&swapped, &ctx.folds)?;
            if s.heldout_rms_mm <= current.heldout_rms_mm * (1.0 + config.min_improvement) {
                effects = swapped;
                current = s;
                if let Some(row) = additive.get_mut(k - always + 1) {
                    row.model = format!("+ {} (replaces the exponential)", effects[k].label());
                }
            }
        }
    }
    // Final model on all data.
    let (model, final_fit) = ctx.full_fit(&effects)?;
    let all: Vec<usize> = (0..data.len()).collect();
    let (_, jac) = residuals(base, &model, &final_fit.theta, data, &all, &ctx.pre, true)?;
    let observability = observability(&jac, &final_fit.free);
    let reported: Vec<usize> = (always..effects.len()).collect();
    let mut leave_one_out = Vec::new();
    let mut without = Vec::new();
    for &k in &reported {
        let rest: Vec<Effect> = effects.iter().enumerate().filter(|(i, _)| *i != k).map(|(_, e)| *e).collect();
        let s = ctx.heldout(&rest, &ctx.folds)?;
        leave_one_out.push(TableRow { model: format!("all − {}", effects[k].label()), stats: s });
        without.push(s.heldout_rms_mm);
    }
    let names = model.parameter_names();
    let mut reports: Vec<EffectReport> = reported
        .iter()
        .enumerate()
        .map(|(r, &k)| {
            let e = effects[k];
            let o = model.offsets[k];
            let parameters = (0..e.len())
                .map(|p| {
                    let v = final_fit.theta[o + p];
                    let s = final_fit.std[o + p];
                    (
                        names[o + p].clone(),
                        ParameterValue { value: e.to_report_units(p, v), std: e.to_report_units(p, s).abs() },
                    )
                })
                .collect();
            let mut equivalent = static_equivalents(&e, n);
            equivalent.extend(skipped.iter().filter(|(_, why)| why.contains(&e.label())).map(|(c, _)| c.clone()));
            equivalent.sort();
            equivalent.dedup();
            EffectReport {
                effect: e.kind_name().to_string(),
                label: e.label(),
                joints: e.joint.map(|j| vec![j + 1]).unwrap_or_default(),
                heldout_rms_before_mm: before_after[r].0,
                heldout_rms_after_mm: before_after[r].1,
                heldout_rms_without_mm: without[r],
                parameters,
                equivalent,
            }
        })
        .collect();
    // Main cause first: the effect whose removal hurts most.
    reports.sort_by(|a, b| (b.heldout_rms_without_mm).total_cmp(&a.heldout_rms_without_mm));
    let nominal_model = ctx.model(&effects[..always], &all);
    let nominal_fit = fit(base, &nominal_model, data, &all, &ctx.pre)?;
    Ok(Report {
        nominal,
        validation,
        effects: reports,
        additive,
        leave_one_out,
        identifiability: Identifiability { observability, fixed: final_fit.fixed.clone(), skipped_candidates: skipped },
        residuals_before: breakdown(base, data, &nominal_model, &nominal_fit.theta, &ctx.pre)?,
        residuals_after: breakdown(base, data, &model, &final_fit.theta, &ctx.pre)?,
        bic,
    })
}

/// The equivalences that hold by construction in the same-orientation convention.
fn static_equivalents(e: &Effect, dof: usize) -> Vec<String> {
    match (e.kind, e.joint) {
        (EffectKind::BaseFrame, _) => vec!["link_deviation[1]".into()],
        (EffectKind::ToolFrame, _) => vec![format!("link_deviation[{dof}] (translation)")],
        (EffectKind::JointOffset, Some(j)) => vec![format!("link_deviation[{}] (rotation about its own axis)", j + 1)],
        _ => Vec::new(),
    }
}
