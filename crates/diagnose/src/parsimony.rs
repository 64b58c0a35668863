//! Phase 5 of the selection: parsimony. An exponential drift not significantly better than its linear
//! twin becomes the linear one, and a drift not significantly better than its row's static deviation
//! becomes the static one; then each chosen block is replaced by the smallest combination (one or
//! two) of eligible smaller catalogue blocks its directions contain on the data (rank test) when the
//! larger is not significantly better held out — the same gate, the other way round. Two offsets of
//! parallel joints inside one link row come out as the two offsets.

use thermokin_identify::{DriftShape, Effect};

use crate::config::Config;
use crate::drifts::{keeps_its_law, rising_minutes};
use crate::error::DiagnoseError;
use crate::scoring::{Relation, Scorer, significantly_better};
use crate::selection::{Joined, Selection, Step, without};
use crate::stats::Stats;

/// Both rules of the phase, in order.
pub(crate) fn parsimony(
    scorer: &Scorer<'_>,
    config: &Config,
    sel: &mut Selection,
    eligible: &[Effect],
) -> Result<(), DiagnoseError> {
    linear_for_exponential(scorer, config, sel)?;
    static_for_drift(scorer, config, sel, eligible)?;
    let mut k = sel.always;
    while k < sel.effects.len() {
        k += match smaller_replacement(scorer, config, sel, k, eligible)? {
            Some(r) => {
                let n = r.blocks.len();
                r.apply(sel, k);
                n
            }
            None => 1,
        };
    }
    Ok(())
}

/// An exponential drift not significantly better than its linear twin — over the session, nor over the
/// minutes in which it rises ([`crate::drifts`]) — becomes the linear one.
fn linear_for_exponential(scorer: &Scorer<'_>, config: &Config, sel: &mut Selection) -> Result<(), DiagnoseError> {
    for k in sel.always..sel.effects.len() {
        if let Effect::ThermalDrift(j, DriftShape::Exponential) = sel.effects[k] {
            let mut swapped = sel.effects.clone();
            swapped[k] = Effect::ThermalDrift(j, DriftShape::Linear);
            let (stats, errors) = scorer.heldout_errors(&swapped, &scorer.folds)?;
            let rising = rising_minutes(scorer, &sel.effects, k)?;
            if !keeps_its_law(scorer, config, &errors, &sel.errors, rising) {
                let row = format!("{} replaces the exponential (not significantly worse)", swapped[k].label());
                // The linear drift takes the exponential's step in the additive table.
                for s in sel.steps.iter_mut().filter(|s| s.effect == sel.effects[k]) {
                    s.effect = swapped[k];
                }
                sel.replace(swapped, stats, errors, row);
            }
        }
    }
    Ok(())
}

/// A thermal drift not significantly better than its row's static deviation becomes the static one: a
/// drift over before the data begin (an exponential whose time constant is short against the first
/// measurement) or one the data cannot tell from constant is a static deviation in disguise, and the
/// static explanation wins — it holds at every time, the drift's extrapolates. An exponential drift
/// significantly better over the minutes in which it rises stays, whatever its plateau makes of the
/// session's average ([`crate::drifts`]): those minutes are what its compensation is for.
fn static_for_drift(
    scorer: &Scorer<'_>,
    config: &Config,
    sel: &mut Selection,
    eligible: &[Effect],
) -> Result<(), DiagnoseError> {
    for k in sel.always..sel.effects.len() {
        let Effect::ThermalDrift(j, shape) = sel.effects[k] else { continue };
        let row = Effect::LinkDeviation(j);
        if shape == DriftShape::Temperature || !eligible.contains(&row) || sel.effects.contains(&row) {
            continue;
        }
        let mut swapped = sel.effects.clone();
        swapped[k] = row;
        let (stats, errors) = scorer.heldout_errors(&swapped, &scorer.folds)?;
        let rising = rising_minutes(scorer, &sel.effects, k)?;
        if !keeps_its_law(scorer, config, &errors, &sel.errors, rising) {
            let drift = sel.effects[k];
            let text =
                format!("{} replaces {} (a static deviation, not significantly worse)", row.label(), drift.label());
            for s in sel.steps.iter_mut().filter(|s| s.effect == drift) {
                s.effect = row;
            }
            sel.replace(swapped, stats, errors, text);
        }
    }
    Ok(())
}

/// Smaller blocks that replace a larger one, scored.
struct Replacement {
    /// The block replaced.
    big: Effect,
    /// The smaller blocks, in the order they take its place.
    blocks: Vec<Effect>,
    /// Their parameters in all.
    size: usize,
    stats: Stats,
    errors: Vec<f64>,
}

impl Replacement {
    /// Puts the smaller blocks in the place of the larger one at `k`, their steps taking its step.
    fn apply(self, sel: &mut Selection, k: usize) {
        let mut with = without(&sel.effects, k);
        with.splice(k..k, self.blocks.iter().copied());
        let names: Vec<String> = self.blocks.iter().map(Effect::label).collect();
        let parameters = |n: usize| if n == 1 { "1 parameter".to_string() } else { format!("{n} parameters") };
        // Said as measured: not significantly worse by the gate, its RMS before and after.
        let row = format!(
            "{} replaces {} (not significantly worse held out, RMS {:.4} → {:.4} mm, with {} instead of {})",
            names.join(" + "),
            self.big.label(),
            sel.current.heldout_rms_mm,
            self.stats.heldout_rms_mm,
            parameters(self.size),
            self.big.len()
        );
        for (s, &c) in sel.steps.iter_mut().filter(|s| s.effect == self.big).zip(&self.blocks) {
            s.effect = c;
        }
        for &c in self.blocks.iter().skip(1) {
            sel.steps.push(Step {
                effect: c,
                before_mm: None,
                after_mm: self.stats.heldout_rms_mm,
                joined: Joined::Replacing { larger: self.big },
            });
        }
        sel.replace(with, self.stats, self.errors, row);
    }
}

/// The smallest combination of one or two eligible smaller blocks that the chosen block at `k` contains
/// on the data, each adding something identifiable without it, and not significantly worse held out;
/// ties to the lower error.
fn smaller_replacement(
    scorer: &Scorer<'_>,
    config: &Config,
    sel: &Selection,
    k: usize,
    eligible: &[Effect],
) -> Result<Option<Replacement>, DiagnoseError> {
    let big = sel.effects[k];
    let mut smaller: Vec<Effect> = Vec::new();
    for &c in eligible.iter().filter(|c| c.len() < big.len() && !sel.effects.contains(c)) {
        if scorer.relations(c, &[big])?.iter().any(|(_, r)| *r == Relation::ContainedIn) {
            smaller.push(c);
        }
    }
    // Combinations of one or two smaller blocks with fewer parameters than the larger.
    let rest = without(&sel.effects, k);
    let mut combos: Vec<Vec<Effect>> = smaller.iter().map(|&c| vec![c]).collect();
    for (a, &x) in smaller.iter().enumerate() {
        for &y in &smaller[a + 1..] {
            if x.len() + y.len() < big.len() {
                combos.push(vec![x, y]);
            }
        }
    }
    let mut best: Option<Replacement> = None;
    for blocks in combos {
        let mut with = rest.clone();
        let mut adds = true;
        for &c in &blocks {
            adds &= scorer.new_free(&with, c)?.new_free > 0;
            with.push(c);
        }
        if !adds {
            continue;
        }
        let (stats, errors) = scorer.heldout_errors(&with, &scorer.folds)?;
        if significantly_better(&errors, &sel.errors, config.gate_standard_errors, &scorer.blocks) {
            continue; // The larger block is significantly better.
        }
        let size: usize = blocks.iter().map(Effect::len).sum();
        let better = match &best {
            None => true,
            Some(b) => (size, stats.heldout_rms_mm) < (b.size, b.stats.heldout_rms_mm),
        };
        if better {
            best = Some(Replacement { big, blocks, size, stats, errors });
        }
    }
    Ok(best)
}
