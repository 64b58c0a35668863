//! Gravity compliance without masses: the functions of the joint values that any load's gravity torque
//! about a joint is a weighted sum of, so that a joint's deflection under unknown masses is linear in a
//! few lumped parameters.
//!
//! The torque about revolute joint `j` ([`crate::gravity_torques_into`]) is
//! `τⱼ = aⱼ · Σ_{l ≥ j} (cₗ − oⱼ) × mₗ g = Σ_{l ≥ j} mₗ (cₗ − oⱼ) · wⱼ` with `wⱼ = d × aⱼ`, `d` the unit
//! direction of gravity and `g` its magnitude folded into the masses. Write each centre as its link's
//! origin plus a vector fixed in the link, `cₗ = oₗ + Rₗ sₗ`: the term `mₗ Rₗ sₗ · wⱼ` is
//! `vₗ · (Rₗᵀ wⱼ)` with the first moment `vₗ = mₗ sₗ` constant in link `l`'s frame. The origin terms
//! fold inwards: `oₗ = oₗ₋₁ + Rₗ₋₁ tₗ` (+ `qₗ Rₗ₋₁ aₗ` for a prismatic joint), so `mₗ (oₗ − oⱼ)` is a
//! moment `mₗ tₗ` of link `l − 1` (plus, for a slide, its travel times the mass it carries), down to
//! `oⱼ − oⱼ = 0`. Hence
//!
//! `τⱼ(q) = Σ_{l ≥ j} vₗ · (Rₗᵀ wⱼ) + Σ_{prismatic l > j} Mₗ qₗ (Rₗ aₗ) · wⱼ`,
//!
//! linear in the moments `vₗ` and the carried masses `Mₗ`. Two components of each moment are enough: the
//! one along link `l`'s own axis does not turn with joint `l` (`Rₗ aₗ = Rₗ₋₁ aₗ`), so it is a moment of
//! link `l − 1`; along joint `j`'s own axis it meets `wⱼ ⟂ aⱼ`. The deflection `Δqⱼ = kⱼ τⱼ` is then a
//! weighted sum of the functions [`gravity_load_basis_into`] evaluates, the weights `kⱼ g vₗ` (radians)
//! and `kⱼ g Mₗ` (radians per mm) — what a fit can identify with no mass known. A test checks that the
//! gravity torques of a robot with masses lie in their span.

use nalgebra::{Matrix3, Unit, Vector3};

use crate::{Chain, ChainError, JointKind};

/// Two unit directions perpendicular to `axis` (and to each other), the same for the same axis.
pub(crate) fn perpendiculars(axis: &Vector3<f64>) -> [Vector3<f64>; 2] {
    let a = axis.normalize();
    // The base axis least aligned with `a` makes a well-conditioned first perpendicular.
    let pick = if a.x.abs() <= a.y.abs() && a.x.abs() <= a.z.abs() {
        Vector3::x()
    } else if a.y.abs() <= a.z.abs() {
        Vector3::y()
    } else {
        Vector3::z()
    };
    let e1 = (pick - a * a.dot(&pick)).normalize();
    [e1, a.cross(&e1)]
}

/// The number of functions [`gravity_load_basis_into`] gives for joint `joint` (0-based): two per
/// revolute joint from `joint` outwards and one per prismatic joint beyond it; zero for a prismatic
/// `joint` or one past the chain.
pub fn gravity_load_basis_len(chain: &Chain, joint: usize) -> usize {
    let joints = chain.joints();
    if joints.get(joint).is_none_or(|j| j.kind != JointKind::Revolute) {
        return 0;
    }
    joints[joint..]
        .iter()
        .enumerate()
        .map(|(i, j)| match j.kind {
            JointKind::Revolute => 2,
            JointKind::Prismatic if i > 0 => 1,
            JointKind::Prismatic => 0,
        })
        .sum()
}

/// The functions of the joint values `q` whose weighted sum is revolute joint `joint`'s gravity torque
/// under any masses on the links it carries (the module's derivation), into `out` (length
/// [`gravity_load_basis_len`]): for each joint `l` from `joint` outwards, a revolute one's
/// `eₗ,ₖ · (Rₗᵀ (d × aⱼ))` for the two perpendiculars `eₗ,ₖ` of its axis, a prismatic one's
/// `qₗ (Rₗ aₗ) · (d × aⱼ)` (mm). `given` is `(sin q_i, cos q_i)` when the caller has them.
///
/// ```
/// use nalgebra::Vector3;
/// use thermokin_chain::{Chain, FixedRow, Joint, gravity_load_basis_into, gravity_load_basis_len};
/// # fn main() -> Result<(), thermokin_chain::ChainError> {
/// // A shoulder and an elbow about horizontal axes: the shoulder's torque under any two links' masses
/// // is a sum of four functions of the two angles.
/// let joints = vec![
///     Joint::revolute("shoulder", Vector3::zeros(), Vector3::y_axis()),
///     Joint::revolute("elbow", Vector3::new(0.0, 0.0, 300.0), Vector3::y_axis()),
/// ];
/// let chain = Chain::new(FixedRow::identity(), joints, FixedRow::identity())?;
/// let mut basis = Vec::new();
/// gravity_load_basis_into(&chain, &[0.3, -0.5], None, &-Vector3::z_axis(), 0, &mut basis)?;
/// assert_eq!((basis.len(), gravity_load_basis_len(&chain, 0)), (4, 4));
/// # Ok(())
/// # }
/// ```
pub fn gravity_load_basis_into(
    chain: &Chain,
    q: &[f64],
    given: Option<&[(f64, f64)]>,
    down: &Unit<Vector3<f64>>,
    joint: usize,
    out: &mut Vec<f64>,
) -> Result<(), ChainError> {
    out.clear();
    if gravity_load_basis_len(chain, joint) == 0 {
        return Ok(());
    }
    let joints = chain.joints();
    let mut w = Vector3::zeros();
    chain.visit_joint_frames(q, given, |i, _parent, rot: &Matrix3<f64>, _origin| {
        if i < joint {
            return;
        }
        let axis = &joints[i].axis;
        if i == joint {
            w = down.cross(&(rot * axis.into_inner()));
        }
        let (terms, n) = link_terms(joints[i].kind, axis, rot, q[i], &w, false);
        out.extend_from_slice(&terms[..n]);
    })
}

/// The functions of joint `l`'s link for a moment along `w = d × u` (the module's derivation): a
/// revolute one's `eₗ,ₖ · (Rₗᵀ w)` for the two perpendiculars of its axis, a prismatic one's
/// `qₗ (Rₗ aₗ) · w` — and, for the loaded joint's own link of a lateral moment (`own_axial`, revolute or
/// prismatic), all three components `eₗ,₁`, `eₗ,₂`, `aₗ` of `Rₗᵀ w`; how many of the three are used.
fn link_terms(
    kind: JointKind,
    axis: &Unit<Vector3<f64>>,
    rot: &Matrix3<f64>,
    q: f64,
    w: &Vector3<f64>,
    own_axial: bool,
) -> ([f64; 3], usize) {
    match kind {
        JointKind::Prismatic if !own_axial => ([q * (rot * axis.into_inner()).dot(w), 0.0, 0.0], 1),
        _ => {
            let rw = rot.transpose() * w;
            let [e1, e2] = perpendiculars(axis);
            ([e1.dot(&rw), e2.dot(&rw), axis.dot(&rw)], if own_axial { 3 } else { 2 })
        }
    }
}

/// The number of functions [`lateral_load_basis_into`] gives for joint `joint` (0-based): per lateral
/// direction, three for the joint's own link and, from the next joint outwards, two per revolute and one
/// per prismatic joint; zero for a joint past the chain.
pub fn lateral_load_basis_len(chain: &Chain, joint: usize) -> usize {
    let joints = chain.joints();
    if joint >= joints.len() {
        return 0;
    }
    let beyond: usize = joints[joint + 1..].iter().map(|j| if j.kind == JointKind::Revolute { 2 } else { 1 }).sum();
    2 * (3 + beyond)
}

/// The functions of the joint values `q` whose weighted sums are joint `joint`'s gravity moments across
/// its axis ([`crate::lateral_gravity_moments_into`], along its two [`crate::lateral_directions`]
/// `uₖ`) under any masses on the links it carries, into `out` (length [`lateral_load_basis_len`]; the
/// first half along `u₁`, the second along `u₂`).
///
/// The moment along a direction `u` is `u · Σ (cₗ − oⱼ) × mₗ g = Σ mₗ (cₗ − oⱼ) · w` with `w = d × u`:
/// the torque's derivation ([`gravity_load_basis_into`], the module's) with `w` for `d × aⱼ`. The terms
/// fold inwards alike, with one difference: the joint's own link keeps all three components of its first
/// moment, since `w` is not perpendicular to the joint's axis (its component along the axis does not
/// turn with the joint, but still varies with the joints before; a slide's own link does not turn with
/// it at all, and its moment about the carriage's origin is the same three terms). So each direction gives
/// `eⱼ,₁ · (Rⱼᵀ w)`, `eⱼ,₂ · (Rⱼᵀ w)`, `aⱼ · (Rⱼᵀ w)`, then per joint `l` beyond a revolute one's two
/// `eₗ,ₖ · (Rₗᵀ w)` and a prismatic one's `qₗ (Rₗ aₗ) · w`. A test checks that the lateral moments of a
/// robot with masses lie in their span.
pub fn lateral_load_basis_into(
    chain: &Chain,
    q: &[f64],
    given: Option<&[(f64, f64)]>,
    down: &Unit<Vector3<f64>>,
    joint: usize,
    out: &mut Vec<f64>,
) -> Result<(), ChainError> {
    out.clear();
    let n = lateral_load_basis_len(chain, joint);
    if n == 0 {
        return Ok(());
    }
    out.resize(n, 0.0);
    let half = n / 2;
    let joints = chain.joints();
    let directions = perpendiculars(&joints[joint].axis);
    let mut w = [Vector3::zeros(); 2];
    let mut at = 0;
    chain.visit_joint_frames(q, given, |i, parent: &Matrix3<f64>, rot: &Matrix3<f64>, _origin| {
        if i < joint {
            return;
        }
        let axis = &joints[i].axis;
        if i == joint {
            for k in 0..2 {
                w[k] = down.cross(&(parent * directions[k]));
            }
        }
        let mut used = 0;
        for (k, w) in w.iter().enumerate() {
            let (terms, n) = link_terms(joints[i].kind, axis, rot, q[i], w, i == joint);
            out[k * half + at..k * half + at + n].copy_from_slice(&terms[..n]);
            used = n;
        }
        at += used;
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use nalgebra::{DMatrix, DVector, Vector3};

    use super::*;
    use crate::{FixedRow, Joint, LinkMass, gravity_torques};

    /// A 6-joint arm with the IRB 140's axes and offsets, a prismatic lift under it, masses on every
    /// link off their axes.
    fn lifted_arm() -> (Chain, Vec<Option<LinkMass>>) {
        let axes = [
            Vector3::z_axis(),
            Vector3::z_axis(),
            Vector3::y_axis(),
            Vector3::y_axis(),
            Vector3::x_axis(),
            Vector3::y_axis(),
            Vector3::x_axis(),
        ];
        let offsets = [
            Vector3::zeros(),
            Vector3::new(0.0, 0.0, 352.0),
            Vector3::new(70.0, 0.0, 0.0),
            Vector3::new(0.0, 0.0, 360.0),
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(380.0, 0.0, 0.0),
            Vector3::zeros(),
        ];
        let joints = axes
            .iter()
            .zip(offsets)
            .enumerate()
            .map(|(i, (axis, offset))| {
                if i == 0 {
                    Joint::prismatic("lift", offset, *axis)
                } else {
                    Joint::revolute(format!("j{i}"), offset, *axis)
                }
            })
            .collect();
        let tool = FixedRow::from_isometry(&nalgebra::Isometry3::translation(65.0, 0.0, 0.0));
        let chain = Chain::new(FixedRow::identity(), joints, tool).unwrap();
        let masses = [8.0, 30.0, 12.0, 9.0, 4.0, 2.0, 0.7]
            .iter()
            .enumerate()
            .map(|(i, &m)| {
                Some(LinkMass { mass_kg: m, com_mm: Vector3::new(40.0 - 9.0 * i as f64, 15.0 + 3.0 * i as f64, 25.0) })
            })
            .collect();
        (chain, masses)
    }

    /// Joint values spread over the range, seeded.
    fn poses(n: usize) -> Vec<Vec<f64>> {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n).map(|_| (0..7).map(|i| if i == 0 { 600.0 * next() } else { 6.0 * next() - 3.0 }).collect()).collect()
    }

    #[test]
    fn the_torques_of_any_masses_lie_in_the_span_and_no_function_is_spare() {
        let (chain, masses) = lifted_arm();
        let down = -Vector3::z_axis();
        let qs = poses(300);
        for joint in 1..7 {
            let n = gravity_load_basis_len(&chain, joint);
            let mut rows = Vec::new();
            let mut torques = Vec::new();
            let mut basis = Vec::new();
            for q in &qs {
                gravity_load_basis_into(&chain, q, None, &down, joint, &mut basis).unwrap();
                assert_eq!(basis.len(), n);
                rows.extend_from_slice(&basis);
                torques.push(gravity_torques(&chain, &masses, q, &down).unwrap()[joint]);
            }
            let a = DMatrix::from_row_slice(qs.len(), n, &rows);
            let b = DVector::from_vec(torques);
            let svd = a.clone().svd(true, true);
            let x = svd.solve(&b, 1e-12).unwrap();
            let misfit = (&a * &x - &b).norm() / b.norm().max(1e-300);
            // The torques are computed by another route (crate::gravity_torques_into: the masses' moments
            // summed from the tip): they must lie in the span to rounding.
            assert!(misfit < 1e-9, "joint {}: {misfit}", joint + 1);
            // None of the functions is a combination of the others, except where the arm's geometry
            // makes one (joint 2 vertical: nothing loads it, all vanish).
            let s = svd.singular_values;
            let (hi, lo) = (s.max(), s.min());
            if joint == 1 {
                assert!(hi < 1e-12, "a vertical axis carries no gravity torque: {hi}");
            } else {
                assert!(lo > 1e-6 * hi, "joint {}: singular values {s:?}", joint + 1);
            }
        }
        // A prismatic joint has no basis; one past the chain neither.
        assert_eq!(gravity_load_basis_len(&chain, 0), 0);
        assert_eq!(gravity_load_basis_len(&chain, 7), 0);
    }

    #[test]
    fn the_lateral_moments_of_any_masses_lie_in_the_span() {
        let (chain, masses) = lifted_arm();
        // Gravity a little off the base's −Z (a registered base): no function may rely on its direction.
        let down = Unit::new_normalize(Vector3::new(0.03, -0.02, -1.0));
        let qs = poses(300);
        // The lift (joint 1) too: a column's moments about its carriage.
        for joint in 0..7 {
            let n = lateral_load_basis_len(&chain, joint);
            if joint > 0 {
                assert_eq!(n, 2 * (gravity_load_basis_len(&chain, joint) + 1));
            }
            let mut basis = Vec::new();
            let mut moments = Vec::new();
            for k in 0..2 {
                let (mut rows, mut along) = (Vec::new(), Vec::new());
                for q in &qs {
                    lateral_load_basis_into(&chain, q, None, &down, joint, &mut basis).unwrap();
                    assert_eq!(basis.len(), n);
                    rows.extend_from_slice(&basis[k * n / 2..(k + 1) * n / 2]);
                    // The moments by another route: crate::lateral_gravity_moments_into sums the masses'
                    // moments from the tip.
                    crate::lateral_gravity_moments_into(&chain, &masses, q, None, &down, &mut moments).unwrap();
                    along.push(moments[joint][k]);
                }
                let a = DMatrix::from_row_slice(qs.len(), n / 2, &rows);
                let b = DVector::from_vec(along);
                let x = a.clone().svd(true, true).solve(&b, 1e-12).unwrap();
                let misfit = (&a * &x - &b).norm() / b.norm().max(1e-300);
                assert!(misfit < 1e-9, "joint {} direction {k}: {misfit}", joint + 1);
            }
        }
        assert_eq!(lateral_load_basis_len(&chain, 0), 2 * (3 + 12));
        assert_eq!(lateral_load_basis_len(&chain, 7), 0);
    }
}
