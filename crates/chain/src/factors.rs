//! Any chain description as alternating fixed transforms and joint motions ([`JointFactor`]), and the
//! exact conversion of such a list into the same-orientation extended table and back
//! ([`Chain::from_factors`], [`Chain::to_factors`]) — paper section 2.3's two rules: every joint at its
//! axis line at the zero configuration, every joint frame world-aligned. Classic and modified DH
//! (`dh.rs`) and URDF (`thermokin-urdf`) are lists of factors.

use nalgebra::{Isometry3, Translation3, Unit, Vector3};

use crate::ChainError;
use crate::chain::{Chain, FixedRow, Joint, JointKind, JointLimits};

/// One joint of a chain written as alternating fixed transforms and joint motions:
/// `world_from_tcp = before_1 · M_1(q_1) · before_2 · M_2(q_2) · … · tail`, where `M_i` turns about (or
/// slides along) `axis`, a unit vector of the frame reached after `before_i`. Every convention — classic
/// and modified DH, URDF — is a list of these, and [`Chain::from_factors`] turns any such list into the
/// same-orientation extended table exactly.
#[derive(Clone, Debug, PartialEq)]
pub struct JointFactor {
    /// The fixed transform before the joint, from the previous joint's moving frame.
    pub before: Isometry3<f64>,
    /// The joint axis in the frame reached after `before`.
    pub axis: Unit<Vector3<f64>>,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Joint name.
    pub name: String,
    /// Limits of the joint variable.
    pub limits: Option<JointLimits>,
}

impl Chain {
    /// The exact same-orientation extended table of a chain given as fixed transforms and joint motions.
    ///
    /// At the zero configuration each joint's axis is a line `(o_i, z_i)` in the world frame. The extended
    /// chain puts joint `i` at `o_i` with axis `z_i`, every joint frame world-aligned, so that
    /// `p_i = o_i − o_{i−1}`; a rotation about the line through `o_i` equals `G_i M(q) G_i⁻¹`, which is
    /// why the two FKs agree for every `q`, not only at zero. The tool row takes what remains.
    pub fn from_factors(factors: &[JointFactor], tail: &Isometry3<f64>) -> Result<Chain, ChainError> {
        let mut world_from_joint = Isometry3::identity();
        let mut previous_origin = Vector3::zeros();
        let mut joints = Vec::with_capacity(factors.len());
        for f in factors {
            world_from_joint *= f.before;
            let origin = world_from_joint.translation.vector;
            let axis = snap_axis(&(world_from_joint.rotation * f.axis.into_inner()));
            let mut joint = match f.kind {
                JointKind::Revolute => Joint::revolute(f.name.clone(), origin - previous_origin, axis),
                JointKind::Prismatic => Joint::prismatic(f.name.clone(), origin - previous_origin, axis),
            };
            joint.limits = f.limits;
            joints.push(joint);
            previous_origin = origin;
        }
        let world_from_tcp = world_from_joint * tail;
        let last_from_tcp = Isometry3::from_parts(
            Translation3::from(world_from_tcp.translation.vector - previous_origin),
            world_from_tcp.rotation,
        );
        Chain::new(FixedRow::identity(), joints, FixedRow::from_isometry(&last_from_tcp))
    }

    /// This chain as fixed transforms and joint motions (the inverse of [`Chain::from_factors`]): each
    /// joint's `before` is its fixed row (`Trans(p + Δp) · R(Δθ)`) with its zero offset folded in, so that
    /// the motion is the bare joint variable; the base row is folded into the first factor and the tool
    /// row is the tail. Exact: the product equals the chain's FK for every configuration.
    pub fn to_factors(&self) -> (Vec<JointFactor>, Isometry3<f64>) {
        let mut pending = self.base().pose();
        let mut out = Vec::with_capacity(self.dof());
        for j in self.joints() {
            let fixed = j.error.row_transform(&j.offset);
            let zero = match j.kind {
                JointKind::Revolute => Isometry3::rotation(j.axis.into_inner() * j.zero),
                JointKind::Prismatic => Isometry3::translation(j.axis.x * j.zero, j.axis.y * j.zero, j.axis.z * j.zero),
            };
            out.push(JointFactor {
                before: pending * fixed * zero,
                axis: j.axis,
                kind: j.kind,
                name: j.name.clone(),
                limits: j.limits,
            });
            pending = Isometry3::identity();
        }
        (out, pending * self.tool().pose())
    }
}

/// Rounds away components below 1e-14 (the `cos(π/2) = 6e-17` of a floating-point twist), so that the
/// axes of ordinary robots come out as exact ±X, ±Y, ±Z. The change is below 1e-14 rad: at a 2 m reach
/// that moves the TCP by 2e-11 mm, far under the 1e-9 mm the conversions are held to.
fn snap_axis(v: &Vector3<f64>) -> Unit<Vector3<f64>> {
    let snapped = v.map(|c| if c.abs() < 1e-14 { 0.0 } else { c });
    Unit::new_normalize(snapped)
}
