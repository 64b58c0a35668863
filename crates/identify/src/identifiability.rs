//! Which parameters the data can identify (ordered Gram–Schmidt on the column-scaled Jacobian, by an
//! orthogonal factorisation), and the observability indices of those they can.

use faer::linalg::matmul::matmul;
use faer::linalg::solvers::DenseSolveCore;
use faer::{Accum, Mat, MatRef, Par};
use serde::Serialize;

/// A parameter the data cannot identify, fixed at its starting value.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FixedParameter {
    /// Parameter name.
    pub parameter: String,
    /// Why: the block it duplicates, or that it has no effect on the measured positions.
    pub reason: String,
}

/// Observability of the identified parameters (singular values σ of the column-scaled Jacobian, m rows).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Observability {
    /// Free parameters.
    pub parameters: usize,
    /// Residual rows.
    pub rows: usize,
    /// σ_max / σ_min.
    pub condition_number: f64,
    /// O1 = (σ1 ⋯ σp)^(1/p) / √m (Borm & Menq).
    pub o1: f64,
    /// O2 = σ_min / σ_max.
    pub o2: f64,
    /// O3 = σ_min.
    pub o3: f64,
    /// O4 = σ_min² / σ_max (noise amplification index).
    pub o4: f64,
    /// O5 = 1 / Σ 1/σ_i.
    pub o5: f64,
}

/// Distance below which a unit column counts as a combination of earlier ones: well above the ~1e-15
/// of rounding in an orthogonal factorisation, well below the ~1e-3 of a weakly but truly identifiable
/// parameter of a 30-pose data set.
pub const DEPENDENT: f64 = 1e-6;

/// Column norm, relative to the largest column's, at or below which a parameter has no effect on the
/// measurements. Relative, not absolute: a column that is zero in exact arithmetic (a rotation about an
/// axis through the tool point) is rounding, ~1e-16 of the positions it is formed from per row — 4e-12 mm
/// over 1,500 poses of a 1 m arm, above any absolute threshold set for millimetres, and pure noise in
/// direction, which the gate would keep and the first step would follow without bound.
pub(crate) const INERT: f64 = 1e-12;

/// The Euclidean norm of each column of `jac`: the square root of [`dot`]'s sum of squares where the
/// column is contiguous (a Jacobian's always is), faer's scaled norm otherwise. A plain sum suffices here:
/// a Jacobian's entries (mm per unit of a parameter) are nowhere near the 1e±154 where squares overflow
/// or vanish, and a column that small would be inert beside the others anyway. It is what decides which
/// columns are inert and scales them to unit length for [`identifiable`], twice per fit: faer's
/// overflow-safe norm (sums kept at three scales) was about 3 % of a diagnosis's samples.
pub(crate) fn column_norms(jac: MatRef<'_, f64>) -> Vec<f64> {
    (0..jac.ncols())
        .map(|c| {
            let col = jac.col(c);
            match col.try_as_col_major() {
                Some(contiguous) => {
                    let x = contiguous.as_slice();
                    dot(x, x).sqrt()
                }
                None => col.norm_l2(),
            }
        })
        .collect()
}

/// Whether each column of `jac` is inert ([`INERT`] of the largest column's norm), from the norms.
pub(crate) fn inert_columns(norm: &[f64]) -> Vec<bool> {
    let largest = norm.iter().copied().fold(0.0, f64::max);
    norm.iter().map(|n| *n <= INERT * largest).collect()
}

/// Largest `‖L⁻¹‖_F` of the unit columns' Gram–Cholesky factor for which the Gram matrix alone decides
/// that every column is identifiable ([`identifiable`]'s fast path).
const WELL_CONDITIONED: f64 = 1e3;

/// Rows per block of [`unit_r_factor`]: a block's columns (at most ~60 × 128 × 8 bytes) stay in cache
/// while every reflection is applied to them.
const R_BLOCK_ROWS: usize = 128;

/// Ordered Gram–Schmidt on the column-scaled Jacobian: earlier (conventional, smaller) blocks win, a later
/// column within [`DEPENDENT`] of the span of the accepted unit columns is fixed, and the reason names
/// the accepted column it is most aligned with.
///
/// The distances are those of an orthogonal (Householder) factorisation `A = QR` of the unit columns —
/// distances between combinations of `A`'s columns are those of the same combinations of `R`'s — accurate
/// to a few rounding units whatever the accepted columns' conditioning. A distance formed from the Gram
/// matrix `AᵀA` (`√(1 − l·l)`, `l = L⁻¹g`) is not: with an accepted column at 1e-6 from the others, `L⁻¹`
/// amplifies the Gram's rounding (~1e-16) by 1e6, and a later column's squared distance is known to
/// ~1e-10, a hundred times the threshold's 1e-12 — on the 12,000-pose bench it decided one call in ten
/// differently, fixing drift components that were identifiable.
///
/// Two shortcuts decide from the Gram matrix where it is exact enough (a cosine of unit columns is
/// resolved to ~1e-14, so that `1 − cos²` is known to ~1e-13 against the threshold's 1e-12):
/// - a column within [`DEPENDENT`] of one earlier kept column is dependent whatever else is accepted
///   (its distance from any span holding that column is smaller still);
/// - when the other columns' Gram matrix has a Cholesky factor with `‖L⁻¹‖_F ≤` `WELL_CONDITIONED`,
///   the smallest singular value of their `A` is at least ~1e-3: every one of them is at least that far
///   from the span of the others, and the Gram's rounding (≤ m·1e-16 ≈ 1e-12 on its entries) cannot
///   bring any near [`DEPENDENT`]. All are identifiable and no factorisation is needed.
pub fn identifiable(jac: MatRef<'_, f64>, prior: &[bool]) -> Identifiable {
    let p = jac.ncols();
    let norm = column_norms(jac);
    let mut free = vec![false; p];
    let mut fixed = Vec::new();
    let mut candidates = Vec::new();
    let inert = inert_columns(&norm);
    for c in 0..p {
        if !prior.get(c).copied().unwrap_or(true) {
            continue;
        }
        if inert[c] {
            fixed.push(Dependence { column: c, on: DependsOn::Nothing });
        } else {
            candidates.push(c);
        }
    }
    let mut gram = Mat::<f64>::zeros(p, p);
    matmul(gram.as_mut(), Accum::Replace, jac.transpose(), jac, 1.0, Par::Seq);
    let cos = |a: usize, b: usize| gram[(a, b)] / (norm[a] * norm[b]);
    let mut kept: Vec<usize> = Vec::new();
    let mut parallel: Vec<usize> = Vec::new();
    for &c in &candidates {
        if kept.iter().any(|&a| 1.0 - cos(a, c).powi(2) < DEPENDENT * DEPENDENT) {
            parallel.push(c);
        } else {
            kept.push(c);
        }
    }
    if well_conditioned(&gram, &norm, &kept) {
        for &c in &kept {
            free[c] = true;
        }
        // The reason names an accepted column before `c` (columns are tested in order).
        fixed.extend(parallel.iter().map(|&c| {
            let before = kept.iter().take_while(|&&a| a < c).count();
            Dependence::on(c, &kept[..before], &cos)
        }));
    } else {
        let r = unit_r_factor(jac, &norm, &candidates);
        let column = |c: usize| -> Vec<f64> {
            let k = candidates.iter().position(|&x| x == c).unwrap_or(0);
            (0..r.nrows()).map(|i| r[(i, k)]).collect()
        };
        // The cosine of two unit columns of A: the dot product of their columns of R.
        let r_cos = |a: usize, b: usize| column(a).iter().zip(column(b)).map(|(x, y)| x * y).sum::<f64>();
        let mut basis: Vec<Vec<f64>> = Vec::new();
        let mut accepted: Vec<usize> = Vec::new();
        for &c in &candidates {
            // Gram–Schmidt on R's columns.
            let mut v = column(c);
            let d = project_out(&basis, &mut v);
            if d < DEPENDENT {
                fixed.push(Dependence::on(c, &accepted, &r_cos));
            } else {
                basis.push(v.iter().map(|x| x / d).collect());
                accepted.push(c);
                free[c] = true;
            }
        }
    }
    fixed.sort_by_key(|d| d.column);
    Identifiable { free, fixed }
}

/// What [`identifiable`] decided: the free columns, and why each other column (allowed by the prior) is
/// fixed, in column order.
#[derive(Clone, Debug, PartialEq)]
pub struct Identifiable {
    /// Whether each column is free (identifiable).
    pub free: Vec<bool>,
    /// The columns fixed, each with what it depends on.
    pub fixed: Vec<Dependence>,
}

/// A column the data cannot identify, and why.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dependence {
    /// The column.
    pub column: usize,
    /// What it depends on.
    pub on: DependsOn,
}

/// Why a column is not identifiable.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DependsOn {
    /// It moves nothing measured (its column is zero).
    Nothing,
    /// It is (within [`DEPENDENT`]) a multiple of an accepted column, or mostly along one: `|cos| > 0.5`.
    Column {
        /// The accepted column it is most aligned with.
        column: usize,
        /// `|cos|` of the angle between them.
        cos: f64,
    },
    /// A combination of the accepted columns, along none of them in particular.
    Combination,
}

impl Dependence {
    /// Column `c`, dependent on the `accepted` ones: named by the accepted column it is most aligned with
    /// when that alignment is clear (`|cos| > 0.5`).
    fn on(c: usize, accepted: &[usize], cos: &dyn Fn(usize, usize) -> f64) -> Self {
        let best = accepted.iter().map(|&a| (a, cos(a, c).abs())).max_by(|x, y| x.1.total_cmp(&y.1));
        let on = match best {
            Some((a, cos)) if cos > 0.5 => DependsOn::Column { column: a, cos },
            _ => DependsOn::Combination,
        };
        Self { column: c, on }
    }
}

/// Removes from `v` its components along the orthonormal `basis` — twice ("twice is enough": the second
/// pass takes out what rounding left of the first) — and returns the norm of what remains.
pub fn project_out(basis: &[Vec<f64>], v: &mut [f64]) -> f64 {
    for _ in 0..2 {
        for q in basis {
            let h: f64 = q.iter().zip(v.iter()).map(|(a, b)| a * b).sum();
            v.iter_mut().zip(q).for_each(|(x, y)| *x -= h * y);
        }
    }
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Whether the `kept` unit columns are so far from dependent that the Gram matrix decides
/// ([`identifiable`]): their Gram matrix has a Cholesky factor with `‖L⁻¹‖_F ≤` [`WELL_CONDITIONED`].
fn well_conditioned(gram: &Mat<f64>, norm: &[f64], kept: &[usize]) -> bool {
    let unit_gram =
        Mat::from_fn(kept.len(), kept.len(), |i, j| gram[(kept[i], kept[j])] / (norm[kept[i]] * norm[kept[j]]));
    let Ok(llt) = unit_gram.llt(faer::Side::Lower) else { return false };
    // ‖L⁻¹‖_F² = ‖G⁻¹‖_trace = Σ (G⁻¹)_ii.
    let inverse = llt.inverse();
    let trace: f64 = (0..kept.len()).map(|i| inverse[(i, i)]).sum();
    trace.is_finite() && trace >= 0.0 && trace.sqrt() <= WELL_CONDITIONED
}

/// The upper-triangular R of `A = QR`, `A` the unit `columns` of `jac` (Householder reflections applied
/// block of rows by block of rows, each block staying in cache; `Q` is not formed). A column that is an
/// exact combination of earlier ones leaves a zero on R's diagonal.
fn unit_r_factor(jac: MatRef<'_, f64>, norm: &[f64], columns: &[usize]) -> Mat<f64> {
    let (m, p) = (jac.nrows(), columns.len());
    let mut r = Mat::<f64>::zeros(p, p);
    let b = R_BLOCK_ROWS;
    let mut block = vec![0.0; b * p];
    let mut r0 = 0;
    while r0 < m {
        let n = b.min(m - r0);
        for (k, &c) in columns.iter().enumerate() {
            let scale = 1.0 / norm[c];
            for (i, x) in block[k * b..k * b + n].iter_mut().enumerate() {
                *x = jac[(r0 + i, c)] * scale;
            }
        }
        for j in 0..p {
            let (head, tail) = block.split_at_mut((j + 1) * b);
            let vj = &head[j * b..j * b + n];
            let s = dot(vj, vj);
            if s == 0.0 {
                continue;
            }
            // The reflection zeroing the block's column j against R's diagonal: v = (r_jj − α, block_j).
            let rjj = r[(j, j)];
            let alpha = -rjj.signum() * (rjj * rjj + s).sqrt();
            let v0 = rjj - alpha;
            let scale = 2.0 / (v0 * v0 + s);
            for k in j + 1..p {
                let bk = &mut tail[(k - j - 1) * b..(k - j - 1) * b + n];
                let f = (v0 * r[(j, k)] + dot(vj, bk)) * scale;
                r[(j, k)] -= f * v0;
                bk.iter_mut().zip(vj).for_each(|(x, y)| *x -= f * y);
            }
            r[(j, j)] = alpha;
        }
        r0 += n;
    }
    r
}

/// Independent partial sums of [`dot`]: each lane's additions wait for its previous one (four cycles or
/// so), so the dot product runs as fast as lanes are in flight — sixteen keep every adder busy, where four
/// left the reflections (a tenth of a diagnosis) waiting on the sum.
const DOT_LANES: usize = 16;

/// A dot product in [`DOT_LANES`] lanes, which the compiler vectorises (the order of the sum is fixed:
/// lane by lane, then the lanes pairwise, then the tail).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut lanes = [0.0f64; DOT_LANES];
    let (ca, cb) = (a.chunks_exact(DOT_LANES), b.chunks_exact(DOT_LANES));
    let tail: f64 = ca.remainder().iter().zip(cb.remainder()).map(|(x, y)| x * y).sum();
    for (x, y) in ca.zip(cb) {
        for i in 0..DOT_LANES {
            lanes[i] += x[i] * y[i];
        }
    }
    let mut width = DOT_LANES;
    while width > 1 {
        width /= 2;
        for i in 0..width {
            lanes[i] += lanes[i + width];
        }
    }
    lanes[0] + tail
}

/// Observability indices of the free columns (column-scaled): the singular values of the unit columns'
/// R factor (`unit_r_factor`: Householder reflections a block of rows at a time), which are theirs —
/// `A = QR` with `Q`'s columns orthonormal — without a copy of the Jacobian or an SVD of its height (a
/// week's Jacobian is 100 MB and more).
pub fn observability(jac: &Mat<f64>, free: &[bool]) -> Option<Observability> {
    let cols: Vec<usize> = (0..jac.ncols()).filter(|&c| free[c]).collect();
    if cols.is_empty() || jac.nrows() == 0 {
        return None;
    }
    let m = jac.nrows();
    let norm: Vec<f64> =
        (0..jac.ncols()).map(|c| (0..m).map(|r| jac[(r, c)] * jac[(r, c)]).sum::<f64>().sqrt().max(1e-300)).collect();
    let sv = unit_r_factor(jac.as_ref(), &norm, &cols).singular_values().ok()?;
    let max = sv.iter().copied().fold(0.0, f64::max);
    let min = sv.iter().copied().fold(f64::INFINITY, f64::min);
    let p = sv.len() as f64;
    let geo = (sv.iter().map(|s| s.max(1e-300).ln()).sum::<f64>() / p).exp();
    Some(Observability {
        parameters: cols.len(),
        rows: m,
        condition_number: max / min,
        o1: geo / (m as f64).sqrt(),
        o2: min / max,
        o3: min,
        o4: min * min / max,
        o5: 1.0 / sv.iter().map(|s| 1.0 / s.max(1e-300)).sum::<f64>(),
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use faer::Mat;

    use super::{DEPENDENT, DependsOn, column_norms, identifiable, observability};

    /// The plain sum of squares agrees with faer's overflow-safe norm to rounding on columns from 1e-8 to
    /// 1e8 (a Jacobian's range and beyond), contiguous or not (a transposed view takes faer's own path).
    #[test]
    fn column_norms_are_faers_to_rounding() {
        let jac = Mat::from_fn(1_001, 7, |r, c| ((r * 7 + c) as f64 * 0.618).sin() * 10f64.powi(4 * c as i32 - 8));
        let transposed = Mat::from_fn(7, 1_001, |r, c| jac[(c, r)]);
        for view in [jac.as_ref(), transposed.transpose()] {
            for (c, n) in column_norms(view).iter().enumerate() {
                let faer = view.col(c).norm_l2();
                assert!((n - faer).abs() <= 1e-14 * faer, "column {c}: {n} against {faer}");
            }
        }
    }

    /// Columns built from exactly orthogonal directions (indicators of disjoint row blocks), so that each
    /// column's distance from the span of the earlier accepted ones is known in closed form, then scaled
    /// by factors from 1e-3 to 1e3 (the decision is on unit columns). Column 1 is 2e-6 from column 0
    /// (accepted, barely): a Gram-based distance divides by it and loses every later decision; the
    /// factorised one keeps them.
    #[test]
    fn identifiability_follows_the_exact_distances_past_a_nearly_dependent_column() {
        let (m, blocks) = (3_000, 5);
        let rows_per = m / blocks;
        // q_b: the unit indicator of row block b.
        let q = |b: usize, r: usize| if r / rows_per == b { 1.0 / (rows_per as f64).sqrt() } else { 0.0 };
        let column = |c: usize, r: usize| match c {
            0 => q(0, r),
            // 2e-6 from q0: accepted.
            1 => q(0, r) + 2e-6 * q(1, r),
            // 5e-7 / |c| from q0: dependent.
            2 => q(0, r) + 5e-7 * q(2, r),
            // q1 lies in span(c0, c1) exactly.
            3 => q(1, r),
            // 1e-5 / |c| from span(c0, c1) = span(q0, q1): identifiable.
            4 => q(1, r) + 1e-5 * q(3, r),
            // 3e-5 from span(q0, q1, q3) along q4, after a large part along q0: identifiable.
            _ => 0.7 * q(0, r) - 0.2 * q(3, r) + 3e-5 * q(4, r),
        };
        let expected = [true, true, false, false, true, true];
        let scales = [1e-3, 1e3, 1.0, 42.0, 1e-2, 7e2];
        let jac = Mat::from_fn(m, 6, |r, c| scales[c] * column(c, r));
        let decided = identifiable(jac.as_ref(), &[true; 6]);
        let fixed = &decided.fixed;
        assert_eq!(decided.free, expected, "fixed: {fixed:?}");
        assert_eq!(fixed.iter().map(|f| f.column).collect::<Vec<_>>(), [2, 3]);
        assert!(matches!(fixed[0].on, DependsOn::Column { column: 0, .. }), "{:?}", fixed[0]);
        // The threshold sits between the distances chosen above.
        const { assert!(5e-7 < DEPENDENT && DEPENDENT < 2e-6) };
    }

    /// A well-conditioned set (the fast path) keeps every column, and a column parallel to an earlier one
    /// is fixed with the earlier one's name whatever the conditioning of the rest.
    #[test]
    fn parallel_columns_are_fixed_and_independent_ones_kept() {
        let m = 400;
        let jac = Mat::from_fn(m, 4, |r, c| {
            let t = r as f64 / m as f64;
            match c {
                0 => 1.0,
                1 => t,
                2 => -3.0 * t,
                _ => (6.0 * t).sin(),
            }
        });
        let decided = identifiable(jac.as_ref(), &[true; 4]);
        assert_eq!(decided.free, [true, true, false, true]);
        assert_eq!(decided.fixed.len(), 1);
        assert_eq!(decided.fixed[0].column, 2);
        assert!(
            matches!(decided.fixed[0].on, DependsOn::Column { column: 1, cos } if (cos - 1.0).abs() < 1e-12),
            "{:?}",
            decided.fixed[0]
        );
    }

    /// The observability indices from the R factor equal those of faer's thin SVD of the unit columns
    /// themselves (an independent computation): a random 3,000 × 8 Jacobian whose columns span 1e-4 to
    /// 1e4 and one of which is nearly the sum of two others, one column left out as not free. To 1e-9
    /// relative: both are backward stable (rounding ~1e-16 × the condition number, here ~1e5).
    #[test]
    fn observability_from_the_r_factor_is_the_singular_values_of_the_unit_columns() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let (m, p) = (3_000, 8);
        let mut jac = Mat::from_fn(m, p, |_, _| rng.random_range(-1.0..1.0));
        for r in 0..m {
            jac[(r, 5)] = jac[(r, 1)] + jac[(r, 2)] + 1e-5 * jac[(r, 5)];
        }
        for c in 0..p {
            let scale = 10f64.powf(-4.0 + 8.0 * c as f64 / (p - 1) as f64);
            for r in 0..m {
                jac[(r, c)] *= scale;
            }
        }
        let free = [true, true, true, false, true, true, true, true];
        let got = observability(&jac, &free).unwrap();
        let cols: Vec<usize> = (0..p).filter(|&c| free[c]).collect();
        let unit = Mat::from_fn(m, cols.len(), |r, k| jac[(r, cols[k])] / jac.col(cols[k]).norm_l2());
        let sv = unit.singular_values().unwrap();
        let (max, min) = (sv.iter().copied().fold(0.0, f64::max), sv.iter().copied().fold(f64::INFINITY, f64::min));
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs();
        assert!(close(got.condition_number, max / min), "{} vs {}", got.condition_number, max / min);
        assert!(close(got.o3, min), "{} vs {min}", got.o3);
        assert!(close(got.o5, 1.0 / sv.iter().map(|s| 1.0 / s).sum::<f64>()));
        assert_eq!((got.parameters, got.rows), (7, m));
    }
}
