//! The same-orientation extended table (paper section 3, Tables 5–7, eq. 18–22): joints, base and tool
//! rows, forward kinematics and the geometric Jacobian.
//!
//! Conversions of a chain live beside it, one file per source: [`Chain::from_factors`] and
//! [`Chain::to_factors`] (any list of fixed transforms and joint motions, `factors.rs`),
//! [`crate::DhTable::to_extended`] and [`Chain::to_modified_dh`] (classic and modified DH, `dh.rs`), the
//! parameter Jacobian below ([`Chain::parameter_jacobian`]).

use nalgebra::{Isometry3, Matrix3, Matrix6xX, Unit, Vector3};

use crate::ChainError;
use crate::error_params::ErrorParams;
use crate::frame::{AxisKind, Frame};

/// A joint frame as its rotation matrix and origin in the base frame (mm).
/// Whether a joint turns or slides along its axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointKind {
    /// Rotation about the axis; the joint variable is an angle (radians inside the library).
    Revolute,
    /// Translation along the axis; the joint variable is a length (millimetres).
    Prismatic,
}

/// Lower and upper bound of a joint variable (radians or millimetres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointLimits {
    /// Lower bound.
    pub lower: f64,
    /// Upper bound.
    pub upper: f64,
}

impl JointLimits {
    /// `true` when `lower ≤ q ≤ upper`.
    pub fn contains(&self, q: f64) -> bool {
        q >= self.lower && q <= self.upper
    }

    /// `q` clamped into the limits.
    pub fn clamp(&self, q: f64) -> f64 {
        q.clamp(self.lower, self.upper)
    }
}

/// One joint row of the extended table (Table 7).
///
/// The row transform, in the canonical grouping (see [`crate::ErrorGrouping`]), is
/// `Trans(offset + Δp) · Rx(Δθx) · Ry(Δθy) · Rz(Δθz) · Rot_axis(q + zero)` for a revolute joint and
/// `… · Trans(axis · (q + zero))` for a prismatic one. The offset is expressed in the previous joint's
/// frame; at the zero configuration of an error-free chain every joint frame has the base's orientation
/// (the paper's first rule, section 2.3), and the joint turns about one of its own axes (second rule).
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// Name, used in reports and files.
    pub name: String,
    /// Translation (px, py, pz) from the previous joint, mm, in the previous joint's frame.
    pub offset: Vector3<f64>,
    /// The joint axis in the joint's own frame: ±X, ±Y, ±Z or any unit axis (imported robots).
    pub axis: Unit<Vector3<f64>>,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Zero offset added to the joint variable (radians or mm).
    pub zero: f64,
    /// Limits of the joint variable as commanded (before the zero offset), if known.
    pub limits: Option<JointLimits>,
    /// The six error parameters of this row.
    pub error: ErrorParams,
}

impl Joint {
    /// A revolute joint with the given offset (mm) and axis, no zero offset, no limits, no errors.
    pub fn revolute(name: impl Into<String>, offset: Vector3<f64>, axis: Unit<Vector3<f64>>) -> Self {
        Self {
            name: name.into(),
            offset,
            axis,
            kind: JointKind::Revolute,
            zero: 0.0,
            limits: None,
            error: ErrorParams::ZERO,
        }
    }

    /// A prismatic joint with the given offset (mm) and axis.
    pub fn prismatic(name: impl Into<String>, offset: Vector3<f64>, axis: Unit<Vector3<f64>>) -> Self {
        Self { kind: JointKind::Prismatic, ..Self::revolute(name, offset, axis) }
    }

    /// Sets the limits.
    pub fn with_limits(mut self, lower: f64, upper: f64) -> Self {
        self.limits = Some(JointLimits { lower, upper });
        self
    }
}

/// A fixed row of the table: the base row (row 0 of Table 7) or the tool (last joint → TCP).
///
/// Transform: `Trans(translation + Δp) · Rx(Δθx) · Ry(Δθy) · Rz(Δθz) · rotation`.
#[derive(Clone, Debug, PartialEq)]
pub struct FixedRow {
    /// Nominal translation, mm.
    pub translation: Vector3<f64>,
    /// Nominal rotation.
    pub rotation: nalgebra::UnitQuaternion<f64>,
    /// Error parameters of the row.
    pub error: ErrorParams,
}

impl FixedRow {
    /// The identity row.
    pub fn identity() -> Self {
        Self::from_isometry(&Isometry3::identity())
    }

    /// A row with the given nominal pose and no errors.
    pub fn from_isometry(iso: &Isometry3<f64>) -> Self {
        Self { translation: iso.translation.vector, rotation: iso.rotation, error: ErrorParams::ZERO }
    }

    /// The nominal pose, errors ignored.
    pub fn nominal(&self) -> Isometry3<f64> {
        Isometry3::from_parts(self.translation.into(), self.rotation)
    }

    /// The pose including the errors.
    pub fn pose(&self) -> Isometry3<f64> {
        self.frame().to_isometry()
    }

    fn frame(&self) -> Frame {
        let nominal_rot = *self.rotation.to_rotation_matrix().matrix();
        Frame::new(self.error.rotation_matrix() * nominal_rot, self.translation + self.error.translation)
    }
}

/// The TCP pose and the parameter Jacobian of one configuration ([`Chain::pose_and_parameter_jacobian`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PoseAndJacobian {
    /// `base_from_tcp` translation, mm.
    pub position: Vector3<f64>,
    /// `base_from_tcp` rotation.
    pub rotation: Matrix3<f64>,
    /// As [`Chain::parameter_jacobian`].
    pub jacobian: Matrix6xX<f64>,
}

/// Precomputed per-joint data for the FK hot path.
#[derive(Clone, Debug, PartialEq)]
struct Link {
    /// `Trans(offset + Δp) · R(Δθ)`.
    fixed: Frame,
    /// `R(Δθ)` is exactly the identity (no error rotation: every row of a same-orientation table without
    /// one): the frame behind the row is then its parent's rotation and a translated origin — the same
    /// numbers the product gives (a product with an exact identity reproduces the other factor), for a
    /// third of its work.
    translation_only: bool,
    /// `Rx(Δθx)` and `Rx(Δθx) · Ry(Δθy)`: the partial error rotations the parameter Jacobian needs.
    partial: [Matrix3<f64>; 2],
    axis: AxisKind,
    axis_vec: Vector3<f64>,
    kind: JointKind,
    zero: f64,
    /// `(sin zero, cos zero)`: the joint's motion from given sines of `q` by angle addition.
    zero_sin_cos: (f64, f64),
}

impl Link {
    /// The frame behind this link's fixed row, from the frame `before` it: `before · fixed`.
    #[inline(always)]
    fn behind(&self, before: &Frame) -> Frame {
        if self.translation_only {
            Frame { rot: before.rot, trans: before.rot * self.fixed.trans + before.trans }
        } else {
            before.mul(&self.fixed)
        }
    }
}

/// A serial chain in the same-orientation extended convention: base row, joints, tool row.
///
/// The forward model is eq. 22 in the canonical grouping:
/// `base_from_tcp = base_row · Π_i (Trans(p_i + Δp_i) · R(Δθ_i) · Rot_axis_i(q_i + zero_i)) · tool_row`.
/// A `Chain` is an immutable value: changing error parameters returns a new chain.
///
/// ```
/// use approx::assert_relative_eq;
/// use nalgebra::{Isometry3, Vector3};
/// use thermokin_chain::{Chain, FixedRow, Joint};
/// let joints = vec![
///     Joint::revolute("j1", Vector3::new(0.0, 0.0, 100.0), Vector3::z_axis()),
///     Joint::revolute("j2", Vector3::new(0.0, 0.0, 200.0), Vector3::y_axis()),
/// ];
/// let tool = FixedRow::from_isometry(&Isometry3::translation(0.0, 0.0, 300.0));
/// let chain = Chain::new(FixedRow::identity(), joints, tool).unwrap();
/// let q = [0.0, 90f64.to_radians()];
/// let base_from_tcp = chain.tool_pose(&q).unwrap();
/// assert_relative_eq!(base_from_tcp.translation.vector, Vector3::new(300.0, 0.0, 300.0), epsilon = 1e-9);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    base: FixedRow,
    joints: Vec<Joint>,
    tool: FixedRow,
    base_frame: Frame,
    /// The base frame is exactly the identity (no base row, no registration): FK starts from the first
    /// joint's fixed row instead of multiplying it by the identity (`Chain::after_fixed`).
    base_is_identity: bool,
    tool_frame: Frame,
    /// Partial error rotations of the base and tool rows (see [`Link::partial`]).
    row_partials: [[Matrix3<f64>; 2]; 2],
    links: Vec<Link>,
}

impl Chain {
    /// Builds a chain, checking that every number is finite and every axis has unit length.
    pub fn new(base: FixedRow, joints: Vec<Joint>, tool: FixedRow) -> Result<Self, ChainError> {
        check_row("base", &base)?;
        check_row("tool", &tool)?;
        let mut links = Vec::with_capacity(joints.len());
        for (index, joint) in joints.iter().enumerate() {
            let what = |field: &'static str| ChainError::NonFinite { joint: index + 1, field };
            if !joint.offset.iter().all(|v| v.is_finite()) {
                return Err(what("offset"));
            }
            if !joint.zero.is_finite() {
                return Err(what("zero"));
            }
            if !joint.error.is_finite() {
                return Err(what("error"));
            }
            let n = joint.axis.norm();
            if !n.is_finite() || (n - 1.0).abs() > 1e-9 {
                return Err(ChainError::BadAxis { joint: index + 1 });
            }
            if let Some(l) = joint.limits
                && (!(l.lower.is_finite() && l.upper.is_finite()) || l.lower > l.upper)
            {
                return Err(ChainError::BadLimits { joint: index + 1, lower: l.lower, upper: l.upper });
            }
            // As `set_joint_error` computes them, so that a row rewritten in place equals a rebuilt one.
            let (rotation, partial) = row_rotations(&joint.error.rotation);
            links.push(Link {
                fixed: Frame::new(rotation, joint.offset + joint.error.translation),
                translation_only: rotation == Matrix3::identity(),
                partial,
                axis: AxisKind::classify(&joint.axis),
                axis_vec: joint.axis.into_inner(),
                kind: joint.kind,
                zero: joint.zero,
                zero_sin_cos: sin_cos(joint.zero),
            });
        }
        let base_frame = base.frame();
        Ok(Self {
            base_is_identity: base_frame.rot == Matrix3::identity() && base_frame.trans == Vector3::zeros(),
            base_frame,
            tool_frame: tool.frame(),
            row_partials: [partial_rotations(&base.error.rotation), partial_rotations(&tool.error.rotation)],
            base,
            joints,
            tool,
            links,
        })
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The joints.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// The base row.
    pub fn base(&self) -> &FixedRow {
        &self.base
    }

    /// The tool row (last joint → TCP).
    pub fn tool(&self) -> &FixedRow {
        &self.tool
    }

    /// A copy with the error parameters replaced: `joints[i]` for joint `i`, then base and tool.
    pub fn with_errors(
        &self,
        base: ErrorParams,
        joints: &[ErrorParams],
        tool: ErrorParams,
    ) -> Result<Chain, ChainError> {
        if joints.len() != self.dof() {
            return Err(ChainError::WrongJointCount { expected: self.dof(), got: joints.len() });
        }
        let mut base_row = self.base.clone();
        base_row.error = base;
        let mut tool_row = self.tool.clone();
        tool_row.error = tool;
        let js = self.joints.iter().zip(joints).map(|(j, e)| Joint { error: *e, ..j.clone() }).collect();
        Chain::new(base_row, js, tool_row)
    }

    /// A copy with the error parameters and the joint zero offsets replaced at once (one construction).
    pub fn with_errors_and_zeros(
        &self,
        base: ErrorParams,
        joints: &[ErrorParams],
        tool: ErrorParams,
        zeros: &[f64],
    ) -> Result<Chain, ChainError> {
        if joints.len() != self.dof() || zeros.len() != self.dof() {
            return Err(ChainError::WrongJointCount { expected: self.dof(), got: joints.len().min(zeros.len()) });
        }
        let mut base_row = self.base.clone();
        base_row.error = base;
        let mut tool_row = self.tool.clone();
        tool_row.error = tool;
        let js = self
            .joints
            .iter()
            .zip(joints)
            .zip(zeros)
            .map(|((j, e), z)| Joint { error: *e, zero: *z, ..j.clone() })
            .collect();
        Chain::new(base_row, js, tool_row)
    }

    /// Replaces joint `index`'s error parameters in place, recomputing only that row's precomputed
    /// frame: the fast path for a model whose error rows change from one measurement to the next (a
    /// drift growing with time), where rebuilding the whole chain costs more than the FK. The chain stays
    /// validated: a non-finite error or a joint the chain lacks is refused and leaves it unchanged.
    pub fn set_joint_error(&mut self, index: usize, error: ErrorParams) -> Result<(), ChainError> {
        if index >= self.dof() {
            return Err(ChainError::WrongJointCount { expected: self.dof(), got: index + 1 });
        }
        if !error.is_finite() {
            return Err(ChainError::NonFinite { joint: index + 1, field: "error" });
        }
        let joint = &mut self.joints[index];
        joint.error = error;
        let link = &mut self.links[index];
        let (rotation, partial) = row_rotations(&error.rotation);
        link.fixed = Frame::new(rotation, joint.offset + error.translation);
        link.translation_only = rotation == Matrix3::identity();
        link.partial = partial;
        Ok(())
    }

    /// A copy with every error parameter set to zero: the nominal robot.
    pub fn nominal(&self) -> Chain {
        let zeros = vec![ErrorParams::ZERO; self.dof()];
        // Cannot fail: removing errors keeps every number finite.
        self.with_errors(ErrorParams::ZERO, &zeros, ErrorParams::ZERO).unwrap_or_else(|_| self.clone())
    }

    /// A copy with the given joint zero offsets (radians or mm).
    pub fn with_zeros(&self, zeros: &[f64]) -> Result<Chain, ChainError> {
        if zeros.len() != self.dof() {
            return Err(ChainError::WrongJointCount { expected: self.dof(), got: zeros.len() });
        }
        let js = self.joints.iter().zip(zeros).map(|(j, z)| Joint { zero: *z, ..j.clone() }).collect();
        Chain::new(self.base.clone(), js, self.tool.clone())
    }

    /// A copy with a different tool row.
    pub fn with_tool(&self, tool: FixedRow) -> Result<Chain, ChainError> {
        Chain::new(self.base.clone(), self.joints.clone(), tool)
    }

    /// A copy with a different base row.
    pub fn with_base(&self, base: FixedRow) -> Result<Chain, ChainError> {
        Chain::new(base, self.joints.clone(), self.tool.clone())
    }

    /// `Ok` when `q` has one finite value per joint: the check every evaluation makes first.
    pub fn check_joint_count(&self, q: &[f64]) -> Result<(), ChainError> {
        self.check_q(q)
    }

    fn check_q(&self, q: &[f64]) -> Result<(), ChainError> {
        if q.len() != self.dof() {
            return Err(ChainError::WrongJointCount { expected: self.dof(), got: q.len() });
        }
        if let Some(i) = q.iter().position(|v| !v.is_finite()) {
            return Err(ChainError::NonFiniteJoint { joint: i + 1 });
        }
        Ok(())
    }

    /// `true` when every joint value lies within its limits (joints without limits always do).
    pub fn within_limits(&self, q: &[f64]) -> bool {
        self.joints.iter().zip(q).all(|(j, &v)| j.limits.is_none_or(|l| l.contains(v)))
    }

    /// The (0-based) joints whose values in `q` lie outside their limits.
    pub fn outside_limits(&self, q: &[f64]) -> Vec<usize> {
        self.joints
            .iter()
            .zip(q)
            .enumerate()
            .filter(|(_, (j, v))| j.limits.is_some_and(|l| !l.contains(**v)))
            .map(|(i, _)| i)
            .collect()
    }

    /// Applies joint `i`'s motion to the frame in front of it (after its fixed row); `given` is
    /// `(sin q, cos q)` when the caller has it (then `q + zero` by angle addition, no sine evaluated).
    #[inline(always)]
    fn apply_joint(link: &Link, frame: &mut Frame, q: f64, given: Option<(f64, f64)>) {
        match link.kind {
            JointKind::Revolute => {
                let (s, c) = match given {
                    Some((sq, cq)) => {
                        let (sz, cz) = link.zero_sin_cos;
                        (sq * cz + cq * sz, cq * cz - sq * sz)
                    }
                    None => crate::trig::sin_cos_reduced(q + link.zero),
                };
                frame.rotate_local(&link.axis, s, c);
            }
            JointKind::Prismatic => frame.translate_local(&(link.axis_vec * (q + link.zero))),
        }
    }

    /// `base_from_link` after link `i`'s fixed row, from the frame before it: the product — or, for the
    /// first link of a chain whose base is exactly the identity, the row itself. The fast path is exact:
    /// a product with an exact identity reproduces the row's numbers (to the sign of a zero), so it only
    /// saves one 3 × 3 product per evaluation (a seventh of FK's).
    #[inline(always)]
    fn after_fixed(&self, i: usize, before: &Frame, link: &Link) -> Frame {
        if i == 0 && self.base_is_identity { link.fixed } else { link.behind(before) }
    }

    /// Forward kinematics, unchecked length: `base_from_tcp`.
    #[inline]
    fn tool_frame_unchecked(&self, q: &[f64], given: Option<&[(f64, f64)]>) -> Frame {
        let mut base_from_link = self.base_frame;
        for (i, (link, &qi)) in self.links.iter().zip(q).enumerate() {
            base_from_link = self.after_fixed(i, &base_from_link, link);
            Self::apply_joint(link, &mut base_from_link, qi, given.map(|g| g[i]));
        }
        base_from_link.mul(&self.tool_frame)
    }

    /// Checks a caller's sines of the joint values: one `(sin q_i, cos q_i)` per joint, each the sine
    /// and cosine of the same angle to rounding (`s² + c² = 1` within 1e-12).
    fn check_sin_cos(&self, q_sin_cos: &[(f64, f64)]) -> Result<(), ChainError> {
        if q_sin_cos.len() != self.dof() {
            return Err(ChainError::WrongJointCount { expected: self.dof(), got: q_sin_cos.len() });
        }
        match q_sin_cos.iter().position(|(s, c)| {
            let off = (s * s + c * c - 1.0).abs();
            off.is_nan() || off > 1e-12
        }) {
            Some(i) => {
                let (s, c) = q_sin_cos[i];
                Err(ChainError::BadSinCos { joint: i + 1, norm: s * s + c * c })
            }
            None => Ok(()),
        }
    }

    /// The TCP pose in the base frame (`base_from_tcp`), mm. `q` in radians (mm for prismatic joints).
    pub fn tool_pose(&self, q: &[f64]) -> Result<Isometry3<f64>, ChainError> {
        self.check_q(q)?;
        Ok(self.tool_frame_unchecked(q, None).to_isometry())
    }

    /// The TCP position and rotation matrix, without building a quaternion (the IK inner loop).
    pub fn tool_position_rotation(&self, q: &[f64]) -> Result<(Vector3<f64>, Matrix3<f64>), ChainError> {
        self.check_q(q)?;
        let f = self.tool_frame_unchecked(q, None);
        Ok((f.trans, f.rot))
    }

    /// [`Chain::tool_position_rotation`] with the caller's `(sin q_i, cos q_i)` of each joint value
    /// (read for revolute joints; a prismatic joint uses `q_i`): the identification's fast path, which
    /// evaluates the same measured joints at every iteration and computes their sines once. The joint's
    /// zero offset is added by angle addition; the result equals the plain path to rounding.
    pub fn tool_position_rotation_sin_cos(
        &self,
        q: &[f64],
        q_sin_cos: &[(f64, f64)],
    ) -> Result<(Vector3<f64>, Matrix3<f64>), ChainError> {
        self.check_q(q)?;
        self.check_sin_cos(q_sin_cos)?;
        let f = self.tool_frame_unchecked(q, Some(q_sin_cos));
        Ok((f.trans, f.rot))
    }

    /// Every joint frame in the base frame, after the joint's motion (`base_from_joint_i`), then the TCP:
    /// `dof + 1` poses.
    pub fn joint_frames(&self, q: &[f64]) -> Result<Vec<Isometry3<f64>>, ChainError> {
        self.check_q(q)?;
        let mut out = Vec::with_capacity(self.dof() + 1);
        let mut base_from_link = self.base_frame;
        for (link, &qi) in self.links.iter().zip(q) {
            base_from_link = link.behind(&base_from_link);
            Self::apply_joint(link, &mut base_from_link, qi, None);
            out.push(base_from_link.to_isometry());
        }
        out.push(base_from_link.mul(&self.tool_frame).to_isometry());
        Ok(out)
    }

    /// Calls `visit(i, parent_rotation, rotation, origin)` with every joint frame after the joint's motion,
    /// beside the orientation of the frame its row's errors are in (the previous joint's after its motion,
    /// or the base's) (no quaternion,
    /// no allocation: the fast path of [`crate::gravity_torques_into`], which runs per pose per fit
    /// evaluation of a compliance); `given` is `(sin q_i, cos q_i)` of each joint value when the caller
    /// has them ([`Chain::tool_position_rotation_sin_cos`]'s rule).
    pub(crate) fn visit_joint_frames(
        &self,
        q: &[f64],
        given: Option<&[(f64, f64)]>,
        mut visit: impl FnMut(usize, &Matrix3<f64>, &Matrix3<f64>, &Vector3<f64>),
    ) -> Result<(), ChainError> {
        self.check_q(q)?;
        if let Some(g) = given {
            self.check_sin_cos(g)?;
        }
        let mut base_from_link = self.base_frame;
        for (i, (link, &qi)) in self.links.iter().zip(q).enumerate() {
            let parent = base_from_link.rot;
            base_from_link = link.behind(&base_from_link);
            Self::apply_joint(link, &mut base_from_link, qi, given.map(|g| g[i]));
            visit(i, &parent, &base_from_link.rot, &base_from_link.trans);
        }
        Ok(())
    }

    /// The geometric Jacobian (6 × dof) at the TCP in the base frame: rows 0–2 linear velocity (mm per
    /// radian, or mm/mm for a prismatic joint), rows 3–5 angular velocity.
    ///
    /// Column i of a revolute joint is `[z_i × (p_tcp − o_i); z_i]` with `z_i` the joint axis and `o_i` its
    /// origin in the base frame; a prismatic joint gives `[z_i; 0]`.
    pub fn jacobian(&self, q: &[f64]) -> Result<Matrix6xX<f64>, ChainError> {
        let mut cols = vec![[0.0; 6]; self.dof()];
        self.pose_and_jacobian_into(q, &mut cols)?;
        Ok(Matrix6xX::from_fn(self.dof(), |r, c| cols[c][r]))
    }

    /// TCP pose and Jacobian together, the Jacobian written column by column into `columns` (length
    /// `dof`); no allocation. Returns the TCP position and rotation matrix.
    pub fn pose_and_jacobian_into(
        &self,
        q: &[f64],
        columns: &mut [[f64; 6]],
    ) -> Result<(Vector3<f64>, Matrix3<f64>), ChainError> {
        self.check_q(q)?;
        if columns.len() != self.dof() {
            return Err(ChainError::WrongJointCount { expected: self.dof(), got: columns.len() });
        }
        let mut base_from_link = self.base_frame;
        for (i, ((link, &qi), col)) in self.links.iter().zip(q).zip(columns.iter_mut()).enumerate() {
            base_from_link = self.after_fixed(i, &base_from_link, link);
            // The axis is the same before and after the joint's own motion; store it and the origin now,
            // the lever arm is completed once the TCP is known.
            let z = base_from_link.rot * link.axis_vec;
            let o = base_from_link.trans;
            *col = [o.x, o.y, o.z, z.x, z.y, z.z];
            Self::apply_joint(link, &mut base_from_link, qi, None);
        }
        let tcp = base_from_link.mul(&self.tool_frame);
        let p = tcp.trans;
        for (link, col) in self.links.iter().zip(columns.iter_mut()) {
            let o = Vector3::new(col[0], col[1], col[2]);
            let z = Vector3::new(col[3], col[4], col[5]);
            *col = match link.kind {
                JointKind::Revolute => {
                    let v = z.cross(&(p - o));
                    [v.x, v.y, v.z, z.x, z.y, z.z]
                }
                JointKind::Prismatic => [z.x, z.y, z.z, 0.0, 0.0, 0.0],
            };
        }
        Ok((p, tcp.rot))
    }
}

/// `(sin x, cos x)`, by their Taylor polynomials for the small angles of error parameters and drifts
/// (|x| ≤ 1e-2 rad: the first omitted terms, `x⁹/9!` and `x¹⁰/10!`, are below 3e-22 of the result,
/// far under its rounding of 1.1e-16), by one argument reduction and fdlibm's kernels otherwise
/// (`trig`, within 1 ulp of the library) — the per-measurement rows of a drift pay no library sine.
pub fn sin_cos(x: f64) -> (f64, f64) {
    if x.abs() <= 1e-2 {
        let x2 = x * x;
        let s = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0)));
        let c = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)));
        (s, c)
    } else {
        crate::trig::sin_cos_reduced(x)
    }
}

/// `[Rx(a), Rx(a) · Ry(b)]` for error angles `(a, b, c)`.
fn partial_rotations(angles: &Vector3<f64>) -> [Matrix3<f64>; 2] {
    row_rotations(angles).1
}

/// A row's angular correction `Rx(a) · Ry(b) · Rz(c)` (eq. 19, as [`crate::xyz_rotation`]) with its
/// partial products `[Rx(a), Rx(a) · Ry(b)]` (the axes of its Jacobian columns), from one sine and
/// cosine per angle: the per-measurement path of a drifting row ([`Chain::set_joint_error`]).
fn row_rotations(angles: &Vector3<f64>) -> (Matrix3<f64>, [Matrix3<f64>; 2]) {
    let [(sa, ca), (sb, cb), (sc, cc)] = [sin_cos(angles.x), sin_cos(angles.y), sin_cos(angles.z)];
    let full = crate::error_params::xyz_rotation_from_sines([(sa, ca), (sb, cb), (sc, cc)]);
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, ca, -sa, 0.0, sa, ca);
    let rx_ry = Matrix3::new(cb, 0.0, sb, sa * sb, ca, -sa * cb, -ca * sb, sa, ca * cb);
    (full, [rx, rx_ry])
}

fn check_row(which: &'static str, row: &FixedRow) -> Result<(), ChainError> {
    let ok = row.translation.iter().all(|v| v.is_finite())
        && row.rotation.coords.iter().all(|v| v.is_finite())
        && row.error.is_finite();
    if ok { Ok(()) } else { Err(ChainError::NonFiniteRow { row: which }) }
}

/// Layout of the columns of [`Chain::parameter_jacobian`]: six error parameters for the base row, six per
/// joint, six for the tool row, then one zero offset per joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ParameterLayout {
    /// Number of joints.
    pub dof: usize,
}

impl ParameterLayout {
    /// Total number of columns: `6 (base) + 6·dof + 6 (tool) + dof`.
    pub fn len(&self) -> usize {
        12 + 7 * self.dof
    }
    /// Never empty (the base and tool rows are always there).
    pub fn is_empty(&self) -> bool {
        false
    }
    /// First column of the base row.
    pub fn base(&self) -> usize {
        0
    }
    /// First column of joint `i` (0-based).
    pub fn joint(&self, i: usize) -> usize {
        6 + 6 * i
    }
    /// First column of the tool row.
    pub fn tool(&self) -> usize {
        6 + 6 * self.dof
    }
    /// Column of the zero offset of joint `i` (0-based).
    pub fn zero(&self, i: usize) -> usize {
        12 + 6 * self.dof + i
    }
}

impl Chain {
    /// The column layout of [`Chain::parameter_jacobian`].
    pub fn parameter_layout(&self) -> ParameterLayout {
        ParameterLayout { dof: self.dof() }
    }

    /// Derivatives of the TCP pose with respect to every error parameter (mm and rad) and every joint zero
    /// offset, as twists in the base frame at the TCP: rows 0–2 linear, 3–5 angular; columns as in
    /// [`ParameterLayout`].
    ///
    /// Each row is `Trans(p + Δp) · Rx(a) · Ry(b) · Rz(c) · motion` behind a parent frame `P`. A change of
    /// `Δp` moves everything behind it along `R_P e_k`: column `[R_P e_k; 0]`. A change of `a`, `b`, `c`
    /// turns everything behind it about the axis `u = R_P e_x`, `R_P Rx(a) e_y`, `R_P Rx(a) Ry(b) e_z`
    /// through the row's origin `o`: column `[u × (p_tcp − o); u]`. A zero offset acts like the joint.
    pub fn parameter_jacobian(&self, q: &[f64]) -> Result<Matrix6xX<f64>, ChainError> {
        Ok(self.pose_and_parameter_jacobian(q)?.jacobian)
    }

    /// The TCP position and rotation matrix with [`Chain::parameter_jacobian`], from one pass along the
    /// chain (an identification evaluates both at every measurement).
    pub fn pose_and_parameter_jacobian(&self, q: &[f64]) -> Result<PoseAndJacobian, ChainError> {
        let mut jacobian = Matrix6xX::zeros(self.parameter_layout().len());
        let (position, rotation) = self.pose_and_parameter_jacobian_into(q, &mut jacobian)?;
        Ok(PoseAndJacobian { position, rotation, jacobian })
    }

    /// [`Chain::pose_and_parameter_jacobian`] into a caller's matrix (`6 × parameter_layout().len()`,
    /// every entry overwritten): no allocation, one pass along the chain.
    pub fn pose_and_parameter_jacobian_into(
        &self,
        q: &[f64],
        jac: &mut Matrix6xX<f64>,
    ) -> Result<(Vector3<f64>, Matrix3<f64>), ChainError> {
        self.check_q(q)?;
        self.parameter_jacobian_unchecked(q, None, jac, &ParameterRows::all(self.dof()))
    }

    /// [`Chain::pose_and_parameter_jacobian_into`] for the rows `rows` names only, the other columns of
    /// `jac` left as they were: the identification's per-measurement path, where a model identifies a
    /// few rows and pays for those. A translation parameter's column is its direction `u`; a rotation's
    /// is `[u × (p − o); u]` with `o` the row's origin and `p` the TCP; a zero offset's is the joint's
    /// own column of the geometric Jacobian. The TCP is known only at the end of the pass, so a rotation
    /// column is first written as `[o × u; u]` (that is `−u × o`) and `u × p` added once `p` is known.
    pub fn pose_and_parameter_jacobian_rows(
        &self,
        q: &[f64],
        jac: &mut Matrix6xX<f64>,
        rows: &ParameterRows,
    ) -> Result<(Vector3<f64>, Matrix3<f64>), ChainError> {
        self.check_q(q)?;
        self.parameter_jacobian_unchecked(q, None, jac, rows)
    }

    /// [`Chain::pose_and_parameter_jacobian_rows`] with the caller's `(sin q_i, cos q_i)`, as in
    /// [`Chain::tool_position_rotation_sin_cos`].
    pub fn pose_and_parameter_jacobian_rows_sin_cos(
        &self,
        q: &[f64],
        q_sin_cos: &[(f64, f64)],
        jac: &mut Matrix6xX<f64>,
        rows: &ParameterRows,
    ) -> Result<(Vector3<f64>, Matrix3<f64>), ChainError> {
        self.check_q(q)?;
        self.check_sin_cos(q_sin_cos)?;
        self.parameter_jacobian_unchecked(q, Some(q_sin_cos), jac, rows)
    }

    /// The pass behind the parameter Jacobians, `q` checked.
    fn parameter_jacobian_unchecked(
        &self,
        q: &[f64],
        given: Option<&[(f64, f64)]>,
        jac: &mut Matrix6xX<f64>,
        rows: &ParameterRows,
    ) -> Result<(Vector3<f64>, Matrix3<f64>), ChainError> {
        let layout = self.parameter_layout();
        if jac.ncols() != layout.len() {
            return Err(ChainError::DescriptionLength {
                field: "parameter jacobian",
                expected: layout.len(),
                got: jac.ncols(),
            });
        }
        if rows.joints.len() != self.dof() || rows.zeros.len() != self.dof() {
            let got = rows.joints.len().min(rows.zeros.len());
            return Err(ChainError::WrongJointCount { expected: self.dof(), got });
        }
        /// Column `col`: a direction (`None`: a translation) or a turn about `u` through `origin`, its
        /// `u × p` part still to add.
        fn put(jac: &mut Matrix6xX<f64>, col: usize, u: Vector3<f64>, origin: Option<Vector3<f64>>) {
            let (linear, angular) = match origin {
                Some(o) => (o.cross(&u), u),
                None => (u, Vector3::zeros()),
            };
            jac.fixed_view_mut::<3, 1>(0, col).copy_from(&linear);
            jac.fixed_view_mut::<3, 1>(3, col).copy_from(&angular);
        }
        /// The six columns of a row whose parent frame is `parent` and whose translation ends at `origin`:
        /// rotation axes `R_P e_x`, `R_P Rx(a) e_y`, `R_P Rx(a) Ry(b) e_z`.
        fn row(
            jac: &mut Matrix6xX<f64>,
            first: usize,
            parent: &Frame,
            origin: Vector3<f64>,
            partial: &[Matrix3<f64>; 2],
        ) {
            for k in 0..3 {
                put(jac, first + k, parent.rot.column(k).into_owned(), None);
            }
            put(jac, first + 3, parent.rot.column(0).into_owned(), Some(origin));
            put(jac, first + 4, parent.rot * partial[0].column(1), Some(origin));
            put(jac, first + 5, parent.rot * partial[1].column(2), Some(origin));
        }
        let world = Frame::new(Matrix3::identity(), Vector3::zeros());
        if rows.base {
            let base_origin = self.base.translation + self.base.error.translation;
            row(jac, layout.base(), &world, base_origin, &self.row_partials[0]);
        }
        let mut frame = self.base_frame;
        for (i, (link, &qi)) in self.links.iter().zip(q).enumerate() {
            if rows.joints[i] {
                let origin = frame.rot * link.fixed.trans + frame.trans;
                row(jac, layout.joint(i), &frame, origin, &link.partial);
            }
            frame = link.behind(&frame);
            if rows.zeros[i] {
                let z = frame.rot * link.axis_vec;
                let revolute = link.kind == JointKind::Revolute;
                put(jac, layout.zero(i), z, revolute.then_some(frame.trans));
            }
            Self::apply_joint(link, &mut frame, qi, given.map(|g| g[i]));
        }
        if rows.tool {
            let tool_origin = frame.rot * (self.tool.translation + self.tool.error.translation) + frame.trans;
            row(jac, layout.tool(), &frame, tool_origin, &self.row_partials[1]);
        }
        let tcp = frame.mul(&self.tool_frame);
        let p = tcp.trans;
        let mut finish = |col: usize| {
            let u: Vector3<f64> = jac.fixed_view::<3, 1>(3, col).into_owned();
            let add = u.cross(&p);
            let mut linear = jac.fixed_view_mut::<3, 1>(0, col);
            linear += add;
        };
        if rows.base {
            (0..6).for_each(|k| finish(layout.base() + k));
        }
        for i in 0..self.dof() {
            if rows.joints[i] {
                (0..6).for_each(|k| finish(layout.joint(i) + k));
            }
            if rows.zeros[i] {
                finish(layout.zero(i));
            }
        }
        if rows.tool {
            (0..6).for_each(|k| finish(layout.tool() + k));
        }
        Ok((tcp.trans, tcp.rot))
    }
}

/// Which rows of [`Chain::parameter_jacobian`] a caller needs
/// ([`Chain::pose_and_parameter_jacobian_rows`]): the base row, each joint's error row, the tool row,
/// each joint's zero offset.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParameterRows {
    /// The base row's six columns.
    pub base: bool,
    /// Joint `i`'s six error columns.
    pub joints: Vec<bool>,
    /// The tool row's six columns.
    pub tool: bool,
    /// Joint `i`'s zero-offset column.
    pub zeros: Vec<bool>,
}

impl ParameterRows {
    /// Every row of a chain with `dof` joints.
    pub fn all(dof: usize) -> Self {
        Self { base: true, joints: vec![true; dof], tool: true, zeros: vec![true; dof] }
    }

    /// No row of a chain with `dof` joints: the pose only.
    pub fn none(dof: usize) -> Self {
        Self { base: false, joints: vec![false; dof], tool: false, zeros: vec![false; dof] }
    }
}
