//! Phase 4 of the selection: backward elimination — an effect chosen early as a stand-in for later ones
//! leaves again.

use rayon::prelude::*;

use crate::config::Config;
use crate::drifts::{keeps_its_law, rising_minutes};
use crate::error::DiagnoseError;
use crate::scoring::Scorer;
use crate::selection::{Selection, without};
use crate::stats::Stats;

/// One chosen effect's removal scored: its index, the model without it on the folds (statistics and
/// errors), and the minutes its law rises in where it is an exponential drift.
type Removal = (usize, Stats, Vec<f64>, Option<(f64, f64)>);

/// Phase 4: backward elimination. While some chosen effect can leave without the gate rejecting the
/// smaller model (the full one is not significantly better held out), the one whose removal leaves the
/// lowest held-out error leaves. An effect chosen early as a stand-in for later ones goes here. An
/// exponential drift significantly better over the minutes in which it rises stays ([`crate::drifts`]).
pub(crate) fn backward(scorer: &Scorer<'_>, config: &Config, sel: &mut Selection) -> Result<(), DiagnoseError> {
    loop {
        let without: Vec<Removal> = (sel.always..sel.effects.len())
            .into_par_iter()
            .map(|k| {
                let rest = without(&sel.effects, k);
                let (s, e) = scorer.heldout_errors(&rest, &scorer.folds)?;
                Ok((k, s, e, rising_minutes(scorer, &sel.effects, k)?))
            })
            .collect::<Result<_, DiagnoseError>>()?;
        let removable = without
            .into_iter()
            .filter(|(_, _, e, rising)| !keeps_its_law(scorer, config, e, &sel.errors, *rising))
            .min_by(|a, b| a.1.heldout_rms_mm.total_cmp(&b.1.heldout_rms_mm));
        let Some((k, stats, errors, _)) = removable else { return Ok(()) };
        let gone = sel.effects[k];
        let mut rest = sel.effects.clone();
        rest.remove(k);
        let row = format!("− {} (backward: not significantly better with it)", gone.label());
        sel.replace(rest, stats, errors, row);
    }
}
