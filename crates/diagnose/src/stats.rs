//! Statistics of held-out errors.

use serde::Serialize;

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

#[cfg(test)]
mod tests {
    #[test]
    fn a_span_is_the_lowest_and_the_highest() {
        assert_eq!(super::span([3.0, -1.0, 2.0].into_iter()), (-1.0, 3.0));
    }
}
