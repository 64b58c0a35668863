//! A rigid transform kept as a rotation matrix and a translation, for the FK hot path.
//!
//! `Isometry3` (unit quaternion + translation) is the public type; inside the forward kinematics a plain
//! 3 × 3 matrix is cheaper to compose with the principal-axis joint rotations, which touch only two columns.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// A rigid transform `x ↦ rot · x + trans` (millimetres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Frame {
    pub rot: Matrix3<f64>,
    pub trans: Vector3<f64>,
}

impl Frame {
    pub fn new(rot: Matrix3<f64>, trans: Vector3<f64>) -> Self {
        Self { rot, trans }
    }

    pub fn to_isometry(self) -> Isometry3<f64> {
        let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(self.rot));
        Isometry3::from_parts(Translation3::from(self.trans), rotation)
    }

    /// `self · other`.
    #[inline(always)]
    pub fn mul(&self, other: &Frame) -> Frame {
        Frame { rot: self.rot * other.rot, trans: self.rot * other.trans + self.trans }
    }

    /// `self · Trans(v)`.
    #[inline(always)]
    pub fn translate_local(&mut self, v: &Vector3<f64>) {
        self.trans += self.rot * v;
    }

    /// `self · Rot(axis, angle)` given `sin` and `cos` of the angle.
    #[inline(always)]
    pub fn rotate_local(&mut self, axis: &AxisKind, s: f64, c: f64) {
        match axis {
            AxisKind::Principal { index, sign } => {
                // R · R_k(θ) mixes the two columns other than k: for X they are (1, 2), for Y (2, 0),
                // for Z (0, 1), each pair ordered so that the rotation is right-handed.
                let (a, b) = match index {
                    0 => (1, 2),
                    1 => (2, 0),
                    _ => (0, 1),
                };
                let s = s * sign;
                let ca = self.rot.column(a).into_owned();
                let cb = self.rot.column(b).into_owned();
                self.rot.set_column(a, &(ca * c + cb * s));
                self.rot.set_column(b, &(cb * c - ca * s));
            }
            AxisKind::General(u) => {
                self.rot *= axis_angle_matrix(u, s, c);
            }
        }
    }
}

/// How a joint axis is stored for fast rotation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum AxisKind {
    /// ±X (0), ±Y (1) or ±Z (2).
    Principal { index: usize, sign: f64 },
    /// Any other unit axis.
    General(Vector3<f64>),
}

impl AxisKind {
    pub fn classify(u: &Vector3<f64>) -> Self {
        for index in 0..3 {
            let others_zero = (0..3).filter(|&k| k != index).all(|k| u[k] == 0.0);
            if others_zero && u[index].abs() == 1.0 {
                return AxisKind::Principal { index, sign: u[index] };
            }
        }
        AxisKind::General(*u)
    }
}

/// Rodrigues' formula: the rotation by the angle with the given sine and cosine about the unit axis `u`.
#[inline]
pub(crate) fn axis_angle_matrix(u: &Vector3<f64>, s: f64, c: f64) -> Matrix3<f64> {
    let t = 1.0 - c;
    let (x, y, z) = (u.x, u.y, u.z);
    Matrix3::new(
        t * x * x + c,
        t * x * y - s * z,
        t * x * z + s * y,
        t * x * y + s * z,
        t * y * y + c,
        t * y * z - s * x,
        t * x * z - s * y,
        t * y * z + s * x,
        t * z * z + c,
    )
}
