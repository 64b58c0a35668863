//! The predicted error of a fitted model where the robot will work: the mean squared error of the
//! predicted tool position over some poses of use, once the frame a test there re-measures is fitted
//! on them — what a plan promises (`thermokin-planner`) and what a diagnosis predicts of itself
//! (`thermokin-diagnose`), by one formula.
//!
//! With `M` the position rows of the poses of use (3 per pose, `u` poses) on a model's columns and `Σ`
//! a covariance of the parameters, the predicted positions err by `M δ`, `δ ~ (0, Σ)`. A test fits the
//! frame columns `F` (a tracker's registration, an unknown tool) once over all its poses, which takes up
//! the part of any error in their span: what remains is `(I − P) M δ`, `P` the projection onto `M[:, F]`.
//! Its mean squared norm per pose is `trace(W Σ)` with `W = (1/u) Mᵀ(I − P)M` ([`frame_refitted_weight`]).
//! A measured test adds its own noise, of which the frame's fit takes `k` of the `3u` coordinates'
//! worth: `σ² (3 − k/u)` per pose ([`heldout_rms`]).

use faer::linalg::matmul::matmul;
use faer::prelude::Solve;
use faer::{Accum, Mat, Par};

use crate::{Effect, Model};

/// `W = (1/u) Mᵀ(I − P)M` of the poses of use whose rows are `rows` (3 per pose), `P` the projection
/// onto the columns `frame` over all of them together. With `G = MᵀM` this is the Schur complement
/// `(G − G[:, F] G[F, F]⁻¹ G[F, :]) / u`; `G[F, F]` is ridged by `1e-12` of its largest diagonal entry,
/// so that a frame column the poses cannot pin down (fewer than three poses) still solves. The frame's
/// own rows and columns of `W` are zero: a test re-measures them.
///
/// ```
/// use faer::Mat;
/// // Two poses, one frame column (a shift along x) and one other column.
/// let rows = Mat::from_fn(6, 2, |r, c| if c == 0 { (r % 3 == 0) as u8 as f64 } else { r as f64 });
/// let w = thermokin_identify::frame_refitted_weight(&rows, &[0]);
/// assert_eq!(w[(0, 0)], 0.0);
/// assert!(w[(1, 1)] > 0.0);
/// ```
pub fn frame_refitted_weight(rows: &Mat<f64>, frame: &[usize]) -> Mat<f64> {
    let u = (rows.nrows() / 3).max(1) as f64;
    let p = rows.ncols();
    let mut g = Mat::<f64>::zeros(p, p);
    matmul(g.as_mut(), Accum::Replace, rows.as_ref().transpose(), rows.as_ref(), 1.0, Par::Seq);
    if !frame.is_empty() {
        let largest = frame.iter().map(|&c| g[(c, c)]).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
        let gff = Mat::from_fn(frame.len(), frame.len(), |i, k| {
            g[(frame[i], frame[k])] + if i == k { 1e-12 * largest } else { 0.0 }
        });
        let gfa = Mat::from_fn(frame.len(), p, |i, k| g[(frame[i], k)]);
        if let Ok(llt) = gff.llt(faer::Side::Lower) {
            let x = llt.solve(&gfa);
            matmul(g.as_mut(), Accum::Add, gfa.as_ref().transpose(), x.as_ref(), -1.0, Par::Seq);
        }
        for &c in frame {
            for k in 0..p {
                g[(c, k)] = 0.0;
                g[(k, c)] = 0.0;
            }
        }
    }
    g *= faer::Scale(1.0 / u);
    g
}

/// The positions in `columns` (model columns) of the parameters of the frame a test re-measures on its own
/// poses — a tracker's registration, an unknown tool's point and rotation: the `frame` of
/// [`frame_refitted_weight`].
pub fn refitted_frame(model: &Model, columns: &[usize]) -> Vec<usize> {
    (0..columns.len())
        .filter(|&k| {
            matches!(
                model.parameter(columns[k]),
                Some((Effect::Registration | Effect::ToolPoint | Effect::ToolRotation, _))
            )
        })
        .collect()
}

/// The predicted held-out RMS per pose of use (3-D): `√(v + σ²(3 − k/u))` for a model's share `v`
/// (`trace(W Σ)`, mm²), a test's noise `σ` (mm per axis), `k` frame parameters fitted over `u` poses.
pub fn heldout_rms(model_share_mm2: f64, noise_mm: f64, refitted: usize, poses_of_use: usize) -> f64 {
    let u = poses_of_use.max(1) as f64;
    let own = (3.0 - refitted as f64 / u).max(0.0);
    (model_share_mm2.max(0.0) + noise_mm * noise_mm * own).sqrt()
}

/// The standard error of a held-out RMS measured over `u` poses of use with `k` frame parameters fitted
/// there, as a fraction of that RMS: a mean of `ν = 3u − k` squared normal coordinates has relative
/// standard deviation `√(2/ν)`, its square root half that, `1/√(2ν)`.
pub fn heldout_resolution(refitted: usize, poses_of_use: usize) -> f64 {
    let nu = (3 * poses_of_use).saturating_sub(refitted).max(1) as f64;
    1.0 / (2.0 * nu).sqrt()
}

/// `trace(a · b)` of two square matrices of one size.
pub fn trace_of_product(a: &Mat<f64>, b: &Mat<f64>) -> f64 {
    (0..a.nrows()).map(|i| (0..a.ncols()).map(|k| a[(i, k)] * b[(k, i)]).sum::<f64>()).sum()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use faer::Mat;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::{frame_refitted_weight, trace_of_product};

    /// `trace(W Σ)` is what it claims: the mean squared norm, per pose, of the errors `M δ` left after a
    /// least-squares fit of the frame columns over all the poses — checked by sampling `δ ~ N(0, Σ)`,
    /// fitting the frame columns to `M δ` directly (normal equations) and averaging the remainders. To 3 %:
    /// 20,000 draws of a mean of squares have a relative standard error near 1 %.
    #[test]
    fn the_weight_is_the_error_left_after_the_frame_is_refitted() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let (u, p) = (7, 5);
        let m = Mat::from_fn(3 * u, p, |_, _| rng.random_range(-1.0..1.0));
        let frame = [0, 2];
        let w = frame_refitted_weight(&m, &frame);
        // Σ = L Lᵀ, L lower triangular with a positive diagonal.
        let l = Mat::from_fn(p, p, |i, k| {
            if k < i {
                rng.random_range(-0.5..0.5)
            } else if k == i {
                1.0
            } else {
                0.0
            }
        });
        let sigma = &l * l.transpose();
        let predicted = trace_of_product(&w, &sigma);
        let mf = Mat::from_fn(3 * u, frame.len(), |r, c| m[(r, frame[c])]);
        let nff = mf.transpose() * &mf;
        let llt = nff.llt(faer::Side::Lower).unwrap();
        let draws = 20_000;
        let mut sum = 0.0;
        for _ in 0..draws {
            let z = Mat::from_fn(p, 1, |_, _| crate::normal(&mut rng));
            let e = &m * (&l * z);
            let coef = faer::prelude::Solve::solve(&llt, &(mf.transpose() * &e));
            let rest = &e - &mf * coef;
            sum += rest.squared_norm_l2() / u as f64;
        }
        let sampled = sum / draws as f64;
        assert!((sampled / predicted - 1.0).abs() < 0.03, "sampled {sampled}, predicted {predicted}");
    }
}
