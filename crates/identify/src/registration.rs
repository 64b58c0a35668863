//! The starting frames of a model: the tracker registration by a closed-form rigid fit (Kabsch) of the
//! nominal predictions to the measurements, and an unknown tool point by closed-form least squares,
//! alternating with it.

use nalgebra::{Isometry3, Matrix3, Vector3};
use thermokin_chain::{Dataset, Robot};

use crate::effect::Effect;
use crate::error::IdentifyError;
use crate::model::{Model, StartFrames};
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

/// Iterations of the alternating start at most; each costs one pass over the poses.
const START_ITERATIONS: usize = 200;
/// The alternation stops when the tool point moves less than this, mm (a thousandth of a tracker's
/// noise: the identification takes it from there).
const START_TOOL_STEP_MM: f64 = 1e-6;

/// The starting frames of a model of `effects` on the measurements `rows` of `data`.
///
/// With [`Effect::Registration`]: the Kabsch fit of the predicted to the measured points. With
/// [`Effect::ToolPoint`]: the tool point `t` (in the tool row's parent frame, the last joint's) that
/// minimises `Σ |m_i − T(p_i + R_i t)|²` for the registration `T` (`p_i`, `R_i` the nominal tool point and
/// the parent frame's rotation at pose `i`) — `t = mean R_iᵀ(T⁻¹m_i − p_i)`, since `R_iᵀR_i = I` —
/// alternating with the Kabsch fit when both are estimated (each step lowers the same sum of squares).
/// Starting the tool point at the robot's tool instead (on the last joint's axis for a flange) leaves
/// every rotation of the last joint's frame without effect at the start: the identifiability gate would
/// fix a real wrist effect as moving nothing, or — at rounding's level — keep a column of noise whose
/// first step runs away.
pub fn initial_frames(
    robot: &Robot,
    data: &Dataset,
    rows: &[usize],
    effects: &[Effect],
) -> Result<StartFrames, IdentifyError> {
    let model = Model::new(robot, vec![])?;
    let zeros = vec![0.0; robot.chain().dof()];
    let inputs = PoseInputs::plain(&zeros);
    let tool_rotation = robot.chain().tool().pose().rotation;
    let mut nominal = Vec::new();
    let mut measured = Vec::new();
    for &i in rows {
        let m = &data.measurements[i];
        if let Ok((p, r)) = model.predict(robot, &[], m, &inputs, None, &mut None) {
            let base_from_parent =
                nalgebra::Rotation3::from_matrix_unchecked(r) * tool_rotation.inverse().to_rotation_matrix();
            nominal.push((p, base_from_parent));
            measured.push(m.position_mm);
        }
    }
    let register = effects.contains(&Effect::Registration);
    let tool = effects.contains(&Effect::ToolPoint) && nominal.len() >= 3;
    let mut start = StartFrames { registration: Isometry3::identity(), tool_point_mm: Vector3::zeros() };
    for _ in 0..START_ITERATIONS {
        if register {
            let predicted: Vec<Vector3<f64>> = nominal.iter().map(|(p, r)| p + r * start.tool_point_mm).collect();
            start.registration = kabsch(&predicted, &measured);
        }
        if !tool {
            break;
        }
        let base_from_tracker = start.registration.inverse();
        let t = nominal
            .iter()
            .zip(&measured)
            .map(|((p, r), m)| r.transpose() * ((base_from_tracker * nalgebra::Point3::from(*m)).coords - p))
            .sum::<Vector3<f64>>()
            / nominal.len() as f64;
        let step = (t - start.tool_point_mm).norm();
        start.tool_point_mm = t;
        if step < START_TOOL_STEP_MM || !register {
            break;
        }
    }
    Ok(start)
}
