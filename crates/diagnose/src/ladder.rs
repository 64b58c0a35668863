//! The ladder: candidate effects added one at a time, each judged on held-out data, the smaller block
//! preferred when two explain the data alike; then the final model on all data and the report.

use rayon::prelude::*;
use serde::Serialize;
use thermokin_chain::Robot;

use crate::fit::{fit, observability, residuals};
use crate::model::{DriftShape, Effect, JointIndex, prepare};
use crate::report::{
    EffectReport, Identifiability, ParameterValue, Report, Stats, TableRow, breakdown, static_equivalents,
};
use crate::validation::{Ctx, Scored, forward_chained, kfold};
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

/// The catalogue's candidates for this robot and data set, in catalogue order.
fn candidates(robot: &Robot, data: &Dataset, config: &Config) -> Result<Vec<Effect>, DiagnoseError> {
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

/// Runs the diagnosis of `data` against `base`. `holdout`, when given, replaces cross-validation.
///
/// ```
/// use thermokin_diagnose::{Config, Effect, HiddenEffect, JointIndex, Robot, SimulationConfig, diagnose, simulate};
///
/// let robot = Robot::new("IRB 140", thermokin_testdata::irb140_table9());
/// // A hidden zero offset of +0.05° on joint 2 (index 1), measured with 5 µm noise.
/// let offset = Effect::JointOffset(JointIndex::of(&robot, 1)?);
/// let hidden = [HiddenEffect { effect: offset, values: vec![0.05f64.to_radians()] }];
/// let data = simulate(&robot, &hidden, &SimulationConfig { poses: 120, ..SimulationConfig::default() })?;
/// let report = diagnose(&robot, &data, None, &Config::default())?;
/// assert_eq!(report.effects[0].label, "joint_offset[2]");
/// # Ok::<(), thermokin_diagnose::DiagnoseError>(())
/// ```
pub fn diagnose(
    robot: &Robot,
    data: &Dataset,
    holdout: Option<&Dataset>,
    config: &Config,
) -> Result<Report, DiagnoseError> {
    let n = robot.chain().dof();
    let needed = 2 * config.folds.max(2);
    if data.len() < needed {
        return Err(DiagnoseError::TooFewMeasurements { count: data.len(), folds: config.folds, needed });
    }
    let sets = [("training", Some(data)), ("hold-out", holdout)];
    for (set, d) in sets.iter().filter_map(|(s, d)| d.map(|d| (*s, d))) {
        if let Some((i, m)) = d.measurements.iter().enumerate().find(|(_, m)| m.q.len() != n) {
            return Err(DiagnoseError::JointCount { set, measurement: i + 1, got: m.q.len(), expected: n });
        }
    }
    let ctx = Ctx {
        robot,
        data,
        pre: prepare(robot, data),
        holdout: holdout.map(|h| (h, prepare(robot, h))),
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
        effects.push(Effect::Registration);
    }
    if config.tool == ToolMode::Unknown {
        effects.push(Effect::ToolPoint);
    }
    let always = effects.len();
    let nominal = ctx.heldout(&effects, &ctx.folds)?;
    let mut current = nominal;
    let mut additive = vec![TableRow { model: "nominal".into(), stats: nominal }];
    let mut bic = vec![ctx.bic(&effects)?];
    let mut before_after: Vec<(f64, f64)> = Vec::new();
    let mut skipped: Vec<(String, String)> = Vec::new();
    let mut pool = candidates(robot, data, config)?;
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
        let is_exp = |c: &Effect| matches!(c, Effect::ThermalDrift(_, DriftShape::Exponential));
        let first: Vec<Effect> = pool.iter().copied().filter(|c| !is_exp(c)).collect();
        let mut scored: Vec<(Effect, Scored)> = first.par_iter().map(|c| (*c, score(c))).collect();
        let best_gain = scored
            .iter()
            .filter_map(|(_, r)| {
                r.as_ref().ok().and_then(|o| o.as_ref()).map(|s| current.heldout_rms_mm - s.2.heldout_rms_mm)
            })
            .fold(0.0, f64::max);
        let linear_gain = |j: Option<JointIndex>| {
            scored
                .iter()
                .filter(|(c, _)| matches!(c, Effect::ThermalDrift(_, DriftShape::Linear)) && c.joint() == j)
                .filter_map(|(_, r)| {
                    r.as_ref().ok().and_then(|o| o.as_ref()).map(|s| current.heldout_rms_mm - s.2.heldout_rms_mm)
                })
                .fold(f64::NEG_INFINITY, f64::max)
        };
        let second: Vec<Effect> = pool
            .iter()
            .copied()
            .filter(|c| is_exp(c) && linear_gain(c.joint()) >= 0.5 * best_gain && best_gain > 0.0)
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
        let conventional = |e: &Effect| matches!(e, Effect::BaseFrame | Effect::ToolFrame | Effect::JointOffset(_));
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
        if let Effect::ThermalDrift(j, DriftShape::Exponential) = effects[k] {
            let mut swapped = effects.clone();
            swapped[k] = Effect::ThermalDrift(j, DriftShape::Linear);
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
    let (_, jac) = residuals(robot, &model, &final_fit.theta, data, &all, &ctx.pre, true)?;
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
            let o = model.offsets()[k];
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
                joints: e.joint().map(|j| vec![j.number()]).unwrap_or_default(),
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
    let nominal_model = ctx.model(&effects[..always], &all)?;
    let nominal_fit = fit(robot, &nominal_model, data, &all, &ctx.pre)?;
    let (calibrated, left_out) = model.calibrated_chain(robot, &final_fit.theta)?;
    Ok(Report {
        nominal,
        calibrated,
        not_in_calibrated: left_out.iter().map(Effect::label).collect(),
        validation,
        effects: reports,
        additive,
        leave_one_out,
        identifiability: Identifiability { observability, fixed: final_fit.fixed.clone(), skipped_candidates: skipped },
        residuals_before: breakdown(robot, data, &nominal_model, &nominal_fit.theta, &ctx.pre)?,
        residuals_after: breakdown(robot, data, &model, &final_fit.theta, &ctx.pre)?,
        bic,
    })
}
