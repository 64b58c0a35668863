//! Score before you fit: every candidate of a forward step ranked by the held-out error one linearised
//! step would give it, so that only a shortlist is fitted in full (issue #23).
//!
//! The residuals `r` and the Jacobian `A` of a model holding the current effects at their fit on all data
//! (`θ̂`) and every candidate at its initial value (zero) are evaluated fold by fold. The normal equations
//! of all data are the sum of the folds' test parts', `N = AᵀA`, `g = Aᵀr`; a fold's training part is all
//! data but its test poses, so its equations are `N − N_test`, `g − g_test` (exact for the linearised
//! step). For each fold
//! and candidate, the Gauss–Newton step from `θ̂` on the training part over the current and the
//! candidate's columns, `δ = (N_f + εI)⁻¹ g_f` on those columns, predicts the test residuals
//! `r_test − A_test δ`, hence the candidate's held-out sum of squares.
//!
//! Why the screen keeps the winner: the full scoring fits each fold from scratch to convergence; the
//! screen takes one Gauss–Newton step from the all-data fit instead. For blocks that enter nearly
//! linearly at the current fit (frames, offsets, link deviations of small angles, compliance, scale,
//! cyclic terms, drift amplitudes) that step is the fold's least-squares solution up to terms of second
//! order in the parameters' change, which is small where every deviation is a fraction of a millimetre
//! against a reach of a metre; and the step starts from the fit on all data, whose difference from a
//! fold's fit is itself of the order of the held-out gains being ranked. So the ranking can be wrong
//! between candidates whose predicted gains differ by less than that — near-ties — and the screen passes
//! [`Screen::keep`] candidates (not one) to the full scoring, which decides. Not linear: an exponential
//! drift's τ (its column is zero at zero amplitude) — exponential drifts are never screened; they are
//! scored in full after their linear drift, as before. Checked, not assumed: `tests/it/screen.rs`
//! compares the screened selection with the exhaustive one (`Screen { keep: 0 }`) on simulated sets and
//! on the real Rokae and UR10 sets — the same choices, the same held-out figures.

use faer::Mat;
use faer::prelude::Solve;

use thermokin_identify::{Effect, residuals_and_jacobian};

use crate::config::Screen;
use crate::error::DiagnoseError;
use crate::scoring::{CHUNK_POSES, RIDGE, Scorer};

/// Columns whose norm is below this fraction of the largest carry no information at the linearisation
/// point (an exponential drift's τ at zero amplitude) and are left out.
const NEGLIGIBLE_COLUMN: f64 = 1e-12;

/// The candidates to fit in full: all when `keep` is 0 or covers them, otherwise the `keep` with the
/// lowest linearised held-out sum of squares over the selection's folds. A prediction is not a fit: the
/// values a candidate's linearised step reaches are not judged here — those fitted in full are, on every
/// fold ([`crate::selection::score`]), and refused with the values measured.
pub(crate) fn shortlist(
    scorer: &Scorer<'_>,
    effects: &[Effect],
    theta: &[f64],
    candidates: &[Effect],
    screen: Screen,
) -> Result<Vec<Effect>, DiagnoseError> {
    if screen.keep == 0 || candidates.len() <= screen.keep {
        return Ok(candidates.to_vec());
    }
    let predicted = linearised_heldout(scorer, effects, theta, candidates)?;
    let mut order: Vec<usize> = (0..candidates.len()).collect();
    order.sort_by(|&a, &b| predicted[a].total_cmp(&predicted[b]));
    Ok(order.into_iter().take(screen.keep).map(|k| candidates[k]).collect())
}

/// Per candidate, the held-out sum of squares (mm²) that one Gauss–Newton step from the current all-data
/// fit on each fold's training part predicts on its test part.
///
/// Fold by fold, never the whole Jacobian at once (with every candidate's columns, ~200 on a six-joint
/// arm with time and temperatures, a week of 12,000 poses would hold 57 MB — the largest matrix of a
/// diagnosis, two of them while two outer folds select at once): a first pass forms each fold's test
/// part's normal equations, `Jₜᵀ Jₜ` and `Jₜᵀ rₜ`, whose sum over the folds (which partition the data)
/// is all data's; a second evaluates each fold's test Jacobian again for the predicted residuals. Twice
/// the evaluations of one pass; a fifth of its memory.
fn linearised_heldout(
    scorer: &Scorer<'_>,
    effects: &[Effect],
    theta: &[f64],
    candidates: &[Effect],
) -> Result<Vec<f64>, DiagnoseError> {
    let all = scorer.all();
    let mut joint_model: Vec<Effect> = effects.to_vec();
    joint_model.extend_from_slice(candidates);
    let model = scorer.model(&joint_model, &all)?;
    let mut at = model.initial();
    at[..theta.len()].copy_from_slice(theta);
    let p = model.len();
    let folds: Vec<&Vec<usize>> = scorer.folds.iter().map(|(_, test)| test).filter(|t| !t.is_empty()).collect();
    // Pass 1: each fold's test part's unscaled normal equations.
    let mut parts: Vec<(Mat<f64>, Mat<f64>)> = Vec::with_capacity(folds.len());
    for test in &folds {
        parts.push(scorer.normal_equations(&model, &at, test)?);
    }
    let mut gram = Mat::<f64>::zeros(p, p);
    let mut grad = Mat::<f64>::zeros(p, 1);
    for (g, h) in &parts {
        gram += g;
        grad += h;
    }
    // Unit columns (mm, radians and minutes weigh alike): `A = J D⁻¹`, `AᵀA = D⁻¹ JᵀJ D⁻¹`; negligible
    // columns (an exponential drift's τ at zero amplitude) dropped.
    let norms: Vec<f64> = (0..p).map(|c| gram[(c, c)].max(0.0).sqrt()).collect();
    let largest = norms.iter().copied().fold(0.0, f64::max);
    let used: Vec<usize> = (0..p).filter(|&c| norms[c] > NEGLIGIBLE_COLUMN * largest).collect();
    let q = used.len();
    let scaled =
        |m: &Mat<f64>| Mat::<f64>::from_fn(q, q, |i, k| m[(used[i], used[k])] / (norms[used[i]] * norms[used[k]]));
    let scaled_g = |g: &Mat<f64>| Mat::<f64>::from_fn(q, 1, |i, _| g[(used[i], 0)] / norms[used[i]]);
    let column = |c: usize| used.iter().position(|&u| u == c);
    let current: Vec<usize> = (0..theta.len()).filter_map(column).collect();
    let offsets = &model.offsets()[effects.len()..];
    let own: Vec<Vec<usize>> =
        candidates.iter().zip(offsets).map(|(c, &o)| (o..o + c.len()).filter_map(column).collect()).collect();
    let (n_all, g_all) = (scaled(&gram), scaled_g(&grad));
    let mut sse = vec![0.0; candidates.len()];
    // Pass 2: each fold's steps from its training part, and its test part's predicted residuals.
    for (test, (g_test, h_test)) in folds.iter().zip(&parts) {
        let n_f = &n_all - scaled(g_test);
        let g_f = &g_all - scaled_g(h_test);
        let steps: Vec<(Vec<usize>, Option<Vec<f64>>)> = own
            .iter()
            .map(|cols| {
                let idx: Vec<usize> = current.iter().chain(cols).copied().collect();
                let step = solve(&n_f, &g_f, &idx);
                (idx, step)
            })
            .collect();
        // The fold's sum per candidate, pose after pose over the blocks of its test part.
        let mut fold_sse = vec![0.0; candidates.len()];
        for block in test.chunks(CHUNK_POSES) {
            let (r, j) = residuals_and_jacobian(scorer.robot, &model, &at, scorer.data, block, &scorer.terms)?;
            for (sum, (idx, step)) in fold_sse.iter_mut().zip(&steps) {
                let Some(step) = step else { continue };
                for row in 0..r.len() {
                    let fitted: f64 = idx.iter().zip(step).map(|(&c, s)| j[(row, used[c])] / norms[used[c]] * s).sum();
                    *sum += (r[row] - fitted).powi(2);
                }
            }
        }
        for (k, (_, step)) in steps.iter().enumerate() {
            if step.is_some() {
                sse[k] += fold_sse[k];
            } else {
                sse[k] = f64::INFINITY;
            }
        }
    }
    Ok(sse)
}

/// Per candidate, the values one Gauss–Newton step on all data from the current fit gives its
/// parameters (internal units; the current effects moving with it, as in [`linearised_heldout`]'s steps):
/// what a candidate refused for its size would be fitted at in the model as it now stands, to first
/// order — so that it is fitted in full again only where that could have changed. A column the data do
/// not determine (negligible, or solved only through the ridge) may come out at any value: an estimate,
/// never a fit.
pub(crate) fn linearised_values(
    scorer: &Scorer<'_>,
    effects: &[Effect],
    theta: &[f64],
    candidates: &[Effect],
) -> Result<Vec<Vec<f64>>, DiagnoseError> {
    let all = scorer.all();
    let mut out = Vec::with_capacity(candidates.len());
    for &c in candidates {
        let mut with = effects.to_vec();
        with.push(c);
        let model = scorer.model(&with, &all)?;
        let mut at = model.initial();
        at[..theta.len()].copy_from_slice(theta);
        // All data's normal equations as the sum of the folds' test parts' (which partition it), as in
        // `linearised_heldout`.
        let p = model.len();
        let (mut n, mut g) = (Mat::<f64>::zeros(p, p), Mat::<f64>::zeros(p, 1));
        for (_, test) in scorer.folds.iter().filter(|(_, t)| !t.is_empty()) {
            let (n_t, g_t) = scorer.normal_equations(&model, &at, test)?;
            n += &n_t;
            g += &g_t;
        }
        let norms: Vec<f64> = (0..p).map(|k| n[(k, k)].max(0.0).sqrt()).collect();
        let largest = norms.iter().copied().fold(0.0, f64::max);
        let used: Vec<usize> = (0..p).filter(|&k| norms[k] > NEGLIGIBLE_COLUMN * largest).collect();
        let q = used.len();
        let n_s = Mat::<f64>::from_fn(q, q, |i, k| n[(used[i], used[k])] / (norms[used[i]] * norms[used[k]]));
        let g_s = Mat::<f64>::from_fn(q, 1, |i, _| g[(used[i], 0)] / norms[used[i]]);
        let o = model.offsets()[effects.len()];
        let mut values: Vec<f64> = at[o..o + c.len()].to_vec();
        if let Some(step) = solve(&n_s, &g_s, &(0..q).collect::<Vec<_>>()) {
            for (i, &col) in used.iter().enumerate() {
                if (o..o + c.len()).contains(&col) {
                    values[col - o] += step[i] / norms[col];
                }
            }
        }
        out.push(values);
    }
    Ok(out)
}

/// The step on columns `idx` of the normal equations `n δ = g`, ridged; `None` when not solvable.
fn solve(n: &Mat<f64>, g: &Mat<f64>, idx: &[usize]) -> Option<Vec<f64>> {
    let q = idx.len();
    let sub = Mat::<f64>::from_fn(q, q, |i, j| n[(idx[i], idx[j])] + if i == j { RIDGE } else { 0.0 });
    let rhs = Mat::<f64>::from_fn(q, 1, |i, _| g[(idx[i], 0)]);
    let llt = sub.llt(faer::Side::Lower).ok()?;
    let step = llt.solve(&rhs);
    Some((0..q).map(|i| step[(i, 0)]).collect())
}
