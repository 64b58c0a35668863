//! Score before you fit: every candidate of a forward step ranked by the held-out error one linearised
//! step would give it, so that only a shortlist is fitted in full (issue #23).
//!
//! One pass over all measurements evaluates the residuals `r` and the Jacobian `A` of a model holding the
//! current effects at their fit on all data (`θ̂`) and every candidate at its initial value (zero). The
//! normal equations are formed once, `N = AᵀA`, `g = Aᵀr`; a fold's training part is all data but its test
//! poses, so its equations are `N − N_test`, `g − g_test` (exact for the linearised step). For each fold
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

use faer::linalg::matmul::matmul;
use faer::prelude::Solve;
use faer::{Accum, Mat, Par};

use thermokin_identify::{Effect, residuals_and_jacobian};

use crate::config::Screen;
use crate::error::DiagnoseError;
use crate::scoring::Scorer;

/// Ridge on the scaled normal equations, relative to their unit diagonal: keeps a candidate that
/// duplicates a current column (no gain, singular equations) solvable without moving the others.
const RIDGE: f64 = 1e-9;
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
    let (r, mut jac) = residuals_and_jacobian(scorer.robot, &model, &at, scorer.data, &all, &scorer.terms)?;
    // Unit columns (mm, radians and minutes weigh alike); negligible columns dropped. Scaled in place and
    // copied only when a column is dropped: with every candidate's columns (~200 on a six-joint arm with
    // time and temperatures) the Jacobian of 12,000 poses is 60 MB, the largest matrix of a diagnosis.
    let norms: Vec<f64> = (0..jac.ncols()).map(|c| jac.col(c).norm_l2()).collect();
    let largest = norms.iter().copied().fold(0.0, f64::max);
    let used: Vec<usize> = (0..jac.ncols()).filter(|&c| norms[c] > NEGLIGIBLE_COLUMN * largest).collect();
    for &c in &used {
        jac.col_mut(c).iter_mut().for_each(|v| *v /= norms[c]);
    }
    let a = if used.len() == jac.ncols() {
        jac
    } else {
        let sub = Mat::<f64>::from_fn(jac.nrows(), used.len(), |i, k| jac[(i, used[k])]);
        drop(jac);
        sub
    };
    let column = |c: usize| used.iter().position(|&u| u == c);
    let current: Vec<usize> = (0..theta.len()).filter_map(column).collect();
    let offsets = &model.offsets()[effects.len()..];
    let own: Vec<Vec<usize>> =
        candidates.iter().zip(offsets).map(|(c, &o)| (o..o + c.len()).filter_map(column).collect()).collect();
    let (n_all, g_all) = normal_equations(&a, &r, None);
    let stride = scorer.terms.stride();
    let mut sse = vec![0.0; candidates.len()];
    for (_, test) in &scorer.folds {
        if test.is_empty() {
            continue;
        }
        let rows: Vec<usize> = test.iter().flat_map(|&i| (0..stride).map(move |k| stride * i + k)).collect();
        let (n_test, g_test) = normal_equations(&a, &r, Some(&rows));
        let n_f = &n_all - &n_test;
        let g_f = &g_all - &g_test;
        for (k, cols) in own.iter().enumerate() {
            let idx: Vec<usize> = current.iter().chain(cols).copied().collect();
            let Some(step) = solve(&n_f, &g_f, &idx) else {
                sse[k] = f64::INFINITY;
                continue;
            };
            sse[k] += rows
                .iter()
                .map(|&row| {
                    let fitted: f64 = idx.iter().zip(&step).map(|(&c, s)| a[(row, c)] * s).sum();
                    (r[row] - fitted).powi(2)
                })
                .sum::<f64>();
        }
    }
    Ok(sse)
}

/// `AᵀA` and `Aᵀr` over all rows, or over `rows` only.
fn normal_equations(a: &Mat<f64>, r: &[f64], rows: Option<&[usize]>) -> (Mat<f64>, Mat<f64>) {
    let p = a.ncols();
    let product = |sub: faer::MatRef<'_, f64>, rv: faer::MatRef<'_, f64>| {
        let mut n = Mat::<f64>::zeros(p, p);
        matmul(n.as_mut(), Accum::Replace, sub.transpose(), sub, 1.0, Par::Seq);
        let mut g = Mat::<f64>::zeros(p, 1);
        matmul(g.as_mut(), Accum::Replace, sub.transpose(), rv, 1.0, Par::Seq);
        (n, g)
    };
    match rows {
        None => product(a.as_ref(), faer::ColRef::from_slice(r).as_mat()),
        Some(rows) => {
            let sub = Mat::<f64>::from_fn(rows.len(), p, |i, k| a[(rows[i], k)]);
            let rv = Mat::<f64>::from_fn(rows.len(), 1, |i, _| r[rows[i]]);
            product(sub.as_ref(), rv.as_ref())
        }
    }
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
