//! The ladder: candidate effects added one at a time, each judged on held-out data, the smaller block
//! preferred when two explain the data alike; then the final model on all data and the report.

use rayon::prelude::*;
use serde::Serialize;
use thermokin_chain::Robot;
use thermokin_io::units;

use crate::fit::{Start, fit, fit_from, initial_registration, norms, observability, residuals};
use crate::model::{DriftShape, Effect, JointIndex, Model, prepare_against};
use crate::report::{
    EffectReport, FittedFrames, HoldoutStats, Identifiability, Nested, ParameterValue, PoseReport, Report, Stats,
    TableRow, breakdown,
};
use crate::validation::{Ctx, Relation, Scored, folds_for, significantly_better};
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
    /// A candidate is accepted only if it lowers the held-out mean squared error by more than this many
    /// standard errors of the paired per-measurement difference (1: the one-standard-error rule). The
    /// same rule keeps a linear drift where the exponential is not significantly better.
    pub gate_standard_errors: f64,
    /// Among candidates within this fraction of the best improvement, the smallest block wins.
    pub parsimony: f64,
    /// Most effects added.
    pub max_effects: usize,
    /// Seed of the fold assignment.
    pub seed: u64,
    /// How the reported held-out error of the whole procedure is obtained.
    pub validation: Validation,
    /// How measurements are grouped into folds, for the selection and for the nested validation.
    pub folds_by: FoldGrouping,
    /// The measurement noise per axis (standard deviation, mm), when known — a tracker's specification:
    /// the verdict compares the held-out error with it. `None`: the verdict says it cannot.
    pub noise_mm: Option<f64>,
    /// The weight of measured orientations (6-D probes), as a lever: a rotation error of δφ radians
    /// counts as the displacement `lever · δφ` mm it causes that far from the tool point, next to the
    /// position error. 0 ignores orientations. The default, 100 mm, weighs 0.01° like 0.017 mm — the
    /// ratio of a 6-D tracker probe's orientation and position accuracy. Every held-out error of a
    /// diagnosis with orientations combines both: `√(|Δp|² + (lever · |δφ|)²)`.
    pub orientation_lever_mm: f64,
    /// The orientation noise per axis of a 6-D probe (standard deviation, degrees), when known: with
    /// orientations fitted, the verdict's noise floor is `√(3σ² + 3(lever · σ_rot)²)`.
    pub orientation_noise_deg: Option<f64>,
}

/// How measurements are grouped into cross-validation folds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum FoldGrouping {
    /// `folds` folds grouped in time when the data span time, a seeded shuffle otherwise (the default).
    #[default]
    Time,
    /// One fold per workspace quadrant (reach × height against their medians): held-out poses lie in a
    /// region the fit never saw.
    WorkspaceRegion,
    /// One fold per arm configuration (elbow against its median × wrist sign): held-out poses are on a
    /// branch the fit never saw.
    JointConfiguration,
}

/// How the diagnosis's own held-out error is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Validation {
    /// Nested cross-validation: the whole selection (the ladder, with its inner folds) is rerun on the
    /// training part of each of `outer` folds, and the model it picks is scored on that fold's test part,
    /// which the selection never saw. The default.
    Nested {
        /// Outer folds.
        outer: usize,
    },
    /// Only the selection's own cross-validation (optimistic: the same scores chose the effects). Faster.
    SelectionOnly,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            folds: 5,
            frame: FrameMode::Base,
            tool: ToolMode::Known,
            gate_standard_errors: 1.0,
            parsimony: 0.9,
            max_effects: 8,
            seed: 0xd1a6,
            validation: Validation::Nested { outer: 5 },
            noise_mm: None,
            folds_by: FoldGrouping::Time,
            orientation_lever_mm: 100.0,
            orientation_noise_deg: None,
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

/// Runs the diagnosis of `data` against `robot`.
///
/// The effects are chosen by cross-validation on `data` (the additive and leave-one-out tables: the
/// selection's scores, optimistic because they chose). The held-out error reported for the procedure
/// itself comes from nested cross-validation ([`Validation::Nested`], the default: [`Report::nested`]),
/// and from `holdout` when given ([`Report::holdout`]) — which never influences the selection.
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
/// // On outer folds the selection never saw, the chosen model is at the noise (5 µm per axis).
/// assert!(report.nested.unwrap().selected.heldout_rms_mm < 0.015);
/// # Ok::<(), thermokin_diagnose::DiagnoseError>(())
/// ```
pub fn diagnose(
    robot: &Robot,
    data: &Dataset,
    holdout: Option<&Dataset>,
    config: &Config,
) -> Result<Report, DiagnoseError> {
    diagnose_with_progress(robot, data, holdout, config, &mut |_| {})
}

/// One finished stage of a diagnosis, for a progress display: `done` of `total` stages (the selection
/// on all data, each outer fold of the nested validation, the hold-out set), each costing about the same.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Progress {
    /// Stages finished.
    pub done: usize,
    /// Stages in all.
    pub total: usize,
    /// The stage just finished.
    pub stage: String,
}

/// [`diagnose`], telling `progress` after each stage.
pub fn diagnose_with_progress(
    robot: &Robot,
    data: &Dataset,
    holdout: Option<&Dataset>,
    config: &Config,
    progress: &mut dyn FnMut(Progress),
) -> Result<Report, DiagnoseError> {
    let outer = match config.validation {
        Validation::Nested { outer } => nested_folds(data, config, outer).len(),
        Validation::SelectionOnly => 0,
    };
    let total = 1 + outer + usize::from(holdout.is_some());
    let mut done = 0;
    let mut tell = |stage: String| {
        done += 1;
        progress(Progress { done, total, stage });
    };
    let n = robot.chain().dof();
    let sets = [("training", Some(data)), ("hold-out", holdout)];
    for (set, d) in sets.iter().filter_map(|(s, d)| d.map(|d| (*s, d))) {
        if let Some((i, m)) = d.measurements.iter().enumerate().find(|(_, m)| m.q.len() != n) {
            return Err(DiagnoseError::JointCount { set, measurement: i + 1, got: m.q.len(), expected: n });
        }
    }
    let (mut report, effects) = select(robot, data, config)?;
    tell("selection on all measurements".into());
    let always = always_estimated(config, data);
    if let Validation::Nested { outer } = config.validation {
        report.nested = Some(nested(robot, data, config, outer, &mut tell)?);
    }
    if let Some(h) = holdout {
        // Fitted on all of `data`, scored on `holdout`: the selection above never saw it. When the
        // registration or the tool point is always estimated, the hold-out file may be in another tracker
        // frame or carry another probe: those blocks (only) are refitted on it, the effects kept as fitted.
        let ctx = Ctx::new(robot, data, config);
        let rows: Vec<usize> = (0..h.len()).collect();
        let pre = prepare_against(robot, h, data, config.orientation_lever_mm);
        let score = |e: &[Effect]| -> Result<Stats, DiagnoseError> {
            let (trained, f) = ctx.full_fit(e)?;
            let (model, theta) = if trained.effects().iter().any(|b| !b.is_reported()) {
                let mut model = Model::new(robot, e.to_vec())?;
                if model.has_registration() {
                    model = model.with_registration(initial_registration(robot, h, &rows)?);
                }
                let mut theta = f.theta.clone();
                let mut movable = vec![false; model.len()];
                for (b, &o) in model.effects().iter().zip(model.offsets()) {
                    if !b.is_reported() {
                        // The frame blocks restart from the hold-out file's own registration.
                        theta[o..o + b.len()].fill(0.0);
                        movable[o..o + b.len()].fill(true);
                    }
                }
                let refit = fit_from(robot, &model, h, &rows, &pre, &Start { theta, movable })?;
                (model, refit.theta)
            } else {
                (trained, f.theta)
            };
            let (r, _) = residuals(robot, &model, &theta, h, &rows, &pre, false)?;
            Ok(Stats::of(&norms(&r, pre.stride())))
        };
        let refitted = always.iter().map(Effect::label).collect();
        report.holdout = Some(HoldoutStats { nominal: score(&always)?, selected: score(&effects)?, refitted });
        tell("hold-out set".into());
    }
    report.warnings = warnings(robot, data, config, &report);
    report.verdict = verdict(config, &report);
    Ok(report)
}

/// Signs that the data were read with the wrong units or frame: the diagnosis would otherwise absorb a
/// radians-for-degrees mix-up or an unregistered tracker frame into hundreds of millimetres of "error".
fn warnings(robot: &Robot, data: &Dataset, config: &Config, report: &Report) -> Vec<String> {
    let mut out = Vec::new();
    let revolute: Vec<usize> = robot
        .chain()
        .joints()
        .iter()
        .enumerate()
        .filter(|(_, j)| j.kind == thermokin_chain::JointKind::Revolute)
        .map(|(i, _)| i)
        .collect();
    let largest = data.measurements.iter().flat_map(|m| revolute.iter().map(|&i| m.q[i].abs())).fold(0.0, f64::max);
    // 2π read as degrees is 0.11 rad: joint values that never leave ±6.3° over a calibration set were
    // most likely written in radians.
    if data.len() >= 10 && !revolute.is_empty() && largest < units::radians(std::f64::consts::TAU) {
        out.push(format!(
            "every revolute joint value is within ±{:.2}°: were they written in radians? (files are read in degrees)",
            units::degrees(largest)
        ));
    }
    // Coverage: an effect of a joint identified over a small part of the joint's travel is an
    // extrapolation elsewhere. A quarter of the range between the limits (all of ±180° without limits),
    // or half a revolution for a cyclic error, whose once- and twice-per-revolution terms trade against
    // an offset and a scale over a short arc.
    for e in &report.effects {
        let Some(&number) = e.joints.first() else { continue };
        let j = number - 1;
        let joint = &robot.chain().joints()[j];
        let (lo, hi) = data
            .measurements
            .iter()
            .map(|m| m.q[j])
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)));
        let covered = hi - lo;
        let travel = joint.limits.map_or(std::f64::consts::TAU, |l| l.upper - l.lower);
        let need = if e.effect == "periodic" { std::f64::consts::PI.min(travel) } else { 0.25 * travel };
        if joint.kind == thermokin_chain::JointKind::Revolute && covered < need {
            out.push(format!(
                "{} was identified with joint {number} between {:.1}° and {:.1}° only ({:.0}% of its travel): it may not hold outside that range — measure poses across the joint's travel",
                e.label,
                units::degrees(lo),
                units::degrees(hi),
                100.0 * covered / travel
            ));
        }
    }
    // A nominal model off by more than 50 mm RMS in the base frame: the robot cannot be that wrong; the
    // measurements are in another frame.
    if config.frame == FrameMode::Base && report.nominal.heldout_rms_mm > 50.0 {
        out.push(format!(
            "the nominal model misses by {:.0} mm RMS in the base frame: are the measurements in a tracker frame? (--frame tracker estimates the registration)",
            report.nominal.heldout_rms_mm
        ));
    }
    out
}

/// Whether what the effects leave is the noise: the nested held-out RMS (or the selection's own CV
/// without nesting) against `√3 · σ` of the stated per-axis noise (`√(3σ² + 3(lever · σ_rot)²)` with
/// orientations fitted), with a factor 1.5 of margin (the 3-D RMS of Gaussian noise scatters by ~10 %
/// over 100 poses; a model error shows as more).
fn verdict(config: &Config, report: &Report) -> String {
    let (held, how) = match &report.nested {
        Some(n) => (n.selected.heldout_rms_mm, "nested held-out"),
        None => (
            report.additive.last().map_or(report.nominal.heldout_rms_mm, |r| r.stats.heldout_rms_mm),
            "cross-validated",
        ),
    };
    let floor = match (config.noise_mm, report.orientation_lever_mm, config.orientation_noise_deg) {
        (None, ..) => None,
        (Some(sigma), None, _) => Some((sigma * 3f64.sqrt(), format!("σ = {sigma} mm per axis"))),
        (Some(sigma), Some(lever), Some(rot)) => Some((
            (3.0 * sigma * sigma + 3.0 * (lever * units::radians(rot)).powi(2)).sqrt(),
            format!("σ = {sigma} mm and {rot}° per axis, lever {lever} mm"),
        )),
        (Some(_), Some(_), None) => {
            return format!(
                "{held:.4} mm RMS {how} remains (position and orientation combined); the orientation noise is not stated (--orientation-noise), so whether that is noise cannot be said"
            );
        }
    };
    match floor {
        None => format!(
            "{held:.4} mm RMS {how} remains; the measurement noise is not stated (--noise), so whether that is noise or an unexplained effect cannot be said"
        ),
        Some((floor, stated)) => {
            if held <= 1.5 * floor {
                format!("explained: {held:.4} mm RMS {how} is at the stated noise ({floor:.4} mm RMS for {stated})")
            } else {
                format!(
                    "not explained: {held:.4} mm RMS {how} remains, {:.1}× the stated noise ({floor:.4} mm RMS): an effect outside the catalogue, or more noise than stated",
                    held / floor
                )
            }
        }
    }
}

/// The blocks every model estimates (never reported as causes): the tracker registration and an unknown
/// tool point.
fn always_estimated(config: &Config, data: &Dataset) -> Vec<Effect> {
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

/// The outer folds of the nested validation (their own seed: not the selection's folds).
fn nested_folds(data: &Dataset, config: &Config, outer: usize) -> crate::validation::Folds {
    folds_for(data, outer, config.seed ^ 0x0e7e_5eed, config.folds_by)
}

/// Nested cross-validation of the whole procedure: for each outer fold, the selection runs on the
/// training part only, the model it picks is fitted there and scored on the fold's test part; the
/// nominal model (the always-estimated blocks) is scored the same way.
fn nested(
    robot: &Robot,
    data: &Dataset,
    config: &Config,
    outer: usize,
    tell: &mut dyn FnMut(String),
) -> Result<Nested, DiagnoseError> {
    let folds = nested_folds(data, config, outer);
    let inner = Config { validation: Validation::SelectionOnly, ..config.clone() };
    let always = always_estimated(config, data);
    let mut nominal_norms = Vec::new();
    let mut selected_norms = Vec::new();
    let mut selections = Vec::new();
    for (k, (train, test)) in folds.iter().enumerate() {
        if train.is_empty() || test.is_empty() {
            continue;
        }
        let subset = data.subset(train);
        let (_, effects) = select(robot, &subset, &inner)?;
        tell(format!("nested validation, outer fold {} of {}", k + 1, folds.len()));
        selections.push(effects.iter().filter(|e| e.is_reported()).map(Effect::label).collect());
        let ctx = Ctx::new(robot, &subset, &inner);
        let test_set = data.subset(test);
        let test_pre = prepare_against(robot, &test_set, &subset, config.orientation_lever_mm);
        let rows: Vec<usize> = (0..test.len()).collect();
        for (e, errors) in [(&always, &mut nominal_norms), (&effects, &mut selected_norms)] {
            let (model, f) = ctx.full_fit(e)?;
            let (r, _) = residuals(robot, &model, &f.theta, &test_set, &rows, &test_pre, false)?;
            errors.extend(norms(&r, test_pre.stride()));
        }
    }
    Ok(Nested {
        outer_folds: outer,
        nominal: Stats::of(&nominal_norms),
        selected: Stats::of(&selected_norms),
        selections,
    })
}

/// The ladder on `data`: candidates chosen by cross-validation, the final model fitted on all of it. The
/// report's held-out figures here are the selection's own (optimistic) scores.
fn select(robot: &Robot, data: &Dataset, config: &Config) -> Result<(Report, Vec<Effect>), DiagnoseError> {
    let needed = 2 * config.folds.max(2);
    if data.len() < needed {
        return Err(DiagnoseError::TooFewMeasurements { count: data.len(), folds: config.folds, needed });
    }
    let ctx = Ctx::new(robot, data, config);
    let validation = if config.folds_by == FoldGrouping::WorkspaceRegion {
        "leave one workspace region out (4 quadrants of reach × height)".to_string()
    } else if config.folds_by == FoldGrouping::JointConfiguration {
        "leave one arm configuration out (elbow × wrist)".to_string()
    } else if data.time_span() > 0.0 {
        format!(
            "{}-fold cross-validation, folds grouped in time; time-dependent effects also forward-chained",
            config.folds
        )
    } else {
        format!("{}-fold cross-validation (seeded shuffle)", config.folds)
    };
    let mut effects = always_estimated(config, data);
    let always = effects.len();
    let (nominal, nominal_errors) = ctx.heldout_errors(&effects, &ctx.folds)?;
    let mut current = nominal;
    let mut current_errors = nominal_errors;
    let mut additive = vec![TableRow { model: "nominal".into(), stats: nominal }];
    let mut bic = vec![ctx.bic(&effects)?];
    let mut before_after: Vec<(f64, f64)> = Vec::new();
    let mut skipped: Vec<(String, String)> = Vec::new();
    let catalogue = candidates(robot, data, config)?;
    let mut pool = catalogue.clone();
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
            let (stats, errors) = ctx.heldout_errors(&with, &ctx.folds)?;
            Ok(Some((*c, new, stats, errors)))
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
        let Some(best) = results.iter().min_by(|a, b| a.2.heldout_rms_mm.total_cmp(&b.2.heldout_rms_mm)) else {
            break;
        };
        if !significantly_better(&current_errors, &best.3, config.gate_standard_errors) {
            break;
        }
        let gain = current.heldout_rms_mm - best.2.heldout_rms_mm;
        // Parsimony: the smallest block within `parsimony` of the best gain, itself significant; then the
        // lowest error.
        let mut eligible: Vec<&(Effect, usize, Stats, Vec<f64>)> = results
            .iter()
            .filter(|r| current.heldout_rms_mm - r.2.heldout_rms_mm >= config.parsimony * gain)
            .filter(|r| significantly_better(&current_errors, &r.3, config.gate_standard_errors))
            .collect();
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
            if cand.0.is_time_dependent() {
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
            chosen = Some((cand.0, cand.2, cand.3.clone(), b));
            break;
        }
        let Some((effect, stats, errors, b)) = chosen else { break };
        before_after.push((current.heldout_rms_mm, stats.heldout_rms_mm));
        effects.push(effect);
        pool.retain(|c| *c != effect);
        current = stats;
        current_errors = errors;
        additive.push(TableRow { model: format!("+ {}", effect.label()), stats });
        bic.push(b);
    }
    // An exponential drift that is not significantly better than its linear twin on held-out data (the
    // same gate) is reported as the linear one: the smaller model.
    for k in always..effects.len() {
        if let Effect::ThermalDrift(j, DriftShape::Exponential) = effects[k] {
            let mut swapped = effects.clone();
            swapped[k] = Effect::ThermalDrift(j, DriftShape::Linear);
            let (_, errors) = ctx.heldout_errors(&swapped, &ctx.folds)?;
            if !significantly_better(&errors, &current_errors, config.gate_standard_errors) {
                effects = swapped;
                current_errors = errors;
                if let Some(row) = additive.get_mut(k - always + 1) {
                    row.model = format!("+ {} (replaces the exponential)", effects[k].label());
                }
            }
        }
    }
    // Parsimony across steps: a block chosen early may hold a smaller one that explains as much once the
    // later blocks are in (a joint offset inside a link deviation). Each chosen block is replaced by the
    // smallest catalogue block its directions contain (rank test on the data) when the larger is not
    // significantly better held out (the same gate, the other way round).
    for k in always..effects.len() {
        let big = effects[k];
        let mut smaller: Vec<Effect> = Vec::new();
        for &c in catalogue.iter().filter(|c| c.len() < big.len() && !effects.contains(c)) {
            if ctx.relations(c, &[big])?.iter().any(|(_, r)| *r == Relation::ContainedIn) {
                smaller.push(c);
            }
        }
        // Of the smaller blocks as good as the larger, the fewest parameters, then the lowest error.
        let mut best: Option<(Effect, Stats, Vec<f64>)> = None;
        for c in smaller {
            let mut swapped = effects.clone();
            swapped[k] = c;
            let (stats, errors) = ctx.heldout_errors(&swapped, &ctx.folds)?;
            if significantly_better(&errors, &current_errors, config.gate_standard_errors) {
                continue;
            }
            let better = match &best {
                None => true,
                Some((b, s, _)) => (c.len(), stats.heldout_rms_mm) < (b.len(), s.heldout_rms_mm),
            };
            if better {
                best = Some((c, stats, errors));
            }
        }
        if let Some((c, stats, errors)) = best {
            effects[k] = c;
            current_errors = errors;
            if let Some(row) = additive.get_mut(k - always + 1) {
                row.model = format!(
                    "+ {} (replaces {}: as good held out with {} parameters instead of {})",
                    c.label(),
                    big.label(),
                    c.len(),
                    big.len()
                );
                row.stats = stats;
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
        .map(|(r, &k)| -> Result<EffectReport, DiagnoseError> {
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
            let relations = ctx.relations(e, &catalogue)?;
            let of = |kind: Relation| -> Vec<String> {
                relations.iter().filter(|(_, r)| *r == kind).map(|(b, _)| b.label()).collect()
            };
            let (equivalent, contained_in, contains) =
                (of(Relation::Equivalent), of(Relation::ContainedIn), of(Relation::Contains));
            Ok(EffectReport {
                effect: e.kind_name().to_string(),
                label: e.label(),
                joints: e.joint().map(|j| vec![j.number()]).unwrap_or_default(),
                heldout_rms_before_mm: before_after[r].0,
                heldout_rms_after_mm: before_after[r].1,
                heldout_rms_without_mm: without[r],
                parameters,
                equivalent,
                contained_in,
                contains,
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
    let report = Report {
        frames,
        warnings: Vec::new(),
        verdict: String::new(),
        nominal,
        nested: None,
        holdout: None,
        calibrated,
        not_in_calibrated: left_out.iter().map(Effect::label).collect(),
        validation,
        orientation_lever_mm: ctx.pre.lever_mm,
        effects: reports,
        additive,
        leave_one_out,
        identifiability: Identifiability {
            observability,
            fixed: final_fit.fixed.clone(),
            skipped_candidates: skipped,
            correlated: final_fit.correlated.clone(),
        },
        residuals_before: breakdown(robot, data, &nominal_model, &nominal_fit.theta, &ctx.pre)?,
        residuals_after: breakdown(robot, data, &model, &final_fit.theta, &ctx.pre)?,
        bic,
    };
    Ok((report, effects))
}
