//! The selection, as phases over one state ([`Selection`]):
//!
//! 1. **candidates** — the catalogue for this robot and these data ([`thermokin_identify::Setup::candidates`]),
//!    and where the measurements have an order, the likeliest step of the measurement frame
//!    ([`crate::steps`]);
//! 2. **eligibility** — what the data cannot pin down is refused before anything is scored
//!    ([`crate::eligibility`]);
//! 3. **forward** — the candidate with the lowest held-out error joins while it beats the current
//!    model by more than the gate, over blocks of neighbouring poses ([`crate::forward`]);
//! 4. **backward** — every effect whose removal the gate does not reject leaves again, the least useful
//!    first ([`crate::backward`]);
//! 5. **parsimony** — an exponential drift not better than its linear twin becomes linear; each block is
//!    replaced by the smallest combination of smaller catalogue blocks it contains when that is not
//!    significantly worse ([`crate::parsimony`]); then every chosen function of a joint's angle or load
//!    that makes the model significantly worse beyond the measured poses — fitted on one half of a
//!    joint's arc, scored on the other — leaves, refused ([`crate::extrapolation`]);
//! 6. **completion** — the model completed for use (every eligible joint row, and every compliance the
//!    data determine, beside the chosen effects) unless the selected model is significantly better held
//!    out ([`crate::completion`]); then every chosen compliance coupling beside both joints' own
//!    compliances, refused where the pair's compliance matrix is not positive semidefinite
//!    ([`crate::pairs`]);
//! 7. **shrinkage** — the chosen model's static effects shrunk toward the nominal robot, as strongly as
//!    cross-validation asks ([`crate::shrinkage`]);
//! 8. **tables** — the final model on all data, its tables and relations ([`crate::tables`]).

use thermokin_identify::Effect;

use crate::backward::backward;
use crate::completion::complete;
use crate::config::Config;
use crate::eligibility::check;
use crate::error::DiagnoseError;
use crate::extrapolation::beyond_the_measured_poses;
use crate::forward::forward;
use crate::pairs::physical_pairs;
use crate::parsimony::parsimony;
use crate::profile::{Clock, Phase};
use crate::report::TableRow;
use crate::scoring::Scorer;
use crate::selection::Selection;
use crate::shrinkage::shrink;
use crate::steps::frame_steps;

/// What the selection chose, and the catalogue it chose from.
pub(crate) struct Selected {
    pub(crate) selection: Selection,
    pub(crate) catalogue: Vec<Effect>,
}

/// Phases 1–7 on the scorer's data: candidates chosen by cross-validation on its folds, each phase's
/// wall time added to `clock`.
pub(crate) fn select(scorer: &Scorer<'_>, config: &Config, clock: &Clock) -> Result<Selected, DiagnoseError> {
    let data = scorer.data;
    let needed = config.minimum_poses();
    if data.len() < needed {
        return Err(DiagnoseError::TooFewMeasurements { count: data.len(), folds: config.folds, needed });
    }
    let setup = config.setup();
    let always = setup.always_estimated(data);
    // 1–2. Candidates and eligibility.
    let (catalogue, eligible, mut selection) = clock.time(Phase::Eligibility, || {
        let mut catalogue = setup.candidates(scorer.robot, data)?;
        // What only the order of measuring shows: a step of the measurement frame.
        catalogue.extend(frame_steps(scorer, &always, config.order)?);
        let (eligible, refused) = check(scorer, &always, &catalogue, &config.eligibility)?;
        let (nominal, nominal_errors) = scorer.heldout_errors(&always, &scorer.folds)?;
        let (_, nominal_fit) = scorer.full_fit(&always)?;
        let selection = Selection {
            effects: always.clone(),
            always: always.len(),
            current: nominal,
            errors: nominal_errors,
            steps: Vec::new(),
            additive: vec![TableRow { model: "nominal".into(), stats: nominal }],
            bic: vec![scorer.bic_of(&nominal_fit)],
            theta: nominal_fit.theta,
            skipped: Vec::new(),
            refused,
            stopped_quotes: Vec::new(),
            shrinkage: 0.0,
            fallback: None,
        };
        Ok::<_, DiagnoseError>((catalogue, eligible, selection))
    })?;
    // 3–7.
    clock.time(Phase::Forward, || forward(scorer, config, &mut selection, eligible.clone()))?;
    clock.time(Phase::Backward, || backward(scorer, config, &mut selection))?;
    clock.time(Phase::Parsimony, || parsimony(scorer, config, &mut selection, &eligible))?;
    let beyond = clock.time(Phase::Extrapolation, || beyond_the_measured_poses(scorer, config, &mut selection))?;
    let eligible: Vec<Effect> = eligible.into_iter().filter(|e| !beyond.contains(e)).collect();
    clock.time(Phase::Completion, || complete(scorer, config, &mut selection, &eligible))?;
    clock.time(Phase::Pairs, || physical_pairs(scorer, &mut selection, &eligible, config.gate_standard_errors))?;
    clock.time(Phase::Shrinkage, || shrink(scorer, config, &mut selection))?;
    Ok(Selected { selection, catalogue })
}
