//! What a set of poses would give: the predicted standard deviation of every parameter at the tracker's
//! noise, the criterion, the observability indices — for the plan and for random poses of the same pool.

use faer::Mat;
use rand::SeedableRng;
use rand::seq::index::sample;
use rand_chacha::ChaCha8Rng;
use thermokin_identify::{FixedParameter, Observability, identifiable, observability};

use crate::design::Design;
use crate::design::product;
use crate::select::{information, log_det_inverse};

/// What one set of poses gives.
pub(crate) struct Precision {
    /// `log det(δI + MᵀM)`: the criterion.
    pub criterion: f64,
    /// `trace(W B)`, `B = (δI + MᵀM)⁻¹`: the mean squared error of the predicted tool position over
    /// the poses of use per unit of noise variance ([`thermokin_identify::frame_refitted_weight`]).
    pub variance: f64,
    /// The same at the poses of use as given where some were taken at their nearest candidates
    /// ([`Design::as_given_weight`]).
    pub variance_as_given: Option<f64>,
    /// Per free column of the design, its predicted standard deviation in model units (mm, radians, …)
    /// at noise 1 mm; `None` where these poses cannot identify it.
    pub sigma_per_mm: Vec<Option<f64>>,
    /// The free columns these poses cannot identify, each with its reason.
    pub not_identifiable: Vec<FixedParameter>,
    /// The observability indices over the design's free columns.
    pub observability: Option<Observability>,
}

/// The precision of candidates `rows` after the measured poses.
pub(crate) fn precision(design: &Design, rows: &[usize]) -> Precision {
    let m = design.rows_with_measured(rows);
    let (criterion, variance, variance_as_given) = match log_det_inverse(&information(&m)) {
        Some((d, b)) => (
            d,
            thermokin_identify::trace_of_product(&design.use_weight, &b),
            design.as_given_weight.as_ref().map(|w| thermokin_identify::trace_of_product(w, &b)),
        ),
        None => (f64::NEG_INFINITY, f64::INFINITY, design.as_given_weight.as_ref().map(|_| f64::INFINITY)),
    };
    let ident = identifiable(m.as_ref(), &vec![true; m.ncols()]);
    let cols: Vec<usize> = (0..m.ncols()).filter(|&c| ident.free[c]).collect();
    let mut sigma_per_mm = vec![None; m.ncols()];
    let sub = Mat::from_fn(m.nrows(), cols.len(), |r, k| m[(r, cols[k])]);
    let normal = product(sub.as_ref().transpose(), sub.as_ref());
    if let Some((_, inverse)) = log_det_inverse(&normal) {
        for (k, &c) in cols.iter().enumerate() {
            // θ = u / scale: var θ = var u / scale².
            sigma_per_mm[c] = Some(inverse[(k, k)].max(0.0).sqrt() / design.scale[c]);
        }
    }
    // The fixed columns named as the model names them (design column → model column).
    let fixed: Vec<thermokin_identify::Dependence> = ident
        .fixed
        .iter()
        .map(|d| thermokin_identify::Dependence {
            column: design.free[d.column],
            on: match d.on {
                thermokin_identify::DependsOn::Column { column, cos } => {
                    thermokin_identify::DependsOn::Column { column: design.free[column], cos }
                }
                other => other,
            },
        })
        .collect();
    Precision {
        criterion,
        variance,
        variance_as_given,
        sigma_per_mm,
        not_identifiable: design.model.fixed_parameters(&fixed),
        observability: observability(&m, &vec![true; m.ncols()]),
    }
}

/// The precision of `draws` seeded random sets of `n` candidates each.
pub(crate) fn random_sets(design: &Design, n: usize, draws: usize, seed: u64) -> Vec<Precision> {
    let count = design.candidates.nrows() / 3;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..draws).map(|_| precision(design, &sample(&mut rng, count, n.min(count)).into_vec())).collect()
}

/// The median of finite values; `None` when fewer than half are finite (a median that is "not
/// identifiable" in most draws is not a number).
pub(crate) fn median(values: impl Iterator<Item = Option<f64>>) -> Option<f64> {
    let all: Vec<Option<f64>> = values.collect();
    let mut v: Vec<f64> = all.iter().map(|x| x.unwrap_or(f64::INFINITY)).collect();
    v.sort_by(f64::total_cmp);
    let mid = v.get(v.len() / 2).copied()?;
    let mid = if v.len().is_multiple_of(2) && v.len() >= 2 { 0.5 * (v[v.len() / 2 - 1] + mid) } else { mid };
    mid.is_finite().then_some(mid)
}
