//! Lateral gravity moments: what tilts a joint's bearing or bends a column, about the two directions
//! perpendicular to its axis.
//!
//! The moment of gravity about joint `j`'s origin `oⱼ` of every link it carries is
//! `Mⱼ = Σ_{l ≥ j} (cₗ − oⱼ) × mₗ g` — the vector whose component along the axis is the torque the joint's
//! drive holds ([`crate::gravity_torques_into`]); the two components across it load the bearing (or, for a
//! slide, the column) and tilt it. They are given in the frame the joint's row errors are in — its
//! parent's, the previous joint's after its motion (or the base's) — along [`lateral_directions`], so that
//! a tilt `φₖ` about direction `eₖ` is the row's error angles moved by `φₖ eₖ` (eq. 19's angles, small).
//! Each component is `−∂V/∂φ` of gravity's potential `V` under a turn `φ` of the carried links about
//! `eₖ` through `oⱼ`: a test checks it against finite differences of `V`.

use nalgebra::{Matrix3, Unit, Vector3};

use crate::gravity_loads::perpendiculars;
use crate::{Chain, ChainError, LinkMass};

/// The two unit directions, perpendicular to joint `joint`'s axis and to each other, that its lateral
/// moments are taken along and its row tilts about, in its parent's frame (the frame of its row's errors).
/// `None` past the chain.
pub fn lateral_directions(chain: &Chain, joint: usize) -> Option<[Vector3<f64>; 2]> {
    chain.joints().get(joint).map(|j| perpendiculars(&j.axis))
}

/// Per joint, the moment of gravity about its origin of the links it carries (its own and beyond, with
/// `masses`, one entry per joint), along its two [`lateral_directions`], N·m, into `out` (its length set to
/// the joints'). `given` is `(sin q_i, cos q_i)` of the joint values when the caller has them.
///
/// ```
/// use nalgebra::Vector3;
/// use thermokin_chain::{Chain, FixedRow, Joint, LinkMass, lateral_gravity_moments_into};
/// # fn main() -> Result<(), thermokin_chain::ChainError> {
/// // A vertical column carrying 10 kg 500 mm out along x: 49 N·m across it, none along it.
/// let joints = vec![Joint::prismatic("column", Vector3::zeros(), Vector3::z_axis())];
/// let chain = Chain::new(FixedRow::identity(), joints, FixedRow::identity())?;
/// let masses = [Some(LinkMass { mass_kg: 10.0, com_mm: Vector3::new(500.0, 0.0, 0.0) })];
/// let mut out = Vec::new();
/// lateral_gravity_moments_into(&chain, &masses, &[300.0], None, &-Vector3::z_axis(), &mut out)?;
/// let [a, b] = out[0];
/// assert!((a.hypot(b) - 0.5 * 10.0 * 9.80665).abs() < 1e-9);
/// # Ok(())
/// # }
/// ```
pub fn lateral_gravity_moments_into(
    chain: &Chain,
    masses: &[Option<LinkMass>],
    q: &[f64],
    given: Option<&[(f64, f64)]>,
    down: &Unit<Vector3<f64>>,
    out: &mut Vec<[f64; 2]>,
) -> Result<(), ChainError> {
    out.clear();
    out.resize(chain.dof(), [0.0; 2]);
    let parent_of = |_: usize, parent: &Matrix3<f64>, _: &Matrix3<f64>| *parent;
    crate::robot::visit_carried_loads(chain, masses, q, given, down, parent_of, |j, parent, moment, _| {
        let local = parent.transpose() * moment;
        let [e1, e2] = perpendiculars(&chain.joints()[j].axis);
        out[j] = [crate::units::newton_metres(e1.dot(&local)), crate::units::newton_metres(e2.dot(&local))];
    })
}

/// The functions of a branch's load on revolute joint `joint` into `out`, one piece for every place that
/// evaluates it (the fit, the plausibility scale, the robot model): about the axis
/// ([`crate::branch_load_basis_into`]) or, `across`, along its two lateral directions
/// ([`crate::branch_lateral_basis_into`]) — and, when the branch [carries
/// masses](crate::Branch::carries_masses), the load of the measured chain's own links (`masses`, one per
/// joint) added to the branch's torque or moments: with the masses known a branch's load is on the joint's
/// compliance under everything the joint carries, and one compliance multiplies the sum.
pub fn branch_load_functions_into(
    chain: &Chain,
    masses: &[Option<LinkMass>],
    branch: &crate::Branch,
    (q, branch_q): (&[f64], &[f64]),
    down: &Unit<Vector3<f64>>,
    (joint, across): (usize, bool),
    out: &mut Vec<f64>,
) -> Result<(), ChainError> {
    if across {
        crate::branch_lateral_basis_into(chain, branch, q, branch_q, down, joint, out)?;
    } else {
        crate::branch_load_basis_into(chain, branch, q, branch_q, down, joint, out)?;
    }
    if branch.carries_masses() {
        add_chain_load(chain, masses, q, down, (joint, across), out)?;
    }
    Ok(())
}

/// Adds to `out` (one entry about the axis, or two across it) the gravity torque (the two moments) of the
/// measured chain's own links about revolute joint `joint`, `masses` one per joint, N·m, as
/// [`crate::Robot::gravity_torques`] and [`lateral_gravity_moments_into`] give them. `out` of another
/// length is left as it is.
fn add_chain_load(
    chain: &Chain,
    masses: &[Option<LinkMass>],
    q: &[f64],
    down: &Unit<Vector3<f64>>,
    (joint, across): (usize, bool),
    out: &mut [f64],
) -> Result<(), ChainError> {
    if across && out.len() == 2 {
        let mut moments = Vec::with_capacity(chain.dof());
        lateral_gravity_moments_into(chain, masses, q, None, down, &mut moments)?;
        if let Some(m) = moments.get(joint) {
            out[0] += m[0];
            out[1] += m[1];
        }
    } else if !across && out.len() == 1 {
        let mut torques = Vec::with_capacity(chain.dof());
        crate::gravity_torques_into(chain, masses, q, None, down, &mut torques)?;
        out[0] += torques.get(joint).copied().unwrap_or(0.0);
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use nalgebra::{Rotation3, Unit, Vector3};

    use super::*;
    use crate::link_mass::STANDARD_GRAVITY;
    use crate::{FixedRow, Joint, LinkMass};

    /// A column (prismatic, tilted a little off vertical) carrying three revolute links with masses off
    /// their axes, on a base turned off the identity.
    fn column_arm() -> (Chain, Vec<Option<LinkMass>>) {
        let joints = vec![
            Joint::prismatic(
                "column",
                Vector3::new(0.0, 0.0, 200.0),
                Unit::new_normalize(Vector3::new(0.05, 0.0, 1.0)),
            ),
            Joint::revolute("j1", Vector3::new(0.0, 0.0, 100.0), Vector3::z_axis()),
            Joint::revolute("j2", Vector3::new(150.0, 0.0, 0.0), Vector3::y_axis()),
            Joint::revolute("j3", Vector3::new(0.0, 0.0, 600.0), Vector3::y_axis()),
        ];
        let base = nalgebra::Isometry3::new(Vector3::new(10.0, -20.0, 5.0), Vector3::new(0.02, -0.03, 0.4));
        let chain = Chain::new(FixedRow::from_isometry(&base), joints, FixedRow::identity()).unwrap();
        let masses = [
            (60.0, [0.0, 0.0, 300.0]),
            (20.0, [30.0, 10.0, 50.0]),
            (12.0, [20.0, 5.0, 280.0]),
            (6.0, [250.0, -8.0, 20.0]),
        ]
        .iter()
        .map(|&(m, c)| Some(LinkMass { mass_kg: m, com_mm: Vector3::from(c) }))
        .collect();
        (chain, masses)
    }

    /// Gravity's potential (N·mm) of the links from `joint` on, their centres turned by `phi` about the
    /// world direction `u` through joint `joint`'s origin.
    fn potential(
        chain: &Chain,
        masses: &[Option<LinkMass>],
        q: &[f64],
        joint: usize,
        u: &Unit<Vector3<f64>>,
        phi: f64,
    ) -> f64 {
        let frames = chain.joint_frames(q).unwrap();
        let origin = frames[joint].translation.vector;
        let turn = Rotation3::from_axis_angle(u, phi);
        let down = -Vector3::z();
        (joint..chain.dof())
            .map(|l| {
                let m = masses[l].unwrap();
                let c = frames[l] * nalgebra::Point3::from(m.com_mm);
                let moved = origin + turn * (c.coords - origin);
                -m.mass_kg * STANDARD_GRAVITY * down.dot(&moved)
            })
            .sum()
    }

    #[test]
    fn each_moment_is_the_potentials_slope_under_a_tilt_about_its_direction() {
        let (chain, masses) = column_arm();
        let down = -Vector3::z_axis();
        let mut out = Vec::new();
        for q in [[120.0, 0.3, -0.7, 1.1], [480.0, -2.0, 0.4, -0.2], [10.0, 1.4, 1.2, 2.5]] {
            lateral_gravity_moments_into(&chain, &masses, &q, None, &down, &mut out).unwrap();
            let frames = chain.joint_frames(&q).unwrap();
            for joint in 0..chain.dof() {
                // The parent frame's rotation: the previous joint's after its motion, or the base's.
                let parent = if joint == 0 { chain.base().pose().rotation } else { frames[joint - 1].rotation };
                for (k, e) in lateral_directions(&chain, joint).unwrap().iter().enumerate() {
                    let u = Unit::new_normalize(parent * e);
                    let h = 1e-6;
                    let slope = (potential(&chain, &masses, &q, joint, &u, h)
                        - potential(&chain, &masses, &q, joint, &u, -h))
                        / (2.0 * h);
                    let expected = -crate::units::newton_metres(slope);
                    assert!(
                        (out[joint][k] - expected).abs() < 1e-6 * (1.0 + expected.abs()),
                        "joint {joint} dir {k}: {} vs {expected}",
                        out[joint][k]
                    );
                }
            }
        }
    }
}
