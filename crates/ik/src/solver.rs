//! The Levenberg–Marquardt solver, its workspace, and the batch driver.
//!
//! Residual: `e = [p_target − p(q); L · log(R_target R(q)ᵀ)]` (mm), where `L` (mm/rad) weighs
//! orientation against position. Linearisation `e(q + δ) ≈ e − J_w δ` with the weighted geometric
//! Jacobian `J_w` (angular rows × L). Each iteration solves, in faer, the damped normal equations
//! `(J_wᵀ J_w + λ (diag(J_wᵀ J_w) + ε)) δ = J_wᵀ e` (Marquardt's scaling, with a floor ε so that a column
//! that vanishes at a singularity is still damped) by an in-place Cholesky factorisation on a reused
//! stack buffer; λ shrinks after an accepted step and grows after a rejected one.

use std::time::{Duration, Instant};

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};
use nalgebra::{Isometry3, Matrix3, Matrix6, Vector3, Vector6};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;
use thermokin_chain::{Chain, JointKind, rotation_angle, rotation_log};

use crate::IkError;

/// What the solver must reach.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// Position and orientation of the TCP in the base frame.
    Pose(Isometry3<f64>),
    /// TCP position only (mm); orientation free.
    Position(Vector3<f64>),
}

impl Target {
    fn position(&self) -> Vector3<f64> {
        match self {
            Target::Pose(p) => p.translation.vector,
            Target::Position(p) => *p,
        }
    }
    fn is_finite(&self) -> bool {
        match self {
            Target::Pose(p) => {
                p.translation.vector.iter().all(|v| v.is_finite()) && p.rotation.coords.iter().all(|v| v.is_finite())
            }
            Target::Position(p) => p.iter().all(|v| v.is_finite()),
        }
    }
}

/// Whether joint limits bind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum LimitPolicy {
    /// Every iterate is clamped into the limits; seeds are drawn inside them.
    Enforce,
    /// Limits are ignored.
    Ignore,
}

/// Which linear algebra runs the step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Backend {
    /// faer, dynamic sizes, in-place Cholesky on a reused stack (the default).
    Faer,
    /// nalgebra fixed-size 6 × 6 (six-joint chains only; others fall back to faer). For comparison.
    NalgebraFixed6,
}

/// Solver settings.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Params {
    /// Iterations per attempt (one attempt per seed).
    pub max_iterations: usize,
    /// Converged when the position error is at most this (mm).
    pub position_tolerance_mm: f64,
    /// … and the orientation error at most this (degrees).
    pub orientation_tolerance_deg: f64,
    /// Random restarts after the first attempt fails.
    pub restarts: usize,
    /// Optional wall-clock budget for one target, all attempts together. `None` (the default) makes the
    /// result a function of the inputs alone: the iteration and restart budgets bound the work, and the
    /// same target gives the same answer on a busy or an idle machine, on 1 or N threads.
    pub time_budget: Option<Duration>,
    /// Joint limits.
    pub limits: LimitPolicy,
    /// Seed of the restart generator (combined with the target index: the batch is deterministic).
    pub rng_seed: u64,
    /// Weight of orientation against position, mm per radian.
    pub length_scale_mm: f64,
    /// Initial damping λ (relative to the diagonal of JᵀJ).
    pub initial_damping: f64,
    /// Reject a solution farther than this from its seed (∞-norm over joints, radians or mm).
    pub max_distance_from_seed: Option<f64>,
    /// Largest move of a revolute joint in one iteration, radians (a trust region), once the TCP is
    /// within 50 mm of the target.
    pub max_step_rad: f64,
    /// The same while the TCP is farther than 50 mm from the target.
    pub max_step_far_rad: f64,
    /// Linear algebra of the step.
    pub backend: Backend,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            position_tolerance_mm: 1e-9,
            orientation_tolerance_deg: 1e-9,
            restarts: 100,
            time_budget: None,
            limits: LimitPolicy::Enforce,
            rng_seed: 0x7e57_0140,
            length_scale_mm: 100.0,
            initial_damping: 1e-3,
            max_distance_from_seed: None,
            max_step_rad: 0.3,
            max_step_far_rad: 1.0,
            backend: Backend::Faer,
        }
    }
}

/// How a solve ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[non_exhaustive]
pub enum Status {
    /// Within both tolerances.
    Converged,
    /// The best solution found sits on a joint limit: the target needs a joint beyond it.
    JointLimit,
    /// The target cannot be reached (beyond the workspace, or no attempt could reduce the error).
    Unreachable,
    /// The best solution is at a singular configuration where the error stopped decreasing.
    Singular,
    /// A solution was found, but farther from the seed than `max_distance_from_seed` allows.
    FarFromSeed,
    /// The solver's residual reached the tolerances but the independent recomputation of the pose error
    /// (see [`solve`]) did not: the answer is not trusted. Never expected; a bug if seen.
    Unverified,
}

/// The result of one solve.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Solution {
    /// Joint values (radians / mm): the converged solution, or the best found.
    pub q: Vec<f64>,
    /// How it ended.
    pub status: Status,
    /// Iterations over all attempts.
    pub iterations: usize,
    /// Random restarts used.
    pub restarts: usize,
    /// Final position error, mm.
    pub position_error_mm: f64,
    /// Final orientation error, degrees (0 for position targets).
    pub orientation_error_deg: f64,
}

impl Solution {
    /// `true` when converged.
    pub fn converged(&self) -> bool {
        self.status == Status::Converged
    }
}

/// Reusable buffers for one thread: nothing is allocated inside the iteration loop.
pub struct Workspace {
    dof: usize,
    cols: Vec<[f64; 6]>,
    cols_try: Vec<[f64; 6]>,
    jac: Mat<f64>,
    normal: Mat<f64>,
    rhs: Mat<f64>,
    buf: MemBuffer,
    q_try: Vec<f64>,
    best: Vec<f64>,
    held: Vec<bool>,
}

impl Workspace {
    /// Buffers for a chain with `dof` joints.
    pub fn new(dof: usize) -> Self {
        let req = llt::factor::cholesky_in_place_scratch::<f64>(dof, Par::Seq, Default::default())
            .or(llt::solve::solve_in_place_scratch::<f64>(dof, 1, Par::Seq));
        Self {
            dof,
            cols: vec![[0.0; 6]; dof],
            cols_try: vec![[0.0; 6]; dof],
            jac: Mat::zeros(6, dof),
            normal: Mat::zeros(dof, dof),
            rhs: Mat::zeros(dof, 1),
            buf: MemBuffer::new(req),
            q_try: vec![0.0; dof],
            best: vec![0.0; dof],
            held: vec![false; dof],
        }
    }
}

/// Weighted residual and its pieces at one configuration.
#[derive(Clone, Copy)]
struct Eval {
    e: Vector6<f64>,
    rows: usize,
    cost: f64,
    pos_err: f64,
    rot_err: f64,
}

fn evaluate(chain: &Chain, q: &[f64], target: &Target, l: f64, cols: &mut [[f64; 6]]) -> Option<Eval> {
    let (p, r) = chain.pose_and_jacobian_into(q, cols).ok()?;
    let dp = target.position() - p;
    Some(match target {
        Target::Pose(t) => {
            let r_err: Matrix3<f64> = t.rotation.to_rotation_matrix().matrix() * r.transpose();
            let w = rotation_log(&r_err);
            let e = Vector6::new(dp.x, dp.y, dp.z, l * w.x, l * w.y, l * w.z);
            Eval { e, rows: 6, cost: e.norm_squared(), pos_err: dp.norm(), rot_err: w.norm() }
        }
        Target::Position(_) => {
            let e = Vector6::new(dp.x, dp.y, dp.z, 0.0, 0.0, 0.0);
            Eval { e, rows: 3, cost: dp.norm_squared(), pos_err: dp.norm(), rot_err: 0.0 }
        }
    })
}

/// Copies Jacobian columns into the faer matrix, angular rows scaled by `l`.
fn fill_jacobian(jac: &mut Mat<f64>, cols: &[[f64; 6]], l: f64) {
    for (c, col) in cols.iter().enumerate() {
        for r in 0..3 {
            jac[(r, c)] = col[r];
            jac[(r + 3, c)] = col[r + 3] * l;
        }
    }
}

fn clamp_into_limits(chain: &Chain, q: &mut [f64], policy: LimitPolicy) {
    if policy == LimitPolicy::Ignore {
        return;
    }
    for (v, j) in q.iter_mut().zip(chain.joints()) {
        if let Some(l) = j.limits {
            *v = l.clamp(*v);
        }
    }
}

/// Solves the damped normal equations for the step δ (written into `ws.rhs`); `false` when the matrix is
/// not positive definite even with damping.
///
/// Joints resting on a limit whose gradient `Jᵀe` pushes further out are held fixed for this step (an
/// active set): their row and column of the normal matrix become the identity and their right-hand
/// side zero, so the other joints still move. Merely clamping the full step instead stalls the solver on
/// the limit.
fn step(ws: &mut Workspace, ev: &Eval, lambda: f64, backend: Backend) -> bool {
    let rows = ev.rows;
    let n = ws.dof;
    let held = &ws.held;
    let any_held = held.iter().any(|&h| h);
    if backend == Backend::NalgebraFixed6 && n == 6 {
        let mut j = Matrix6::<f64>::zeros();
        for r in 0..rows {
            for c in 0..6 {
                j[(r, c)] = ws.jac[(r, c)];
            }
        }
        let mut a = j.transpose() * j;
        let g = j.transpose() * ev.e;
        let mut g = g;
        for i in 0..6 {
            a[(i, i)] += lambda * (a[(i, i)] + DAMPING_FLOOR);
        }
        if any_held {
            for i in (0..6).filter(|&i| held[i]) {
                for k in 0..6 {
                    a[(i, k)] = 0.0;
                    a[(k, i)] = 0.0;
                }
                a[(i, i)] = 1.0;
                g[i] = 0.0;
            }
        }
        return match a.cholesky() {
            Some(ch) => {
                let d = ch.solve(&g);
                for i in 0..6 {
                    ws.rhs[(i, 0)] = d[i];
                }
                true
            }
            None => false,
        };
    }
    let jac = ws.jac.as_ref().subrows(0, rows);
    matmul(ws.normal.as_mut(), Accum::Replace, jac.transpose(), jac, 1.0, Par::Seq);
    for r in 0..n {
        let mut s = 0.0;
        for k in 0..rows {
            s += jac[(k, r)] * ev.e[k];
        }
        ws.rhs[(r, 0)] = s;
    }
    for i in 0..n {
        let d = ws.normal[(i, i)];
        ws.normal[(i, i)] = d + lambda * (d + DAMPING_FLOOR);
    }
    if any_held {
        for i in (0..n).filter(|&i| held[i]) {
            for k in 0..n {
                ws.normal[(i, k)] = 0.0;
                ws.normal[(k, i)] = 0.0;
            }
            ws.normal[(i, i)] = 1.0;
            ws.rhs[(i, 0)] = 0.0;
        }
    }
    let stack = MemStack::new(&mut ws.buf);
    if llt::factor::cholesky_in_place(ws.normal.as_mut(), Default::default(), Par::Seq, stack, Default::default())
        .is_err()
    {
        return false;
    }
    let stack = MemStack::new(&mut ws.buf);
    llt::solve::solve_in_place(ws.normal.as_ref(), ws.rhs.as_mut(), Par::Seq, stack);
    true
}

/// `true` once an optional deadline has passed (never without one).
fn past(deadline: Option<Instant>) -> bool {
    deadline.is_some_and(|d| Instant::now() > d)
}

/// Position error (mm) above which the wide trust region applies.
const FAR_MM: f64 = 50.0;

/// Restarts drawn near the seed before the uniform ones.
const LOCAL_RESTARTS: usize = 4;

/// Marks in `ws.held` the joints on a limit whose descent direction `Jᵀe` points outward.
fn update_held(chain: &Chain, q: &[f64], ws: &mut Workspace, ev: &Eval, policy: LimitPolicy) {
    ws.held.fill(false);
    if policy == LimitPolicy::Ignore {
        return;
    }
    for (i, j) in chain.joints().iter().enumerate() {
        let Some(l) = j.limits else { continue };
        let at_lower = q[i] <= l.lower;
        let at_upper = q[i] >= l.upper;
        if !(at_lower || at_upper) {
            continue;
        }
        let g: f64 = (0..ev.rows).map(|k| ws.jac[(k, i)] * ev.e[k]).sum();
        ws.held[i] = (at_upper && g > 0.0) || (at_lower && g < 0.0);
    }
}

/// Added to each diagonal entry before damping, mm²: keeps a vanishing column (a singular direction)
/// damped. Tiny against the ~1e4–1e6 mm² of a real arm's JᵀJ diagonal, so it does not slow convergence.
const DAMPING_FLOOR: f64 = 1e-6;

/// One attempt from `seed`: returns (best evaluation, iterations, converged).
fn attempt(
    chain: &Chain,
    target: &Target,
    q: &mut [f64],
    params: &Params,
    ws: &mut Workspace,
    deadline: Option<Instant>,
) -> (Option<Eval>, usize, bool) {
    let l = params.length_scale_mm;
    let tol_rot = params.orientation_tolerance_deg.to_radians();
    let converged = |ev: &Eval| ev.pos_err <= params.position_tolerance_mm && ev.rot_err <= tol_rot;
    clamp_into_limits(chain, q, params.limits);
    let Some(mut ev) = evaluate(chain, q, target, l, &mut ws.cols) else { return (None, 0, false) };
    fill_jacobian(&mut ws.jac, &ws.cols, l);
    let mut lambda = params.initial_damping;
    let mut slow = 0usize;
    for it in 0..params.max_iterations {
        if converged(&ev) {
            return (Some(ev), it, true);
        }
        if it % 16 == 15 && past(deadline) {
            return (Some(ev), it, false);
        }
        // An attempt still far off after many iterations is in a poor basin (a local minimum or a
        // limit): a fresh seed is cheaper than crawling on. Near convergence LM is quadratic, so a
        // solvable attempt is well inside 1 mm by then.
        if it == params.max_iterations / 5 && ev.pos_err > 5.0 {
            return (Some(ev), it, false);
        }
        update_held(chain, q, ws, &ev, params.limits);
        if !step(ws, &ev, lambda, params.backend) {
            lambda *= 10.0;
            if lambda > 1e12 {
                return (Some(ev), it, false);
            }
            continue;
        }
        // Trust region: no revolute joint moves more than `max_step_rad` in one step. Near a wrist
        // singularity the damped step in the two aligned joints can otherwise be huge, throwing the
        // solver onto another branch or into a limit.
        let largest = chain
            .joints()
            .iter()
            .enumerate()
            .filter(|(_, j)| j.kind == JointKind::Revolute)
            .map(|(i, _)| ws.rhs[(i, 0)].abs())
            .fold(0.0, f64::max);
        // Far from the target (a random seed) a wider region crosses the workspace in fewer steps.
        let region = if ev.pos_err > FAR_MM { params.max_step_far_rad } else { params.max_step_rad };
        let shrink = if largest > region { region / largest } else { 1.0 };
        for (i, qt) in ws.q_try.iter_mut().enumerate() {
            *qt = q[i] + shrink * ws.rhs[(i, 0)];
        }
        clamp_into_limits(chain, &mut ws.q_try, params.limits);
        let Some(trial) = evaluate(chain, &ws.q_try, target, l, &mut ws.cols_try) else {
            return (Some(ev), it, false);
        };
        if trial.cost < ev.cost {
            slow = if trial.cost > ev.cost * 0.999 { slow + 1 } else { 0 };
            q.copy_from_slice(&ws.q_try);
            std::mem::swap(&mut ws.cols, &mut ws.cols_try);
            fill_jacobian(&mut ws.jac, &ws.cols, l);
            ev = trial;
            lambda = (lambda * 0.1).max(1e-15);
            if slow >= 8 {
                // Crawling: a local minimum with a non-zero residual.
                return (Some(ev), it + 1, converged(&ev));
            }
        } else {
            lambda *= 10.0;
            if lambda > 1e12 {
                return (Some(ev), it + 1, converged(&ev));
            }
        }
    }
    let done = converged(&ev);
    (Some(ev), params.max_iterations, done)
}

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

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// Solves one target from `seed`. `index` only feeds the restart generator (batch determinism).
///
/// `Converged` is a claim checked before it is made: the solver stops when its residual (matrix log of the
/// rotation error, [`rotation_log`]) is within the tolerances, and the answer is then re-measured
/// independently — forward kinematics through [`Chain::tool_pose`] and the quaternion angle
/// [`rotation_angle`]. Only when that too is within the tolerances is the status `Converged`; the errors
/// reported in every [`Solution`] are the independent ones.
///
/// ```
/// use nalgebra::{Isometry3, UnitQuaternion, Vector3};
/// use thermokin_chain::{Chain, FixedRow, Joint};
/// use thermokin_ik::{Params, Target, Workspace, solve};
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
/// let sol = solve(&chain, &Target::Position(goal.translation.vector), &[0.0; 3], &params, &mut ws, 0).unwrap();
/// assert!(sol.converged());
/// assert!(sol.position_error_mm <= 1e-9);
/// # let _ = UnitQuaternion::<f64>::identity();
/// ```
pub fn solve(
    chain: &Chain,
    target: &Target,
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
        Solution {
            q,
            status,
            iterations,
            restarts,
            position_error_mm,
            orientation_error_deg: orientation_error_rad.to_degrees(),
        }
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
    for restart in 0..=params.restarts {
        if restart > 0 {
            if past(deadline) {
                break;
            }
            q = if restart % 2 == 1 && restart < 2 * LOCAL_RESTARTS {
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
fn independent_error(chain: &Chain, q: &[f64], target: &Target) -> (f64, f64) {
    let Ok(base_from_tcp) = chain.tool_pose(q) else { return (f64::NAN, f64::NAN) };
    let position = (target.position() - base_from_tcp.translation.vector).norm();
    let orientation = match target {
        Target::Pose(goal) => rotation_angle(&goal.rotation, &base_from_tcp.rotation),
        Target::Position(_) => 0.0,
    };
    (position, orientation)
}

/// `true` when the independent recomputation of the pose error at `q` is within the tolerances.
///
/// The two metrics compute the same quantities by different arithmetic, so they differ by rounding: a few
/// ulps of the TCP coordinates (|p| ≲ 10 m → ~1e-12 mm) and of the rotation entries (~1e-15 rad). The
/// allowance `64 ε (1 + |p|)` mm and `64 ε` rad covers that and stays three orders below the default
/// tolerances (1e-9 mm, 1.7e-11 rad), so it cannot turn a real miss into a pass.
fn verified(chain: &Chain, q: &[f64], target: &Target, params: &Params) -> bool {
    let (position, orientation) = independent_error(chain, q, target);
    let rounding = 64.0 * f64::EPSILON;
    position <= params.position_tolerance_mm + rounding * (1.0 + target.position().norm())
        && orientation <= params.orientation_tolerance_deg.to_radians() + rounding
}

/// Why the best solution is not a solution.
fn classify(chain: &Chain, q: &[f64], target: &Target, params: &Params) -> Status {
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
    let rows = if matches!(target, Target::Pose(_)) { 6 } else { 3 };
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
        ("orientation_tolerance_deg", params.orientation_tolerance_deg),
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

/// Where the seeds of a batch come from.
#[derive(Clone, Copy, Debug)]
pub enum Seeds<'a> {
    /// Every target from the same seed (parallel).
    Same(&'a [f64]),
    /// One seed per target, e.g. the previous time step's solutions (parallel).
    PerTarget(&'a [Vec<f64>]),
    /// The first target from this seed, each next one from the previous solution (sequential: a program
    /// in the order the robot runs it).
    ChainPrevious(&'a [f64]),
}

/// Solves many targets. Parallel (rayon) unless chained; the output is the same with 1 or N threads,
/// because every target's restart generator depends only on `params.rng_seed` and its index.
pub fn solve_batch(
    chain: &Chain,
    targets: &[Target],
    seeds: Seeds<'_>,
    params: &Params,
) -> Result<Vec<Solution>, IkError> {
    match seeds {
        Seeds::Same(seed) => targets
            .par_iter()
            .enumerate()
            .map_init(|| Workspace::new(chain.dof()), |ws, (i, t)| solve(chain, t, seed, params, ws, i as u64))
            .collect(),
        Seeds::PerTarget(per) => {
            if per.len() != targets.len() {
                return Err(IkError::SeedCount { seeds: per.len(), targets: targets.len() });
            }
            targets
                .par_iter()
                .zip(per)
                .enumerate()
                .map_init(|| Workspace::new(chain.dof()), |ws, (i, (t, s))| solve(chain, t, s, params, ws, i as u64))
                .collect()
        }
        Seeds::ChainPrevious(first) => {
            let mut ws = Workspace::new(chain.dof());
            let mut seed = first.to_vec();
            let mut out = Vec::with_capacity(targets.len());
            for (i, t) in targets.iter().enumerate() {
                let s = solve(chain, t, &seed, params, &mut ws, i as u64)?;
                if s.converged() {
                    seed.clone_from(&s.q);
                }
                out.push(s);
            }
            Ok(out)
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use std::f64::consts::PI;

    use nalgebra::{Isometry3, UnitQuaternion, Vector3};

    use super::{Params, Target, verified};

    #[test]
    fn the_independent_check_sees_a_half_turn() {
        let chain = thermokin_testdata::irb140_table9();
        let q = [0.1, 0.2, -0.3, 0.4, 0.5, 0.6];
        let base_from_tcp = chain.tool_pose(&q).unwrap();
        for axis in [Vector3::x_axis(), Vector3::y_axis(), Vector3::z_axis()] {
            let turned = base_from_tcp.rotation * UnitQuaternion::from_axis_angle(&axis, PI);
            let flipped = Isometry3::from_parts(base_from_tcp.translation, turned);
            assert!(!verified(&chain, &q, &Target::Pose(flipped), &Params::default()));
        }
        assert!(verified(&chain, &q, &Target::Pose(base_from_tcp), &Params::default()));
        let moved = Target::Position(base_from_tcp.translation.vector + Vector3::new(0.0, 0.0, 1e-6));
        assert!(!verified(&chain, &q, &moved, &Params::default()));
    }
}
