//! Identification: Levenberg–Marquardt on faer with column scaling, the parameters the data cannot
//! identify detected (ordered Gram–Schmidt on the scaled Jacobian) and fixed, observability indices from
//! the singular values, and parameter uncertainties.

use faer::linalg::matmul::matmul;
use faer::linalg::solvers::{DenseSolveCore, Solve};
use faer::{Accum, Mat, Par};
use nalgebra::{Isometry3, Matrix3, Matrix6xX, Vector3};
use serde::Serialize;

use thermokin_chain::{Robot, rotation_log};

use crate::model::{Model, Pre, TAU_RANGE_MIN};
use crate::{Dataset, DiagnoseError};

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

/// The outcome of one identification.
#[derive(Clone, Debug)]
pub struct Fit {
    /// All parameters (fixed ones at their starting value).
    pub theta: Vec<f64>,
    /// Standard deviation of each free parameter (NaN for fixed ones).
    pub std: Vec<f64>,
    /// Parameters fixed as unidentifiable.
    pub fixed: Vec<FixedParameter>,
    /// Free-parameter mask.
    pub free: Vec<bool>,
    /// Sum of squared residuals, mm².
    pub ssr: f64,
    /// Pairs of free parameters the data barely tell apart: correlation of their estimates above
    /// [`NEARLY_DEPENDENT`] in magnitude.
    pub correlated: Vec<CorrelatedPair>,
    /// Whether the iteration ended by its own test — the next step predicted or found to gain less than
    /// [`CONVERGED`] of the cost, or no step gaining at all — rather than by [`MAX_ITERATIONS`], after
    /// which the parameters are not at the least-squares minimum.
    pub converged: bool,
}

/// Correlation above which two estimates are reported as a nearly unidentifiable combination: at 0.99
/// each one's standard deviation is inflated 7× (`1/√(1 − ρ²)`) over what it would be alone — the data
/// determine their combination, not each.
pub const NEARLY_DEPENDENT: f64 = 0.99;

/// Two parameters whose estimates move together.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CorrelatedPair {
    /// First parameter.
    pub a: String,
    /// Second parameter.
    pub b: String,
    /// Correlation of the two estimates.
    pub correlation: f64,
}

/// Residual rows `measured − predicted` and the Jacobian of `predicted`: per measurement the position
/// (3 rows, mm) and, when [`Pre::lever_mm`] is set, the rotation `lever · log(R_measured · R_predictedᵀ)`
/// (3 rows, mm at the lever; the Gauss–Newton Jacobian of that log is the angular twist, exact at zero
/// residual).
pub(crate) fn residuals(
    robot: &Robot,
    model: &Model,
    theta: &[f64],
    data: &Dataset,
    rows: &[usize],
    pre: &Pre,
    with_jacobian: bool,
) -> Result<(Vec<f64>, Mat<f64>), DiagnoseError> {
    let stride = pre.stride();
    let mut r = Vec::with_capacity(rows.len() * stride);
    let mut jac = if with_jacobian { Mat::zeros(rows.len() * stride, model.len()) } else { Mat::zeros(0, 0) };
    let mut block = Matrix6xX::zeros(model.len());
    let mut cache = None;
    for (k, &i) in rows.iter().enumerate() {
        let m = &data.measurements[i];
        let (p, rot) = model.predict(
            robot,
            theta,
            m,
            &pre.rise[i],
            &pre.torques[i],
            Some(&pre.sin_cos[i]),
            with_jacobian.then_some(&mut block),
            &mut cache,
        )?;
        let d = m.position_mm - p;
        r.extend_from_slice(&[d.x, d.y, d.z]);
        let lever = pre.lever_mm.unwrap_or(0.0);
        if stride == 6 {
            let measured = m.orientation.map(|o| o.to_rotation_matrix().into_inner()).unwrap_or(rot);
            let e = rotation_log(&(measured * rot.transpose())) * lever;
            r.extend_from_slice(&[e.x, e.y, e.z]);
        }
        if with_jacobian {
            for c in 0..model.len() {
                for a in 0..stride {
                    let w = if a < 3 { 1.0 } else { lever };
                    jac[(stride * k + a, c)] = block[(a, c)] * w;
                }
            }
        }
    }
    Ok((r, jac))
}

/// [`residuals`] as the fit minimises them: position rows weighted by [`Pre::weights`] when the tracker
/// stated its standard deviations (weighted least squares), unchanged otherwise.
fn fit_residuals(
    robot: &Robot,
    model: &Model,
    theta: &[f64],
    data: &Dataset,
    rows: &[usize],
    pre: &Pre,
    with_jacobian: bool,
) -> Result<(Vec<f64>, Mat<f64>), DiagnoseError> {
    let (mut r, mut jac) = residuals(robot, model, theta, data, rows, pre, with_jacobian)?;
    if let Some(weights) = &pre.weights {
        let stride = pre.stride();
        for (k, &i) in rows.iter().enumerate() {
            for a in 0..3 {
                let (row, w) = (stride * k + a, weights[i][a]);
                r[row] *= w;
                if with_jacobian {
                    for c in 0..jac.ncols() {
                        jac[(row, c)] *= w;
                    }
                }
            }
        }
    }
    Ok((r, jac))
}

/// Per-measurement error norms of residual rows of `stride` rows each.
pub(crate) fn norms(r: &[f64], stride: usize) -> Vec<f64> {
    r.chunks(stride).map(|c| c.iter().map(|x| x * x).sum::<f64>().sqrt()).collect()
}

/// Distance below which a unit column counts as a combination of earlier ones: well above the ~1e-15
/// of rounding in an orthogonal factorisation, well below the ~1e-3 of a weakly but truly identifiable
/// parameter of a 30-pose data set.
pub(crate) const DEPENDENT: f64 = 1e-6;

/// Column norm (of the column-scaled Jacobian) at or below which a parameter has no effect on the
/// measurements.
const INERT: f64 = 1e-12;

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
/// - when the other columns' Gram matrix has a Cholesky factor with `‖L⁻¹‖_F ≤` [`WELL_CONDITIONED`],
///   the smallest singular value of their `A` is at least ~1e-3: every one of them is at least that far
///   from the span of the others, and the Gram's rounding (≤ m·1e-16 ≈ 1e-12 on its entries) cannot
///   bring any near [`DEPENDENT`]. All are identifiable and no factorisation is needed.
pub(crate) fn identifiable(jac: &Mat<f64>, names: &[String], prior: &[bool]) -> (Vec<bool>, Vec<FixedParameter>) {
    let p = jac.ncols();
    let norm: Vec<f64> = (0..p).map(|c| jac.col(c).norm_l2()).collect();
    let mut free = vec![false; p];
    let mut fixed = Vec::new();
    let mut candidates = Vec::new();
    for c in 0..p {
        if !prior.get(c).copied().unwrap_or(true) {
            continue;
        }
        if norm[c] <= INERT {
            let reason = if names[c].starts_with("tool_frame.r") {
                "moves no measured point: a tool's rotation is identified from measured orientations (rx, ry, rz)"
            } else {
                "no effect on the measurements"
            };
            fixed.push((c, FixedParameter { parameter: names[c].clone(), reason: reason.into() }));
        } else {
            candidates.push(c);
        }
    }
    let mut gram = Mat::<f64>::zeros(p, p);
    matmul(gram.as_mut(), Accum::Replace, jac.as_ref().transpose(), jac.as_ref(), 1.0, Par::Seq);
    let cos = |a: usize, b: usize| gram[(a, b)] / (norm[a] * norm[b]);
    let reason = |c: usize, accepted: &[usize], cos: &dyn Fn(usize, usize) -> f64| {
        let best = accepted.iter().map(|&a| (a, cos(a, c).abs())).max_by(|x, y| x.1.total_cmp(&y.1));
        let reason = match best {
            Some((a, cos)) if cos > 0.5 => format!("equivalent to {} (|cos| = {cos:.3})", names[a]),
            _ => "a combination of the parameters already identified".into(),
        };
        (c, FixedParameter { parameter: names[c].clone(), reason })
    };
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
            reason(c, &kept[..before], &cos)
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
                fixed.push(reason(c, &accepted, &r_cos));
            } else {
                basis.push(v.iter().map(|x| x / d).collect());
                accepted.push(c);
                free[c] = true;
            }
        }
    }
    fixed.sort_by_key(|(c, _)| *c);
    (free, fixed.into_iter().map(|(_, f)| f).collect())
}

/// Removes from `v` its components along the orthonormal `basis` — twice ("twice is enough": the second
/// pass takes out what rounding left of the first) — and returns the norm of what remains.
pub(crate) fn project_out(basis: &[Vec<f64>], v: &mut [f64]) -> f64 {
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
fn unit_r_factor(jac: &Mat<f64>, norm: &[f64], columns: &[usize]) -> Mat<f64> {
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

/// A dot product in four lanes, which the compiler vectorises (the order of the sum is fixed).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut lanes = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = ca.remainder().iter().zip(cb.remainder()).map(|(x, y)| x * y).sum();
    for (x, y) in ca.zip(cb) {
        for i in 0..4 {
            lanes[i] += x[i] * y[i];
        }
    }
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]) + tail
}

/// Observability indices of the free columns (column-scaled), by faer's thin SVD.
pub(crate) fn observability(jac: &Mat<f64>, free: &[bool]) -> Option<Observability> {
    let cols: Vec<usize> = (0..jac.ncols()).filter(|&c| free[c]).collect();
    if cols.is_empty() || jac.nrows() == 0 {
        return None;
    }
    let m = jac.nrows();
    let mut a = Mat::zeros(m, cols.len());
    for (k, &c) in cols.iter().enumerate() {
        let n = (0..m).map(|r| jac[(r, c)] * jac[(r, c)]).sum::<f64>().sqrt().max(1e-300);
        for r in 0..m {
            a[(r, k)] = jac[(r, c)] / n;
        }
    }
    let sv = a.singular_values().ok()?;
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

/// Relative cost gain below which a Levenberg–Marquardt step counts as converged (predicted from the
/// linearised model, before the step is evaluated).
const CONVERGED: f64 = 1e-9;

/// Levenberg–Marquardt iterations per pass of [`fit_from`] before it stops unconverged.
pub(crate) const MAX_ITERATIONS: usize = 100;

/// Relative cost gain below which the step's Jacobian is reused for the next (chord) step. Near the
/// minimum a gain `g` of the cost `m·σ²` (m rows) is a move of `√(g·m)` standard deviations of the
/// parameters — at 1e-4 about one σ on 10,000 rows, thousandths of a millimetre and millionths of a
/// radian for a calibrated arm — over which the Jacobian (smooth in angles of that size) changes by a
/// few millionths of itself. The chord step's fixed point is still the zero of the gradient, so it
/// converges to the same minimum; a chord step that fails refreshes the Jacobian first.
const REUSE_JACOBIAN: f64 = 1e-4;

/// The state of one Levenberg–Marquardt pass: the column-scaled normal matrix of the current Jacobian
/// (unit columns, so that mm, radians and minutes weigh alike), its scales and the damping. The scaled
/// Jacobian `A = J·D` is never formed: `AᵀA = D·JᵀJ·D` and `Aᵀr = D·Jᵀr` from the Jacobian itself (one
/// pass over its `m × p` entries per product, no copy of them).
struct Lm {
    /// The free columns of the Jacobian.
    cols: Vec<usize>,
    ata: Mat<f64>,
    /// `JᵀJ` of every column, reused for the scales.
    gram: Mat<f64>,
    scale: Vec<f64>,
    /// `∂θ/∂u` of each free column at the Jacobian's parameters: 1, or `−τ²` for a time constant moved
    /// as its rate `u = 1/τ`.
    chain: Vec<f64>,
    lambda: f64,
    /// The Jacobian is not the current parameters' (a chord step reused it).
    stale: bool,
    /// The Jacobian was refreshed after a failed chord step: the iteration is retried with it.
    refreshed: bool,
    /// The damping was raised after a failed step since the last accepted one.
    raised: bool,
}

impl Lm {
    fn new(cols: &[usize]) -> Self {
        let p = cols.len();
        Self {
            cols: cols.to_vec(),
            ata: Mat::zeros(p, p),
            gram: Mat::zeros(0, 0),
            scale: vec![1.0; p],
            chain: vec![1.0; p],
            lambda: 1e-3,
            stale: false,
            refreshed: false,
            raised: false,
        }
    }

    /// Takes `jac`'s free columns (at `theta`), in the coordinates moved ([`Rates`]) and scaled to unit
    /// norm, and forms their normal matrix.
    fn refresh(&mut self, jac: &Mat<f64>, theta: &[f64], rates: &Rates) {
        let n = jac.ncols();
        if self.gram.nrows() != n {
            self.gram = Mat::zeros(n, n);
        }
        matmul(self.gram.as_mut(), Accum::Replace, jac.as_ref().transpose(), jac.as_ref(), 1.0, Par::Seq);
        for (k, &c) in self.cols.iter().enumerate() {
            self.chain[k] = rates.dtheta_du(c, theta[c]);
            // A column that moves nothing here (a time constant held at its bound) keeps scale 1: its
            // row of the normal matrix is zero and the damping alone keeps it where it is.
            let norm = self.gram[(c, c)].max(0.0).sqrt() * self.chain[k].abs();
            self.scale[k] = if norm > 0.0 && norm.is_finite() { norm } else { 1.0 };
        }
        let weight = |k: usize| self.chain[k] / self.scale[k];
        for (k, &c) in self.cols.iter().enumerate() {
            for (l, &d) in self.cols.iter().enumerate() {
                self.ata[(k, l)] = self.gram[(c, d)] * weight(k) * weight(l);
            }
        }
        self.refreshed = self.stale;
        self.stale = false;
    }

    /// `AᵀA` from the scaled columns themselves (one copy of them): the matrix the uncertainties invert.
    /// Near-singular normal matrices (nearly dependent parameters, condition numbers of 1e15) are
    /// factorised more reliably from unit columns than from `D·JᵀJ·D`, whose entries carry the rounding
    /// of columns of very different sizes.
    fn scaled_normal_matrix(&self, jac: &Mat<f64>) -> Mat<f64> {
        let mut a = Mat::<f64>::zeros(jac.nrows(), self.cols.len());
        for (k, &c) in self.cols.iter().enumerate() {
            a.col_mut(k).copy_from(jac.col(c) * (self.chain[k] / self.scale[k]));
        }
        let mut ata = Mat::<f64>::zeros(self.cols.len(), self.cols.len());
        matmul(ata.as_mut(), Accum::Replace, a.as_ref().transpose(), a.as_ref(), 1.0, Par::Seq);
        ata
    }

    /// `Aᵀ r` on the scaled columns of `jac` (the Jacobian of the last refresh).
    fn gradient(&self, jac: &Mat<f64>, r: &[f64]) -> Mat<f64> {
        let mut full = Mat::<f64>::zeros(jac.ncols(), 1);
        let rv = faer::ColRef::from_slice(r);
        matmul(full.as_mut(), Accum::Replace, jac.as_ref().transpose(), rv.as_mat(), 1.0, Par::Seq);
        Mat::from_fn(self.cols.len(), 1, |k, _| full[(self.cols[k], 0)] * self.chain[k] / self.scale[k])
    }

    /// The damped step `(AᵀA + λ·diag) δ = Aᵀr` and the cost gain the linearised model predicts for it,
    /// `2 δᵀAᵀr − δᵀAᵀAδ`; `None` when the damped matrix is not positive definite.
    fn step(&self, g: &Mat<f64>) -> Option<(Vec<f64>, f64)> {
        let p = self.ata.nrows();
        let mut damped = self.ata.clone();
        for i in 0..p {
            damped[(i, i)] += self.lambda * (self.ata[(i, i)] + 1e-12);
        }
        let llt = damped.llt(faer::Side::Lower).ok()?;
        let step = llt.solve(g);
        let delta: Vec<f64> = (0..p).map(|k| step[(k, 0)]).collect();
        let mut quad = 0.0;
        for i in 0..p {
            let row: f64 = (0..p).map(|j| self.ata[(i, j)] * delta[j]).sum();
            quad += delta[i] * row;
        }
        let lin: f64 = (0..p).map(|k| delta[k] * g[(k, 0)]).sum();
        Some((delta, 2.0 * lin - quad))
    }

    /// Whether the iteration is to be repeated: the Jacobian was just refreshed after a failed chord
    /// step (the damping then stays where it was).
    fn retry(&mut self) -> bool {
        std::mem::take(&mut self.refreshed)
    }
}

/// The time constants of a model (an exponential drift's τ), which the fit moves as rates `u = 1/τ`:
/// the drift's departure from the linear one is about proportional to `1/τ`, so that in τ the cost is a
/// long curved valley towards τ → ∞ (a drift the data see as linear) that Gauss–Newton creeps along
/// step by step, while in `1/τ` it is nearly quadratic and the linear limit is the point `u = 1/τ_max`.
/// τ stays in [`TAU_RANGE_MIN`]; the reported τ and its standard deviation are in minutes (the
/// deviation by the delta method, `σ_τ = τ² σ_u`).
struct Rates {
    columns: Vec<usize>,
}

impl Rates {
    /// `∂θ_c/∂u_c` at `θ_c`.
    fn dtheta_du(&self, c: usize, theta: f64) -> f64 {
        if self.columns.contains(&c) { -theta * theta } else { 1.0 }
    }

    /// `θ_c` after the step `du` in column `c`'s moved coordinate.
    fn moved(&self, c: usize, theta: f64, du: f64) -> f64 {
        if self.columns.contains(&c) {
            let (lo, hi) = TAU_RANGE_MIN;
            let rate = (1.0 / theta + du).clamp(1.0 / hi, 1.0 / lo);
            (1.0 / rate).clamp(lo, hi)
        } else {
            theta + du
        }
    }
}

/// Levenberg–Marquardt identification of `model` on the given rows.
pub(crate) fn fit(
    robot: &Robot,
    model: &Model,
    data: &Dataset,
    rows: &[usize],
    pre: &Pre,
) -> Result<Fit, DiagnoseError> {
    fit_from(robot, model, data, rows, pre, &Start::new(model.initial(), vec![true; model.len()]))
}

/// Where a fit starts, what it may move (parameters with `movable[k] = false` keep `theta[k]`), and how
/// many Levenberg–Marquardt iterations per pass it may take.
pub(crate) struct Start {
    pub(crate) theta: Vec<f64>,
    pub(crate) movable: Vec<bool>,
    pub(crate) max_iterations: usize,
}

impl Start {
    /// From `theta`, moving the `movable` parameters, at most [`MAX_ITERATIONS`] per pass.
    pub(crate) fn new(theta: Vec<f64>, movable: Vec<bool>) -> Self {
        Self { theta, movable, max_iterations: MAX_ITERATIONS }
    }
}

// Long on purpose (~140 lines): the two identifiability passes, the damping loop and the covariance share
// the Jacobian, the residuals and the scales in flight; split, each part would take all of them back.
/// [`fit`] from `start`, moving only its movable parameters (a transfer: the effects fitted on one
/// file, only the frame and tool refitted on another).
pub(crate) fn fit_from(
    robot: &Robot,
    model: &Model,
    data: &Dataset,
    rows: &[usize],
    pre: &Pre,
    start: &Start,
) -> Result<Fit, DiagnoseError> {
    let names = model.parameter_names();
    let rates = Rates { columns: model.time_constants() };
    let mut theta = start.theta.clone();
    let (mut r, mut jac) = fit_residuals(robot, model, &theta, data, rows, pre, true)?;
    let ssr = |r: &[f64]| r.iter().map(|x| x * x).sum::<f64>();
    let mut cost = ssr(&r);
    let mut free = vec![false; model.len()];
    let mut fixed = Vec::new();
    let mut cols: Vec<usize> = Vec::new();
    let mut scale: Vec<f64> = Vec::new();
    let mut signs: Vec<f64> = Vec::new();
    let mut last_a = Mat::<f64>::zeros(0, 0);
    // Two passes: a parameter that acts only through another (an exponential drift's τ through its
    // amplitude, zero at the start) becomes identifiable once the first pass has moved the other. The
    // second pass is run only for such a parameter: the others' identifiability is decided once, at the
    // start, and not re-decided at the solution, where a parameter near the threshold could change sides.
    let mut inert = true;
    let mut converged_every_pass = true;
    for _pass in 0..2 {
        if !inert {
            break;
        }
        inert = (0..model.len()).any(|c| start.movable[c] && jac.col(c).norm_l2() <= INERT);
        let (f, fx) = identifiable(&jac, &names, &start.movable);
        if f == free {
            break;
        }
        free = f;
        fixed = fx;
        cols = (0..model.len()).filter(|&c| free[c]).collect();
        let p = cols.len();
        if p == 0 {
            break;
        }
        let mut lm = Lm::new(&cols);
        lm.refresh(&jac, &theta, &rates);
        let mut stopped = false;
        for _ in 0..start.max_iterations {
            let g = lm.gradient(&jac, &r);
            let mut step_taken = false;
            let mut converged = false;
            while lm.lambda < 1e12 {
                let Some((step, predicted)) = lm.step(&g) else {
                    lm.lambda *= 10.0;
                    continue;
                };
                // Converged when the step at this damping is predicted to gain less than 1e-9 of the
                // cost (the parameters then move by ~1e-5 of their uncertainty): the trial is not
                // evaluated — its actual change is rounding, ±1e-13 of the cost, and damping further only
                // shortens the step.
                if predicted <= CONVERGED * cost {
                    break;
                }
                let mut trial = theta.clone();
                for (k, &c) in cols.iter().enumerate() {
                    trial[c] = rates.moved(c, theta[c], step[k] / lm.scale[k]);
                }
                // Residuals first; the Jacobian only for an accepted step.
                let cost_before = cost;
                let (rt, _) = fit_residuals(robot, model, &trial, data, rows, pre, false)?;
                let ct = ssr(&rt);
                if ct < cost {
                    let gain = (cost - ct) / cost.max(1e-300);
                    theta = trial;
                    r = rt;
                    cost = ct;
                    // The damping follows how well the linearised model predicted the gain (ρ, the
                    // trust-region rule): less damping when it did (ρ > 3/4) — unless this damping was
                    // just reached from a failed step, when the smaller one is known to fail (a curved
                    // valley of nearly dependent parameters, where alternating would waste every
                    // other evaluation) — more when the step gained under a quarter of the prediction.
                    let rho = gain * cost_before / predicted.max(1e-300);
                    let raised = std::mem::take(&mut lm.raised);
                    if rho > 0.75 && !raised {
                        lm.lambda = (lm.lambda * 0.1).max(1e-12);
                    } else if rho < 0.25 {
                        lm.lambda *= 10.0;
                    }
                    // A step that gained less than 1e-9 of the cost ends the fit, as a predicted one does.
                    if gain <= CONVERGED {
                        converged = true;
                        break;
                    }
                    // A small step keeps its Jacobian for the next (chord) step ([`REUSE_JACOBIAN`]).
                    if gain >= REUSE_JACOBIAN {
                        jac = fit_residuals(robot, model, &theta, data, rows, pre, true)?.1;
                        lm.refresh(&jac, &theta, &rates);
                    } else {
                        lm.stale = true;
                    }
                    step_taken = true;
                    break;
                }
                if lm.stale {
                    jac = fit_residuals(robot, model, &theta, data, rows, pre, true)?.1;
                    lm.refresh(&jac, &theta, &rates);
                    break;
                }
                lm.lambda *= 10.0;
                lm.raised = true;
            }
            if converged || (!step_taken && !lm.retry()) {
                stopped = true;
                break;
            }
        }
        converged_every_pass &= stopped;
        // Back to θ's coordinates: a column's scale per unit of θ, and the sign `∂θ/∂u` gives a correlation.
        scale = lm.scale.iter().zip(&lm.chain).map(|(s, d)| s / d.abs()).collect();
        signs = lm.chain.iter().map(|d| d.signum()).collect();
        last_a = lm.scaled_normal_matrix(&jac);
    }
    let p = cols.len();
    // Uncertainty: σ̂² (AᵀA)⁻¹ on the scaled columns, unscaled.
    let m = (rows.len() * pre.stride()) as f64;
    let dof = (m - p as f64).max(1.0);
    let sigma2 = cost / dof;
    let mut std = vec![f64::NAN; model.len()];
    let mut correlated = Vec::new();
    if p > 0
        && let Ok(llt) = last_a.llt(faer::Side::Lower)
    {
        let inv = llt.inverse();
        for (k, &c) in cols.iter().enumerate() {
            std[c] = (sigma2 * inv[(k, k)]).max(0.0).sqrt() / scale[k];
        }
        for i in 0..p {
            for j in i + 1..p {
                let rho = signs[i] * signs[j] * inv[(i, j)] / (inv[(i, i)] * inv[(j, j)]).sqrt();
                if rho.abs() > NEARLY_DEPENDENT {
                    correlated.push(CorrelatedPair {
                        a: names[cols[i]].clone(),
                        b: names[cols[j]].clone(),
                        correlation: rho,
                    });
                }
            }
        }
    }
    Ok(Fit { theta, std, fixed, free, ssr: cost, correlated, converged: converged_every_pass })
}

/// Closed-form rigid registration (Kabsch): the `T` minimising Σ |b_i − T a_i|².
pub(crate) fn kabsch(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> Isometry3<f64> {
    if a.len() < 3 {
        return Isometry3::identity();
    }
    let n = a.len() as f64;
    let ca = a.iter().sum::<Vector3<f64>>() / n;
    let cb = b.iter().sum::<Vector3<f64>>() / n;
    let mut h = Matrix3::zeros();
    for (x, y) in a.iter().zip(b) {
        h += (x - ca) * (y - cb).transpose();
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else { return Isometry3::identity() };
    let mut d = Matrix3::identity();
    if (vt.transpose() * u.transpose()).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = vt.transpose() * d * u.transpose();
    let rot = nalgebra::UnitQuaternion::from_matrix(&r);
    let t = cb - rot * ca;
    Isometry3::from_parts(t.into(), rot)
}

/// The starting registration of a tracker-frame model: Kabsch between the nominal predictions and the
/// measurements.
pub(crate) fn initial_registration(
    robot: &Robot,
    data: &Dataset,
    rows: &[usize],
) -> Result<Isometry3<f64>, DiagnoseError> {
    let model = Model::new(robot, vec![])?;
    let n = data.measurements.len();
    let pre = Pre {
        torques: vec![vec![0.0; robot.chain().dof()]; n],
        rise: vec![vec![0.0; robot.chain().dof()]; n],
        lever_mm: None,
        weights: None,
        sin_cos: Vec::new(),
    };
    let mut a = Vec::new();
    let mut b = Vec::new();
    for &i in rows {
        let m = &data.measurements[i];
        if let Ok((p, _)) = model.predict(robot, &[], m, &pre.rise[i], &pre.torques[i], None, None, &mut None) {
            a.push(p);
            b.push(m.position_mm);
        }
    }
    Ok(kabsch(&a, &b))
}

#[cfg(test)]
mod tests {
    use faer::Mat;

    use super::{DEPENDENT, identifiable};

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
        let names: Vec<String> = (0..6).map(|c| format!("p{c}")).collect();
        let (free, fixed) = identifiable(&jac, &names, &[true; 6]);
        assert_eq!(free, expected, "fixed: {fixed:?}");
        assert_eq!(fixed.iter().map(|f| f.parameter.as_str()).collect::<Vec<_>>(), ["p2", "p3"]);
        assert!(fixed[0].reason.contains("equivalent to p0"), "{}", fixed[0].reason);
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
        let names: Vec<String> = ["a", "b", "c", "d"].map(String::from).to_vec();
        let (free, fixed) = identifiable(&jac, &names, &[true; 4]);
        assert_eq!(free, [true, true, false, true]);
        assert_eq!(fixed.len(), 1);
        assert_eq!(fixed[0].parameter, "c");
        assert!(fixed[0].reason.contains("equivalent to b (|cos| = 1.000)"), "{}", fixed[0].reason);
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod convergence {
    use super::{Start, fit_from};
    use crate::model::prepare;
    use crate::{Effect, HiddenEffect, JointIndex, Model, SimulationConfig, simulate};

    /// `converged` is the iteration's own verdict, not the loop's end: one iteration from zero stops by
    /// the limit (unconverged); the full fit stops by its test, and — checked independently of that test —
    /// lands on the hidden values within a few of its standard deviations.
    #[test]
    fn a_fit_stopped_by_the_iteration_limit_says_it_did_not_converge() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let robot = thermokin_io::read_robot(&root.join("configs/irb140.toml")).unwrap();
        let joint = |j| JointIndex::of(&robot, j).unwrap();
        let (offset, link_dx_mm) = (0.05f64.to_radians(), 0.3);
        let hidden = [
            HiddenEffect { effect: Effect::JointOffset(joint(1)), values: vec![offset] },
            HiddenEffect { effect: Effect::LinkDeviation(joint(3)), values: vec![link_dx_mm, 0.0, 0.0, 0.0, 0.0, 0.0] },
        ];
        let data = simulate(&robot, &hidden, &SimulationConfig { poses: 60, ..SimulationConfig::default() }).unwrap();
        let model = Model::new(&robot, vec![Effect::JointOffset(joint(1)), Effect::LinkDeviation(joint(3))]).unwrap();
        let rows: Vec<usize> = (0..data.len()).collect();
        let pre = prepare(&robot, &data, 0.0);
        let start = Start::new(model.initial(), vec![true; model.len()]);
        let one = fit_from(&robot, &model, &data, &rows, &pre, &Start { max_iterations: 1, ..start }).unwrap();
        assert!(!one.converged);
        let full = fit_from(&robot, &model, &data, &rows, &pre, &Start::new(model.initial(), vec![true; model.len()]))
            .unwrap();
        assert!(full.converged);
        assert!(full.ssr < one.ssr);
        for (k, truth) in [(0, offset), (1, link_dx_mm)] {
            assert!(
                (full.theta[k] - truth).abs() < 5.0 * full.std[k],
                "{k}: {} ± {} vs {truth}",
                full.theta[k],
                full.std[k]
            );
        }
    }
}
