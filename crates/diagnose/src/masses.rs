//! Whether the data agree with the robot file's masses. A gravity compliance on the file's masses
//! (`joint_compliance[j]`, one stiffness per joint) holds the shape of each joint's torque over the poses
//! as the masses give it; the same compliance with its loads lumped and identified from the data
//! ([`thermokin_identify::Effect::LumpedCompliance`]) holds any shape the links' masses can make. When
//! the chosen model with every such compliance lumped predicts the selection's held-out poses
//! significantly better (the selection's gate), the masses are what the data disagree with: the report
//! says so and how to diagnose without them (`--masses ignore`).

use thermokin_identify::Effect;

use crate::config::{Config, Masses};
use crate::error::DiagnoseError;
use crate::scoring::{Scorer, significantly_better};
use crate::selection::Selection;

/// The sentence saying that the data disagree with the file's masses, if they do, for the selection's
/// model (its held-out errors on the scorer's folds beside the lumped model's, fitted at the same prior
/// strength).
pub(crate) fn disagreement(
    scorer: &Scorer<'_>,
    config: &Config,
    sel: &Selection,
) -> Result<Option<String>, DiagnoseError> {
    let effects = &sel.effects;
    let compliant: Vec<usize> = effects
        .iter()
        .filter_map(|e| match e {
            Effect::JointCompliance(j) => Some(j.number()),
            _ => None,
        })
        .collect();
    if compliant.is_empty() || config.masses == Masses::Ignored {
        return Ok(None);
    }
    let lumped: Vec<Effect> = effects
        .iter()
        .map(|&e| match e {
            Effect::JointCompliance(j) => Effect::lumped_compliance(scorer.robot, j).unwrap_or(e),
            _ => e,
        })
        .collect();
    let (file, file_errors) = (sel.current, &sel.errors);
    let held = scorer.heldout_fits_with(&lumped, &scorer.folds, sel.shrinkage)?;
    let (data, data_errors) = (held.stats, held.errors);
    if !significantly_better(file_errors, &data_errors, config.gate_standard_errors, &scorer.blocks) {
        return Ok(None);
    }
    let joints: Vec<String> = compliant.iter().map(usize::to_string).collect();
    Ok(Some(format!(
        "the data disagree with the robot file's masses: the gravity compliance of joint {} with its loads identified from the data predicts the held-out poses better than on the file's masses ({:.4} → {:.4} mm RMS on the selection's folds) — check the file's link masses and centres, or diagnose with --masses ignore",
        joints.join(", "),
        file.heldout_rms_mm,
        data.heldout_rms_mm
    )))
}
