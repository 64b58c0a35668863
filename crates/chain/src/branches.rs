//! Robots with branches (issue #59): a torso carrying two arms, a lift carrying a second tool. The
//! measured chain is one path of the robot's tree; a [`Branch`] is a serial chain of joints hanging from
//! one of its links, whose joint values a measurement file may log beside the measured chain's. What
//! hangs from the branch loads the links it shares with the measured chain: its gravity torque about a
//! shared joint changes with the branch's joints, which a model of the measured chain alone reads as
//! noise.
//!
//! The torque of any masses on the branch's links about revolute joint `j` of the measured chain (`j`
//! below the link the branch hangs from) follows [`crate::gravity_load_basis_into`]'s derivation along
//! the branch's path: with `w = d × aⱼ`, each branch link `b` with unknown first moment `v_b` (constant in
//! its frame) adds `v_b · (R_bᵀ w)`, its origin terms folding inwards to a moment of the link the branch
//! hangs from — already among the measured chain's own functions — and a slide of the branch adds its
//! travel times the mass it carries, `q_b (R_b a_b) · w`. So the branch adds, per revolute joint of it,
//! the two functions `e_b,k · (R_bᵀ w)` (the perpendiculars of its axis) and per slide one; `R_b` is the
//! orientation of branch link `b`: the measured chain's link the branch hangs from, turned by the
//! branch's joints in the same-orientation convention (section 2.3: every joint frame keeps the base's
//! orientation at zero, so each branch axis turns about itself as given). A test checks that the torque
//! of masses on a branch, computed by [`crate::Robot::gravity_torques`] on the serial chain along its
//! path, lies in the span of the measured chain's functions and these.
//!
//! When the robot file gives the branch's link masses ([`Branch::masses`]) the load is no longer
//! unknown up to its first moments: the functions are then the torque itself — one, N·m, about joint
//! `j`'s axis `aⱼ · Σ_b (c_b − oⱼ) × m_b g` over the branch's links `b` (centres `c_b`, origin `oⱼ` of
//! joint `j`) — or, across the axis, the two moments along its lateral directions, as
//! [`crate::Robot::gravity_torques`] and [`crate::lateral_gravity_moments_into`] compute them for the
//! links of the chain itself; the weight is then a compliance (radians per N·m), as a joint's with masses.

use nalgebra::{Matrix3, Rotation3, Unit, Vector3};

use crate::gravity_loads::perpendiculars;
use crate::link_mass::LinkMass;
use crate::{Chain, ChainError, Joint, JointKind};

/// A serial chain of joints hanging from one link of the measured chain: its name, the link (0 the
/// robot's base, `k` the link joint `k` of the measured chain moves) and its joints from that link
/// outwards, in the same-orientation table's terms (each joint's offset from the previous one — the
/// first's from the origin of the link it hangs from — and its axis, in the base's orientation at zero).
#[derive(Clone, Debug, PartialEq)]
pub struct Branch {
    /// Its name (a URDF's first link of the branch, or the robot file's).
    pub name: String,
    /// The link of the measured chain it hangs from.
    pub link: usize,
    /// Its joints, from that link outwards (at least one).
    pub joints: Vec<Joint>,
    /// Per joint of the branch, the mass of the link it moves (centre in that joint's same-orientation
    /// frame, mm), as [`crate::Robot::masses`] holds the chain's; empty when the robot file gives none —
    /// the branch's load is then known only up to its first moments (the module's lumped functions).
    pub masses: Vec<Option<LinkMass>>,
}

impl Branch {
    /// Whether the robot file gives a mass on some link of the branch: its load on the joints below it
    /// is then the torque of those masses ([`branch_load_basis_into`]: one function, N·m), not lumped.
    pub fn carries_masses(&self) -> bool {
        self.masses.iter().any(Option::is_some)
    }

    /// Joint `i`'s value in the library's units (radians; mm for a slide) from a measurement file's
    /// reading of it (degrees; mm for a slide) — the one place a branch's logged joint is converted.
    pub fn joint_value(&self, i: usize, reading: f64) -> f64 {
        match self.joints.get(i).map(|j| j.kind) {
            Some(JointKind::Revolute) => crate::units::radians(reading),
            _ => reading,
        }
    }
}

/// The number of functions [`branch_load_basis_into`] gives for joint `joint` (0-based) of the measured
/// chain: two per revolute and one per prismatic joint of `branch` — or one, the torque, when the branch
/// [carries masses](Branch::carries_masses) — when `joint` is revolute and carries the branch (it lies
/// below the link the branch hangs from); zero otherwise.
pub fn branch_load_basis_len(chain: &Chain, branch: &Branch, joint: usize) -> usize {
    let carries = joint < branch.link && chain.joints().get(joint).is_some_and(|j| j.kind == JointKind::Revolute);
    if !carries {
        return 0;
    }
    if branch.carries_masses() {
        return 1;
    }
    branch.joints.iter().map(|j| if j.kind == JointKind::Revolute { 2 } else { 1 }).sum()
}

/// The functions of the measured chain's joints `q` and the branch's `branch_q` (radians; mm for a
/// slide: [`Branch::joint_value`]) whose weighted sum is the gravity torque about revolute joint `joint`
/// of any masses on `branch`'s links (the module's derivation), into `out` (length
/// [`branch_load_basis_len`]) — or, when the branch [carries masses](Branch::carries_masses), that torque
/// itself (N·m). `down` is gravity's direction in the chain's world frame.
///
/// ```
/// use nalgebra::Vector3;
/// use thermokin_chain::{Branch, Chain, FixedRow, Joint, LinkMass, branch_load_basis_into, branch_load_basis_len};
/// # fn main() -> Result<(), thermokin_chain::ChainError> {
/// // A torso turning about a horizontal axis, an arm of two joints hanging from it.
/// let torso = vec![Joint::revolute("torso", Vector3::zeros(), Vector3::y_axis())];
/// let chain = Chain::new(FixedRow::identity(), torso, FixedRow::identity())?;
/// let arm = Branch {
///     name: "left".into(),
///     link: 1,
///     joints: vec![
///         Joint::revolute("left_1", Vector3::new(0.0, 200.0, 400.0), Vector3::y_axis()),
///         Joint::revolute("left_2", Vector3::new(300.0, 0.0, 0.0), Vector3::y_axis()),
///     ],
///     masses: Vec::new(),
/// };
/// let mut basis = Vec::new();
/// branch_load_basis_into(&chain, &arm, &[0.1], &[0.4, -0.3], &-Vector3::z_axis(), 0, &mut basis)?;
/// assert_eq!((basis.len(), branch_load_basis_len(&chain, &arm, 0)), (4, 4));
///
/// // With 2 kg on the arm's last link, 300 mm out along x at zero: one function, the torque (N·m).
/// let carried = LinkMass { mass_kg: 2.0, com_mm: Vector3::zeros() };
/// let arm = Branch { masses: vec![None, Some(carried)], ..arm };
/// branch_load_basis_into(&chain, &arm, &[0.0], &[0.0, 0.0], &-Vector3::z_axis(), 0, &mut basis)?;
/// assert!((basis[0] - 0.3 * 2.0 * 9.80665).abs() < 1e-9 && basis.len() == 1);
/// # Ok(())
/// # }
/// ```
pub fn branch_load_basis_into(
    chain: &Chain,
    branch: &Branch,
    q: &[f64],
    branch_q: &[f64],
    down: &Unit<Vector3<f64>>,
    joint: usize,
    out: &mut Vec<f64>,
) -> Result<(), ChainError> {
    terms_along(chain, branch, (q, branch_q), down, (joint, false), out)
}

/// How many functions [`branch_lateral_basis_into`] gives for `branch` and joint `joint`: twice
/// [`branch_load_basis_len`]'s — one set along each of the joint's two lateral directions.
pub fn branch_lateral_basis_len(chain: &Chain, branch: &Branch, joint: usize) -> usize {
    2 * branch_load_basis_len(chain, branch, joint)
}

/// The functions of the measured chain's joints `q` and the branch's `branch_q` whose weighted sums are
/// the gravity moments across revolute joint `joint`'s axis of any masses on `branch`'s links, along the
/// joint's two lateral directions `uₖ` ([`crate::lateral_directions`]), into `out` (length
/// [`branch_lateral_basis_len`]; the first half along `u₁`, the second along `u₂`) — what a bearing
/// tilts under when a second arm hangs beyond it. [`branch_load_basis_into`]'s derivation with
/// `w = d × uₖ` for `d × aⱼ`, as [`crate::lateral_load_basis_into`] follows the chain's own; the terms of
/// the branch's positions fold into that function's, used beside it. When the branch
/// [carries masses](Branch::carries_masses): the two moments themselves (N·m), one per direction.
pub fn branch_lateral_basis_into(
    chain: &Chain,
    branch: &Branch,
    q: &[f64],
    branch_q: &[f64],
    down: &Unit<Vector3<f64>>,
    joint: usize,
    out: &mut Vec<f64>,
) -> Result<(), ChainError> {
    terms_along(chain, branch, (q, branch_q), down, (joint, true), out)
}

/// The functions of [`branch_load_basis_into`] (`across` false: `w = d × aⱼ`) or
/// [`branch_lateral_basis_into`] (`across`: `w = d × uₖ` for each lateral direction, one set after the
/// other) into `out`: per revolute branch joint `eₖ · (R_bᵀ w)` along its two perpendiculars, per slide
/// its travel times its axis' component along `w`.
fn terms_along(
    chain: &Chain,
    branch: &Branch,
    (q, branch_q): (&[f64], &[f64]),
    down: &Unit<Vector3<f64>>,
    (joint, across): (usize, bool),
    out: &mut Vec<f64>,
) -> Result<(), ChainError> {
    out.clear();
    if branch_load_basis_len(chain, branch, joint) == 0 {
        return Ok(());
    }
    if branch_q.len() != branch.joints.len() {
        return Err(ChainError::WrongJointCount { expected: branch.joints.len(), got: branch_q.len() });
    }
    if let Some(i) = branch_q.iter().position(|v| !v.is_finite()) {
        return Err(ChainError::NonFiniteJoint { joint: i + 1 });
    }
    if branch.carries_masses() {
        return mass_terms(chain, branch, (q, branch_q), down, (joint, across), out);
    }
    let axis = chain.joints()[joint].axis;
    let directions = perpendiculars(&axis);
    let mut w: Vec<Vector3<f64>> = Vec::with_capacity(2);
    let mut hung_from = Matrix3::identity();
    chain.visit_joint_frames(q, None, |i, parent: &Matrix3<f64>, rot: &Matrix3<f64>, _origin| {
        if i == joint {
            if across {
                w.extend(directions.iter().map(|u| down.cross(&(parent * u))));
            } else {
                w.push(down.cross(&(rot * axis.into_inner())));
            }
        }
        if i + 1 == branch.link {
            hung_from = *rot;
        }
    })?;
    for w in w {
        let mut rot = hung_from;
        for (b, &qb) in branch.joints.iter().zip(branch_q) {
            match b.kind {
                JointKind::Revolute => {
                    rot *= Rotation3::from_axis_angle(&b.axis, qb + b.zero).into_inner();
                    let rw = rot.transpose() * w;
                    let [e1, e2] = perpendiculars(&b.axis);
                    out.extend([e1.dot(&rw), e2.dot(&rw)]);
                }
                JointKind::Prismatic => out.push(qb * (rot * b.axis.into_inner()).dot(&w)),
            }
        }
    }
    Ok(())
}

/// [`terms_along`] for a branch that carries masses: the torque of its links' masses about joint
/// `joint`'s axis (`across` false), or their moments along the joint's two lateral directions, N·m — the
/// branch's frames walked from the link it hangs from as [`Chain`] walks its own (each joint's offset in
/// the frame before it, then its motion; a branch's rows are nominal), each centre of mass in the frame
/// after its joint's motion, as [`crate::Robot::gravity_torques`] takes the chain's.
fn mass_terms(
    chain: &Chain,
    branch: &Branch,
    (q, branch_q): (&[f64], &[f64]),
    down: &Unit<Vector3<f64>>,
    (joint, across): (usize, bool),
    out: &mut Vec<f64>,
) -> Result<(), ChainError> {
    let (mut at_joint, mut hung_from) = ((Matrix3::identity(), Matrix3::identity(), Vector3::zeros()), None);
    chain.visit_joint_frames(q, None, |i, parent: &Matrix3<f64>, rot: &Matrix3<f64>, origin: &Vector3<f64>| {
        if i == joint {
            at_joint = (*parent, *rot, *origin);
        }
        if i + 1 == branch.link {
            hung_from = Some((*rot, *origin));
        }
    })?;
    let Some((mut rot, mut origin)) = hung_from else { return Ok(()) };
    let weight = down.into_inner() * crate::link_mass::STANDARD_GRAVITY;
    let (mut moment, mut mass) = (Vector3::zeros(), 0.0);
    for (i, (b, &qb)) in branch.joints.iter().zip(branch_q).enumerate() {
        origin += rot * b.offset;
        match b.kind {
            JointKind::Revolute => rot *= Rotation3::from_axis_angle(&b.axis, qb + b.zero).into_inner(),
            JointKind::Prismatic => origin += rot * (b.axis.into_inner() * (qb + b.zero)),
        }
        if let Some(m) = branch.masses.get(i).copied().flatten() {
            moment += (rot * m.com_mm + origin).cross(&(weight * m.mass_kg));
            mass += m.mass_kg;
        }
    }
    let (parent, rot_j, origin_j) = at_joint;
    // The moment about joint `joint`'s origin, N·mm.
    let about = moment - origin_j.cross(&(weight * mass));
    let axis = chain.joints()[joint].axis;
    if across {
        let local = parent.transpose() * about;
        out.extend(perpendiculars(&axis).map(|e| crate::units::newton_metres(e.dot(&local))));
    } else {
        out.push(crate::units::newton_metres((rot_j * axis.into_inner()).dot(&about)));
    }
    Ok(())
}

/// `branches` checked against `chain`: each named, on a link from 0 to the joint count, with at least
/// one joint, every joint name (the measured chain's and the branches') used once.
pub(crate) fn check_branches(chain: &Chain, branches: &[Branch]) -> Result<(), ChainError> {
    let bad = |name: &str, message: String| Err(ChainError::BadBranch { name: name.to_string(), message });
    let mut names: Vec<&str> = chain.joints().iter().map(|j| j.name.as_str()).collect();
    for b in branches {
        if b.name.trim().is_empty() {
            return bad(&b.name, "a branch needs a name".into());
        }
        if b.link > chain.dof() {
            return bad(&b.name, format!("hangs from link {} of a chain of {} joints", b.link, chain.dof()));
        }
        if b.joints.is_empty() {
            return bad(&b.name, "has no joint".into());
        }
        for j in &b.joints {
            if j.name.trim().is_empty() || names.contains(&j.name.as_str()) {
                return bad(&b.name, format!("joint `{}`: every joint needs a name of its own", j.name));
            }
            if !(j.offset.iter().all(|v| v.is_finite()) && j.zero.is_finite() && j.axis.iter().all(|v| v.is_finite())) {
                return bad(&b.name, format!("joint `{}`: its offset, axis and zero must be finite", j.name));
            }
            names.push(&j.name);
        }
        if !b.masses.is_empty() && b.masses.len() != b.joints.len() {
            return bad(&b.name, format!("{} link masses for its {} joints", b.masses.len(), b.joints.len()));
        }
        if let Some(m) = b
            .masses
            .iter()
            .flatten()
            .find(|m| !(m.mass_kg.is_finite() && m.mass_kg >= 0.0 && m.com_mm.iter().all(|v| v.is_finite())))
        {
            return bad(
                &b.name,
                format!(
                    "a link mass of {} kg at {:?} mm: each must be finite and not negative",
                    m.mass_kg,
                    m.com_mm.as_slice()
                ),
            );
        }
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use super::*;
    use crate::{FixedRow, LinkMass, Robot};
    use nalgebra::{DMatrix, DVector};

    /// A torso of two revolute joints (a vertical turn, a forward bend) and a branch of three joints (a
    /// shoulder, its roll, an elbow) hanging from the torso's second link, off its axis.
    fn torso_and_arm() -> (Chain, Branch) {
        let torso = vec![
            Joint::revolute("turn", Vector3::zeros(), Vector3::z_axis()),
            Joint::revolute("bend", Vector3::new(0.0, 0.0, 300.0), Vector3::y_axis()),
            Joint::revolute("right_1", Vector3::new(0.0, -250.0, 350.0), Vector3::y_axis()),
        ];
        let chain = Chain::new(FixedRow::identity(), torso, FixedRow::identity()).unwrap();
        let arm = Branch {
            name: "left".into(),
            link: 2,
            joints: vec![
                Joint::revolute("left_1", Vector3::new(0.0, 250.0, 350.0), Vector3::y_axis()),
                Joint::revolute("left_2", Vector3::new(0.0, 80.0, 0.0), Vector3::x_axis()),
                Joint::revolute("left_3", Vector3::new(0.0, 0.0, -300.0), Vector3::y_axis()),
            ],
            masses: Vec::new(),
        };
        (chain, arm)
    }

    /// A seeded draw of angles uniform in ±1.5 rad (a linear congruential generator: no dependency).
    fn uniform(mut state: u64) -> impl FnMut() -> f64 {
        move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 3.0 - 1.5
        }
    }

    /// The serial chain along the branch's path (the torso's joints, then the branch's) and masses on the
    /// branch's links only.
    fn along_the_branch(chain: &Chain, arm: &Branch) -> (Chain, Vec<Option<LinkMass>>) {
        let path: Vec<Joint> = chain.joints()[..arm.link].iter().cloned().chain(arm.joints.iter().cloned()).collect();
        let along = Chain::new(FixedRow::identity(), path, FixedRow::identity()).unwrap();
        let masses = vec![
            None,
            None,
            Some(LinkMass { mass_kg: 4.0, com_mm: Vector3::new(10.0, 40.0, -20.0) }),
            Some(LinkMass { mass_kg: 2.5, com_mm: Vector3::new(0.0, 5.0, -150.0) }),
            Some(LinkMass { mass_kg: 1.5, com_mm: Vector3::new(30.0, 0.0, -120.0) }),
        ];
        (along, masses)
    }

    /// The torque about the torso's bend of masses on the branch's links alone, computed independently: by
    /// [`Robot::gravity_torques`] on the serial chain along the branch's path (the torso's joints, then
    /// the branch's), masses on the branch's links only. It lies in the span of the measured chain's own
    /// functions and the branch's (residual at rounding), and not in the span of the chain's alone.
    #[test]
    fn a_branchs_gravity_torque_lies_in_the_span_of_its_functions() {
        let (chain, arm) = torso_and_arm();
        let (along, masses) = along_the_branch(&chain, &arm);
        let along = Robot::new("along", along).with_masses(masses).unwrap();
        let down = -Vector3::z_axis();
        let (mut own, mut extra) = (Vec::new(), Vec::new());
        let mut rows_all = Vec::new();
        let mut rows_own = Vec::new();
        let mut torque = Vec::new();
        let mut next = uniform(7_u64);
        for _ in 0..60 {
            let q = [next(), next(), next()];
            let bq = [next(), next(), next()];
            crate::gravity_load_basis_into(&chain, &q, None, &down, 1, &mut own).unwrap();
            branch_load_basis_into(&chain, &arm, &q, &bq, &down, 1, &mut extra).unwrap();
            rows_own.push(own.clone());
            rows_all.push(own.iter().chain(&extra).copied().collect::<Vec<_>>());
            torque.push(along.gravity_torques(&[q[0], q[1], bq[0], bq[1], bq[2]], &down).unwrap()[1]);
        }
        let residual = |rows: &[Vec<f64>]| {
            let a = DMatrix::from_fn(rows.len(), rows[0].len(), |r, c| rows[r][c]);
            let b = DVector::from_vec(torque.clone());
            let x = a.clone().svd(true, true).solve(&b, 1e-12).unwrap();
            (a * x - &b).norm() / b.norm()
        };
        assert_eq!(extra.len(), branch_load_basis_len(&chain, &arm, 1));
        assert!(residual(&rows_all) < 1e-9, "{}", residual(&rows_all));
        assert!(residual(&rows_own) > 0.05, "the chain's own functions alone: {}", residual(&rows_own));
    }

    /// The moments across the torso's bend of masses on the branch's links alone, computed by
    /// [`crate::lateral_gravity_moments_into`] on the serial chain along the branch's path: along each
    /// lateral direction, in the span of the chain's own lateral functions and the branch's (residual at
    /// rounding), and not in the chain's alone.
    #[test]
    fn a_branchs_lateral_moments_lie_in_the_span_of_its_functions() {
        let (chain, arm) = torso_and_arm();
        let (along, masses) = along_the_branch(&chain, &arm);
        let down = -Vector3::z_axis();
        let (mut own, mut extra, mut moments) = (Vec::new(), Vec::new(), Vec::new());
        let mut rows = [Vec::new(), Vec::new()];
        let mut rows_own = [Vec::new(), Vec::new()];
        let mut moment = [Vec::new(), Vec::new()];
        let mut next = uniform(11_u64);
        for _ in 0..80 {
            let q = [next(), next(), next()];
            let bq = [next(), next(), next()];
            crate::lateral_load_basis_into(&chain, &q, None, &down, 1, &mut own).unwrap();
            branch_lateral_basis_into(&chain, &arm, &q, &bq, &down, 1, &mut extra).unwrap();
            let path_q = [q[0], q[1], bq[0], bq[1], bq[2]];
            crate::lateral_gravity_moments_into(&along, &masses, &path_q, None, &down, &mut moments).unwrap();
            let (h, e) = (own.len() / 2, extra.len() / 2);
            for k in 0..2 {
                rows_own[k].push(own[k * h..(k + 1) * h].to_vec());
                rows[k].push(
                    own[k * h..(k + 1) * h].iter().chain(&extra[k * e..(k + 1) * e]).copied().collect::<Vec<_>>(),
                );
                moment[k].push(moments[1][k]);
            }
        }
        let residual = |rows: &[Vec<f64>], b: &[f64]| {
            let a = DMatrix::from_fn(rows.len(), rows[0].len(), |r, c| rows[r][c]);
            let b = DVector::from_vec(b.to_vec());
            let x = a.clone().svd(true, true).solve(&b, 1e-12).unwrap();
            (a * x - &b).norm() / b.norm()
        };
        assert_eq!(extra.len(), branch_lateral_basis_len(&chain, &arm, 1));
        // The bend's axis is horizontal and the torso turns about the vertical: its second lateral direction
        // stays vertical, along which gravity has no moment, and the functions vanish with it.
        assert!(moment[1].iter().chain(rows[1].iter().flatten()).all(|v| v.abs() < 1e-9));
        assert!(residual(&rows[0], &moment[0]) < 1e-9, "{}", residual(&rows[0], &moment[0]));
        assert!(residual(&rows_own[0], &moment[0]) > 0.05, "{}", residual(&rows_own[0], &moment[0]));
    }

    /// With its masses given, a branch's load is their torque about the joint and their moments across
    /// it — computed independently by [`Robot::gravity_torques`] and [`crate::lateral_gravity_moments_into`]
    /// on the serial chain along its path (a base turned off the identity, the torso's rows deviating),
    /// equal to rounding at every drawn pose; and the torque is gravity's work's derivative (central
    /// differences of the branch's potential energy, its centres placed by [`Chain::joint_frames`]).
    #[test]
    fn a_branchs_masses_give_its_torque_and_moments() {
        let (chain, arm) = torso_and_arm();
        let base = FixedRow::from_isometry(&nalgebra::Isometry3::new(
            Vector3::new(30.0, -20.0, 10.0),
            Vector3::new(0.1, -0.05, 0.3),
        ));
        let mut joints = chain.joints().to_vec();
        joints[1].error = crate::ErrorParams::new(Vector3::new(1.0, -2.0, 0.5), Vector3::new(0.01, -0.02, 0.015));
        let chain = Chain::new(base.clone(), joints, FixedRow::identity()).unwrap();
        let (_, masses) = along_the_branch(&chain, &arm);
        let path: Vec<Joint> = chain.joints()[..arm.link].iter().cloned().chain(arm.joints.iter().cloned()).collect();
        let along = Chain::new(base, path, FixedRow::identity()).unwrap();
        let arm = Branch { masses: masses[arm.link..].to_vec(), ..arm };
        assert!(arm.carries_masses());
        assert!(check_branches(&chain, std::slice::from_ref(&arm)).is_ok());
        assert_eq!((branch_load_basis_len(&chain, &arm, 1), branch_lateral_basis_len(&chain, &arm, 1)), (1, 2));
        let along_robot = Robot::new("along", along.clone()).with_masses(masses.clone()).unwrap();
        let down = Unit::new_normalize(Vector3::new(0.1, 0.05, -1.0));
        let (mut about, mut across, mut moments) = (Vec::new(), Vec::new(), Vec::new());
        let mut next = uniform(5_u64);
        for _ in 0..40 {
            let q = [next(), next(), next()];
            let bq = [next(), next(), next()];
            let path_q = [q[0], q[1], bq[0], bq[1], bq[2]];
            for joint in [0, 1] {
                branch_load_basis_into(&chain, &arm, &q, &bq, &down, joint, &mut about).unwrap();
                branch_lateral_basis_into(&chain, &arm, &q, &bq, &down, joint, &mut across).unwrap();
                let torque = along_robot.gravity_torques(&path_q, &down).unwrap()[joint];
                crate::lateral_gravity_moments_into(&along, &masses, &path_q, None, &down, &mut moments).unwrap();
                assert!((about[0] - torque).abs() < 1e-9 * (1.0 + torque.abs()), "{} {torque}", about[0]);
                for k in 0..2 {
                    assert!((across[k] - moments[joint][k]).abs() < 1e-9 * (1.0 + moments[joint][k].abs()));
                }
                // Gravity's work: τ = −∂V/∂q with V = −Σ m g · c (g along `down`), N·m from N·mm.
                let energy = |qj: f64| {
                    let mut at = path_q;
                    at[joint] = qj;
                    let frames = along.joint_frames(&at).unwrap();
                    (arm.link..path_q.len())
                        .map(|l| {
                            let m = masses[l].unwrap();
                            -(frames[l] * nalgebra::Point3::from(m.com_mm)).coords.dot(&down) * 9.80665 * m.mass_kg
                        })
                        .sum::<f64>()
                };
                let h = 1e-6;
                let fd = -(energy(path_q[joint] + h) - energy(path_q[joint] - h)) / (2.0 * h) / 1000.0;
                assert!((about[0] - fd).abs() < 1e-5 * (1.0 + fd.abs()), "{} against {fd}", about[0]);
            }
        }
        // The masses of one link short are refused by name.
        let short = Branch { masses: masses[arm.link + 1..].to_vec(), ..arm };
        let err = check_branches(&chain, &[short]).unwrap_err().to_string();
        assert!(err.contains("2 link masses for its 3 joints"), "{err}");
    }

    /// A branch carried by no revolute joint below it has no functions; a joint above its link neither.
    #[test]
    fn only_the_joints_below_a_branch_carry_it() {
        let (chain, arm) = torso_and_arm();
        assert_eq!(branch_load_basis_len(&chain, &arm, 0), 6);
        assert_eq!(branch_load_basis_len(&chain, &arm, 2), 0);
        let mut out = vec![1.0];
        branch_load_basis_into(&chain, &arm, &[0.0; 3], &[0.0; 3], &-Vector3::z_axis(), 2, &mut out).unwrap();
        assert!(out.is_empty());
        let err = branch_load_basis_into(&chain, &arm, &[0.0; 3], &[0.0; 2], &-Vector3::z_axis(), 1, &mut out);
        assert!(matches!(err, Err(ChainError::WrongJointCount { expected: 3, got: 2 })));
    }

    /// A branch's joint named as one of the chain's, or on a link past the chain, is refused by name.
    #[test]
    fn a_branch_is_checked_against_its_chain() {
        let (chain, mut arm) = torso_and_arm();
        assert!(check_branches(&chain, std::slice::from_ref(&arm)).is_ok());
        arm.joints[1].name = "bend".into();
        let err = check_branches(&chain, std::slice::from_ref(&arm)).unwrap_err();
        assert!(err.to_string().contains("`bend`"), "{err}");
        let (_, mut arm) = torso_and_arm();
        arm.link = 4;
        assert!(check_branches(&chain, &[arm]).unwrap_err().to_string().contains("link 4"));
    }
}
