//! Statistics: of held-out errors, and the χ² tail the screens and scans test against.

use serde::Serialize;

/// The chance that a clean set with Gaussian residuals gets one false flag, whatever its size.
pub const FALSE_ALARM: f64 = 0.01;

/// The lowest and highest of `values`.
pub(crate) fn span(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)))
}

/// Held-out error statistics of the 3-D position residual, mm.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Stats {
    /// Mean |e|.
    pub heldout_mean_mm: f64,
    /// RMS |e|.
    pub heldout_rms_mm: f64,
    /// Max |e|.
    pub heldout_max_mm: f64,
    /// Median |e|: robust to a few wild poses.
    pub heldout_median_mm: f64,
    /// 95th percentile of |e| (nearest rank).
    pub heldout_p95_mm: f64,
    /// Held-out residuals counted.
    pub heldout_count: usize,
}

impl Stats {
    /// The statistics of these error norms (mm).
    pub fn of(norms: &[f64]) -> Stats {
        let n = norms.len().max(1) as f64;
        let mut sorted = norms.to_vec();
        sorted.sort_by(f64::total_cmp);
        let rank = |p: f64| -> f64 {
            if sorted.is_empty() {
                return 0.0;
            }
            let k = ((p * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
            sorted[k - 1]
        };
        Stats {
            heldout_mean_mm: norms.iter().sum::<f64>() / n,
            heldout_rms_mm: (norms.iter().map(|x| x * x).sum::<f64>() / n).sqrt(),
            heldout_max_mm: norms.iter().copied().fold(0.0, f64::max),
            heldout_median_mm: rank(0.5),
            heldout_p95_mm: rank(0.95),
            heldout_count: norms.len(),
        }
    }
}

/// `x` with `P(χ²_k > x) = p` (0 < p < 1), by bisection on [`chi_square_survival`] (monotone in `x`),
/// to 1e-10 relative.
pub(crate) fn chi_square_upper_quantile(k: usize, p: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    while chi_square_survival(k, hi) > p {
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if chi_square_survival(k, mid) > p {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-10 * hi {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// `P(χ²_k > x)` in closed form: for even `k`, `e^(−x/2) Σ_{i<k/2} (x/2)^i / i!`; for odd `k`,
/// `erfc(√(x/2)) + e^(−x/2) Σ_{i=1}^{(k−1)/2} (x/2)^(i−1/2) / Γ(i + 1/2)`.
pub(crate) fn chi_square_survival(k: usize, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let h = 0.5 * x;
    let e = (-h).exp();
    if k.is_multiple_of(2) {
        let mut term = 1.0;
        let mut sum = 1.0;
        for i in 1..k / 2 {
            term *= h / i as f64;
            sum += term;
        }
        e * sum
    } else {
        // Γ(3/2) = √π / 2, Γ(i + 3/2) = (i + 1/2) Γ(i + 1/2).
        let mut gamma = std::f64::consts::PI.sqrt() / 2.0;
        let mut power = h.sqrt();
        let mut sum = 0.0;
        for i in 1..=(k - 1) / 2 {
            sum += power / gamma;
            power *= h;
            gamma *= i as f64 + 0.5;
        }
        erfc(h.sqrt()) + e * sum
    }
}

/// The complementary error function, by the Chebyshev fit of Numerical Recipes (`erfcc`): fractional
/// error below 1.2e-7 for every `z ≥ 0` — a threshold needs no more.
fn erfc(z: f64) -> f64 {
    let t = 1.0 / (1.0 + 0.5 * z.abs());
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98 + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if z >= 0.0 { r } else { 2.0 - r }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi_square_quantiles_match_the_tables() {
        // Upper quantiles from the standard tables (e.g. NIST/SEMATECH e-Handbook, table 1.3.6.7.4).
        for (k, p, x) in [(3, 0.05, 7.815), (3, 0.001, 16.266), (6, 0.01, 16.812), (1, 0.05, 3.841), (2, 0.1, 4.605)] {
            let q = chi_square_upper_quantile(k, p);
            assert!((q - x).abs() < 2e-3, "χ²_{k} at {p}: {q} vs {x}");
        }
        // The survival function by numerical integration of the density for k = 3 at x = 5.
        let density = |t: f64| (t.sqrt() * (-t / 2.0).exp()) / (2f64.powf(1.5) * std::f64::consts::PI.sqrt() / 2.0);
        let (a, b, n) = (5.0, 200.0, 200_000);
        let h = (b - a) / n as f64;
        let integral: f64 = (0..n).map(|i| density(a + (i as f64 + 0.5) * h) * h).sum();
        assert!((chi_square_survival(3, 5.0) - integral).abs() < 1e-6, "{integral}");
    }

    #[test]
    fn a_span_is_the_lowest_and_the_highest() {
        assert_eq!(span([3.0, -1.0, 2.0].into_iter()), (-1.0, 3.0));
    }
}
