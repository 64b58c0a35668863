//! The choice of poses: greedy selection with rank-three updates, then exchanges.
//!
//! **Criteria.** `M` are the position rows of the chosen (and already measured) poses on the columns of
//! the model the candidates can identify, each column scaled to unit root-mean-square per candidate, and
//! `B = (δI + MᵀM)⁻¹` the parameters' covariance per unit of noise (the ridge `δ`, [`RIDGE`], is a prior
//! of the parameters — a Bayesian design — that keeps it finite while fewer poses than parameters leave
//! directions unseen, so small that each pose first adds the directions nothing has seen yet).
//! - **Prediction (I-optimal, the default):** minimise `trace(W B)`, `W` the mean of `M̃ᵢᵀM̃ᵢ` over the
//!   poses of use (`Region`: the poses given, the program to be compensated, or else the candidates;
//!   one beyond the candidates' arcs taken at its nearest candidate, `BeyondArcs`),
//!   `M̃` their rows with the frame a test re-measures (a tracker's registration, an unknown tool)
//!   projected out over all of them ([`thermokin_identify::frame_refitted_weight`]): the mean squared
//!   error of the predicted tool position where the robot will work, once that frame is fitted there.
//!   That is what a calibration is used for and what a held-out test scores; a parameter counts as much
//!   as it moves the tool where the robot works, and the criterion is invariant under any invertible
//!   change of parameters. Measured on the real arms (docs/planner.md): over the candidates it reaches
//!   series B from 60 poses of the UR10's series C at 0.436 mm (D-optimal 0.482) and the WAM's 20 random
//!   poses from 30 of its grid at 2.672 (D-optimal 2.847), and equals D-optimal on the WAM grid's halves.
//!   (Before its frame was projected out — the registration's columns only zeroed — it lost on the
//!   UR10: 1.02 against 0.68 mm, its poses gathered where the candidates are dense.)
//! - **Parameters (D-optimal):** maximise `log det(δI + MᵀM)`, the volume of the confidence ellipsoid;
//!   FIGAROH's and most of the literature's. Invariant to a re-parameterisation of the whole model (a
//!   rotation of the tracker frame, a change of units). For pinning parameters down: the poses
//!   `diagnose` suggests after refusing an effect for what the poses cover, and an effect that matters
//!   little where the robot works (a wrist's cyclic error where the wrist hardly turns) but is wanted.
//!
//! **Algorithm.** Adding pose `i` (rows `Mᵢ`, 3 × p), with `Sᵢ = Mᵢ B Mᵢᵀ` and `C = I₃ + Sᵢ`, multiplies
//! the determinant by `det C` (the matrix determinant lemma) and, by Woodbury's identity,
//! `B ← B − U C⁻¹ Uᵀ` with `U = B Mᵢᵀ`, which lowers `trace(W B)` by `trace(C⁻¹ Tᵢ)`, `Tᵢ = Mᵢ B W B Mᵢᵀ`.
//! Every candidate keeps its 3 × 3 `Sᵢ` and `Tᵢ`, updated after each change from `Vⱼ = Mⱼ U` and
//! `Zⱼ = Mⱼ B W U`: a step costs `O(p²)` plus `O(p)` per candidate, so the plan's cost grows linearly with
//! the candidates. Removing a pose is the same update with the sign turned, which the exchange passes
//! use (Fedorov's exchange: a chosen pose is swapped for the candidate that gains the most once it is out,
//! whenever that improves the criterion).

use faer::linalg::matmul::matmul;
use faer::linalg::solvers::DenseSolveCore;
use faer::{Accum, Mat, Par};
use nalgebra::Matrix3;

use thermokin_identify::trace_of_product;

use crate::design::{Design, product};
use crate::params::{Criterion, Poses};

/// The ridge `δ` of the criterion, in the scaled columns (where one pose adds about 1 to each column's
/// diagonal): a millionth of a pose's information. Large enough that `δI + MᵀM` stays invertible in
/// double precision (its condition at most ~1e6 × the poses), small enough that a direction seen by any
/// pose outweighs it by orders of magnitude, so that the greedy steps first cover every direction.
pub const RIDGE: f64 = 1e-6;

/// `log det` and the inverse of a symmetric positive definite matrix, by Cholesky.
pub(crate) fn log_det_inverse(a: &Mat<f64>) -> Option<(f64, Mat<f64>)> {
    let llt = a.llt(faer::Side::Lower).ok()?;
    let l = llt.L();
    let log_det = 2.0 * (0..a.nrows()).map(|i| l[(i, i)].ln()).sum::<f64>();
    Some((log_det, llt.inverse()))
}

/// `δI + MᵀM` of the scaled rows `m`.
pub(crate) fn information(m: &Mat<f64>) -> Mat<f64> {
    let p = m.ncols();
    let mut a = Mat::from_fn(p, p, |i, j| if i == j { RIDGE } else { 0.0 });
    matmul(a.as_mut(), Accum::Add, m.as_ref().transpose(), m.as_ref(), 1.0, Par::Seq);
    a
}

/// The 3 × 3 block of rows `3i..3i+3` of a `3n × 3` matrix.
fn block(s: &Mat<f64>, i: usize) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| s[(3 * i + r, c)])
}

/// The state of a design being built: `B = (δI + MᵀM)⁻¹` of the poses in it (measured and chosen), and
/// per candidate `Sᵢ = Mᵢ B Mᵢᵀ` and `Tᵢ = Mᵢ B W B Mᵢᵀ` (rows `3i..3i+3` of `s` and `t`).
struct State<'a> {
    design: &'a Design,
    m: &'a Mat<f64>,
    w: &'a Mat<f64>,
    b: Mat<f64>,
    s: Mat<f64>,
    t: Mat<f64>,
    log_det: f64,
    variance: f64,
    /// The candidates in the design now.
    rows: Vec<usize>,
    /// `trace(W B)` at the last fresh factorisation.
    variance_at_refresh: f64,
}

/// A fresh factorisation is made when `trace(W B)` has fallen below this fraction of its value at the
/// last one: the updates subtract terms as large as what was there (the ridge's `1/δ` directions at
/// first), so each loses ~ε of the largest value seen — 1e-16 × 1e4 keeps the gains exact to ~1e-12.
const REFRESH: f64 = 1e-4;

/// The 3 × 3 diagonal blocks of `a · bᵀ` (`a`, `b`: 3n × p).
fn diagonal_blocks(a: &Mat<f64>, b: &Mat<f64>) -> Mat<f64> {
    Mat::from_fn(a.nrows(), 3, |r, c| {
        let i = r / 3;
        (0..a.ncols()).map(|k| a[(r, k)] * b[(3 * i + c, k)]).sum::<f64>()
    })
}

impl<'a> State<'a> {
    /// The measured poses alone.
    fn new(design: &'a Design) -> Option<Self> {
        Self::fresh(design, Vec::new())
    }

    /// The measured poses and candidates `rows`, factorised afresh.
    fn fresh(design: &'a Design, rows: Vec<usize>) -> Option<Self> {
        let (m, w) = (&design.candidates, &design.use_weight);
        let (log_det, b) = log_det_inverse(&information(&design.rows_with_measured(&rows)))?;
        let mb = product(m.as_ref(), b.as_ref());
        let s = diagonal_blocks(&mb, m);
        let mbw = product(mb.as_ref(), w.as_ref());
        let t = diagonal_blocks(&mbw, &mb);
        let variance = trace_of_product(w, &b);
        Some(Self { design, m, w, b, s, t, log_det, variance, rows, variance_at_refresh: variance })
    }

    /// The criterion's gain when candidate `i` is added (`sign` 1) or removed (−1): the rise of the log
    /// det, or the fall of the mean predicted variance.
    fn gain(&self, i: usize, sign: f64, criterion: Criterion) -> f64 {
        let c = Matrix3::identity() + sign * block(&self.s, i);
        match criterion {
            Criterion::Parameters => c.determinant().max(f64::MIN_POSITIVE).ln(),
            Criterion::Prediction => {
                sign * c.try_inverse().map_or(f64::NEG_INFINITY, |c| (c * block(&self.t, i)).trace())
            }
        }
    }

    /// The criterion's value, larger better (the log det, or the negated mean predicted variance).
    fn value(&self, criterion: Criterion) -> f64 {
        match criterion {
            Criterion::Parameters => self.log_det,
            Criterion::Prediction => -self.variance,
        }
    }

    /// Adds (`sign` 1) or removes (−1) candidate `i`; returns, per column, the fraction of its variance
    /// the change removed (negative for a removal). Factorises afresh when the updates have subtracted
    /// [`REFRESH`] of what was there.
    fn update(&mut self, i: usize, sign: f64) -> Option<Vec<f64>> {
        let reduction = self.rank_three(i, sign)?;
        if sign > 0.0 {
            self.rows.push(i);
        } else {
            self.rows.retain(|&r| r != i);
        }
        if self.variance < REFRESH * self.variance_at_refresh {
            *self = Self::fresh(self.design, std::mem::take(&mut self.rows))?;
        }
        Some(reduction)
    }

    /// The rank-three update of adding (`sign` 1) or removing (−1) candidate `i`.
    fn rank_three(&mut self, i: usize, sign: f64) -> Option<Vec<f64>> {
        let p = self.m.ncols();
        let c_inv = (Matrix3::identity() + sign * block(&self.s, i)).try_inverse()?;
        self.log_det += self.gain(i, sign, Criterion::Parameters);
        self.variance -= self.gain(i, sign, Criterion::Prediction);
        let u = product(self.b.as_ref(), self.m.as_ref().subrows(3 * i, 3).transpose());
        let u_c = Mat::from_fn(p, 3, |r, c| (0..3).map(|k| u[(r, k)] * c_inv[(k, c)]).sum::<f64>());
        let reduction =
            (0..p).map(|k| sign * (0..3).map(|a| u_c[(k, a)] * u[(k, a)]).sum::<f64>() / self.b[(k, k)]).collect();
        // Y = B W U (before B changes), K = Uᵀ W U.
        let wu = product(self.w.as_ref(), u.as_ref());
        let y = product(self.b.as_ref(), wu.as_ref());
        let k = Matrix3::from_fn(|r, c| (0..p).map(|x| u[(x, r)] * wu[(x, c)]).sum::<f64>());
        matmul(self.b.as_mut(), Accum::Add, u_c.as_ref(), u.as_ref().transpose(), -sign, Par::Seq);
        let v = product(self.m.as_ref(), u.as_ref());
        let z = product(self.m.as_ref(), y.as_ref());
        let ckc = c_inv * k * c_inv;
        for j in 0..self.m.nrows() / 3 {
            let (vj, zj) = (block(&v, j), block(&z, j));
            let ds = sign * vj * c_inv * vj.transpose();
            let dt = sign * (vj * c_inv * zj.transpose() + zj * c_inv * vj.transpose()) - vj * ckc * vj.transpose();
            for r in 0..3 {
                for c in 0..3 {
                    self.s[(3 * j + r, c)] -= ds[(r, c)];
                    self.t[(3 * j + r, c)] -= dt[(r, c)];
                }
            }
        }
        Some(reduction)
    }

    /// The candidate not `taken` that gains the most.
    fn best(&self, taken: &[bool], criterion: Criterion) -> Option<(usize, f64)> {
        (0..taken.len())
            .filter(|&i| !taken[i])
            .map(|i| (i, self.gain(i, 1.0, criterion)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
    }
}

/// Exchange passes at most after the greedy choice.
const MAX_EXCHANGE_PASSES: usize = 4;
/// Smallest relative gain of the criterion for which an exchange is made: well above the rounding of
/// the updates, far below what one pose adds.
const EXCHANGE_GAIN: f64 = 1e-9;

/// The predicted held-out RMS error per pose of use (3-D), per unit of noise
/// ([`thermokin_identify::heldout_rms`] of `trace(W B)`).
pub(crate) fn heldout_rms(design: &Design, variance: f64) -> f64 {
    thermokin_identify::heldout_rms(variance, 1.0, design.refitted, design.region_poses)
}

/// The standard error of a held-out RMS measured over the poses of use, as a fraction of it
/// ([`thermokin_identify::heldout_resolution`]).
pub(crate) fn resolution(design: &Design) -> f64 {
    thermokin_identify::heldout_resolution(design.refitted, design.region_poses)
}

/// Why an automatic count stopped ([`crate::Poses::Auto`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct AutoStop {
    /// The fall of the predicted held-out RMS the next pose would have given, per unit of noise.
    pub next_gain: f64,
    /// The standard error of a measured held-out RMS at the poses of use, per unit of noise.
    pub resolution: f64,
}

/// The chosen candidates, and, for an automatic count that stopped before its most, why.
pub(crate) struct Chosen {
    pub rows: Vec<usize>,
    pub stop: Option<AutoStop>,
}

/// Chooses candidates after the measured poses: greedily, then by exchange passes until one makes no
/// exchange. `poses` is the count, or [`Poses::Auto`]: the greedy choice stops at the first pose whose
/// fall of the predicted held-out RMS at the poses of use ([`heldout_rms`]) is below that RMS's own
/// standard error there ([`resolution`]) — a gain no test of those poses could show — but not before
/// the poses' rows (with the measured ones') reach the free parameters' count, below which the
/// predicted error is the ridge's, not the poses'. `None` when the information matrix cannot be
/// factorised (the ridge makes it positive definite: a non-finite Jacobian).
pub(crate) fn choose(design: &Design, poses: Poses, criterion: Criterion) -> Option<Chosen> {
    let mut state = State::new(design)?;
    let mut taken = vec![false; design.candidates.nrows() / 3];
    let mut chosen = Vec::with_capacity(poses.at_most());
    let floor = design.free.len().div_ceil(3).saturating_sub(design.measured.nrows() / 3);
    let mut stop = None;
    while chosen.len() < poses.at_most() {
        let (i, _) = state.best(&taken, criterion)?;
        if matches!(poses, Poses::Auto { .. }) && chosen.len() >= floor {
            let now = heldout_rms(design, state.variance);
            let next_gain = now - heldout_rms(design, state.variance - state.gain(i, 1.0, Criterion::Prediction));
            let resolution = resolution(design) * now;
            if next_gain < resolution {
                stop = Some(AutoStop { next_gain, resolution });
                break;
            }
        }
        state.update(i, 1.0)?;
        taken[i] = true;
        chosen.push(i);
    }
    exchange(&mut state, &mut taken, &mut chosen, criterion)?;
    Some(Chosen { rows: chosen, stop })
}

/// Fedorov's exchange passes over `chosen` until one makes no exchange ([`MAX_EXCHANGE_PASSES`] at most).
fn exchange(state: &mut State<'_>, taken: &mut [bool], chosen: &mut [usize], criterion: Criterion) -> Option<()> {
    for _ in 0..MAX_EXCHANGE_PASSES {
        let mut exchanged = false;
        for k in 0..chosen.len() {
            let out = chosen[k];
            let before = state.value(criterion);
            state.update(out, -1.0)?;
            taken[out] = false;
            let (inn, gain) = state.best(taken, criterion)?;
            let better = state.value(criterion) + gain > before + EXCHANGE_GAIN * before.abs().max(1.0);
            let into = if better { inn } else { out };
            state.update(into, 1.0)?;
            taken[into] = true;
            chosen[k] = into;
            exchanged |= into != out;
        }
        if !exchanged {
            break;
        }
    }
    Some(())
}

/// The criterion after the measured poses and then after each of `rows` in turn — the log det, which
/// never decreases, or the mean predicted variance `trace(W B)`, which never increases (each pose adds a
/// positive semi-definite term to the information) — and per pose the fraction of each column's
/// remaining variance it removed.
pub(crate) fn along(design: &Design, rows: &[usize], which: Criterion) -> Option<(Vec<f64>, Vec<Vec<f64>>)> {
    let mut state = State::new(design)?;
    let value = |s: &State<'_>| match which {
        Criterion::Parameters => s.log_det,
        Criterion::Prediction => s.variance,
    };
    let mut criterion = vec![value(&state)];
    let mut reduction = Vec::with_capacity(rows.len());
    for &i in rows {
        reduction.push(state.update(i, 1.0)?);
        criterion.push(value(&state));
    }
    Some((criterion, reduction))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use faer::Mat;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::{Criterion, State, block, information, log_det_inverse, product, trace_of_product};
    use crate::design::Design;

    /// A design of `n` random candidates on `p` columns after `p` measured random poses.
    fn design(n: usize, p: usize) -> Design {
        let robot = thermokin_chain::Robot::new("irb140", thermokin_testdata::irb140_table9());
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let m = Mat::from_fn(3 * n, p, |_, _| rng.random_range(-1.0..1.0));
        let mut w = product(m.as_ref().transpose(), m.as_ref());
        w *= faer::Scale(1.0 / n as f64);
        Design {
            model: thermokin_identify::Model::new(&robot, vec![]).unwrap(),
            free: (0..p).collect(),
            not_identifiable: vec![],
            scale: vec![1.0; p],
            candidates: m,
            measured: Mat::from_fn(3 * p, p, |_, _| rng.random_range(-1.0..1.0)),
            positions: vec![],
            use_weight: w,
            as_given_weight: None,
            region_poses: n,
            at_nearest: 0,
            refitted: 0,
            left_out: vec![],
        }
    }

    /// The incremental state — after additions and a removal — equals the same quantities computed from
    /// scratch: the log det and `trace(W B)` of the poses in it, and every candidate's `Sᵢ` and `Tᵢ`. To
    /// 1e-9 relative: after measured poses that see every direction the updates subtract nothing much
    /// larger than what remains (rounding ~1e-14); a wrong term in an update is off by order one.
    #[test]
    fn the_rank_three_updates_equal_a_fresh_factorisation() {
        const TOLERANCE: f64 = 1e-9;
        let d = design(40, 12);
        let mut state = State::new(&d).unwrap();
        for i in [3, 17, 5, 29, 11] {
            state.update(i, 1.0).unwrap();
        }
        state.update(17, -1.0).unwrap();
        let rows: Vec<usize> = [3, 5, 29, 11].iter().flat_map(|&i| 3 * i..3 * i + 3).collect();
        let with_measured =
            |rows: &[usize]| {
                let k = d.measured.nrows();
                Mat::from_fn(k + rows.len(), 12, |r, c| {
                    if r < k { d.measured[(r, c)] } else { d.candidates[(rows[r - k], c)] }
                })
            };
        let m = with_measured(&rows);
        let (log_det, b) = log_det_inverse(&information(&m)).unwrap();
        assert!((state.log_det - log_det).abs() < TOLERANCE * log_det.abs().max(1.0), "{} {log_det}", state.log_det);
        let variance = trace_of_product(&d.use_weight, &b);
        let mb = product(d.candidates.as_ref(), b.as_ref());
        let g = product(product(b.as_ref(), d.use_weight.as_ref()).as_ref(), b.as_ref());
        let mg = product(d.candidates.as_ref(), g.as_ref());
        for i in [0, 3, 17, 39] {
            let mi = d.candidates.as_ref().subrows(3 * i, 3);
            let s = product(mb.as_ref().subrows(3 * i, 3), mi.transpose());
            let t = product(mg.as_ref().subrows(3 * i, 3), mi.transpose());
            let (bs, bt) = (block(&state.s, i), block(&state.t, i));
            for r in 0..3 {
                for c in 0..3 {
                    assert!((bs[(r, c)] - s[(r, c)]).abs() < TOLERANCE * (1.0 + s[(r, c)].abs()), "S{i}");
                    assert!(
                        (bt[(r, c)] - t[(r, c)]).abs() < TOLERANCE * (1.0 + t[(r, c)].abs()),
                        "T{i}: {} {}",
                        bt[(r, c)],
                        t[(r, c)]
                    );
                }
            }
        }
        // The gains predicted for a candidate are the changes a fresh factorisation sees.
        let gain_d = state.gain(0, 1.0, Criterion::Parameters);
        let gain_i = state.gain(0, 1.0, Criterion::Prediction);
        let rows0: Vec<usize> = rows.iter().copied().chain(0..3).collect();
        let m0 = with_measured(&rows0);
        let (log_det0, b0) = log_det_inverse(&information(&m0)).unwrap();
        assert!((log_det0 - log_det - gain_d).abs() < TOLERANCE * log_det0.abs().max(1.0));
        assert!((variance - trace_of_product(&d.use_weight, &b0) - gain_i).abs() < TOLERANCE * variance);
    }
}
