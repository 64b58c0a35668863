//! The selection's last phase: the final model on all data (shrunk as phase 7 chose) and what the report says of it — the
//! leave-one-out table, each effect with its parameters and relations, the fitted frames, the
//! identifiability of the final model and where its residuals lie (the selection's own, optimistic
//! scores).

use rayon::prelude::*;
use thermokin_chain::{Chain, FixedRow, units, xyz_angles_for_output};
use thermokin_identify::{Effect, Fit, MAX_ITERATIONS, Model, fit, observability, residuals_and_jacobian};

use crate::config::Config;
use crate::error::DiagnoseError;
use crate::folds::describe;
use crate::report::{
    Breakdown, EffectReport, FittedFrames, Identifiability, ParameterValue, PoseReport, TableRow, breakdown,
    residual_vectors,
};
use crate::scoring::{Relation, Scorer};
use crate::select::Selected;
use crate::selection::{Joined, Selection, requote, without};
use crate::stats::Stats;

/// What the selection reports of its choice: everything in a report but the validation of the whole
/// procedure (nested, hold-out) and the verdict.
pub(crate) struct Tables {
    /// The effects of the final model (the always-estimated blocks first).
    pub(crate) effects: Vec<Effect>,
    /// The prior's strength the final model is fitted with ([`crate::shrinkage`]; 0: none).
    pub(crate) shrinkage: f64,
    /// The reported effects, main cause first (the order of `reports`).
    pub(crate) main_first: Vec<Effect>,
    pub(crate) nominal: Stats,
    pub(crate) validation: String,
    pub(crate) orientation_lever_mm: Option<f64>,
    /// The diagnosed effects' reports, main cause first.
    pub(crate) reports: Vec<EffectReport>,
    /// The rows and compliances the completion added, in the same order ([`crate::Report::completed`]).
    pub(crate) completed: Vec<EffectReport>,
    pub(crate) additive: Vec<TableRow>,
    pub(crate) leave_one_out: Vec<TableRow>,
    pub(crate) identifiability: Identifiability,
    pub(crate) residuals_before: Breakdown,
    pub(crate) residuals_after: Breakdown,
    /// Every measurement's position residual under the nominal and the final model, mm.
    pub(crate) vectors_before: Vec<[f64; 3]>,
    pub(crate) vectors_after: Vec<[f64; 3]>,
    pub(crate) bic: Vec<f64>,
    pub(crate) frames: FittedFrames,
    pub(crate) calibrated: Chain,
    pub(crate) identified: thermokin_deform::RobotModel,
    /// What the final fit says of itself (a fit stopped by its iteration limit).
    pub(crate) warnings: Vec<String>,
}

/// The tables of `selected` on the scorer's data.
pub(crate) fn tables(scorer: &Scorer<'_>, config: &Config, selected: Selected) -> Result<Tables, DiagnoseError> {
    let (robot, data) = (scorer.robot, scorer.data);
    let Selected { selection: mut sel, catalogue } = selected;
    requote(scorer, &mut sel, &config.plausibility)?;
    let effects = sel.effects.clone();
    let shrinkage = sel.shrinkage;
    let (model, final_fit) = scorer.fit_shrunk(&effects, &scorer.all(), shrinkage)?;
    let all = scorer.all();
    let (_, jac) = residuals_and_jacobian(robot, &model, &final_fit.theta, data, &all, &scorer.terms)?;
    let observability = observability(&jac, &final_fit.free);
    // The diagnosed effects' values and their leave-one-out errors come from their own model: beside a
    // complete geometry a zero offset is nearly a combination of its rows' rotations (its value there is
    // a share, not the cause) and any one row's removal is made up by the others.
    let completion: Vec<Effect> =
        sel.steps.iter().filter(|s| s.joined == Joined::Completion).map(|s| s.effect).collect();
    let diagnosed: Vec<Effect> = effects.iter().copied().filter(|e| !completion.contains(e)).collect();
    let diagnosed_fit = if completion.is_empty() { None } else { Some(scorer.full_fit(&diagnosed)?) };
    let in_diagnosed = leave_one_out(scorer, &diagnosed, sel.always..diagnosed.len(), 0.0)?;
    let rows_at: Vec<usize> = (0..effects.len()).filter(|&k| completion.contains(&effects[k])).collect();
    // A completion row's removal is scored in the fit the completed model is scored in: with its prior.
    let in_completed = leave_one_out(scorer, &effects, rows_at, shrinkage)?;
    let without: Vec<(usize, Stats)> = in_diagnosed
        .into_iter()
        .map(|(k, s)| (effects.iter().position(|e| *e == diagnosed[k]).unwrap_or(k), s))
        .chain(in_completed)
        .collect();
    let leave_one_out =
        without.iter().map(|(k, s)| TableRow { model: format!("all − {}", effects[*k].label()), stats: *s }).collect();
    let fitted = Fitted { completed: (&model, &final_fit), diagnosed: diagnosed_fit.as_ref().map(|(m, f)| (m, f)) };
    let mut reports: Vec<(Effect, EffectReport)> = without
        .iter()
        .map(|(k, _)| effects[*k])
        .zip(effect_reports(scorer, &fitted, &sel, &without, &catalogue)?)
        .collect();
    // Main cause first: the effect whose removal hurts most.
    reports.sort_by(|(_, a), (_, b)| (b.heldout_rms_without_mm).total_cmp(&a.heldout_rms_without_mm));
    let (main_first, reports): (Vec<Effect>, Vec<EffectReport>) = reports.into_iter().unzip();
    let completion: Vec<Effect> =
        sel.steps.iter().filter(|s| s.joined == Joined::Completion).map(|s| s.effect).collect();
    let mut completed = Vec::new();
    let mut diagnosed_reports = Vec::new();
    for (e, r) in main_first.iter().zip(reports) {
        if completion.contains(e) { completed.push(r) } else { diagnosed_reports.push(r) }
    }
    let reports = diagnosed_reports;
    let nominal_model = scorer.model(&effects[..sel.always], &all)?;
    let nominal_fit = fit(robot, &nominal_model, data, &all, &scorer.terms)?;
    let (calibrated, left_out) = model.calibrated_chain(robot, &final_fit.theta)?;
    let frames = fitted_frames(&model, &calibrated, robot.chain().tool(), &effects);
    // The identified robot carries every chosen effect: the model written is the model scored.
    let identified = model.robot_model(robot, &final_fit.theta, data)?;
    debug_assert!(left_out.iter().all(|e| !e.is_static()));
    // A claim checked, not assumed: the parameters reported and exported are a least-squares minimum only
    // if the final fit ended by its own test.
    let warnings = if final_fit.converged {
        Vec::new()
    } else {
        vec![format!(
            "the final model's fit stopped at its {MAX_ITERATIONS}-iteration limit before converging: its parameters (and an exported robot) are not at the least-squares minimum"
        )]
    };
    Ok(Tables {
        nominal: sel.additive[0].stats,
        validation: describe(data, config),
        orientation_lever_mm: scorer.terms.lever_mm,
        reports,
        completed,
        leave_one_out,
        identifiability: Identifiability {
            observability,
            fixed: final_fit.fixed.clone(),
            skipped_candidates: sel.skipped,
            not_identifiable: sel.refused,
            correlated: final_fit.correlated.clone(),
        },
        residuals_before: breakdown(robot, data, &nominal_model, &nominal_fit.theta, &scorer.terms)?,
        residuals_after: breakdown(robot, data, &model, &final_fit.theta, &scorer.terms)?,
        vectors_before: residual_vectors(robot, data, &nominal_model, &nominal_fit.theta, &scorer.terms)?,
        vectors_after: residual_vectors(robot, data, &model, &final_fit.theta, &scorer.terms)?,
        additive: sel.additive,
        bic: sel.bic,
        frames,
        calibrated,
        identified,
        warnings,
        effects,
        shrinkage,
        main_first,
    })
}

/// The held-out statistics of the model `effects` without each of the effects at `at` (indices into
/// `effects`), fitted with the prior of strength `lambda` (0: least squares).
fn leave_one_out(
    scorer: &Scorer<'_>,
    effects: &[Effect],
    at: impl IntoIterator<Item = usize>,
    lambda: f64,
) -> Result<Vec<(usize, Stats)>, DiagnoseError> {
    at.into_iter()
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|k| {
            let rest = without(effects, k);
            Ok((k, scorer.heldout_fits_with(&rest, &scorer.folds, lambda)?.stats))
        })
        .collect()
}

/// Where reported parameters come from: the final model's fit, and — when the geometry was completed —
/// the fit of the diagnosed effects alone, which their values are read from.
struct Fitted<'m> {
    completed: (&'m Model, &'m Fit),
    diagnosed: Option<(&'m Model, &'m Fit)>,
}

/// Each reported effect of the final model: its parameters in report units (or why fixed), its steps,
/// its leave-one-out error, and how it relates to the catalogue's blocks on the data.
fn effect_reports(
    scorer: &Scorer<'_>,
    fitted: &Fitted<'_>,
    sel: &Selection,
    without: &[(usize, Stats)],
    catalogue: &[Effect],
) -> Result<Vec<EffectReport>, DiagnoseError> {
    without
        .iter()
        .map(|(k, w)| {
            let e = fitted.completed.0.effects()[*k];
            let (model, fit) = match fitted.diagnosed {
                Some((m, f)) if m.effects().contains(&e) => (m, f),
                _ => fitted.completed,
            };
            let names = model.parameter_names();
            let at = model.effects().iter().position(|x| *x == e).unwrap_or(*k);
            let o = model.offsets()[at];
            let parameters = (0..e.len())
                .map(|p| {
                    let v = fit.theta[o + p];
                    let s = fit.std[o + p];
                    let fixed = fit.fixed.iter().find(|f| f.parameter == names[o + p]).map(|f| f.reason.clone());
                    let std = (fixed.is_none() && s.is_finite()).then(|| e.to_report_units(p, s).abs());
                    (names[o + p].clone(), ParameterValue { value: e.to_report_units(p, v), std, fixed })
                })
                .collect();
            let relations = scorer.relations(e, catalogue)?;
            let of = |kind: Relation| -> Vec<String> {
                relations.iter().filter(|(_, r)| *r == kind).map(|(b, _)| b.label()).collect()
            };
            let step = sel.steps.iter().find(|s| s.effect == e);
            Ok(EffectReport {
                effect: e.kind_name().to_string(),
                label: e.label(),
                joints: e.joint().map(|j| vec![j.number()]).unwrap_or_default(),
                heldout_rms_before_mm: step.and_then(|s| s.before_mm),
                heldout_rms_after_mm: step.map(|s| s.after_mm),
                joined: step.map_or_else(|| "forward step".into(), |s| s.joined.describe()),
                heldout_rms_without_mm: w.heldout_rms_mm,
                parameters,
                equivalent: of(Relation::Equivalent),
                contained_in: of(Relation::ContainedIn),
                contains: of(Relation::Contains),
            })
        })
        .collect()
}

/// The always-estimated frames as fitted: the registration (the measurement frame's pose of the base),
/// the tool point (in the tip frame of the robot as given, `given_tool` its last joint → tip row, and in
/// the last joint's frame) and the probe's rotation, where estimated.
fn fitted_frames(model: &Model, calibrated: &Chain, given_tool: &FixedRow, effects: &[Effect]) -> FittedFrames {
    FittedFrames {
        registration: model.has_registration().then(|| {
            let world_from_base = calibrated.base().pose();
            let t = world_from_base.translation.vector;
            let r = xyz_angles_for_output(world_from_base.rotation.to_rotation_matrix().matrix());
            PoseReport {
                position_mm: [t.x, t.y, t.z],
                xyz_euler_deg: [units::degrees(r.x), units::degrees(r.y), units::degrees(r.z)],
            }
        }),
        tool_point_mm: effects.contains(&Effect::ToolPoint).then(|| {
            let in_joint_frame = calibrated.tool().translation + calibrated.tool().error.translation;
            let t = (given_tool.pose().inverse() * nalgebra::Point3::from(in_joint_frame)).coords;
            [t.x, t.y, t.z]
        }),
        tool_point_joint_frame_mm: effects.contains(&Effect::ToolPoint).then(|| {
            let t = calibrated.tool().translation + calibrated.tool().error.translation;
            [t.x, t.y, t.z]
        }),
        tool_rotation_deg: effects.contains(&Effect::ToolRotation).then(|| {
            let r = calibrated.tool().error.rotation;
            [units::degrees(r.x), units::degrees(r.y), units::degrees(r.z)]
        }),
    }
}
