//! One target: attempts from the seed and seeded restarts, the independent check of a convergence claim,
//! and the classification of a failure.

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::{Chain, JointKind, rotation_angle};

use crate::IkError;
use std::time::Instant;

use crate::analytic::ClosedForm;
use crate::lm::{Eval, Workspace, attempt, past};
use crate::params::{Goal, LimitPolicy, Params, RestartSeeds, Solution, Status};

/// Restarts drawn near the seed before the uniform ones.
const LOCAL_RESTARTS: usize = 4;
/// An upper bound of the distance from joint 1's axis point to the TCP: the sum of every segment length
/// after joint 1 and the tool. `None` when a prismatic joint makes the reach unbounded.
fn reach_bound(chain: &Chain) -> Option<(Vector3<f64>, f64)> {
    let mut reach = 0.0;
    for (i, j) in chain.joints().iter().enumerate() {
        if j.kind == JointKind::Prismatic {
            let l = j.limits?;
            reach += l.lower.abs().max(l.upper.abs()) + j.zero.abs();
        }
        if i > 0 {
            reach += (j.offset + j.error.translation).norm();
        }
    }
    reach += (chain.tool().translation + chain.tool().error.translation).norm();
    let first = chain.joints().first()?;
    let base = chain.base().pose();
    let o1 = base * nalgebra::Point3::from(first.offset + first.error.translation);
    Some((o1.coords, reach))
}

fn random_seed(chain: &Chain, rng: &mut ChaCha8Rng, around: &[f64], policy: LimitPolicy) -> Vec<f64> {
    chain
        .joints()
        .iter()
        .zip(around)
        .map(|(j, &a)| match (j.limits, policy) {
            (Some(l), LimitPolicy::Enforce) => rng.random_range(l.lower..=l.upper),
            _ if j.kind == JointKind::Revolute => rng.random_range(-std::f64::consts::PI..std::f64::consts::PI),
            _ => a + rng.random_range(-100.0..100.0),
        })
        .collect()
}

/// Moves each revolute joint by whole turns toward the seed where the limits allow (same pose).
fn nearest_turn(chain: &Chain, q: &mut [f64], seed: &[f64], policy: LimitPolicy) {
    let tau = std::f64::consts::TAU;
    for ((v, s), j) in q.iter_mut().zip(seed).zip(chain.joints()) {
        if j.kind != JointKind::Revolute {
            continue;
        }
        let k = ((s - *v) / tau).round();
        if k != 0.0 {
            let moved = *v + k * tau;
            let ok = policy == LimitPolicy::Ignore || j.limits.is_none_or(|l| l.contains(moved));
            if ok {
                *v = moved;
            }
        }
    }
}

/// Every arm configuration that reaches `goal` on `chain`, for arms with a closed form
/// ([`ClosedForm`]): each exact branch of the ideal geometry (up to 8) refined on the chain itself
/// from that branch alone (no restarts, at most 0.5 rad from it, so that the refinement keeps the
/// branch), with its solution — `Converged`, or why not (a joint limit). Branches the pose is out of
/// reach for are left out. `None` when the chain has no closed form. A user choosing a configuration
/// (ABB's confdata, KUKA's Status/Turn) picks from these.
pub fn solve_branches(
    chain: &Chain,
    goal: &nalgebra::Isometry3<f64>,
    params: &Params,
    ws: &mut Workspace,
) -> Result<Option<Vec<(crate::Branch, Solution)>>, IkError> {
    let Some(wrist) = ClosedForm::detect(chain) else { return Ok(None) };
    let local = Params { restarts: 0, max_distance_from_seed: Some(0.5), ..params.clone() };
    let mut out = Vec::new();
    let target = Goal::Pose(*goal);
    for (k, mut branch) in wrist.branches(goal).into_iter().filter(|b| b.exact).enumerate() {
        nearest_turn(chain, &mut branch.q, &[0.0; 6], params.limits);
        let solution = if params.limits == LimitPolicy::Enforce && !chain.within_limits(&branch.q) {
            // The configuration exists but needs a joint beyond its limit: reported as such, with the
            // branch's own joint values (refining it inside the limits would land on another branch).
            let (position_error_mm, orientation_error_rad) = independent_error(chain, &branch.q, &target);
            Solution {
                q: branch.q.to_vec(),
                status: Status::JointLimit,
                iterations: 0,
                restarts: 0,
                position_error_mm,
                orientation_error_rad,
            }
        } else {
            solve(chain, &target, &branch.q, &local, ws, k as u64)?
        };
        out.push((branch, solution));
    }
    Ok(Some(out))
}

/// The closed-form solutions of the chain's ideal geometry for a pose goal ([`ClosedForm`]), moved by
/// whole turns toward the seed, those inside the limits (when they bind), nearest to the seed first. Empty
/// for position goals and for chains without a closed form.
fn branch_seeds(chain: &Chain, goal: &Goal, seed: &[f64], params: &Params) -> std::vec::IntoIter<Vec<f64>> {
    let Goal::Pose(pose) = goal else { return Vec::new().into_iter() };
    if params.restart_seeds == RestartSeeds::RandomOnly {
        return Vec::new().into_iter();
    }
    let Some(wrist) = ClosedForm::detect(chain) else { return Vec::new().into_iter() };
    let mut seeds: Vec<(bool, Vec<f64>)> = wrist
        .branches(pose)
        .into_iter()
        .map(|b| {
            let mut q = b.q.to_vec();
            nearest_turn(chain, &mut q, seed, params.limits);
            (b.exact, q)
        })
        .filter(|(_, q)| params.limits == LimitPolicy::Ignore || chain.within_limits(q))
        .collect();
    // Exact branches first (the nearest-solution ones of an out-of-reach equation are rough seeds), each
    // group nearest to the seed first.
    seeds.sort_by(|(ea, a), (eb, b)| eb.cmp(ea).then(distance(a, seed).total_cmp(&distance(b, seed))));
    seeds.into_iter().map(|(_, q)| q).collect::<Vec<_>>().into_iter()
}

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// Solves one target from `seed`. `index` only feeds the restart generator (batch determinism).
///
/// `Converged` is a claim checked before it is made: the solver stops when its residual (matrix log of the
/// rotation error, [`thermokin_chain::rotation_log`]) is within the tolerances, and the answer is then re-measured
/// independently — forward kinematics through [`Chain::tool_pose`] and the quaternion angle
/// [`rotation_angle`]. Only when that too is within the tolerances is the status `Converged`; the errors
/// reported in every [`Solution`] are the independent ones.
///
/// ```
/// use nalgebra::{Isometry3, UnitQuaternion, Vector3};
/// use thermokin_chain::{Chain, FixedRow, Joint};
/// use thermokin_ik::{Params, Goal, Workspace, solve};
///
/// // A planar 3R arm with 300 mm links.
/// let link = Vector3::new(300.0, 0.0, 0.0);
/// let joints = vec![
///     Joint::revolute("j1", Vector3::zeros(), Vector3::z_axis()),
///     Joint::revolute("j2", link, Vector3::z_axis()),
///     Joint::revolute("j3", link, Vector3::z_axis()),
/// ];
/// let tool = FixedRow::from_isometry(&Isometry3::translation(300.0, 0.0, 0.0));
/// let chain = Chain::new(FixedRow::identity(), joints, tool).unwrap();
/// let goal = chain.tool_pose(&[0.3, -0.6, 0.9]).unwrap();
/// let mut ws = Workspace::new(chain.dof());
/// let params = Params { restarts: 20, ..Params::default() };
/// let sol = solve(&chain, &Goal::Position(goal.translation.vector), &[0.0; 3], &params, &mut ws, 0).unwrap();
/// assert!(sol.converged());
/// assert!(sol.position_error_mm <= 1e-9);
/// # let _ = UnitQuaternion::<f64>::identity();
/// ```
pub fn solve(
    chain: &Chain,
    target: &Goal,
    seed: &[f64],
    params: &Params,
    ws: &mut Workspace,
    index: u64,
) -> Result<Solution, IkError> {
    validate(chain, seed, params)?;
    if !target.is_finite() {
        return Err(IkError::BadTarget { index: index as usize });
    }
    if ws.dof != chain.dof() {
        *ws = Workspace::new(chain.dof());
    }
    let deadline = params.time_budget.map(|b| Instant::now() + b);
    let record = |q: Vec<f64>, status, iterations, restarts| {
        let (position_error_mm, orientation_error_rad) = independent_error(chain, &q, target);
        Solution { q, status, iterations, restarts, position_error_mm, orientation_error_rad }
    };
    if let Some((o1, reach)) = reach_bound(chain) {
        let d = (target.position() - o1).norm();
        if d > reach * (1.0 + 1e-9) {
            return Ok(record(seed.to_vec(), Status::Unreachable, 0, 0));
        }
    }
    let mut rng = ChaCha8Rng::seed_from_u64(params.rng_seed ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let mut q = seed.to_vec();
    let mut best: Option<Eval> = None;
    let mut total_iterations = 0;
    let mut far_found = false;
    let mut unverified_found = false;
    // Closed-form branches of the chain's ideal geometry, nearest to the seed first: computed once the
    // seed's own attempt has failed, tried before any random restart.
    let mut branches: Option<std::vec::IntoIter<Vec<f64>>> = None;
    for restart in 0..=params.restarts {
        if restart > 0 {
            if past(deadline) {
                break;
            }
            let next_branch = branches.get_or_insert_with(|| branch_seeds(chain, target, seed, params)).next();
            q = if let Some(b) = next_branch {
                b
            } else if restart % 2 == 1 && restart < 2 * LOCAL_RESTARTS {
                // Every other early restart near the seed (growing spread), which keeps its branch where
                // one exists; the others, and all later ones, anywhere inside the limits.
                let spread = 0.15 * restart.div_ceil(2) as f64;
                seed.iter().map(|v| v + rng.random_range(-spread..spread)).collect()
            } else {
                random_seed(chain, &mut rng, seed, params.limits)
            };
        }
        let (ev, iterations, converged) = attempt(chain, target, &mut q, params, ws, deadline);
        total_iterations += iterations;
        if converged {
            nearest_turn(chain, &mut q, seed, params.limits);
            let too_far = params.max_distance_from_seed.is_some_and(|m| distance(&q, seed) > m);
            if too_far {
                far_found = true;
            } else if verified(chain, &q, target, params) {
                return Ok(record(q, Status::Converged, total_iterations, restart));
            } else {
                // The residual says converged, the independent check does not: not an answer.
                unverified_found = true;
            }
        }
        if let Some(e) = ev
            && best.is_none_or(|b| e.cost < b.cost)
        {
            best = Some(e);
            ws.best.copy_from_slice(&q);
        }
    }
    let restarts_used = params.restarts;
    let q_best = if best.is_some() { ws.best.clone() } else { seed.to_vec() };
    let status = if far_found {
        Status::FarFromSeed
    } else if unverified_found {
        Status::Unverified
    } else {
        classify(chain, &q_best, target, params)
    };
    Ok(record(q_best, status, total_iterations, restarts_used))
}

/// The pose error at `q` recomputed independently of the solver's residual: forward kinematics through
/// [`Chain::tool_pose`] (an isometry with a unit quaternion, not the rotation matrix the residual uses),
/// and the quaternion angle [`rotation_angle`] instead of the matrix log. Returns (mm, rad); NaN when the
/// chain cannot evaluate `q`.
fn independent_error(chain: &Chain, q: &[f64], target: &Goal) -> (f64, f64) {
    let Ok(base_from_tcp) = chain.tool_pose(q) else { return (f64::NAN, f64::NAN) };
    let position = (target.position() - base_from_tcp.translation.vector).norm();
    let orientation = match target {
        Goal::Pose(goal) => rotation_angle(&goal.rotation, &base_from_tcp.rotation),
        Goal::Position(_) => 0.0,
    };
    (position, orientation)
}

/// `true` when the independent recomputation of the pose error at `q` is within the tolerances.
///
/// The two metrics compute the same quantities by different arithmetic, so they differ by rounding: a few
/// ulps of the TCP coordinates (|p| ≲ 10 m → ~1e-12 mm) and of the rotation entries (~1e-15 rad). The
/// allowance `64 ε (1 + |p|)` mm and `64 ε` rad covers that and stays three orders below the default
/// tolerances (1e-9 mm, 1.7e-11 rad), so it cannot turn a real miss into a pass.
fn verified(chain: &Chain, q: &[f64], target: &Goal, params: &Params) -> bool {
    let (position, orientation) = independent_error(chain, q, target);
    let rounding = 64.0 * f64::EPSILON;
    position <= params.position_tolerance_mm + rounding * (1.0 + target.position().norm())
        && orientation <= params.orientation_tolerance_rad + rounding
}

/// Why the best solution is not a solution.
fn classify(chain: &Chain, q: &[f64], target: &Goal, params: &Params) -> Status {
    let at_limit = params.limits == LimitPolicy::Enforce
        && chain
            .joints()
            .iter()
            .zip(q)
            .any(|(j, &v)| j.limits.is_some_and(|l| (v - l.lower).abs() < 1e-9 || (v - l.upper).abs() < 1e-9));
    if at_limit {
        return Status::JointLimit;
    }
    let Ok(j) = chain.jacobian(q) else { return Status::Unreachable };
    let rows = if matches!(target, Goal::Pose(_)) { 6 } else { 3 };
    let mut jw = j.rows(0, rows).into_owned();
    if rows == 6 {
        for c in 0..jw.ncols() {
            for r in 3..6 {
                jw[(r, c)] *= params.length_scale_mm;
            }
        }
    }
    let sv = jw.singular_values();
    let (max, min) = (sv.max(), sv.min());
    // Rank deficiency relative to the largest singular value: 1e-6 is far above rounding (~1e-15) and
    // below any well-conditioned pose of a real arm (IRB 140: ≥ 1e-3 away from singularities).
    if max > 0.0 && min / max < 1e-6 && sv.len() >= rows.min(chain.dof()) {
        Status::Singular
    } else {
        Status::Unreachable
    }
}

fn validate(chain: &Chain, seed: &[f64], params: &Params) -> Result<(), IkError> {
    if seed.len() != chain.dof() {
        return Err(IkError::SeedLength { expected: chain.dof(), got: seed.len() });
    }
    if let Some(i) = seed.iter().position(|v| !v.is_finite()) {
        return Err(IkError::SeedNotFinite { joint: i + 1 });
    }
    let positive = [
        ("position_tolerance_mm", params.position_tolerance_mm),
        ("orientation_tolerance_rad", params.orientation_tolerance_rad),
        ("length_scale_mm", params.length_scale_mm),
        ("initial_damping", params.initial_damping),
        ("max_step_rad", params.max_step_rad),
        ("max_step_far_rad", params.max_step_far_rad),
        ("max_iterations", params.max_iterations as f64),
    ];
    if let Some((field, value)) = positive.into_iter().find(|(_, v)| !(v.is_finite() && *v > 0.0)) {
        return Err(IkError::BadParams { field, value });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use std::f64::consts::PI;

    use nalgebra::{Isometry3, UnitQuaternion, Vector3};

    use super::{Goal, Params, verified};

    #[test]
    fn the_independent_check_sees_a_half_turn() {
        let chain = thermokin_testdata::irb140_table9();
        let q = [0.1, 0.2, -0.3, 0.4, 0.5, 0.6];
        let base_from_tcp = chain.tool_pose(&q).unwrap();
        for axis in [Vector3::x_axis(), Vector3::y_axis(), Vector3::z_axis()] {
            let turned = base_from_tcp.rotation * UnitQuaternion::from_axis_angle(&axis, PI);
            let flipped = Isometry3::from_parts(base_from_tcp.translation, turned);
            assert!(!verified(&chain, &q, &Goal::Pose(flipped), &Params::default()));
        }
        assert!(verified(&chain, &q, &Goal::Pose(base_from_tcp), &Params::default()));
        let moved = Goal::Position(base_from_tcp.translation.vector + Vector3::new(0.0, 0.0, 1e-6));
        assert!(!verified(&chain, &q, &moved, &Params::default()));
    }
}
