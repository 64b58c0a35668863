//! The Levenberg–Marquardt iteration and its workspace.
//!
//! Residual: `e = [p_target − p(q); L · log(R_target R(q)ᵀ)]` (mm), where `L` (mm/rad) weighs
//! orientation against position. Linearisation `e(q + δ) ≈ e − J_w δ` with the weighted geometric
//! Jacobian `J_w` (angular rows × L). Each iteration solves, in faer, the damped normal equations
//! `(J_wᵀ J_w + λ (diag(J_wᵀ J_w) + ε)) δ = J_wᵀ e` (Marquardt's scaling, with a floor ε so that a column
//! that vanishes at a singularity is still damped) by an in-place Cholesky factorisation on a reused
//! stack buffer; λ shrinks after an accepted step and grows after a rejected one.

use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};
use nalgebra::{Matrix3, Matrix6, Vector6};
use thermokin_chain::{Chain, JointKind, rotation_log};

use crate::params::{Backend, Goal, LimitPolicy, Params};

/// Reusable buffers for one thread: nothing is allocated inside the iteration loop.
pub struct Workspace {
    pub(crate) dof: usize,
    cols: Vec<[f64; 6]>,
    cols_try: Vec<[f64; 6]>,
    jac: Mat<f64>,
    normal: Mat<f64>,
    rhs: Mat<f64>,
    buf: MemBuffer,
    q_try: Vec<f64>,
    pub(crate) best: Vec<f64>,
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
pub(crate) struct Eval {
    e: Vector6<f64>,
    rows: usize,
    pub(crate) cost: f64,
    pos_err: f64,
    rot_err: f64,
}

fn evaluate(chain: &Chain, q: &[f64], target: &Goal, l: f64, cols: &mut [[f64; 6]]) -> Option<Eval> {
    let (p, r) = chain.pose_and_jacobian_into(q, cols).ok()?;
    let dp = target.position() - p;
    Some(match target {
        Goal::Pose(t) => {
            let r_err: Matrix3<f64> = t.rotation.to_rotation_matrix().matrix() * r.transpose();
            let w = rotation_log(&r_err);
            let e = Vector6::new(dp.x, dp.y, dp.z, l * w.x, l * w.y, l * w.z);
            Eval { e, rows: 6, cost: e.norm_squared(), pos_err: dp.norm(), rot_err: w.norm() }
        }
        Goal::Position(_) => {
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
pub(crate) fn past(deadline: Option<Instant>) -> bool {
    deadline.is_some_and(|d| Instant::now() > d)
}

/// Position error (mm) above which the wide trust region applies.
const FAR_MM: f64 = 50.0;

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
pub(crate) fn attempt(
    chain: &Chain,
    target: &Goal,
    q: &mut [f64],
    params: &Params,
    ws: &mut Workspace,
    deadline: Option<Instant>,
) -> (Option<Eval>, usize, bool) {
    let l = params.length_scale_mm;
    let tol_rot = params.orientation_tolerance_rad;
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
