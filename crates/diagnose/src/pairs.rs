//! Phase 6b of the selection: a coupled pair made physical. A compliance coupling of joints `j` and
//! `j+1` ([`Effect::ComplianceCoupling`], `c`) is the off-diagonal term of the pair's compliance matrix
//!
//! ```text
//! ⎡ kⱼ  c   ⎤
//! ⎣ c   kⱼ₊₁ ⎦
//! ```
//!
//! whose diagonal are the two joints' own gravity compliances ([`Effect::JointCompliance`]). A real
//! drive stores the work its load does on it: the matrix is positive semidefinite — `kⱼ ≥ 0`,
//! `kⱼ₊₁ ≥ 0` and `c² ≤ kⱼ·kⱼ₊₁` — and a matrix that is not has a load under which the pair would
//! rise against it. So the phase puts beside every chosen coupling both joints' own compliances
//! (eligible ones; a compliance the completion left out as not determined enough is still part of the
//! pair), fits the model on all data, and where the pair is not positive semidefinite — with the three
//! values fitted — fits it on the cone's boundary instead: the cost is convex in `(kⱼ, c, kⱼ₊₁)` (the
//! deflections are linear in them), so where its minimum lies outside the cone the least-squares pair
//! inside it lies on the boundary, the matrices of rank one `w wᵀ` — one elastic element both joints load
//! ([`Effect::CompliancePair`], which replaces the coupling and both compliances) where that passes the
//! selection's gate against the model without the coupling — a single joint's sag lies on the boundary
//! too, `w = (√k, 0)`, and there the second element is a parameter the poses do not ask for; otherwise the
//! coupling leaves with the compliances it brought. The free coupling is recorded as refused either way,
//! with what replaced it. The coupling itself is not gated here (the pair is what it means), and the
//! held-out figures are rescored.
//!
//! (Until 2026-11-30 a pair that was not positive semidefinite was always dropped: on the real WAM's grid,
//! whose default folds choose `compliance_coupling[5]` (k5 = 5.29, k6 = 1.32, c = 3.68 °/N·m fitted
//! beside it), the random poses went to 2.5234 mm refitted; on the boundary, 2.3489.)
//!
//! The pair is judged in the fit it would join: with the prior the completion chose for the model
//! ([`crate::completion`]), kept. (Until issue #49 it was judged in the least-squares fit of the complete
//! geometry and the prior chosen anew after — a fit that on the real UR10's week walked a wrist row out to
//! tens of millimetres until the iteration limit, and the prior chosen around such fits.)

use thermokin_chain::units;
use thermokin_identify::{Effect, JointIndex};

use crate::error::DiagnoseError;
use crate::report::Refusal;
use crate::scoring::{Scorer, significantly_better};
use crate::selection::{Joined, Selection, Step};

/// Phase 6b ([module documentation](self)).
pub(crate) fn physical_pairs(
    scorer: &Scorer<'_>,
    sel: &mut Selection,
    eligible: &[Effect],
    gate: f64,
) -> Result<(), DiagnoseError> {
    let before = sel.effects.clone();
    // The pairs fitted on the cone's boundary.
    let mut bounded: Vec<(JointIndex, JointIndex)> = Vec::new();
    loop {
        let (effects, pairs) = pair_set(scorer, sel, &before, eligible, &bounded);
        if pairs.is_empty() && effects == before {
            return Ok(());
        }
        let (model, full) = scorer.fit_shrunk(&effects, &scorer.all(), sel.shrinkage)?;
        let value = |e: Effect| effects.iter().position(|x| *x == e).map(|i| full.theta[model.offsets()[i]]);
        let broken = pairs.iter().find_map(|&(j, n)| {
            let c = value(Effect::ComplianceCoupling(j))?;
            let (kj, kn) =
                (value(Effect::JointCompliance(j)).unwrap_or(0.0), value(Effect::JointCompliance(n)).unwrap_or(0.0));
            (kj < 0.0 || kn < 0.0 || c * c > kj * kn).then_some((j, n, kj, kn, c))
        });
        let Some((j, n, kj, kn, c)) = broken else { return accept(scorer, sel, &before, effects) };
        // The free coupling is refused either way; the pair goes on the boundary where it passes the
        // selection's gate against the model without it, as any effect joins (a single joint's sag is on
        // the boundary too, `w = (√k, 0)`: there the second element is a parameter the poses do not ask for).
        sel.refused.push(not_physical(j, n, kj, kn, c, None));
        let mut with = bounded.clone();
        with.push((j, n));
        let errors = |b: &[(JointIndex, JointIndex)]| -> Result<Vec<f64>, DiagnoseError> {
            let (set, _) = pair_set(scorer, sel, &before, eligible, b);
            Ok(scorer.heldout_fits_with(&set, &scorer.folds, sel.shrinkage)?.errors)
        };
        if significantly_better(&errors(&bounded)?, &errors(&with)?, gate, &scorer.blocks) {
            // The refusal just recorded (the sets above leave the refused coupling out) names the pair.
            if let Some(last) = sel.refused.last_mut() {
                *last = not_physical(j, n, kj, kn, c, Some(Effect::CompliancePair(j)));
            }
            bounded = with;
        }
    }
}

/// The effects the phase fits next and the coupled pairs among them: the selection's effects without
/// the refused couplings, each remaining coupling with both joints' own compliances (eligible ones), and
/// each pair `bounded` as its [`Effect::CompliancePair`] in place of its joints' compliances.
fn pair_set(
    scorer: &Scorer<'_>,
    sel: &Selection,
    before: &[Effect],
    eligible: &[Effect],
    bounded: &[(JointIndex, JointIndex)],
) -> (Vec<Effect>, Vec<(JointIndex, JointIndex)>) {
    let mut effects = before.iter().copied().filter(|e| !refused(sel, *e)).collect::<Vec<_>>();
    let pairs: Vec<(JointIndex, JointIndex)> = effects
        .iter()
        .filter_map(|e| match e {
            Effect::ComplianceCoupling(j) => j.next(scorer.robot).map(|n| (*j, n)),
            _ => None,
        })
        .collect();
    for &(j, n) in &pairs {
        for k in [j, n] {
            let own = Effect::JointCompliance(k);
            if !effects.contains(&own) && eligible.contains(&own) {
                effects.push(own);
            }
        }
    }
    for &(j, n) in bounded {
        effects.retain(|e| ![Effect::JointCompliance(j), Effect::JointCompliance(n)].contains(e));
        effects.push(Effect::CompliancePair(j));
    }
    (effects, pairs)
}

/// Whether `e` was refused (by this phase: a coupling whose pair is not positive semidefinite).
fn refused(sel: &Selection, e: Effect) -> bool {
    matches!(e, Effect::ComplianceCoupling(_)) && sel.refused.iter().any(|r| r.effect == e.label())
}

/// The refusal of a coupling whose pair's compliance matrix is not positive semidefinite, naming the
/// pair fitted on the cone's boundary `instead` where there is one.
fn not_physical(j: JointIndex, n: JointIndex, kj: f64, kn: f64, c: f64, instead: Option<Effect>) -> Refusal {
    let deg = |x: f64| format!("{:.3e}", units::degrees(x));
    let instead =
        instead.map_or(String::new(), |e| format!(" — the pair is fitted on the boundary instead, {}", e.label()));
    Refusal {
        effect: Effect::ComplianceCoupling(j).label(),
        reason: format!(
            "beside the joints' own compliances it makes their compliance matrix not positive semidefinite (k{} = {}, k{} = {}, c = {} °/N·m; c² must not exceed k{}·k{}): some load would make the pair rise against it{}",
            j.number(),
            deg(kj),
            n.number(),
            deg(kn),
            deg(c),
            j.number(),
            n.number(),
            instead
        ),
        remedy: format!(
            "measure poses that load joints {} and {} apart from each other (one stretched, the other folded, and the other way round)",
            j.number(),
            n.number()
        ),
    }
}

/// The model with the pairs' compliances and without the refused couplings, rescored on the selection's
/// folds; the compliances that joined recorded as completing the pairs.
fn accept(
    scorer: &Scorer<'_>,
    sel: &mut Selection,
    before: &[Effect],
    effects: Vec<Effect>,
) -> Result<(), DiagnoseError> {
    if effects == before {
        return Ok(());
    }
    let lambda = sel.shrinkage;
    let held = scorer.heldout_fits_with(&effects, &scorer.folds, lambda)?;
    let (stats, errors) = (held.stats, held.errors);
    let joined: Vec<Effect> = effects.iter().copied().filter(|e| !before.contains(e)).collect();
    let gone: Vec<Effect> = before.iter().copied().filter(|e| !effects.contains(e)).collect();
    for &e in &joined {
        sel.steps.push(Step { effect: e, before_mm: None, after_mm: stats.heldout_rms_mm, joined: Joined::Completion });
    }
    sel.steps.retain(|s| !gone.contains(&s.effect));
    let names = |v: &[Effect]| v.iter().map(Effect::label).collect::<Vec<_>>().join(", ");
    let row = match (joined.is_empty(), gone.is_empty()) {
        (false, true) => format!("the coupled pairs' own compliances: + {}", names(&joined)),
        (true, false) => format!("− {} (its pair not positive semidefinite)", names(&gone)),
        _ if joined.iter().any(|e| matches!(e, Effect::CompliancePair(_))) => format!(
            "the coupled pairs on the boundary of the positive semidefinite: + {}, − {}",
            names(&joined),
            names(&gone)
        ),
        _ => format!("the coupled pairs: + {}, − {} (not positive semidefinite)", names(&joined), names(&gone)),
    };
    sel.replace(effects, stats, errors, row);
    sel.shrinkage = lambda;
    Ok(())
}
