//! The starting registration of a tracker-frame model: a closed-form rigid fit (Kabsch) of the nominal
//! predictions to the measurements.

use nalgebra::{Isometry3, Matrix3, Vector3};
use thermokin_chain::{Dataset, Robot};

use crate::error::IdentifyError;
use crate::model::Model;
use crate::predict::PoseInputs;

/// Closed-form rigid registration (Kabsch): the `T` minimising Σ |b_i − T a_i|².
pub fn kabsch(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> Isometry3<f64> {
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
pub fn initial_registration(robot: &Robot, data: &Dataset, rows: &[usize]) -> Result<Isometry3<f64>, IdentifyError> {
    let model = Model::new(robot, vec![])?;
    let zeros = vec![0.0; robot.chain().dof()];
    let inputs = PoseInputs { torques: &zeros, temp_rise: &zeros, sin_cos: None };
    let mut a = Vec::new();
    let mut b = Vec::new();
    for &i in rows {
        let m = &data.measurements[i];
        if let Ok((p, _)) = model.predict(robot, &[], m, &inputs, None, &mut None) {
            a.push(p);
            b.push(m.position_mm);
        }
    }
    Ok(kabsch(&a, &b))
}
