//! What the diagnosis predicts of itself where the robot will work ([`crate::Config::poses_of_use`]):
//! the held-out RMS error the final model should show at those poses, from its own fit — the variance
//! its parameters leave there and what its residuals say a measurement adds — set beside what a hold-out
//! set at those poses measured. What a plan promised (`thermokin plan --for`) is the same formula at the
//! tracker's stated noise, before anything was measured; this is it at the noise the fit found, for the
//! model it chose.
//!
//! The model of the final effects is fitted on all measurements by least squares (`Σ = s²(JᵀJ)⁻¹` on its
//! free columns, `s² = SSR / (rows − free)` the residuals' variance per coordinate, unbiased); its
//! position rows at the poses of use (`M`, the robot as at the session's first pose: its time, its
//! temperatures and sensor readings) give `W` with the frame a test re-measures projected out
//! ([`thermokin_identify::frame_refitted_weight`]), and the prediction
//! `√(trace(W Σ) + s²(3 − k/u))` ([`thermokin_identify::heldout_rms`]). A model that is not the robot
//! leaves residuals wider than the tracker's noise, and the prediction carries them: at the poses of use
//! as wide as where it was fitted. Where the poses of use leave the measured arcs, the model's error
//! there may be larger than any variance says (the report's extrapolation warnings).

use faer::Mat;
use thermokin_chain::{Dataset, Measurement};
use thermokin_identify::{
    Effect, PoseTerms, frame_refitted_weight, heldout_resolution, heldout_rms, refitted_frame, residuals_and_jacobian,
    trace_of_product,
};

use crate::error::DiagnoseError;
use crate::report::AtUse;
use crate::scoring::Scorer;

/// The prediction at `poses` (radians; mm for a prismatic joint) of the model of `effects` fitted on the
/// scorer's data; `None` where its normal equations cannot be factorised (no prediction is made).
pub(crate) fn at_use(
    scorer: &Scorer<'_>,
    effects: &[Effect],
    poses: &[Vec<f64>],
) -> Result<Option<AtUse>, DiagnoseError> {
    let (model, fit) = scorer.full_fit(effects)?;
    let all = scorer.all();
    let (_, jac) = residuals_and_jacobian(scorer.robot, &model, &fit.theta, scorer.data, &all, &scorer.terms)?;
    let free: Vec<usize> = (0..model.len()).filter(|&c| fit.free[c]).collect();
    let dof_left = jac.nrows().saturating_sub(free.len()).max(1) as f64;
    let s2 = fit.ssr / dof_left;
    let jf = Mat::from_fn(jac.nrows(), free.len(), |r, k| jac[(r, free[k])]);
    let normal = jf.transpose() * &jf;
    let largest = (0..free.len()).map(|k| normal[(k, k)]).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    let ridged =
        Mat::from_fn(free.len(), free.len(), |i, k| normal[(i, k)] + if i == k { 1e-12 * largest } else { 0.0 });
    let Ok(llt) = ridged.llt(faer::Side::Lower) else { return Ok(None) };
    let mut covariance = faer::linalg::solvers::DenseSolveCore::inverse(&llt);
    covariance *= faer::Scale(s2);
    let use_data = at_the_first_pose(scorer.data, poses);
    let terms = PoseTerms::against(scorer.robot, &use_data, scorer.data, 0.0);
    let rows: Vec<usize> = (0..use_data.len()).collect();
    let (_, ju) = residuals_and_jacobian(scorer.robot, &model, &fit.theta, &use_data, &rows, &terms)?;
    let mu = Mat::from_fn(ju.nrows(), free.len(), |r, k| ju[(r, free[k])]);
    let frame = refitted_frame(&model, &free);
    let w = frame_refitted_weight(&mu, &frame);
    let share = trace_of_product(&w, &covariance);
    Ok(Some(AtUse {
        poses: poses.len(),
        refitted: frame.len(),
        residual_scale_mm: s2.sqrt(),
        model_rms_mm: share.max(0.0).sqrt(),
        predicted_rms_mm: heldout_rms(share, s2.sqrt(), frame.len(), poses.len()),
        resolution: heldout_resolution(frame.len(), poses.len()),
        measured_rms_mm: None,
        promised_rms_mm: None,
        promised_at_nearest: 0,
    }))
}

/// The poses of use as measurements of the robot as at `data`'s first pose (its time, temperatures and
/// sensor readings; no measured position, no orientation, no order).
fn at_the_first_pose(data: &Dataset, poses: &[Vec<f64>]) -> Dataset {
    let first = data.measurements.first();
    let measurements = poses
        .iter()
        .map(|q| Measurement {
            time_min: first.map_or(0.0, |m| m.time_min),
            q: q.clone(),
            position_mm: nalgebra::Vector3::zeros(),
            orientation: None,
            position_std_mm: None,
            temps: first.map_or_else(Vec::new, |m| m.temps.clone()),
        })
        .collect();
    let readings = data.sensor_values.first().cloned();
    Dataset {
        measurements,
        temperature_names: data.temperature_names.clone(),
        source_lines: Vec::new(),
        sensor_names: data.sensor_names.clone(),
        sensor_values: readings.map_or_else(Vec::new, |r| vec![r; poses.len()]),
        approach: Vec::new(),
        tilt_sensors: data.tilt_sensors.clone(),
        branch_columns: data.branch_columns.clone(),
    }
}

/// Whether the hold-out set's poses are the poses of use: the same configurations, in any order.
pub(crate) fn same_poses(holdout: &Dataset, poses: &[Vec<f64>]) -> bool {
    if holdout.len() != poses.len() {
        return false;
    }
    let key = |q: &[f64]| q.iter().map(|v| (v * 1e9).round() as i64).collect::<Vec<i64>>();
    let mut a: Vec<Vec<i64>> = holdout.measurements.iter().map(|m| key(&m.q)).collect();
    let mut b: Vec<Vec<i64>> = poses.iter().map(|q| key(q)).collect();
    a.sort();
    b.sort();
    a == b
}
