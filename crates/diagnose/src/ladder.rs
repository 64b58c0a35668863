//! The ladder: candidate effects added one at a time, each judged on held-out data, the smaller block
//! preferred when two explain the data alike; then the final model on all data and the report.

use rayon::prelude::*;
use serde::Serialize;
use thermokin_chain::Robot;
use thermokin_io::units;

use crate::eligibility::Eligibility;
use crate::fit::{Start, fit_from, initial_registration, norms, residuals};
use crate::model::{Effect, Model, prepare_against};
use crate::report::{HoldoutStats, Nested, OuterFold, Report, Stats};
use crate::screen::Screen;
use crate::select::{Plausibility, always_estimated, select};
use crate::validation::{Ctx, folds_for};
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
    /// The orientation noise per axis of a 6-D probe (standard deviation, radians), when known: with
    /// orientations fitted, the verdict's noise floor is `√(3σ² + 3(lever · σ_rot)²)`.
    pub orientation_noise_rad: Option<f64>,
    /// What the data must show before an effect may be selected ([`Eligibility`]).
    pub eligibility: Eligibility,
    /// Bounds on fitted values beyond which a candidate is refused as implausible ([`Plausibility`]).
    pub plausibility: Plausibility,
    /// How many candidates a forward step fits in full after ranking all by a linearised step
    /// ([`Screen`]; `Screen { keep: 0 }` fits every one).
    pub screen: Screen,
}

/// How measurements are grouped into cross-validation folds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum FoldGrouping {
    /// The default: `folds` folds grouped in time when the data span time (neighbours in time share a
    /// thermal state); otherwise grouped by neighbourhood in joint space — `4 · folds` blocks of
    /// neighbouring arm configurations (k-means), every `folds`-th block in one fold, so that each
    /// candidate is scored on poses unlike those it was fitted on while every fold spans the workspace.
    /// The gate's standard error is taken over the blocks.
    #[default]
    Neighbourhood,
    /// `folds` folds grouped in time when the data span time, a seeded shuffle of single poses
    /// otherwise.
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

impl Config {
    /// Checks every setting against its domain, one rule each: at least 2 folds (and 2 outer folds), a
    /// stated noise a positive standard deviation, a non-negative orientation lever, a gate, parsimony
    /// fraction and effect count that can select something.
    pub fn validate(&self) -> Result<(), DiagnoseError> {
        let bad = |setting, value: f64, rule| Err(DiagnoseError::BadSetting { setting, value, rule });
        if self.folds < 2 {
            return bad("folds", self.folds as f64, "must be at least 2");
        }
        if let Validation::Nested { outer } = self.validation
            && outer < 2
        {
            return bad("validation.outer", outer as f64, "must be at least 2");
        }
        if let Some(n) = self.noise_mm
            && !(n.is_finite() && n > 0.0)
        {
            return bad("noise_mm", n, "must be a positive standard deviation");
        }
        if !(self.orientation_lever_mm.is_finite() && self.orientation_lever_mm >= 0.0) {
            return bad("orientation_lever_mm", self.orientation_lever_mm, "must be ≥ 0");
        }
        if let Some(n) = self.orientation_noise_rad
            && !(n.is_finite() && n > 0.0)
        {
            return bad("orientation_noise_rad", n, "must be a positive standard deviation");
        }
        if !(self.gate_standard_errors.is_finite() && self.gate_standard_errors >= 0.0) {
            return bad("gate_standard_errors", self.gate_standard_errors, "must be ≥ 0");
        }
        if !(self.parsimony.is_finite() && (0.0..=1.0).contains(&self.parsimony)) {
            return bad("parsimony", self.parsimony, "must be a fraction in [0, 1]");
        }
        Ok(())
    }
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
            folds_by: FoldGrouping::Neighbourhood,
            orientation_lever_mm: 100.0,
            orientation_noise_rad: None,
            eligibility: Eligibility::default(),
            plausibility: Plausibility::default(),
            screen: Screen::default(),
        }
    }
}

/// Runs the diagnosis of `data` against `robot`.
///
/// The effects are chosen by cross-validation on `data` (the additive and leave-one-out tables: the
/// selection's scores, optimistic because they chose). The held-out error reported for the procedure
/// itself comes from nested cross-validation ([`Validation::Nested`], the default: [`Report::nested`]),
/// and from `holdout` when given ([`Report::holdout`]) — which never influences the selection.
///
/// ```
/// use thermokin_chain::Robot;
/// use thermokin_diagnose::{Config, Effect, HiddenEffect, JointIndex, SimulationConfig, diagnose, simulate};
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
    progress: &mut (dyn FnMut(Progress) + Send),
) -> Result<Report, DiagnoseError> {
    config.validate()?;
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
        let score = |e: &[Effect]| transfer_score(&ctx, h, e, config);
        let refitted = always.iter().map(Effect::label).collect();
        report.holdout = Some(HoldoutStats { nominal: score(&always)?, selected: score(&effects)?, refitted });
        tell("hold-out set".into());
    }
    let more = warnings(robot, data, config, &report);
    report.warnings.extend(more);
    report.verdict = verdict(config, &report);
    report.honest_end = honest_end(&report);
    Ok(report)
}

/// The model of `effects` fitted on all of `ctx`'s data, scored on `holdout`. When the registration or
/// the tool point is always estimated, the hold-out file may be in another tracker frame or carry another
/// probe: those blocks (only) are refitted on it, the effects kept as fitted.
pub(crate) fn transfer_score(
    ctx: &Ctx<'_>,
    holdout: &Dataset,
    effects: &[Effect],
    config: &Config,
) -> Result<Stats, DiagnoseError> {
    let robot = ctx.robot;
    let rows: Vec<usize> = (0..holdout.len()).collect();
    let pre = prepare_against(robot, holdout, ctx.data, config.orientation_lever_mm);
    let (trained, f) = ctx.full_fit(effects)?;
    let (model, theta) = if trained.effects().iter().any(|b| !b.is_reported()) {
        let mut model = Model::new(robot, effects.to_vec())?;
        if model.has_registration() {
            model = model.with_registration(initial_registration(robot, holdout, &rows)?);
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
        let refit = fit_from(robot, &model, holdout, &rows, &pre, &Start::new(theta, movable))?;
        (model, refit.theta)
    } else {
        (trained, f.theta)
    };
    let (r, _) = residuals(robot, &model, &theta, holdout, &rows, &pre, false)?;
    Ok(Stats::of(&norms(&r, pre.stride())))
}

/// The model of `effects` (the always-estimated blocks are added) fitted on all of `data` and scored on
/// `holdout` as [`diagnose`] scores its choice: for comparing a model of one's own with the diagnosis's.
pub fn evaluate(
    robot: &Robot,
    data: &Dataset,
    holdout: &Dataset,
    effects: &[Effect],
    config: &Config,
) -> Result<Stats, DiagnoseError> {
    config.validate()?;
    let ctx = Ctx::new(robot, data, config);
    let mut all = always_estimated(config, data);
    for e in effects {
        if !all.contains(e) {
            all.push(*e);
        }
    }
    transfer_score(&ctx, holdout, &all, config)
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
    // extrapolation elsewhere — the arc eligibility asks of a scale or cyclic error (`eligibility`),
    // said here of every chosen joint effect.
    for e in &report.effects {
        let Some(&number) = e.joints.first() else { continue };
        let j = number - 1;
        let (lo, hi) = crate::eligibility::arc(data, j);
        let travel = crate::eligibility::travel(robot, j);
        let need = crate::eligibility::needed_arc(travel, e.effect == "periodic", &config.eligibility);
        if robot.chain().joints()[j].kind == thermokin_chain::JointKind::Revolute && hi - lo < need {
            out.push(format!(
                "{} was identified with joint {number} between {:.1}° and {:.1}° only ({:.0}% of its travel): it may not hold outside that range — measure poses across the joint's travel",
                e.label,
                units::degrees(lo),
                units::degrees(hi),
                100.0 * (hi - lo) / travel
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

/// The sentence said first when the diagnosis does not beat the nominal model where it was not fitted:
/// the nested validation's mean error, any of its outer folds (also when the selection on all data
/// chose nothing: the procedure itself is then not to be trusted on these data), or the hold-out set's.
fn honest_end(report: &Report) -> Option<String> {
    let mut out = Vec::new();
    if let Some(n) = &report.nested {
        if n.selected.heldout_mean_mm > n.nominal.heldout_mean_mm
            || (!report.effects.is_empty() && n.selected.heldout_mean_mm >= n.nominal.heldout_mean_mm)
        {
            out.push(format!(
                "on outer folds the selection never saw, its choices' mean error {:.4} mm does not beat the nominal model's {:.4} mm",
                n.selected.heldout_mean_mm, n.nominal.heldout_mean_mm
            ));
        }
        if !n.worse_than_nominal.is_empty() {
            let list: Vec<String> = n.worse_than_nominal.iter().map(ToString::to_string).collect();
            out.push(format!(
                "in outer fold{} {} the model chosen there predicts worse than the nominal one",
                if list.len() > 1 { "s" } else { "" },
                list.join(", ")
            ));
        }
    }
    if let Some(h) = &report.holdout
        && !report.effects.is_empty()
        && h.selected.heldout_mean_mm >= h.nominal.heldout_mean_mm
    {
        out.push(format!(
            "on the hold-out set the chosen model's mean error {:.4} mm does not beat the nominal model's {:.4} mm",
            h.selected.heldout_mean_mm, h.nominal.heldout_mean_mm
        ));
    }
    (!out.is_empty()).then(|| format!("the diagnosis does not transfer: {}", out.join("; ")))
}

/// Whether what the effects leave is the noise: the nested held-out RMS (or the selection's own CV
/// without nesting) against `√3 · σ` of the stated per-axis noise (`√(3σ² + 3(lever · σ_rot)²)` with
/// orientations fitted), with a factor 1.5 of margin (the 3-D RMS of Gaussian noise scatters by ~10 %
/// over 100 poses; a model error shows as more). With nested validation the median and 95th percentile
/// follow, robust to a few wild poses, and an outer fold holding most of the squared error is named.
fn verdict(config: &Config, report: &Report) -> String {
    let robust = match &report.nested {
        Some(n) => {
            let mut t = format!(
                " (nested held-out median {:.4} mm, 95th percentile {:.4} mm",
                n.selected.heldout_median_mm, n.selected.heldout_p95_mm
            );
            if let Some(k) = n.dominated_by {
                t +=
                    &format!("; outer fold {k} holds more than half of the squared error: the RMS is mostly that fold");
            }
            t + ")"
        }
        None => String::new(),
    };
    verdict_sentence(config, report) + &robust
}

/// The verdict's sentence, on the RMS.
fn verdict_sentence(config: &Config, report: &Report) -> String {
    let (held, how) = match &report.nested {
        Some(n) => (n.selected.heldout_rms_mm, "nested held-out"),
        None => (
            report.additive.last().map_or(report.nominal.heldout_rms_mm, |r| r.stats.heldout_rms_mm),
            "cross-validated",
        ),
    };
    let floor = match (config.noise_mm, report.orientation_lever_mm, config.orientation_noise_rad) {
        (None, ..) => None,
        (Some(sigma), None, _) => Some((sigma * 3f64.sqrt(), format!("σ = {sigma} mm per axis"))),
        (Some(sigma), Some(lever), Some(rot)) => Some((
            (3.0 * sigma * sigma + 3.0 * (lever * rot).powi(2)).sqrt(),
            // Degrees as the user gave them: the round trip through radians rounded off at 1e-9°.
            format!("σ = {sigma} mm and {}° per axis, lever {lever} mm", (units::degrees(rot) * 1e9).round() / 1e9),
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

/// The outer folds of the nested validation (their own seed: not the selection's folds).
fn nested_folds(data: &Dataset, config: &Config, outer: usize) -> crate::validation::Folds {
    folds_for(data, outer, config.seed ^ 0x0e7e_5eed, config.folds_by).folds
}

/// One outer fold's outcome and its test poses' errors under the nominal and the selected model.
type OuterOutcome = (OuterFold, Vec<f64>, Vec<f64>);

/// Nested cross-validation of the whole procedure: for each outer fold, the selection runs on the
/// training part only, the model it picks is fitted there and scored on the fold's test part; the
/// nominal model (the always-estimated blocks) is scored the same way. Every outer fold is reported on
/// its own: a fold whose model predicts its test poses worse than the nominal one is named, and so is
/// a fold that holds most of the squared error.
fn nested(
    robot: &Robot,
    data: &Dataset,
    config: &Config,
    outer: usize,
    tell: &mut (dyn FnMut(String) + Send),
) -> Result<Nested, DiagnoseError> {
    let folds = nested_folds(data, config, outer);
    let inner = Config { validation: Validation::SelectionOnly, ..config.clone() };
    let always = always_estimated(config, data);
    // Outer folds in parallel (each selection is parallel inside too; the outer level keeps both cores
    // busy through the selection's sequential parts), told as each finishes, gathered in fold order.
    let told = std::sync::Mutex::new((tell, 0usize));
    let per_fold: Vec<Option<OuterOutcome>> = folds
        .par_iter()
        .enumerate()
        .map(|(k, (train, test))| {
            if train.is_empty() || test.is_empty() {
                return Ok(None);
            }
            let subset = data.subset(train);
            let (_, effects) = select(robot, &subset, &inner)?;
            // Told as folds finish, counted (their order varies with the threads; the count does not).
            if let Ok(mut state) = told.lock() {
                state.1 += 1;
                let n = state.1;
                (state.0)(format!("nested validation, {n} of {} outer folds done", folds.len()));
            }
            let ctx = Ctx::new(robot, &subset, &inner);
            let test_set = data.subset(test);
            let test_pre = prepare_against(robot, &test_set, &subset, config.orientation_lever_mm);
            let rows: Vec<usize> = (0..test.len()).collect();
            let mut fold_norms = Vec::with_capacity(2);
            for e in [&always, &effects] {
                let (model, f) = ctx.full_fit(e)?;
                let (r, _) = residuals(robot, &model, &f.theta, &test_set, &rows, &test_pre, false)?;
                fold_norms.push(norms(&r, test_pre.stride()));
            }
            let selected = fold_norms.pop().unwrap_or_default();
            let nominal = fold_norms.pop().unwrap_or_default();
            let outcome = OuterFold {
                fold: k + 1,
                poses: test.len(),
                nominal: Stats::of(&nominal),
                selected: Stats::of(&selected),
                effects: effects.iter().filter(|e| e.is_reported()).map(Effect::label).collect(),
            };
            Ok(Some((outcome, nominal, selected)))
        })
        .collect::<Result<_, DiagnoseError>>()?;
    let mut nominal_norms = Vec::new();
    let mut selected_norms = Vec::new();
    let mut outcomes = Vec::new();
    for (outcome, nominal, selected) in per_fold.into_iter().flatten() {
        nominal_norms.extend(nominal);
        selected_norms.extend(selected);
        outcomes.push(outcome);
    }
    let total: f64 = selected_norms.iter().map(|x| x * x).sum();
    // One fold dominates when it holds more than half of the squared error with at most twice its
    // share of the poses.
    let dominated_by = outcomes
        .iter()
        .find(|f| {
            let share = f.selected.heldout_rms_mm.powi(2) * f.poses as f64 / total.max(1e-300);
            share > 0.5 && f.poses * outcomes.len() <= 2 * selected_norms.len().max(1)
        })
        .map(|f| f.fold);
    Ok(Nested {
        outer_folds: outer,
        nominal: Stats::of(&nominal_norms),
        selected: Stats::of(&selected_norms),
        selections: outcomes.iter().map(|f| f.effects.clone()).collect(),
        worse_than_nominal: outcomes
            .iter()
            .filter(|f| f.selected.heldout_rms_mm > f.nominal.heldout_rms_mm)
            .map(|f| f.fold)
            .collect(),
        dominated_by,
        folds: outcomes,
    })
}
