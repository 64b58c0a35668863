//! The six error parameters of a joint row (paper section 3, Tables 6–7) and their two groupings.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// Six error parameters of one row of the extended table: ΔX, ΔY, ΔZ (mm) and Δθx, Δθy, Δθz (radians
/// inside the library; degrees at the file boundary).
///
/// The angular part is the rotation `Rx(Δθx) · Ry(Δθy) · Rz(Δθz)` (eq. 19: the three rotation matrices
/// multiplied in the order X, Y, Z, each about the already-rotated axes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorParams {
    /// (ΔX, ΔY, ΔZ) in millimetres, in the parent joint's frame.
    pub translation: Vector3<f64>,
    /// (Δθx, Δθy, Δθz) in radians.
    pub rotation: Vector3<f64>,
}

/// How a row's error parameters are grouped with its segment translation `p`.
///
/// Both groupings describe the same family of rigid transforms; [`ErrorParams::regroup`] converts exactly.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorGrouping {
    /// `Trans(p + Δp) · Rx(Δθx) · Ry(Δθy) · Rz(Δθz) · Rot_axis(θ)`: the error sits at the joint, in its
    /// parent's frame, before the joint turns. Table 7's reading and what the authors' data show; the one
    /// this library uses internally.
    Canonical,
    /// `Trans(Δp) · Rx(Δθx) · Ry(Δθy) · Rz(Δθz) · Trans(p) · Rot_axis(θ)`: eq. 18–22, where the angular
    /// correction is applied before the segment translation, so that `p` runs along the corrected axes
    /// (the correction matrix `T_C` of eq. 21).
    PaperEq21,
}

impl ErrorParams {
    /// All six parameters zero.
    pub const ZERO: ErrorParams =
        ErrorParams { translation: Vector3::new(0.0, 0.0, 0.0), rotation: Vector3::new(0.0, 0.0, 0.0) };

    /// From millimetres and radians.
    pub fn new(translation: Vector3<f64>, rotation: Vector3<f64>) -> Self {
        Self { translation, rotation }
    }

    /// The six values as one vector `[ΔX, ΔY, ΔZ, Δθx, Δθy, Δθz]` (mm, rad).
    pub fn as_array(&self) -> [f64; 6] {
        [self.translation.x, self.translation.y, self.translation.z, self.rotation.x, self.rotation.y, self.rotation.z]
    }

    /// Inverse of [`ErrorParams::as_array`].
    pub fn from_array(v: [f64; 6]) -> Self {
        Self::new(Vector3::new(v[0], v[1], v[2]), Vector3::new(v[3], v[4], v[5]))
    }

    /// `true` when all six parameters are exactly zero.
    pub fn is_zero(&self) -> bool {
        self.translation == Vector3::zeros() && self.rotation == Vector3::zeros()
    }

    /// `true` when all six parameters are finite.
    pub fn is_finite(&self) -> bool {
        self.translation.iter().chain(self.rotation.iter()).all(|v| v.is_finite())
    }

    /// Element-wise sum.
    pub fn add(&self, other: &ErrorParams) -> ErrorParams {
        ErrorParams::new(self.translation + other.translation, self.rotation + other.rotation)
    }

    /// Element-wise scaling (a warm-up profile scales a table by a factor in [0, ∞)).
    pub fn scaled(&self, factor: f64) -> ErrorParams {
        ErrorParams::new(self.translation * factor, self.rotation * factor)
    }

    /// The angular correction `Rx(Δθx) · Ry(Δθy) · Rz(Δθz)` (eq. 19).
    ///
    /// ```
    /// use approx::assert_relative_eq;
    /// use nalgebra::Vector3;
    /// use thermokin_chain::ErrorParams;
    /// let e = ErrorParams::new(Vector3::zeros(), Vector3::new(0.0, 0.0, 90f64.to_radians()));
    /// let x = e.rotation_matrix() * Vector3::x();
    /// assert_relative_eq!(x, Vector3::y(), epsilon = 1e-15);
    /// ```
    pub fn rotation_matrix(&self) -> Matrix3<f64> {
        xyz_rotation(&self.rotation)
    }

    /// The rigid transform of a row with segment translation `p`, in the canonical grouping:
    /// `Trans(p + Δp) · Rx · Ry · Rz`.
    pub fn row_transform(&self, p: &Vector3<f64>) -> Isometry3<f64> {
        let rot = Rotation3::from_matrix_unchecked(self.rotation_matrix());
        Isometry3::from_parts(Translation3::from(p + self.translation), UnitQuaternion::from_rotation_matrix(&rot))
    }

    /// Converts these parameters, read in grouping `from`, to the equivalent parameters in grouping `to`
    /// for a row whose segment translation is `p` (mm). Exact: both give the same row transform.
    ///
    /// Canonical → eq. 21: `Trans(p + Δp_c) · R = Trans(Δp_21) · R · Trans(p)` holds when
    /// `Δp_21 = p + Δp_c − R p`; the angles are unchanged.
    pub fn regroup(&self, from: ErrorGrouping, to: ErrorGrouping, p: &Vector3<f64>) -> ErrorParams {
        let r = self.rotation_matrix();
        let translation = match (from, to) {
            (ErrorGrouping::Canonical, ErrorGrouping::PaperEq21) => p + self.translation - r * p,
            (ErrorGrouping::PaperEq21, ErrorGrouping::Canonical) => self.translation + r * p - p,
            _ => self.translation,
        };
        ErrorParams::new(translation, self.rotation)
    }

    /// The error parameters whose angular part is the rotation matrix `r` (decomposed as X-Y-Z) and whose
    /// translation is `translation`. At `Δθy = ±90°` the split between X and Z is not unique; the
    /// decomposition then puts it on Z.
    pub fn from_rotation_matrix(translation: Vector3<f64>, r: &Matrix3<f64>) -> ErrorParams {
        ErrorParams::new(translation, xyz_angles(r))
    }
}

/// `Rx(a) · Ry(b) · Rz(c)` for `angles = (a, b, c)` in radians.
pub fn xyz_rotation(angles: &Vector3<f64>) -> Matrix3<f64> {
    xyz_rotation_from_sines([angles.x.sin_cos(), angles.y.sin_cos(), angles.z.sin_cos()])
}

/// `Rx(a) · Ry(b) · Rz(c)` from `[(sin a, cos a), (sin b, cos b), (sin c, cos c)]`.
pub(crate) fn xyz_rotation_from_sines(sines: [(f64, f64); 3]) -> Matrix3<f64> {
    let [(sa, ca), (sb, cb), (sc, cc)] = sines;
    Matrix3::new(
        cb * cc,
        -cb * sc,
        sb,
        ca * sc + sa * sb * cc,
        ca * cc - sa * sb * sc,
        -sa * cb,
        sa * sc - ca * sb * cc,
        sa * cc + ca * sb * sc,
        ca * cb,
    )
}

/// The angles `(a, b, c)` with `Rx(a) · Ry(b) · Rz(c) = r` (X-Y-Z Euler, CoppeliaSim's convention for
/// object orientations), with `b` in [−π/2, π/2].
pub fn xyz_angles(r: &Matrix3<f64>) -> Vector3<f64> {
    // a from the third column; b and c then from entries combined with a, so that the three angles
    // rebuild `r` to rounding even next to b = ±90°, where a and c alone are ill-defined (the split of
    // a ± c then goes to c; at exactly ±90° a = 0).
    let a = (-r[(1, 2)]).atan2(r[(2, 2)]);
    let (sa, ca) = a.sin_cos();
    let cb = (r[(0, 0)] * r[(0, 0)] + r[(0, 1)] * r[(0, 1)]).sqrt();
    let b = r[(0, 2)].atan2(cb);
    let c = (ca * r[(1, 0)] + sa * r[(2, 0)]).atan2(ca * r[(1, 1)] + sa * r[(2, 1)]);
    Vector3::new(a, b, c)
}

/// `cos β` below which X-Y-Z Euler angles are at their singularity (β within ~1e-9 rad of ±90°), where
/// only `a ± c` is defined.
const GIMBAL_COS: f64 = 1e-9;

/// X-Y-Z Euler angles for reports and files: as [`xyz_angles`], but at the singularity (β within 1e-9 rad
/// of ±90°) β is exactly ±90° and the split is fixed explicitly, `a = 0`, instead of being left to
/// rounding — which turned (0, 90°, 0) into (−180°, 89.99999999999999°, 180°).
pub fn xyz_angles_for_output(r: &Matrix3<f64>) -> Vector3<f64> {
    let cos_b = (r[(0, 0)] * r[(0, 0)] + r[(0, 1)] * r[(0, 1)]).sqrt();
    if cos_b < GIMBAL_COS {
        // R = Ry(±90°)·Rz(c): row 1 is (sin c, cos c, 0).
        let b = std::f64::consts::FRAC_PI_2.copysign(r[(0, 2)]);
        return Vector3::new(0.0, b, r[(1, 0)].atan2(r[(1, 1)]));
    }
    xyz_angles(r)
}
