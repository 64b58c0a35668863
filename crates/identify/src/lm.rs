//! One Levenberg–Marquardt pass's state: the column-scaled normal matrix, its damping, and the time
//! constants moved as rates.

use faer::linalg::matmul::matmul;
use faer::linalg::solvers::Solve;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Accum, Mat, Par};

use crate::effect::TAU_RANGE_MIN;

/// Relative cost gain below which a Levenberg–Marquardt step counts as converged (predicted from the
/// linearised model, before the step is evaluated), whatever the data's size.
pub(crate) const CONVERGED: f64 = 1e-9;

/// The smallest move, in standard deviations of the parameters, that a fit still takes: a step predicted
/// (or found) to gain less than `SETTLED² · σ̂²` of the cost ends the fit, `σ̂² = cost / (m − p)` the
/// residual variance of `m` rows and `p` free parameters. Why: near the minimum a step's gain is
/// `δᵀAᵀAδ`, and `σ̂²(AᵀA)⁻¹` is the parameters' covariance, so the gain over `σ̂²` is the step's squared
/// length in standard deviations (Mahalanobis) — below 0.1² the fit is at its minimum to a tenth of
/// its own uncertainty. Measured on the real UR10 (issue #49): the complete geometry's fits on 2,000
/// poses crept along a flat valley at gains of 1e-8 of the cost per step (a hundredth of σ each, a
/// large-residual problem where Gauss–Newton converges only linearly) until the 100-iteration cap —
/// 45 of 168 such fits, a quarter of the diagnosis's work; [`CONVERGED`] alone asks for steps of 0.003 σ
/// there (`√(1e-9 · m)`), and a thousandth of σ on a week of poses.
pub(crate) const SETTLED: f64 = 0.1;

/// The cost gain below which a fit has converged at `cost` — of which `prior_cost` is its prior's rows —
/// over `rows` residual rows of data with `free` parameters: [`CONVERGED`] of the cost, or a move under
/// [`SETTLED`] of the parameters' standard deviations (`σ̂²` from the data's rows), whichever is larger —
/// the latter only where the prior's rows hold under a hundredth of the cost: a strong prior's tension
/// against the data is no noise to measure a move by (a tool point pulled by its prior 0.5 mm from where
/// 25 poses put it within 0.01 mm would stop a tenth of its true σ short), and such a fit reaches its
/// minimum in a few steps anyway; a weak one (the completion's weakest, a hundredth of a row per
/// parameter) leaves the data's noise as it is, and its fit creeps along the same flat valleys as least
/// squares.
pub(crate) fn converged_gain(cost: f64, prior_cost: f64, rows: usize, free: usize) -> f64 {
    if strong_prior(cost, prior_cost) {
        return CONVERGED * cost;
    }
    let dof = (rows as f64 - free as f64).max(1.0);
    (CONVERGED * cost).max(SETTLED * SETTLED * (cost - prior_cost) / dof)
}

/// The predicted gain below which a fit that settles its residuals alone ([`Settle::Residuals`]) ends
/// beside [`converged_gain`]: its `relative_gain` of the data rows' cost (0 for [`Settle::Parameters`]),
/// only where the prior's rows hold under a hundredth of the cost, as there. A prediction, not a step's
/// found gain: a chord step ([`REUSE_JACOBIAN`]) may gain a tenth of what its stale Jacobian predicts and
/// still leave as much to gain as before — on the real UR10's series A such a step ended the screen's
/// fit 0.13 % of its residual scale early.
pub(crate) fn residuals_settled_gain(cost: f64, prior_cost: f64, settle: Settle) -> f64 {
    match settle {
        Settle::Residuals { relative_gain } if !strong_prior(cost, prior_cost) => relative_gain * (cost - prior_cost),
        _ => 0.0,
    }
}

/// Whether the prior's rows hold a hundredth of the cost or more: their tension against the data is then
/// no noise to measure a move by ([`converged_gain`], [`residuals_settled_gain`]).
fn strong_prior(cost: f64, prior_cost: f64) -> bool {
    prior_cost > 0.01 * cost
}

/// Relative cost gain below which the step's Jacobian is reused for the next (chord) step. Near the
/// minimum a gain `g` of the cost `m·σ²` (m rows) is a move of `√(g·m)` standard deviations of the
/// parameters — at 1e-4 about one σ on 10,000 rows, thousandths of a millimetre and millionths of a
/// radian for a calibrated arm — over which the Jacobian (smooth in angles of that size) changes by a
/// few millionths of itself. The chord step's fixed point is still the zero of the gradient, so it
/// converges to the same minimum; a chord step that fails refreshes the Jacobian first.
pub(crate) const REUSE_JACOBIAN: f64 = 1e-4;

/// How many times [`REUSE_JACOBIAN`]'s gain a step must be predicted to gain for its trial to be
/// evaluated with its Jacobian (speculatively: an accepted step that gains that much refreshes the
/// Jacobian at once, and one pass along the poses then gives both). Two: a step gains about what the
/// linearised model predicts (the gain ratio ρ near 1 where Gauss–Newton works), so one predicted at
/// twice the threshold nearly always clears it, and a miss costs one Jacobian pass. Counted on the real
/// UR10's series C with B held out (issue #60): of the 2,913 trials so evaluated, 2,866 were accepted
/// with a refresh (each one residual pass saved) and 47 were not (each one Jacobian pass more, to put
/// the iterate's back); of all 3,826 first trials of a step, 2,939 refreshed the Jacobian.
pub(crate) const SPECULATE: f64 = 2.0;

/// Rows of the scaled Jacobian copied at a time into [`Lm::scaled_normal_matrix`]'s block (3,000 rows ×
/// 60 columns: 1.4 MB), whatever the poses: a copy of the whole Jacobian was a week's largest allocation
/// after the Jacobian itself.
const NORMAL_BLOCK_ROWS: usize = 3000;

/// What a fit must settle before it stops ([`crate::Start::settle`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Settle {
    /// The parameters, to a tenth of their standard deviation (or a gain of 1e-9 of the cost): every fit
    /// whose values are reported, compared or carried on.
    #[default]
    Parameters,
    /// The residuals only: a step predicted to gain less than `relative_gain` of the cost ends the fit
    /// too. A gain `g` of the cost `m·σ̂²` moves the `m` residual rows by `√g·σ̂` in RMS, so `1e-6` stops
    /// where the next step would move the rows by a thousandth of their scale — what a fit whose
    /// residuals alone are used (the gross-error screen's, judged against a few σ̂) needs, where the
    /// parameters' own rule asks for a tenth of their σ, which shrinks as `1/√m`: a week of 100,000 poses
    /// creeps along its flat valleys for steps the residuals do not see (issue #60).
    Residuals {
        /// The cost's relative gain below which a predicted step ends the fit.
        relative_gain: f64,
    },
}

/// The state of one Levenberg–Marquardt pass: the column-scaled normal matrix of the current Jacobian
/// (unit columns, so that mm, radians and minutes weigh alike), its scales and the damping. The scaled
/// Jacobian `A = J·D` is never formed: `AᵀA = D·JᵀJ·D` and `Aᵀr = D·Jᵀr` from the Jacobian itself (one
/// pass over its `m × p` entries per product, no copy of them).
pub(crate) struct Lm {
    /// The free columns of the Jacobian.
    pub(crate) cols: Vec<usize>,
    pub(crate) ata: Mat<f64>,
    /// `JᵀJ` of every column, reused for the scales.
    pub(crate) gram: Mat<f64>,
    pub(crate) scale: Vec<f64>,
    /// `∂θ/∂u` of each free column at the Jacobian's parameters: 1, or `−τ²` for a time constant moved
    /// as its rate `u = 1/τ`.
    pub(crate) chain: Vec<f64>,
    pub(crate) lambda: f64,
    /// The Jacobian is not the current parameters' (a chord step reused it).
    pub(crate) stale: bool,
    /// The Jacobian was refreshed after a failed chord step: the iteration is retried with it.
    pub(crate) refreshed: bool,
    /// The factor the next failed step raises the damping by ([`Lm::raise`]).
    pub(crate) nu: f64,
}

impl Lm {
    pub(crate) fn new(cols: &[usize]) -> Self {
        let p = cols.len();
        Self {
            cols: cols.to_vec(),
            ata: Mat::zeros(p, p),
            gram: Mat::zeros(0, 0),
            scale: vec![1.0; p],
            chain: vec![1.0; p],
            // Near Nielsen's start for a good initial guess (`τ = 1e-6` of the unit-scaled normal matrix's
            // diagonal; Madsen, Nielsen & Tingleff 2004, §3.2): every fit starts at the robot file's
            // values, near its end. At 1e-3 the rule's at most threefold decrease per step cost the
            // simulated weeks' short, well-conditioned fits two or three steps each (3,000 and 12,000
            // poses 1.55× and 1.44× the old rule's time; 1.09× and 1.11× from here). A tenth of τ:
            // the first step of an affine fit is the exact solution but for the damping's relative
            // shortening, which at 1e-6 left a tool point 1.2e-6 mm off its ridge solution (held to
            // 1e-6 mm by `the_prior_gives_the_ridge_solution_of_an_affine_problem`, fit.rs), and then
            // stopped, the rest being under a tenth of its σ.
            lambda: 1e-7,
            stale: false,
            refreshed: false,
            nu: 2.0,
        }
    }

    /// Takes `jac`'s free columns (at `theta`), in the coordinates moved ([`Rates`]) and scaled to unit
    /// norm, and forms their normal matrix.
    pub(crate) fn refresh(&mut self, jac: &Mat<f64>, theta: &[f64], rates: &Rates) {
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

    /// `AᵀA` from the scaled columns themselves, a block of [`NORMAL_BLOCK_ROWS`] rows copied at a time:
    /// the matrix the uncertainties invert. Near-singular normal matrices (nearly dependent parameters,
    /// condition numbers of 1e15) are factorised more reliably from unit columns than from `D·JᵀJ·D`,
    /// whose entries carry the rounding of columns of very different sizes.
    pub(crate) fn scaled_normal_matrix(&self, jac: &Mat<f64>) -> Mat<f64> {
        let q = self.cols.len();
        let mut ata = Mat::<f64>::zeros(q, q);
        let mut a = Mat::<f64>::zeros(NORMAL_BLOCK_ROWS.min(jac.nrows()), q);
        for start in (0..jac.nrows()).step_by(NORMAL_BLOCK_ROWS) {
            let rows = NORMAL_BLOCK_ROWS.min(jac.nrows() - start);
            let mut block = a.as_mut().subrows_mut(0, rows);
            for (k, &c) in self.cols.iter().enumerate() {
                block.rb_mut().col_mut(k).copy_from(jac.col(c).subrows(start, rows) * (self.chain[k] / self.scale[k]));
            }
            matmul(ata.as_mut(), Accum::Add, block.rb().transpose(), block.rb(), 1.0, Par::Seq);
        }
        ata
    }

    /// `Aᵀ r` on the scaled columns of `jac` (the Jacobian of the last refresh).
    pub(crate) fn gradient(&self, jac: &Mat<f64>, r: &[f64]) -> Mat<f64> {
        let mut full = Mat::<f64>::zeros(jac.ncols(), 1);
        let rv = faer::ColRef::from_slice(r);
        matmul(full.as_mut(), Accum::Replace, jac.as_ref().transpose(), rv.as_mat(), 1.0, Par::Seq);
        Mat::from_fn(self.cols.len(), 1, |k, _| full[(self.cols[k], 0)] * self.chain[k] / self.scale[k])
    }

    /// The damped step `(AᵀA + λ·diag) δ = Aᵀr` and the cost gain the linearised model predicts for it,
    /// `2 δᵀAᵀr − δᵀAᵀAδ`; `None` when the damped matrix is not positive definite.
    pub(crate) fn step(&self, g: &Mat<f64>) -> Option<(Vec<f64>, f64)> {
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

    /// The damping after an accepted step, from how well the linearised model predicted its gain (`ρ`, the
    /// gain ratio): Nielsen's continuous rule, `λ ← λ·max(1/3, 1 − (2ρ − 1)³)`, and the factor of the
    /// next failure back to 2 (H. B. Nielsen, *Damping parameter in Marquardt's method*, IMM-REP-1999-05;
    /// K. Madsen, H. B. Nielsen, O. Tingleff, *Methods for non-linear least squares problems*, 2004,
    /// eq. 3.16). Why not the step rule it replaces (÷10 above ρ = 3/4, ×10 below 1/4 or on a failure,
    /// and a damping reached from a failed step never lowered): in the flat valleys of nearly dependent
    /// parameters — the complete geometry beside a tracker frame, a probe and compliances — the damping
    /// at which steps gain lies between two powers of ten. The step rule alternated between them, failing
    /// at the lower and crawling at the higher (on the UR10's series A a fit's gain shrank 0.86× a step
    /// until the 100-iteration limit); the continuous rule settles where steps gain.
    pub(crate) fn adapt(&mut self, rho: f64) {
        let x = 2.0 * rho - 1.0;
        self.lambda = (self.lambda * (1.0 / 3.0f64).max(1.0 - x * x * x)).max(1e-12);
        self.nu = 2.0;
    }

    /// The damping after a failed step: raised by `ν`, which doubles with each failure in a row
    /// ([`Lm::adapt`]'s rule).
    pub(crate) fn raise(&mut self) {
        self.lambda *= self.nu;
        self.nu *= 2.0;
    }

    /// Whether the iteration is to be repeated: the Jacobian was just refreshed after a failed chord
    /// step (the damping then stays where it was).
    pub(crate) fn retry(&mut self) -> bool {
        std::mem::take(&mut self.refreshed)
    }
}

/// The time constants of a model (an exponential drift's τ), which the fit moves as rates `u = 1/τ`:
/// the drift's departure from the linear one is about proportional to `1/τ`, so that in τ the cost is a
/// long curved valley towards τ → ∞ (a drift the data see as linear) that Gauss–Newton creeps along
/// step by step, while in `1/τ` it is nearly quadratic and the linear limit is the point `u = 1/τ_max`.
/// τ stays in [`TAU_RANGE_MIN`]; the reported τ and its standard deviation are in minutes (the
/// deviation by the delta method, `σ_τ = τ² σ_u`).
pub(crate) struct Rates {
    pub(crate) columns: Vec<usize>,
}

impl Rates {
    /// `∂θ_c/∂u_c` at `θ_c`.
    pub(crate) fn dtheta_du(&self, c: usize, theta: f64) -> f64 {
        if self.columns.contains(&c) { -theta * theta } else { 1.0 }
    }

    /// `θ_c` after the step `du` in column `c`'s moved coordinate.
    pub(crate) fn moved(&self, c: usize, theta: f64, du: f64) -> f64 {
        if self.columns.contains(&c) {
            let (lo, hi) = TAU_RANGE_MIN;
            let rate = (1.0 / theta + du).clamp(1.0 / hi, 1.0 / lo);
            (1.0 / rate).clamp(lo, hi)
        } else {
            theta + du
        }
    }
}
