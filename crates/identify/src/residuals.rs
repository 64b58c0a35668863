//! Residual rows `measured − predicted` of a model at a parameter vector, and their Jacobian.

use faer::Mat;
use nalgebra::Matrix6xX;
use thermokin_chain::{Dataset, Robot, rotation_log};

use crate::error::IdentifyError;
use crate::model::Model;
use crate::predict::PoseInputs;
use crate::terms::PoseTerms;

/// The residual rows of `rows` of `data`: per measurement the position (3 rows, mm) and, when
/// [`PoseTerms::lever_mm`] is set, the rotation `lever · log(R_measured · R_predictedᵀ)` (3 rows, mm at
/// the lever).
pub fn residuals(
    robot: &Robot,
    model: &Model,
    theta: &[f64],
    data: &Dataset,
    rows: &[usize],
    terms: &PoseTerms,
) -> Result<Vec<f64>, IdentifyError> {
    evaluate(robot, model, theta, data, rows, terms, None)
}

/// [`residuals`] and the Jacobian of `predicted` (the Gauss–Newton Jacobian of the rotation rows' log is
/// the angular twist, exact at zero residual): one row per residual, one column per parameter.
pub fn residuals_and_jacobian(
    robot: &Robot,
    model: &Model,
    theta: &[f64],
    data: &Dataset,
    rows: &[usize],
    terms: &PoseTerms,
) -> Result<(Vec<f64>, Mat<f64>), IdentifyError> {
    let mut jac = Mat::zeros(rows.len() * terms.stride(), model.len());
    let r = evaluate(robot, model, theta, data, rows, terms, Some(&mut jac))?;
    Ok((r, jac))
}

/// The one loop behind [`residuals`] and [`residuals_and_jacobian`]: `jac` is filled when given.
fn evaluate(
    robot: &Robot,
    model: &Model,
    theta: &[f64],
    data: &Dataset,
    rows: &[usize],
    terms: &PoseTerms,
    mut jac: Option<&mut Mat<f64>>,
) -> Result<Vec<f64>, IdentifyError> {
    let stride = terms.stride();
    let mut r = Vec::with_capacity(rows.len() * stride);
    let mut block = Matrix6xX::zeros(model.len());
    let mut cache = None;
    let lever = terms.lever_mm.unwrap_or(0.0);
    for (k, &i) in rows.iter().enumerate() {
        let m = &data.measurements[i];
        let inputs = PoseInputs { temp_rise: &terms.rise[i], sin_cos: Some(&terms.sin_cos[i]) };
        let (p, rot) = model.predict(robot, theta, m, &inputs, jac.is_some().then_some(&mut block), &mut cache)?;
        let d = m.position_mm - p;
        r.extend_from_slice(&[d.x, d.y, d.z]);
        if stride == 6 {
            let measured = m.orientation.map(|o| o.to_rotation_matrix().into_inner()).unwrap_or(rot);
            let e = rotation_log(&(measured * rot.transpose())) * lever;
            r.extend_from_slice(&[e.x, e.y, e.z]);
        }
        if let Some(jac) = jac.as_deref_mut() {
            for c in 0..model.len() {
                for a in 0..stride {
                    let w = if a < 3 { 1.0 } else { lever };
                    jac[(stride * k + a, c)] = block[(a, c)] * w;
                }
            }
        }
    }
    Ok(r)
}

/// [`residuals`] (and the Jacobian when `jac` is given) as the fit minimises them: position rows weighted
/// by the tracker's stated standard deviations (weighted least squares), unchanged otherwise.
pub(crate) fn weighted(
    robot: &Robot,
    model: &Model,
    theta: &[f64],
    data: &Dataset,
    rows: &[usize],
    terms: &PoseTerms,
    mut jac: Option<&mut Mat<f64>>,
) -> Result<Vec<f64>, IdentifyError> {
    let mut r = evaluate(robot, model, theta, data, rows, terms, jac.as_deref_mut())?;
    if let Some(weights) = &terms.weights {
        let stride = terms.stride();
        for (k, &i) in rows.iter().enumerate() {
            for a in 0..3 {
                let (row, w) = (stride * k + a, weights[i][a]);
                r[row] *= w;
                if let Some(jac) = jac.as_deref_mut() {
                    for c in 0..jac.ncols() {
                        jac[(row, c)] *= w;
                    }
                }
            }
        }
    }
    Ok(r)
}

/// Per-measurement error norms of residual rows of `stride` rows each.
pub fn norms(r: &[f64], stride: usize) -> Vec<f64> {
    r.chunks(stride).map(|c| c.iter().map(|x| x * x).sum::<f64>().sqrt()).collect()
}
