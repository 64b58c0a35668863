//! A model's prediction of one measured pose and the Jacobian of it — the identification's
//! per-measurement hot path (from [`thermokin_chain::Chain::parameter_jacobian`]'s rows).

use nalgebra::{Matrix3, Matrix6xX, Unit, Vector3};
use thermokin_chain::{Approach, Chain, ErrorParams, JointKind, Measurement, ParameterLayout, ParameterRows, Robot};

use crate::effect::{BranchAt, DriftShape, Effect, LINEAR_DRIFT_REFERENCE_MIN, TAU_RANGE_MIN, six_at, tilt_turn};
use crate::error::IdentifyError;
use crate::model::Model;

/// The chain of one parameter vector, kept across the measurements of one evaluation, with its joint
/// rows' errors before any drift (a drift row is rewritten from them per measurement).
pub struct ChainCache {
    chain: Chain,
    joint_err: Vec<ErrorParams>,
    /// Buffers reused across measurements: the joint values the chain sees, the chain's parameter
    /// Jacobian.
    q: Vec<f64>,
    pj: Matrix6xX<f64>,
    /// The chain rows this model's Jacobian reads ([`Model::parameter_rows`]).
    rows: ParameterRows,
    /// Per measurement: each drift's factor and each drifting row's deviation.
    drift_scale: Vec<DriftFactor>,
    drift_rows: Vec<(usize, ErrorParams)>,
    /// Per measurement: each measured tilt's turn, `∂turn/∂ψ` and `∂turn/∂ψ_b` ([`tilt_turn`]), by the
    /// effect's place.
    tilt_rates: Vec<(usize, [Vector3<f64>; 3])>,
    /// `(sin, cos)` of the joint values the chain sees.
    sin_cos: Vec<(f64, f64)>,
    /// For a model with a compliance: the static chain (no drift) and gravity's direction in its world
    /// frame, which the gravity torques are computed on — the law the identified robot evaluates at use
    /// ([`Model::robot_model`]), so that its predictions are the fit's exactly — and the torques of the
    /// current measurement.
    gravity: Option<(Chain, Unit<Vector3<f64>>)>,
    torques: Vec<f64>,
    /// A compliance without masses ([`Effect::LumpedCompliance`]): its basis at the current measurement,
    /// at the effect's parameter offsets (zero elsewhere), and a buffer for one joint's basis.
    loads: Vec<f64>,
    basis: Vec<f64>,
    /// A branch's joint values at the current measurement ([`Effect::BranchLoad`]).
    branch_q: Vec<f64>,
    /// For a model with a lateral compliance: each joint's gravity moments across its axis at the current
    /// measurement ([`thermokin_chain::lateral_gravity_moments_into`]), N·m.
    lateral: Option<Vec<[f64; 2]>>,
}

/// `row`'s deviation added to joint `j`'s in `rows` (a row several effects move at one measurement).
fn add_to_row(rows: &mut Vec<(usize, ErrorParams)>, j: usize, row: ErrorParams) {
    match rows.iter_mut().find(|(r, _)| *r == j) {
        Some((_, d)) => *d = d.add(&row),
        None => rows.push((j, row)),
    }
}

/// A measured tilt's row at one pose ([`Effect::Tilt`], its parameters from `p[0]`): `(r × Δθ, Δθ)`, with
/// `[Δθ, ∂Δθ/∂ψ, ∂Δθ/∂ψ_b]` (the last zero without a sensor below).
fn tilt_row(
    sensors: &[f64],
    column: usize,
    over: crate::effect::TiltOver,
    p: &[f64],
) -> (ErrorParams, [Vector3<f64>; 3]) {
    let (mut turn, rate) = tilt_turn(sensors, column, p[0]);
    let mut below_rate = Vector3::zeros();
    if over == crate::effect::TiltOver::Below {
        let (under, r) = tilt_turn(sensors, column + 3, p[4]);
        turn -= under;
        below_rate = -r;
    }
    let pivot = Vector3::new(p[1], p[2], p[3]);
    (ErrorParams { translation: pivot.cross(&turn), rotation: turn }, [turn, rate, below_rate])
}

/// A measured tilt's Jacobian columns from `o`: its row (columns `row..row + 6` of the chain's `pj`)
/// moves by `(r × Δθ, Δθ)` — `∂/∂ψ` through `Δθ`'s rate, `∂/∂r_k = (e_k × Δθ, 0)`, `∂/∂ψ_b` through the
/// rate of the tilt below. `at`: `[Δθ, ∂Δθ/∂ψ, ∂Δθ/∂ψ_b]`.
fn tilt_columns(
    pj: &Matrix6xX<f64>,
    row: usize,
    o: usize,
    over: crate::effect::TiltOver,
    pivot: Vector3<f64>,
    at: [Vector3<f64>; 3],
    jac: &mut Matrix6xX<f64>,
) {
    let [turn, rate, below_rate] = at;
    let moved = |dt: Vector3<f64>, dr: Vector3<f64>, r: usize| -> f64 {
        (0..3).map(|c| pj[(r, row + c)] * dt[c] + pj[(r, row + 3 + c)] * dr[c]).sum()
    };
    for r in 0..6 {
        jac[(r, o)] = moved(pivot.cross(&rate), rate, r);
        for (a, axis) in [Vector3::x(), Vector3::y(), Vector3::z()].iter().enumerate() {
            jac[(r, o + 1 + a)] = moved(axis.cross(&turn), Vector3::zeros(), r);
        }
        if over == crate::effect::TiltOver::Below {
            jac[(r, o + 4)] = moved(pivot.cross(&below_rate), below_rate, r);
        }
    }
}

/// A drift's factor at one measurement: `s = f(t) / f(180)` and `∂s/∂τ`, for the effect at `effect` in
/// the model's list.
#[derive(Clone, Copy, Debug)]
struct DriftFactor {
    effect: usize,
    s: f64,
    ds_dtau: f64,
}

/// What one measurement's pose depends on besides the parameters and its joints: the temperature rise
/// per joint ([`crate::PoseTerms`]), and the sines of its measured joints when they are known. (Gravity
/// torques are computed on the model's own chain, as the identified robot computes them.)
#[derive(Clone, Copy, Debug)]
pub struct PoseInputs<'a> {
    /// The temperature rise each joint's drift follows, K.
    pub temp_rise: &'a [f64],
    /// `(sin q_i, cos q_i)` of the measured joints, when computed once beforehand.
    pub sin_cos: Option<&'a [(f64, f64)]>,
    /// Its line in the measurements file, when read from one (where a step of the measurement frame at
    /// a line puts it).
    pub line: Option<usize>,
    /// In the frame the training measurements ended in, whatever its time and line (a test set of
    /// another file): every step of the frame applies.
    pub latest_frame: bool,
    /// Its reading of each sensor column ([`thermokin_chain::Dataset::sensor_values`]; empty: none).
    pub sensors: &'a [f64],
    /// The direction each joint last moved in before it ([`thermokin_chain::Dataset::approach`]; empty:
    /// unknown, no backlash applied).
    pub approach: &'a [Approach],
}

impl PoseInputs<'_> {
    /// Inputs with no temperature rise, no precomputed sines, no line: a pose on its own.
    pub fn plain(temp_rise: &[f64]) -> PoseInputs<'_> {
        PoseInputs { temp_rise, sin_cos: None, line: None, latest_frame: false, sensors: &[], approach: &[] }
    }
}

impl Model {
    /// The drift factor `s = f(t) / f(180)` of a shape at one measurement (`f` the law of the deform
    /// profile, [`DriftShape::profile`]) and `ds/dτ` for the exponential — zero where τ is held at a
    /// bound of [`TAU_RANGE_MIN`], as `s` is.
    fn drift_factor(shape: DriftShape, m: &Measurement, temp_rise: f64, tau: f64) -> (f64, f64) {
        let held = !(TAU_RANGE_MIN.0 < tau && tau < TAU_RANGE_MIN.1);
        let tau = tau.clamp(TAU_RANGE_MIN.0, TAU_RANGE_MIN.1);
        let Some(profile) = shape.profile(tau) else { return (temp_rise, 0.0) };
        let f = |t: f64| profile.time_factor(t).unwrap_or(0.0);
        let (ft, fr) = (f(m.time_min), f(LINEAR_DRIFT_REFERENCE_MIN));
        let ds = match shape {
            DriftShape::Exponential => {
                let df = |t: f64| profile.time_factor_dtau(t).unwrap_or(0.0);
                if held { 0.0 } else { (df(m.time_min) * fr - ft * df(LINEAR_DRIFT_REFERENCE_MIN)) / (fr * fr) }
            }
            _ => 0.0,
        };
        (ft / fr, ds)
    }

    /// The cache of `theta`'s static chain, built on the first measurement of an evaluation.
    fn cache<'c>(
        &self,
        robot: &Robot,
        theta: &[f64],
        dof: usize,
        cache: &'c mut Option<ChainCache>,
    ) -> Result<&'c mut ChainCache, IdentifyError> {
        Ok(match cache {
            Some(c) => c,
            None => {
                let (chain, joint_err) = self.static_chain(robot, theta)?;
                let pj = Matrix6xX::zeros(chain.parameter_layout().len());
                let rows = self.parameter_rows(chain.dof());
                let gravity = self
                    .effects()
                    .iter()
                    .any(|e| {
                        matches!(
                            e,
                            Effect::JointCompliance(_)
                                | Effect::LumpedCompliance(..)
                                | Effect::BranchLoad(..)
                                | Effect::LateralCompliance(..)
                                | Effect::LumpedLateralCompliance(..)
                                | Effect::ComplianceCoupling(_)
                                | Effect::CompliancePair(_)
                        )
                    })
                    .then(|| (chain.clone(), self.gravity_down(&chain, robot)));
                let bends = self.effects().iter().any(|e| matches!(e, Effect::LateralCompliance(..)));
                cache.insert(ChainCache {
                    chain,
                    joint_err,
                    q: Vec::with_capacity(dof),
                    pj,
                    rows,
                    drift_scale: Vec::new(),
                    tilt_rates: Vec::new(),
                    drift_rows: Vec::new(),
                    sin_cos: Vec::with_capacity(dof),
                    gravity,
                    torques: Vec::with_capacity(dof),
                    loads: vec![0.0; self.len()],
                    basis: Vec::new(),
                    branch_q: Vec::new(),
                    lateral: bends.then(|| Vec::with_capacity(dof)),
                })
            }
        })
    }

    /// Per measurement: the joint values the joint-level effects move (into `q`), each drift's factor and
    /// each drifting row's deviation, the drifting rows written into the cached chain.
    #[inline]
    fn move_joints_and_drift(
        &self,
        robot: &Robot,
        theta: &[f64],
        m: &Measurement,
        inputs: &PoseInputs<'_>,
        cached: &mut ChainCache,
        q: &mut Vec<f64>,
    ) -> Result<(), IdentifyError> {
        q.clear();
        q.extend_from_slice(&m.q);
        gravity_at(robot, &m.q, inputs.sin_cos, cached)?;
        let mut drift_rows = std::mem::take(&mut cached.drift_rows);
        cached.drift_scale.clear();
        cached.tilt_rates.clear();
        drift_rows.clear();
        for (k, (e, &o)) in self.effects().iter().zip(self.offsets()).enumerate() {
            match *e {
                Effect::JointCompliance(j) => {
                    let j = j.index();
                    q[j] += theta[o] * cached.torques[j];
                }
                Effect::LumpedCompliance(j, n) => {
                    let (j, n) = (j.index(), n as usize);
                    load_basis(cached, *e, &m.q, inputs.sin_cos, o)?;
                    q[j] += cached.loads[o..o + n].iter().zip(&theta[o..o + n]).map(|(f, t)| f * t).sum::<f64>();
                }
                Effect::BranchLoad(j, first, at) => {
                    let (j, n) = (j.index(), at.count as usize);
                    branch_basis(cached, robot, at, first.index(), &m.q, inputs.sensors, j, o)?;
                    if at.lateral {
                        // The bearing's tilt under the branch's moment, as a lateral compliance's one set.
                        let basis = &cached.loads[o..o + n];
                        let row =
                            thermokin_deform::lumped_lateral_row_on(robot.chain(), j, basis, &theta[o..o + n], m.q[j]);
                        add_to_row(&mut drift_rows, j, row);
                    } else {
                        q[j] += cached.loads[o..o + n].iter().zip(&theta[o..o + n]).map(|(f, t)| f * t).sum::<f64>();
                    }
                }
                Effect::ComplianceCoupling(j) => {
                    let j = j.index();
                    q[j] += theta[o] * cached.torques[j + 1];
                    q[j + 1] += theta[o] * cached.torques[j];
                }
                Effect::CompliancePair(j) => {
                    // One element loaded by `wᵀτ`, moving each joint by its share `w`.
                    let j = j.index();
                    let (a, b) = (theta[o], theta[o + 1]);
                    let load = a * cached.torques[j] + b * cached.torques[j + 1];
                    q[j] += a * load;
                    q[j + 1] += b * load;
                }
                Effect::JointScale(j) | Effect::Periodic(j) | Effect::Backlash(j) => {
                    let (j, s) = (j.index(), inputs.approach.get(j.index()).map_or(0.0, |a| a.sign()));
                    q[j] +=
                        e.joint_basis(m.q[j], s).as_slice().iter().zip(&theta[o..]).map(|(b, t)| b * t).sum::<f64>();
                }
                Effect::ThermalDrift(j, shape) => {
                    let j = j.index();
                    let tau = if shape == DriftShape::Exponential { theta[o + 6] } else { 0.0 };
                    let (s, ds_dtau) = Self::drift_factor(shape, m, inputs.temp_rise[j], tau);
                    add_to_row(&mut drift_rows, j, six_at(theta, o).scaled(s));
                    cached.drift_scale.push(DriftFactor { effect: k, s, ds_dtau });
                }
                Effect::SensorDrift(j, sensor) => {
                    let (j, s) = (j.index(), inputs.sensors.get(sensor.index()).copied().unwrap_or(0.0));
                    add_to_row(&mut drift_rows, j, six_at(theta, o).scaled(s));
                    cached.drift_scale.push(DriftFactor { effect: k, s, ds_dtau: 0.0 });
                }
                Effect::Tilt(j, sensor, over) => {
                    let (row, at) = tilt_row(inputs.sensors, sensor.index(), over, &theta[o..]);
                    cached.tilt_rates.push((k, at));
                    add_to_row(&mut drift_rows, j.index(), row);
                }
                Effect::LumpedLateralCompliance(j, n, support) => {
                    let (j, n) = (j.index(), n as usize);
                    load_basis(cached, *e, &m.q, inputs.sin_cos, o)?;
                    let basis = &cached.loads[o..o + n / support.sets()];
                    let row =
                        thermokin_deform::lumped_lateral_row_on(robot.chain(), j, basis, &theta[o..o + n], m.q[j]);
                    add_to_row(&mut drift_rows, j, row);
                }
                Effect::Straightness(j) | Effect::LateralCompliance(j, _) => {
                    let moments = cached.lateral.as_ref().map_or([0.0; 2], |l| l[j.index()]);
                    let row = bent_row(*e, robot.chain(), &theta[o..o + e.len()], moments, m.q[j.index()]);
                    add_to_row(&mut drift_rows, j.index(), row);
                }
                _ => {}
            }
        }
        for &(j, d) in &drift_rows {
            let row = cached.joint_err[j].add(&d);
            cached.chain.set_joint_error(j, row)?;
        }
        cached.drift_rows = drift_rows;
        Ok(())
    }

    /// Predicted TCP position and rotation of one measurement and, if asked, the 6 × len Jacobian of the
    /// pose as twists in the measurement frame (rows 0–2 the position, 3–5 the rotation: a small turn
    /// `δφ` of the predicted rotation, `R ↦ exp(δφ)·R`).
    ///
    /// `cache` holds the chain of one parameter vector across the measurements of one evaluation: the
    /// static effects are built once; a thermal drift, which differs per measurement, rewrites only its
    /// own rows ([`Chain::set_joint_error`]).
    pub fn predict(
        &self,
        robot: &Robot,
        theta: &[f64],
        m: &Measurement,
        inputs: &PoseInputs<'_>,
        jacobian: Option<&mut Matrix6xX<f64>>,
        cache: &mut Option<ChainCache>,
    ) -> Result<(Vector3<f64>, Matrix3<f64>), IdentifyError> {
        let cached = self.cache(robot, theta, m.q.len(), cache)?;
        let mut q = std::mem::take(&mut cached.q);
        let moved = self.move_joints_and_drift(robot, theta, m, inputs, cached, &mut q);
        if let Err(e) = moved {
            cached.q = q;
            return Err(e);
        }
        // The measured joints' sines, moved by angle addition where a joint-level effect moved the joint
        // (by a small angle: [`thermokin_chain::sin_cos`] takes it without a library sine).
        let sc = inputs.sin_cos.map(|given| {
            cached.sin_cos.clear();
            cached.sin_cos.extend(given.iter().zip(&q).zip(&m.q).map(|((&(s, c), &moved), &measured)| {
                let d = moved - measured;
                if d == 0.0 {
                    (s, c)
                } else {
                    let (sd, cd) = thermokin_chain::sin_cos(d);
                    (s * cd + c * sd, c * cd - s * sd)
                }
            }));
            &cached.sin_cos[..]
        });
        let registered = &cached.chain;
        let Some(jac) = jacobian else {
            let pose = match sc {
                Some(sc) => registered.tool_position_rotation_sin_cos(&q, sc),
                None => registered.tool_position_rotation(&q),
            };
            cached.q = q;
            return Ok(self.frame_steps(theta, m, inputs, pose?, None));
        };
        let pose = match sc {
            Some(sc) => registered.pose_and_parameter_jacobian_rows_sin_cos(&q, sc, &mut cached.pj, &cached.rows),
            None => registered.pose_and_parameter_jacobian_rows(&q, &mut cached.pj, &cached.rows),
        };
        cached.q = q;
        let pose = pose?;
        self.fill_jacobian(robot.chain(), theta, m, inputs.approach, cached, jac);
        Ok(self.frame_steps(theta, m, inputs, pose, Some(jac)))
    }

    /// The pose (and its Jacobian) moved by every step of the measurement frame this measurement comes
    /// after ([`Effect::FrameStep`]), in the model's order: `p ↦ R_s p + t_s`, `R ↦ R_s R` with
    /// `R_s = Rx(a)·Ry(b)·Rz(c)`. The columns already filled turn with the frame (positions and rotation
    /// twists alike); the step's own are `∂p/∂t = I`, `∂p/∂a = ω_a × (p − t_s)` with `ω_a = x`,
    /// `ω_b = Rx(a)·y`, `ω_c = Rx(a)·Ry(b)·z` (the angular velocities of `Rx·Ry·Rz` in the outer frame),
    /// and the rotation twist of each angle its `ω`.
    fn frame_steps(
        &self,
        theta: &[f64],
        m: &Measurement,
        inputs: &PoseInputs<'_>,
        (p, rot): (Vector3<f64>, Matrix3<f64>),
        jac: Option<&mut Matrix6xX<f64>>,
    ) -> (Vector3<f64>, Matrix3<f64>) {
        let applies = |at: &crate::StepAt| inputs.latest_frame || at.applies(m.time_min, inputs.line);
        let steps = || {
            self.effects().iter().zip(self.offsets()).filter_map(move |(e, &o)| match e {
                Effect::FrameStep(at) if applies(at) => Some(o),
                _ => None,
            })
        };
        // Every step in force turns what came before it: their product, applied once to the columns
        // filled so far, as turning them step after step does (O(columns), not O(steps · columns)).
        let rotation_at =
            |o: usize| thermokin_chain::xyz_rotation(&Vector3::new(theta[o + 3], theta[o + 4], theta[o + 5]));
        let total = steps().fold(Matrix3::identity(), |r, o| rotation_at(o) * r);
        let Some(jac) = jac else {
            let p = steps().fold(p, |p, o| rotation_at(o) * p + Vector3::new(theta[o], theta[o + 1], theta[o + 2]));
            return (p, total * rot);
        };
        if total != Matrix3::identity() {
            for c in 0..jac.ncols() {
                let turned_p = total * Vector3::new(jac[(0, c)], jac[(1, c)], jac[(2, c)]);
                let turned_w = total * Vector3::new(jac[(3, c)], jac[(4, c)], jac[(5, c)]);
                for a in 0..3 {
                    jac[(a, c)] = turned_p[a];
                    jac[(3 + a, c)] = turned_w[a];
                }
            }
        }
        // Each step's own columns, at the point it leaves, turned by the steps after it: `total · upto⁻¹`.
        let (mut p, mut upto) = (p, Matrix3::identity());
        for o in steps() {
            let t = Vector3::new(theta[o], theta[o + 1], theta[o + 2]);
            let angles = Vector3::new(theta[o + 3], theta[o + 4], theta[o + 5]);
            let r_s = rotation_at(o);
            p = r_s * p + t;
            upto = r_s * upto;
            let after = total * upto.transpose();
            let rx = thermokin_chain::xyz_rotation(&Vector3::new(angles.x, 0.0, 0.0));
            let rxy = thermokin_chain::xyz_rotation(&Vector3::new(angles.x, angles.y, 0.0));
            let omegas = [Vector3::x(), rx * Vector3::y(), rxy * Vector3::z()];
            for a in 0..3 {
                let unit = after.column(a).into_owned();
                let (dp, dw) = (after * omegas[a].cross(&(p - t)), after * omegas[a]);
                for r in 0..3 {
                    jac[(r, o + a)] = unit[r];
                    jac[(3 + r, o + a)] = 0.0;
                    jac[(r, o + 3 + a)] = dp[r];
                    jac[(3 + r, o + 3 + a)] = dw[r];
                }
            }
        }
        (p, total * rot)
    }

    /// The model's 6 × len Jacobian from the chain's parameter Jacobian `cached.pj`: each effect's
    /// columns are its rows' columns, scaled by what moves them (a torque, a joint basis, a drift
    /// factor); an exponential drift's τ column is its row's columns times the amplitudes and `∂s/∂τ`.
    #[inline]
    fn fill_jacobian(
        &self,
        chain: &Chain,
        theta: &[f64],
        m: &Measurement,
        approach: &[Approach],
        cached: &ChainCache,
        jac: &mut Matrix6xX<f64>,
    ) {
        let pj = &cached.pj;
        let layout: ParameterLayout = cached.chain.parameter_layout();
        // One memset: nalgebra's `fill` steps an element iterator, which was two thirds of `predict`'s own time.
        jac.as_mut_slice().fill(0.0);
        let mut drift = cached.drift_scale.iter();
        for (k, (e, &o)) in self.effects().iter().zip(self.offsets()).enumerate() {
            // Column `dst` of `jac` is column `src` of `pj` times `scale` (both 6 rows, column-major).
            let mut copy = |dst: usize, src: usize, scale: f64| {
                let from = &pj.as_slice()[6 * src..6 * src + 6];
                jac.as_mut_slice()[6 * dst..6 * dst + 6].iter_mut().zip(from).for_each(|(d, s)| *d = s * scale);
            };
            match *e {
                Effect::Registration | Effect::BaseFrame => (0..6).for_each(|c| copy(o + c, layout.base() + c, 1.0)),
                Effect::ToolPoint => (0..3).for_each(|c| copy(o + c, layout.tool() + c, 1.0)),
                Effect::ToolRotation => (0..3).for_each(|c| copy(o + c, layout.tool() + 3 + c, 1.0)),
                Effect::ToolFrame => (0..6).for_each(|c| copy(o + c, layout.tool() + c, 1.0)),
                Effect::JointOffset(j) => copy(o, layout.zero(j.index()), 1.0),
                Effect::LinkDeviation(j) => (0..6).for_each(|c| copy(o + c, layout.joint(j.index()) + c, 1.0)),
                Effect::JointCompliance(j) => {
                    let j = j.index();
                    let scale = if chain.joints()[j].kind == JointKind::Revolute { cached.torques[j] } else { 0.0 };
                    copy(o, layout.zero(j), scale);
                }
                Effect::BranchLoad(j, _, BranchAt { lateral: true, .. }) => {
                    bend_columns(*e, chain, pj, &layout, m.q[j.index()], cached, o, jac);
                }
                Effect::LumpedCompliance(j, n) | Effect::BranchLoad(j, _, BranchAt { count: n, .. }) => {
                    // ∂p/∂θ_b = ∂p/∂zero_j · f_b(q).
                    let zero = layout.zero(j.index());
                    (0..n as usize).for_each(|b| copy(o + b, zero, cached.loads[o + b]));
                }
                Effect::ComplianceCoupling(j) => {
                    // Both joints move: ∂p/∂c = ∂p/∂zero_j · τ_{j+1} + ∂p/∂zero_{j+1} · τ_j.
                    let j = j.index();
                    let (a, b) = (layout.zero(j), layout.zero(j + 1));
                    for r in 0..6 {
                        jac[(r, o)] = pj[(r, a)] * cached.torques[j + 1] + pj[(r, b)] * cached.torques[j];
                    }
                }
                Effect::CompliancePair(j) => pair_columns(j.index(), &layout, &theta[o..o + 2], cached, o, jac),
                Effect::JointScale(j) | Effect::Periodic(j) | Effect::Backlash(j) => {
                    // Δq enters exactly as a zero offset does: ∂p/∂θ_k = ∂p/∂zero · basis_k(q, s).
                    let (j, s) = (j.index(), approach.get(j.index()).map_or(0.0, |a| a.sign()));
                    for (k, b) in e.joint_basis(m.q[j], s).as_slice().iter().enumerate() {
                        copy(o + k, layout.zero(j), *b);
                    }
                }
                // Filled after the pose (zero for a measurement before the step): `frame_steps`.
                Effect::FrameStep(_) => {}
                Effect::Straightness(j) | Effect::LateralCompliance(j, _) | Effect::LumpedLateralCompliance(j, ..) => {
                    bend_columns(*e, chain, pj, &layout, m.q[j.index()], cached, o, jac);
                }
                Effect::Tilt(j, _, over) => {
                    let found = cached.tilt_rates.iter().find(|(e, ..)| *e == k);
                    if let Some(&(_, at)) = found {
                        let pivot = Vector3::new(theta[o + 1], theta[o + 2], theta[o + 3]);
                        tilt_columns(pj, layout.joint(j.index()), o, over, pivot, at, jac);
                    }
                }
                Effect::SensorDrift(j, _) => {
                    let none = DriftFactor { effect: k, s: 0.0, ds_dtau: 0.0 };
                    let f = drift.next().filter(|d| d.effect == k).copied().unwrap_or(none);
                    (0..6).for_each(|c| copy(o + c, layout.joint(j.index()) + c, f.s));
                }
                Effect::ThermalDrift(j, shape) => {
                    let j = j.index();
                    let none = DriftFactor { effect: k, s: 0.0, ds_dtau: 0.0 };
                    let f = drift.next().filter(|d| d.effect == k).copied().unwrap_or(none);
                    (0..6).for_each(|c| copy(o + c, layout.joint(j) + c, f.s));
                    if shape == DriftShape::Exponential {
                        for r in 0..6 {
                            let mut v = 0.0;
                            for c in 0..6 {
                                v += pj[(r, layout.joint(j) + c)] * theta[o + c] * f.ds_dtau;
                            }
                            jac[(r, o + 6)] = v;
                        }
                    }
                }
            }
        }
    }
}

/// A [`Effect::CompliancePair`]'s two columns from the chain's: `Δq_j = w_j·L`, `Δq_{j+1} = w_{j+1}·L`
/// with `L = w_j τ_j + w_{j+1} τ_{j+1}`, so `∂Δq_j/∂w_j = L + w_j τ_j`, `∂Δq_{j+1}/∂w_j = w_{j+1} τ_j`, and
/// the same for `w_{j+1}`.
fn pair_columns(
    j: usize,
    layout: &ParameterLayout,
    w: &[f64],
    cached: &ChainCache,
    o: usize,
    jac: &mut Matrix6xX<f64>,
) {
    let pj = &cached.pj;
    let (zj, zn) = (layout.zero(j), layout.zero(j + 1));
    let (a, b, tj, tn) = (w[0], w[1], cached.torques[j], cached.torques[j + 1]);
    let load = a * tj + b * tn;
    let (da, db) = ([load + a * tj, b * tj], [a * tn, load + b * tn]);
    for r in 0..6 {
        jac[(r, o)] = pj[(r, zj)] * da[0] + pj[(r, zn)] * da[1];
        jac[(r, o + 1)] = pj[(r, zj)] * db[0] + pj[(r, zn)] * db[1];
    }
}

/// The Jacobian columns of an effect that bends joint `j`'s row with the configuration, at offset `o`:
/// a lateral compliance — the row's angles move along `eₖ` and its translation along `eₖ × a`
/// ([`thermokin_deform::lateral_row_error`]): `∂p/∂cₖ = ∂p/∂angles · eₖ Mₖ`,
/// `∂p/∂c′ₖ = d ∂p/∂cₖ − ∂p/∂translation · (eₖ × a) Mₖ d²/2`, `∂p/∂sₖ = ∂p/∂translation · (eₖ × a) Mₖ` —
/// or a slide's straightness — the angles along `d·e₁, d·e₂, d·a`, the translation along `d²(eₖ × a)`
/// ([`thermokin_deform::straightness_row_error`]) — or a lateral compliance without masses, each weight's
/// column its coefficient's at unit moment times its function ([`thermokin_deform::lumped_lateral_row_error`]).
/// `d` is the joint's value (a slide's extension).
#[allow(clippy::too_many_arguments)] // The Jacobian's inputs, as fill_jacobian holds them.
fn bend_columns(
    e: Effect,
    chain: &Chain,
    pj: &Matrix6xX<f64>,
    layout: &ParameterLayout,
    d: f64,
    cached: &ChainCache,
    o: usize,
    jac: &mut Matrix6xX<f64>,
) {
    let Some(j) = e.joint().map(|j| j.index()) else { return };
    let dirs = thermokin_chain::lateral_directions(chain, j).unwrap_or([Vector3::zeros(); 2]);
    let axis = chain.joints()[j].axis.into_inner();
    let row = layout.joint(j);
    let along = |r: usize, at: usize, v: &Vector3<f64>| (0..3).map(|c| pj[(r, row + at + c)] * v[c]).sum::<f64>();
    // A lumped lateral load's weights and sets: a lateral compliance without masses', or a branch's load
    // across the joint (a bearing's one set).
    let lumped = match e {
        Effect::LumpedLateralCompliance(_, n, support) => Some((n as usize, support.sets())),
        Effect::BranchLoad(_, _, at) if at.lateral => Some((at.count as usize, 1)),
        _ => None,
    };
    match (e, lumped) {
        (_, Some((n, sets))) => {
            // Per set s, direction k, function b: the column of c (s = 0), c′ (1) or s (2) above at unit
            // moment, times fₖ,b(q) — ∂p/∂θ = ∂p/∂c · fₖ,b.
            let half = n / 2 / sets;
            for (k, dir) in dirs.iter().enumerate() {
                let across = dir.cross(&axis);
                for r in 0..6 {
                    let (turn, shift) = (along(r, 3, dir), along(r, 0, &across));
                    let per_set = [turn, turn * d - shift * 0.5 * d * d, shift];
                    for (s, v) in per_set.iter().enumerate().take(sets) {
                        for b in 0..half {
                            let col = o + s * 2 * half + k * half + b;
                            jac[(r, col)] = v * cached.loads[col];
                        }
                    }
                }
            }
        }
        (Effect::LateralCompliance(_, n), None) => {
            let moments = cached.lateral.as_ref().map_or([0.0; 2], |l| l[j]);
            for (k, dir) in dirs.iter().enumerate() {
                let across = dir.cross(&axis);
                for r in 0..6 {
                    let turn = along(r, 3, dir) * moments[k];
                    let shift = along(r, 0, &across) * moments[k];
                    jac[(r, o + k)] = turn;
                    if n == 6 {
                        jac[(r, o + 2 + k)] = turn * d - shift * 0.5 * d * d;
                        jac[(r, o + 4 + k)] = shift;
                    }
                }
            }
        }
        (Effect::Straightness(_), None) => {
            let (b1, b2) = (dirs[0].cross(&axis), dirs[1].cross(&axis));
            for r in 0..6 {
                jac[(r, o)] = along(r, 3, &dirs[0]) * d;
                jac[(r, o + 1)] = along(r, 3, &dirs[1]) * d;
                jac[(r, o + 2)] = along(r, 3, &axis) * d;
                jac[(r, o + 3)] = along(r, 0, &b1) * d * d;
                jac[(r, o + 4)] = along(r, 0, &b2) * d * d;
            }
        }
        _ => {}
    }
}

/// The error an effect that bends joint `j`'s row adds to it at joint value `d` (a slide's extension),
/// `c` its parameters, `moments` the gravity moments across the joint (a lateral compliance's:
/// [`thermokin_deform::lateral_row_error`]; a straightness': [`thermokin_deform::straightness_row_error`]).
fn bent_row(e: Effect, chain: &Chain, c: &[f64], moments: [f64; 2], d: f64) -> ErrorParams {
    let Some(j) = e.joint().map(|j| j.index()) else { return ErrorParams::ZERO };
    let directions = thermokin_chain::lateral_directions(chain, j).unwrap_or([Vector3::zeros(); 2]);
    let axis = chain.joints()[j].axis.into_inner();
    match e {
        Effect::LateralCompliance(..) => thermokin_deform::lateral_row_error(c, &directions, &axis, moments, d),
        Effect::Straightness(_) => {
            let c = [c[0], c[1], c[2], c[3], c[4]];
            thermokin_deform::straightness_row_error(&c, &directions, &axis, d)
        }
        _ => ErrorParams::ZERO,
    }
}

/// The gravity torques (and, for a lateral compliance, the moments across each joint) at the measured
/// joints `q`, on the model's gravity chain, into the cache — for a model with a compliance.
#[inline]
fn gravity_at(
    robot: &Robot,
    q: &[f64],
    sin_cos: Option<&[(f64, f64)]>,
    cached: &mut ChainCache,
) -> Result<(), IdentifyError> {
    if let Some((chain, down)) = &cached.gravity {
        thermokin_chain::gravity_torques_into(chain, robot.masses(), q, sin_cos, down, &mut cached.torques)?;
        if let Some(lateral) = cached.lateral.as_mut() {
            thermokin_chain::lateral_gravity_moments_into(chain, robot.masses(), q, sin_cos, down, lateral)?;
        }
    }
    Ok(())
}

/// A branch's load functions on joint `j` ([`Effect::BranchLoad`]) at the measured joints `q` and the
/// branch's readings (the sensor columns from `column`), on the model's gravity chain, kept in
/// `cached.loads` at the effect's offset `o` for its Jacobian. A pose without the readings has none.
#[allow(clippy::too_many_arguments)] // The pose's inputs, as move_joints_and_drift holds them.
fn branch_basis(
    cached: &mut ChainCache,
    robot: &Robot,
    at: BranchAt,
    column: usize,
    q: &[f64],
    sensors: &[f64],
    j: usize,
    o: usize,
) -> Result<(), IdentifyError> {
    let n = at.count as usize;
    let (Some(branch), Some((chain, down))) = (robot.branches().get(at.branch as usize), &cached.gravity) else {
        cached.loads[o..o + n].fill(0.0);
        return Ok(());
    };
    let Some(readings) = sensors.get(column..column + branch.joints.len()) else {
        cached.loads[o..o + n].fill(0.0);
        return Ok(());
    };
    cached.branch_q.clear();
    cached.branch_q.extend(readings.iter().enumerate().map(|(i, r)| branch.joint_value(i, *r)));
    let (masses, joints) = (robot.masses(), (q, cached.branch_q.as_slice()));
    thermokin_chain::branch_load_functions_into(
        chain,
        masses,
        branch,
        joints,
        down,
        (j, at.lateral),
        &mut cached.basis,
    )?;
    let used = cached.basis.len().min(n);
    cached.loads[o..o + used].copy_from_slice(&cached.basis[..used]);
    Ok(())
}

/// A compliance without masses' functions of the measured joint values `q` (as the torques are computed,
/// on the model's gravity chain), kept in `cached.loads` at the effect's offset `o` for its Jacobian:
/// [`thermokin_chain::gravity_load_basis_into`]'s for a joint's, [`thermokin_chain::lateral_load_basis_into`]'s
/// for a lateral one.
fn load_basis(
    cached: &mut ChainCache,
    e: Effect,
    q: &[f64],
    given: Option<&[(f64, f64)]>,
    o: usize,
) -> Result<(), IdentifyError> {
    let Some(j) = e.joint().map(|j| j.index()) else { return Ok(()) };
    if let Some((chain, down)) = &cached.gravity {
        match e {
            Effect::LumpedCompliance(..) => {
                thermokin_chain::gravity_load_basis_into(chain, q, given, down, j, &mut cached.basis)?
            }
            _ => thermokin_chain::lateral_load_basis_into(chain, q, given, down, j, &mut cached.basis)?,
        }
    }
    // A column's three sets of weights share the functions: one copy per set, each weight's own.
    let (n, per_set) = (e.len(), cached.basis.len().min(e.len()));
    for at in (o..o + n).step_by(per_set.max(1)) {
        cached.loads[at..at + per_set].copy_from_slice(&cached.basis[..per_set]);
    }
    Ok(())
}
