//! The unit and orientation boundary: millimetres and degrees outside, millimetres and radians inside.
//!
//! Joint values convert per joint kind (a prismatic joint's millimetres stay millimetres). Orientations
//! come in three conventions — the paper's X-Y-Z Euler angles, ROS roll-pitch-yaw, and unit quaternions —
//! and leave as all three, with the Euler singularity (pitch ±90°) handled explicitly rather than printed
//! as rounding noise.

use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion, Vector3};
use thermokin_chain::{Chain, ErrorParams, xyz_rotation};

/// How three or four numbers describe an orientation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Orientation {
    /// X-Y-Z Euler angles in degrees, `R = Rx(rx)·Ry(ry)·Rz(rz)`: the paper's and CoppeliaSim's
    /// convention. `(0, 90, 0)` points the tool's Z axis along world +X.
    #[default]
    XyzEuler,
    /// ROS / URDF roll, pitch, yaw in degrees about the fixed X, Y, Z axes: `R = Rz(yaw)·Ry(pitch)·Rx(roll)`.
    Rpy,
    /// A unit quaternion `w, x, y, z`.
    Quaternion,
}

impl Orientation {
    /// Numbers the convention takes.
    pub fn arity(self) -> usize {
        match self {
            Orientation::XyzEuler | Orientation::Rpy => 3,
            Orientation::Quaternion => 4,
        }
    }

    /// The rotation these numbers describe, or what is wrong with them.
    ///
    /// A quaternion must have unit norm within 1e-3 (a paste with four decimals is within 2e-4) and is
    /// then normalised; anything farther is refused rather than silently rescaled.
    pub fn rotation(self, values: &[f64]) -> Result<UnitQuaternion<f64>, String> {
        if values.len() != self.arity() {
            return Err(format!("{:?} takes {} numbers, got {}", self, self.arity(), values.len()));
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err("orientation values must be finite".into());
        }
        Ok(match self {
            Orientation::XyzEuler => xyz_rotation_deg([values[0], values[1], values[2]]),
            Orientation::Rpy => {
                let [roll, pitch, yaw] = [values[0], values[1], values[2]].map(radians);
                UnitQuaternion::from_euler_angles(roll, pitch, yaw)
            }
            Orientation::Quaternion => {
                let q = Quaternion::new(values[0], values[1], values[2], values[3]);
                let norm = q.norm();
                if (norm - 1.0).abs() > 1e-3 {
                    return Err(format!("quaternion (w, x, y, z) has norm {norm:.6}, not 1"));
                }
                UnitQuaternion::from_quaternion(q)
            }
        })
    }
}

impl std::fmt::Display for Orientation {
    /// The convention's name on command lines: `xyz`, `rpy` or `quat`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Orientation::XyzEuler => "xyz",
            Orientation::Rpy => "rpy",
            Orientation::Quaternion => "quat",
        })
    }
}

impl std::str::FromStr for Orientation {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "xyz" | "xyz-euler" | "euler" => Ok(Orientation::XyzEuler),
            "rpy" | "ros" => Ok(Orientation::Rpy),
            "quat" | "quaternion" | "wxyz" => Ok(Orientation::Quaternion),
            _ => Err(format!("unknown orientation convention `{s}`: use xyz, rpy or quat")),
        }
    }
}

/// A rotation matrix given as numbers (e.g. from JSON), checked: orthonormal to 1e-6 and right-handed.
pub fn rotation_from_matrix(rows: [[f64; 3]; 3]) -> Result<UnitQuaternion<f64>, String> {
    let m = Matrix3::from_fn(|r, c| rows[r][c]);
    if m.iter().any(|v| !v.is_finite()) {
        return Err("rotation matrix entries must be finite".into());
    }
    let off = (m.transpose() * m - Matrix3::identity()).abs().max();
    if off > 1e-6 || m.determinant() < 0.0 {
        return Err(format!("not a rotation matrix (RᵀR − I up to {off:.2e}, det {:.6})", m.determinant()));
    }
    Ok(UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&m)))
}

/// `cos(pitch)` below which ROS roll-pitch-yaw is at its singularity (pitch within ~1e-9 rad of ±90°):
/// roll is then fixed at 0 (the same rule as [`thermokin_chain::xyz_angles_for_output`]).
const GIMBAL_COS: f64 = 1e-9;

/// Removes rounding noise for printing: −0 becomes 0 and −180° becomes 180°.
fn tidy_deg(v: f64) -> f64 {
    let v = v + 0.0;
    if (v + 180.0).abs() < 1e-9 { 180.0 } else { v }
}

/// X-Y-Z Euler angles in degrees (`R = Rx·Ry·Rz`), with `ry` in [−90°, 90°]; at the singularity `rx = 0`
/// ([`thermokin_chain::xyz_angles_for_output`]).
pub fn xyz_euler_deg(rotation: &UnitQuaternion<f64>) -> [f64; 3] {
    let r = rotation.to_rotation_matrix().into_inner();
    let d = thermokin_chain::xyz_angles_for_output(&r).map(degrees);
    [tidy_deg(d.x), tidy_deg(d.y), tidy_deg(d.z)]
}

/// The rotation of X-Y-Z Euler angles in degrees (`R = Rx·Ry·Rz`): the inverse of [`xyz_euler_deg`].
pub fn xyz_rotation_deg(angles: [f64; 3]) -> UnitQuaternion<f64> {
    let r = xyz_rotation(&Vector3::from(angles).map(radians));
    UnitQuaternion::from_matrix(&r)
}

/// ROS roll, pitch, yaw in degrees (`R = Rz(yaw)·Ry(pitch)·Rx(roll)`), pitch in [−90°, 90°]; at the
/// singularity roll = 0.
pub fn ros_rpy_deg(rotation: &UnitQuaternion<f64>) -> [f64; 3] {
    let r = rotation.to_rotation_matrix().into_inner();
    let cos_p = (r[(0, 0)] * r[(0, 0)] + r[(1, 0)] * r[(1, 0)]).sqrt();
    let pitch = (-r[(2, 0)]).atan2(cos_p);
    // Roll first; yaw then from entries combined with it (column 1 of R·Rx(−roll) = Rz(yaw)·Ry(pitch) is
    // (−sin yaw, cos yaw, 0)), so that the three angles rebuild R to rounding also next to the
    // singularity, where roll alone is ill-conditioned.
    let roll = if cos_p < GIMBAL_COS { 0.0 } else { r[(2, 1)].atan2(r[(2, 2)]) };
    let (sr, cr) = roll.sin_cos();
    let yaw = (-(r[(0, 1)] * cr - r[(0, 2)] * sr)).atan2(r[(1, 1)] * cr - r[(1, 2)] * sr);
    [tidy_deg(degrees(roll)), tidy_deg(degrees(pitch)), tidy_deg(degrees(yaw))]
}

pub use thermokin_chain::quaternion_wxyz;

// A joint value per joint kind: the core's one conversion, here beside the edge's others.
pub use thermokin_chain::units::{joint_value_in, joint_value_out};

/// Joint values from a file or flag (degrees for revolute joints, mm for prismatic ones) to the library's
/// radians and mm. `None` when the count does not match the chain.
pub fn joints_to_internal(chain: &Chain, values: &[f64]) -> Option<Vec<f64>> {
    (values.len() == chain.dof())
        .then(|| chain.joints().iter().zip(values).map(|(j, &v)| joint_value_in(j.kind, v)).collect())
}

/// The library's joint values (radians, mm) to the edge's degrees and mm.
pub fn joints_to_external(chain: &Chain, q: &[f64]) -> Vec<f64> {
    chain.joints().iter().zip(q).map(|(j, &v)| joint_value_out(j.kind, v)).collect()
}

/// The base conversions ([`thermokin_chain::units`]), here beside the edge's joint and orientation ones.
pub use thermokin_chain::units::{MM_PER_M, degrees, metres, millimetres, radians};

/// Three angles of the library (radians) in degrees.
pub fn degrees3(radians: [f64; 3]) -> [f64; 3] {
    radians.map(degrees)
}

/// Six error parameters as files and the paper's tables give them (`Dx,Dy,Dz,Dox,Doy,Doz`: mm, mm, mm,
/// degrees, degrees, degrees) in the library's millimetres and radians.
pub fn error_params_in(values: [f64; 6]) -> ErrorParams {
    ErrorParams::new(
        Vector3::new(values[0], values[1], values[2]),
        Vector3::new(values[3], values[4], values[5]).map(radians),
    )
}

/// Six error parameters of the library in the files' millimetres and degrees (the inverse of
/// [`error_params_in`]).
pub fn error_params_out(e: &ErrorParams) -> [f64; 6] {
    let r = e.rotation.map(degrees);
    [e.translation.x, e.translation.y, e.translation.z, r.x, r.y, r.z]
}

/// `x` rounded to `decimals` places for printing: the meaningful precision, not the binary noise
/// (`9.999999999999999e-10` → `1e-9`, `-360.0000000000237` → `-360`).
pub fn rounded(x: f64, decimals: i32) -> f64 {
    if !x.is_finite() {
        return x;
    }
    let scale = 10f64.powi(decimals);
    (x * scale).round() / scale + 0.0
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn the_singularity_prints_clean() {
        // The case: (0, 90, 0) used to print as (−180, 89.99999999999999, 180).
        let r = Orientation::XyzEuler.rotation(&[0.0, 90.0, 0.0]).unwrap();
        assert_eq!(xyz_euler_deg(&r), [0.0, 90.0, 0.0]);
        let r = Orientation::XyzEuler.rotation(&[30.0, 90.0, 10.0]).unwrap();
        let [a, b, c] = xyz_euler_deg(&r);
        assert_eq!((a, b), (0.0, 90.0));
        assert!((c - 40.0).abs() < 1e-9, "{c}");
    }
}
