//! Phase 5b of the selection: beyond the measured poses. A chosen effect that is a function of a joint's
//! angle or load — a gear-ratio scale, a cyclic error, a gravity compliance or a coupling — leaves again
//! when the model is significantly worse with it beyond the poses it was fitted on, by more than it gains
//! among them.
//!
//! **Why.** The selection's folds test each pose among training poses around it (blocks of neighbouring
//! arm configurations): an effect that follows a trend *inside* the measured poses passes, whatever it
//! does outside them. A calibration is used outside them: in the arm's other configurations. On the real
//! UR10 `joint_scale[3]` gained 0.0009 mm RMS among series C's neighbouring poses (0.4856 → 0.4847) and
//! passed the gate; fitted on the lower half of C's joint-2 arc it comes out at −7.7e-4, on the upper
//! half at +5.0e-4, and series B — the same arm in other configurations, one tracker frame — was missed
//! by 0.853 mm with it and 0.632 without (the model's least-squares fit used as exported). The phase
//! scores the model on folds that extrapolate ([`joint_halves`]: for every joint the data move, one half
//! of its measured arc fitted and the other half scored, both ways). An effect leaves when the model
//! without it is significantly better there — the selection's own gate, over the same blocks of
//! neighbouring poses — and what it costs there (held-out RMS) exceeds what it gains on the selection's
//! folds: the export is used among the measured poses and beyond them, and neither is known to weigh
//! more. Of those, the one with the largest excess leaves, refused with what was measured, and the phase
//! judges the smaller model again.
//!
//! **Why the gain among the poses is weighed too.** A half split extrapolates by half the measured arc;
//! where the poses cover most of the travel the robot is used over, that is further than the robot goes
//! beyond them. On a simulated IRB 140 with a two-joint coupling no catalogue effect describes, measured
//! over 80 % of every joint's travel, the half splits alone refused joint 3's cyclic error, which takes
//! poses drawn anew over the same travel from 0.0870 to 0.0817 mm; weighed, it stays. What the phase
//! cannot see: a shape whose error beyond the poses grows faster than across their own halves (a joint
//! that lags only past some angle, measured across it) — the report's warning that an effect was
//! identified over part of its joint's travel is what remains there.
//!
//! The joint rows and zero offsets are not judged here: they are the constant geometry of a rigid
//! link, which the robot's own kinematics carries to every pose; the functions of an angle or a load are
//! the catalogue's shapes, and a shape can follow another cause over part of the arm (the
//! thermal drifts are judged against their static twins, [`crate::parsimony`]). A half split is used
//! only when its fitted half has [`MIN_REDUNDANCY`] residual rows per parameter of the model: on fewer
//! poses each half's fit would bend to its own noise, and the phase stands aside.
//!
//! The diagnosis' nested validation reruns this phase inside every outer fold.

use rayon::prelude::*;
use thermokin_chain::{JointKind, Robot, units};
use thermokin_identify::{Effect, Model};

use crate::config::{Config, Extrapolation};
use crate::error::DiagnoseError;
use crate::folds::{Folds, Half, joint_halves};
use crate::outliers::MIN_REDUNDANCY;
use crate::report::Refusal;
use crate::scoring::{Scorer, significantly_better};
use crate::selection::{Selection, without};
use crate::stats::Stats;

/// Whether `e` is a function of a joint's angle or load (the shapes this phase judges).
fn shaped(e: Effect) -> bool {
    matches!(
        e,
        Effect::JointScale(_)
            | Effect::Periodic(_)
            | Effect::JointCompliance(_)
            | Effect::LumpedCompliance(..)
            | Effect::LateralCompliance(..)
            | Effect::LumpedLateralCompliance(..)
            | Effect::Straightness(_)
            | Effect::ComplianceCoupling(_)
            | Effect::Backlash(_)
    )
}

/// The half splits whose fitted half holds [`MIN_REDUNDANCY`] residual rows per parameter of `effects`.
fn usable<'h>(scorer: &Scorer<'_>, halves: &'h [Half], effects: &[Effect]) -> Result<Vec<&'h Half>, DiagnoseError> {
    let parameters = Model::new(scorer.robot, effects.to_vec())?.len();
    let stride = scorer.terms.stride();
    Ok(halves.iter().filter(|h| h.train.len() * stride >= MIN_REDUNDANCY * parameters).collect())
}

/// A model's held-out errors (in fold order) and their statistics.
struct Scored {
    stats: Stats,
    errors: Vec<f64>,
}

impl Scored {
    fn of(scorer: &Scorer<'_>, effects: &[Effect], folds: &Folds) -> Result<Self, DiagnoseError> {
        let (stats, errors) = scorer.heldout_errors(effects, folds)?;
        Ok(Self { stats, errors })
    }
}

/// The model without one chosen effect, scored both ways.
struct Without {
    /// The effect's place in the model.
    k: usize,
    /// On the extrapolating folds.
    beyond: Scored,
    /// On the selection's folds.
    among: Scored,
}

/// Phase 5b as set by [`Config::extrapolation`]. Returns the effects it removed (the completion does not
/// propose them again).
pub(crate) fn beyond_the_measured_poses(
    scorer: &Scorer<'_>,
    config: &Config,
    sel: &mut Selection,
) -> Result<Vec<Effect>, DiagnoseError> {
    let mut removed = Vec::new();
    if config.extrapolation == Extrapolation::Off {
        return Ok(removed);
    }
    let halves = joint_halves(scorer.data);
    loop {
        let used = usable(scorer, &halves, &sel.effects)?;
        let candidates: Vec<usize> = (sel.always..sel.effects.len()).filter(|&k| shaped(sel.effects[k])).collect();
        if used.is_empty() || candidates.is_empty() {
            return Ok(removed);
        }
        let folds: Folds = used.iter().map(|h| (h.train.clone(), h.test.clone())).collect();
        let blocks: Vec<usize> = used.iter().flat_map(|h| h.test.iter().map(|&i| scorer.block_of[i])).collect();
        let with = Scored::of(scorer, &sel.effects, &folds)?;
        let scored: Vec<Without> = candidates
            .into_par_iter()
            .map(|k| {
                let smaller = without(&sel.effects, k);
                Ok(Without {
                    k,
                    beyond: Scored::of(scorer, &smaller, &folds)?,
                    among: Scored::of(scorer, &smaller, &scorer.folds)?,
                })
            })
            .collect::<Result<_, DiagnoseError>>()?;
        // What an effect costs beyond the measured poses, less what it gains among them (held-out RMS):
        // the export is used in both places, and neither is known to weigh more.
        let net = |w: &Without| {
            (with.stats.heldout_rms_mm - w.beyond.stats.heldout_rms_mm)
                - (w.among.stats.heldout_rms_mm - sel.current.heldout_rms_mm)
        };
        let leaving = scored
            .into_iter()
            .filter(|w| {
                significantly_better(&with.errors, &w.beyond.errors, config.gate_standard_errors, &blocks)
                    && net(w) > 0.0
            })
            .max_by(|a, b| net(a).total_cmp(&net(b)));
        let Some(w) = leaving else { return Ok(removed) };
        let gone = sel.effects[w.k];
        sel.refused.push(refusal(scorer.robot, gone, sel.current, &with, &w, &used));
        let row = format!("− {} (costs more beyond the poses it was fitted on than it gains among them)", gone.label());
        sel.replace(without(&sel.effects, w.k), w.among.stats, w.among.errors, row);
        removed.push(gone);
    }
}

/// The refusal of `gone`, with what was measured: both scores with and without it, and the half split
/// where it costs most.
fn refusal(robot: &Robot, gone: Effect, current: Stats, with: &Scored, w: &Without, used: &[&Half]) -> Refusal {
    let worst = worst_half(used, &with.errors, &w.beyond.errors)
        .map(|x| {
            format!(", most where {} ({:.3} → {:.3} mm)", describe(robot, x.half), x.without_rms_mm, x.with_rms_mm)
        })
        .unwrap_or_default();
    Refusal {
        effect: gone.label(),
        reason: format!(
            "among neighbouring poses it takes the held-out RMS from {:.4} to {:.4} mm, but fitted on one half of a joint's measured arc and scored on the other the model is worse with it ({:.4} → {:.4} mm RMS){worst}: it does not hold beyond the poses it was fitted on",
            w.among.stats.heldout_rms_mm,
            current.heldout_rms_mm,
            w.beyond.stats.heldout_rms_mm,
            with.stats.heldout_rms_mm,
        ),
        remedy: "it follows another cause over these poses, and an export would carry it into the arm's other configurations — measure poses in more of the arm's configurations (other joint ranges, other arm branches) before it can be told".into(),
    }
}

/// The half split where an effect costs most, with both models' RMS there.
struct Worst<'h> {
    half: &'h Half,
    with_rms_mm: f64,
    without_rms_mm: f64,
}

fn worst_half<'h>(used: &[&'h Half], with: &[f64], without: &[f64]) -> Option<Worst<'h>> {
    let rms = |e: &[f64]| (e.iter().map(|x| x * x).sum::<f64>() / e.len().max(1) as f64).sqrt();
    let mut start = 0;
    let mut worst: Option<Worst<'h>> = None;
    for h in used {
        let range = start..start + h.test.len();
        start = range.end;
        let (w, o) = (rms(&with[range.clone()]), rms(&without[range]));
        if worst.as_ref().is_none_or(|x| w - o > x.with_rms_mm - x.without_rms_mm) {
            worst = Some(Worst { half: h, with_rms_mm: w, without_rms_mm: o });
        }
    }
    worst
}

/// "joint 2's poses below −138.0° predicted from those above".
fn describe(robot: &Robot, h: &Half) -> String {
    let kind = robot.chain().joints()[h.joint].kind;
    let (scored, fitted) = if h.lower_scored { ("below", "above") } else { ("at or above", "below") };
    format!(
        "joint {}'s poses {scored} {:.1}{} are predicted from those {fitted}",
        h.joint + 1,
        units::joint_value_out(kind, h.median),
        if kind == JointKind::Revolute { "°" } else { " mm" }
    )
}
