//! Physical sense of fitted values: a candidate whose values move the tool point by more than
//! [`Plausibility`] allows in the robot's own scale ([`RobotScale`]), or contradict physics — a joint
//! rising under its load, a drift over before the next measurement — is a fit running away or a static
//! effect in disguise, not a property of the robot.

use thermokin_chain::{Dataset, Robot, units};
use thermokin_deform::MAX_CORRECTION_SLOPE;
use thermokin_identify::{DriftShape, Effect, max_gravity_torques};

use crate::config::Plausibility;
use crate::report::Refusal;

/// A lateral compliance's tilt at the largest moment across joint `j` (a slide's at its largest
/// extension), radians, and what it moves the tool point by at most: the tilt at the row's lever, plus a
/// slide's shift, mm.
fn lateral_reach(scale: &RobotScale, j: usize, n: u8, v: &[f64]) -> (f64, f64) {
    let (most, d) = (scale.max_lateral_nm[j], if n == 6 { scale.reach[j] } else { 0.0 });
    let at = |k: usize| v.get(k).copied().unwrap_or(0.0);
    let tilt = (at(0).hypot(at(1)) + d * at(2).hypot(at(3))) * most;
    let shift = (at(4).hypot(at(5)) + 0.5 * d * d * at(2).hypot(at(3))) * most;
    (tilt, tilt * scale.lever_mm[j].max(1.0) + shift)
}

/// The robot's scale over a data set, what plausibility is judged against: the arm's extent, each joint
/// row's lever to the tool point, each joint's largest gravity torque, the measurements' time spacing.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RobotScale {
    /// The largest distance from joint 1 to the tool point over the data (nominal FK), mm.
    pub(crate) extent_mm: f64,
    /// Per joint, the largest distance from the joint to the tool point over the data, mm: what a
    /// rotation of the joint's row about any axis moves the tool point by, per radian, at most.
    pub(crate) lever_mm: Vec<f64>,
    /// Per joint, the largest distance of the tool point from the joint's axis over the data, mm: what a
    /// turn about the axis itself (an offset, a gear-ratio or cyclic error, a compliance) moves it by, per
    /// radian.
    pub(crate) axis_lever_mm: Vec<f64>,
    /// Per joint, the largest gravity torque about it over its joint space, N·m.
    pub(crate) max_torque_nm: Vec<f64>,
    /// Per joint, the largest |q| over the data (radians or mm).
    pub(crate) reach: Vec<f64>,
    /// Per joint, whether it turns (its offsets and motions are angles) rather than slides.
    pub(crate) revolute: Vec<bool>,
    /// The measurement times, minutes, sorted (empty without time).
    pub(crate) times_min: Vec<f64>,
    /// Per sensor column, the largest |reading| over the data.
    pub(crate) sensor_reach: Vec<f64>,
    /// Per joint, the largest gravity moment across its axis over the data (the file's masses), N·m.
    pub(crate) max_lateral_nm: Vec<f64>,
    /// For a robot without masses (whose compliances are lumped), per joint the lumped load functions
    /// at every pose of the data, pose after pose: [`thermokin_chain::gravity_load_basis_into`]'s and
    /// [`thermokin_chain::lateral_load_basis_into`]'s, with the joint's value (a slide's extension) — so
    /// that a lumped compliance is bounded by what it does over the data, as every other effect is.
    pub(crate) loads: Vec<LumpedLoads>,
    /// For each branch the data log (its joints' columns, [`thermokin_chain::Dataset::branch_columns`]) and
    /// each joint below it: the branch's load functions at every pose
    /// ([`thermokin_chain::branch_load_basis_into`]; across the joint, [`thermokin_chain::branch_lateral_basis_into`]),
    /// pose after pose — `(joint, branch, across, per pose, functions)`.
    pub(crate) branch_loads: Vec<BranchFunctions>,
}

/// How far `Σ θ_b f_b` changes over the poses of `values` (`len` functions per pose; largest less
/// smallest): what a zero offset cannot take.
fn weighted_change(values: &[f64], len: usize, weights: &[f64]) -> f64 {
    let dot = |f: &[f64]| f.iter().zip(weights).map(|(f, w)| f * w).sum::<f64>();
    let (lo, hi) = crate::stats::span(values.chunks(len.max(1)).map(dot));
    if lo <= hi { hi - lo } else { 0.0 }
}

/// A branch's load functions on one joint over the data: `(joint, branch, across the joint, functions per
/// pose, the functions pose after pose)`.
pub(crate) type BranchFunctions = (usize, usize, bool, usize, Vec<f64>);

/// The load functions of each branch `data` logs on each revolute joint below it, about the joint and
/// across it, at every pose ([`RobotScale::branch_loads`]).
fn branch_loads_of(robot: &Robot, data: &Dataset) -> Vec<BranchFunctions> {
    let (chain, down) = (robot.chain(), -nalgebra::Vector3::z_axis());
    let mut out = Vec::new();
    for columns in &data.branch_columns {
        let Some(branch) = robot.branches().get(columns.branch) else { continue };
        for (j, across) in (0..chain.dof()).flat_map(|j| [(j, false), (j, true)]) {
            let len = match across {
                false => thermokin_chain::branch_load_basis_len(chain, branch, j),
                true => thermokin_chain::branch_lateral_basis_len(chain, branch, j),
            };
            if len == 0 {
                continue;
            }
            let (mut values, mut basis) = (Vec::with_capacity(len * data.len()), Vec::new());
            for (m, r) in data.measurements.iter().zip(&data.sensor_values) {
                let Some(readings) = r.get(columns.column..columns.column + columns.len) else { continue };
                let bq: Vec<f64> = readings.iter().enumerate().map(|(i, v)| branch.joint_value(i, *v)).collect();
                let (masses, joints) = (robot.masses(), (m.q.as_slice(), bq.as_slice()));
                let found = thermokin_chain::branch_load_functions_into(
                    chain,
                    masses,
                    branch,
                    joints,
                    &down,
                    (j, across),
                    &mut basis,
                );
                if found.is_ok() {
                    values.extend_from_slice(&basis);
                }
            }
            out.push((j, columns.branch, across, len, values));
        }
    }
    out
}

/// One joint's lumped load functions over the data ([`RobotScale::loads`]), pose-major.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct LumpedLoads {
    /// [`thermokin_chain::gravity_load_basis_into`]'s functions, `gravity_len` per pose.
    gravity: Vec<f64>,
    gravity_len: usize,
    /// [`thermokin_chain::lateral_load_basis_into`]'s functions, `lateral_len` per pose.
    lateral: Vec<f64>,
    lateral_len: usize,
    /// The joint's value at each pose.
    q: Vec<f64>,
}

impl LumpedLoads {
    /// Joint `j`'s functions over `data` (gravity along −Z of the base, as the catalogue judges them).
    fn of(robot: &Robot, data: &Dataset, j: usize) -> Self {
        let chain = robot.chain();
        let down = -nalgebra::Vector3::z_axis();
        let (mut loads, mut basis) = (Self::default(), Vec::new());
        for m in &data.measurements {
            if thermokin_chain::gravity_load_basis_into(chain, &m.q, None, &down, j, &mut basis).is_ok() {
                loads.gravity_len = basis.len();
                loads.gravity.extend_from_slice(&basis);
            }
            if thermokin_chain::lateral_load_basis_into(chain, &m.q, None, &down, j, &mut basis).is_ok() {
                loads.lateral_len = basis.len();
                loads.lateral.extend_from_slice(&basis);
            }
            loads.q.push(m.q[j]);
        }
        loads
    }

    /// How far the deflection `Σ θ_b f_b(q)` of a compliance without masses changes over the data
    /// (largest less smallest, radians): what a zero offset cannot take. Its level is not bounded — the
    /// functions' span holds offset-like parts that trade with the joint's offset, whose own bound holds.
    fn deflection_change(&self, weights: &[f64]) -> f64 {
        weighted_change(&self.gravity, self.gravity_len, weights)
    }

    /// How far a lateral compliance without masses (`sets` sets of weights: a bearing's tilt, a column's
    /// tilt, bend and shift — [`thermokin_deform::lumped_lateral_row_error`]) changes its row over the
    /// data: the change of its tilt (radians; each direction's largest less smallest, combined) and what
    /// that moves the tool point by at `lever` with the change of the row's shift, mm — what a fixed link
    /// deviation cannot take, as [`LumpedLoads::deflection_change`].
    fn tilt_change(&self, weights: &[f64], sets: usize, lever: f64) -> (f64, f64) {
        let n = self.lateral_len.max(1);
        // Per pose the turn about, and the shift along, the two (orthonormal) directions.
        let rows: Vec<[f64; 4]> = self
            .lateral
            .chunks(n)
            .zip(&self.q)
            .map(|(f, &d)| {
                let set = |s: usize| {
                    weights
                        .get(s * n..(s + 1) * n)
                        .filter(|_| s < sets)
                        .map_or([0.0; 2], |w| thermokin_deform::lumped_tilts(f, w))
                };
                let ([t1, t2], [b1, b2], [s1, s2]) = (set(0), set(1), set(2));
                [t1 + b1 * d, t2 + b2 * d, s1 - 0.5 * b1 * d * d, s2 - 0.5 * b2 * d * d]
            })
            .collect();
        let change = |k: usize| {
            let (lo, hi) = crate::stats::span(rows.iter().map(|r| r[k]));
            if lo <= hi { hi - lo } else { 0.0 }
        };
        let (tilt, shift) = (change(0).hypot(change(1)), change(2).hypot(change(3)));
        (tilt, tilt * lever + shift)
    }
}

impl RobotScale {
    /// The scale of `robot` over `data`.
    pub(crate) fn of(robot: &Robot, data: &Dataset) -> Self {
        let chain = robot.chain();
        let dof = chain.dof();
        let mut lever_mm = vec![0.0f64; dof];
        let mut axis_lever_mm = vec![0.0f64; dof];
        let mut max_lateral_nm = vec![0.0f64; dof];
        let mut moments = Vec::new();
        let down = -nalgebra::Vector3::z_axis();
        let massive = robot.masses().iter().any(Option::is_some);
        for m in &data.measurements {
            if massive
                && thermokin_chain::lateral_gravity_moments_into(chain, robot.masses(), &m.q, None, &down, &mut moments)
                    .is_ok()
            {
                for (most, [a, b]) in max_lateral_nm.iter_mut().zip(&moments) {
                    *most = most.max(a.hypot(*b));
                }
            }
            let (Ok(frames), Ok(tool)) = (chain.joint_frames(&m.q), chain.tool_pose(&m.q)) else { continue };
            for (j, f) in frames.iter().take(dof).enumerate() {
                let arm = tool.translation.vector - f.translation.vector;
                let axis = f.rotation * chain.joints()[j].axis.into_inner();
                lever_mm[j] = lever_mm[j].max(arm.norm());
                axis_lever_mm[j] = axis_lever_mm[j].max(arm.cross(&axis).norm());
            }
        }
        let mut times_min: Vec<f64> = data.measurements.iter().map(|m| m.time_min).collect();
        times_min.sort_by(f64::total_cmp);
        if times_min.first() == times_min.last() {
            times_min.clear();
        }
        let reach = (0..dof).map(|j| data.measurements.iter().map(|m| m.q[j].abs()).fold(0.0, f64::max)).collect();
        let sensor_reach = (0..data.sensor_names.len())
            .map(|k| data.sensor_values.iter().filter_map(|v| v.get(k)).fold(0.0, |a: f64, x| a.max(x.abs())))
            .collect();
        let loads = if massive { Vec::new() } else { (0..dof).map(|j| LumpedLoads::of(robot, data, j)).collect() };
        Self {
            loads,
            branch_loads: branch_loads_of(robot, data),
            extent_mm: lever_mm.first().copied().unwrap_or(0.0),
            reach,
            revolute: chain.joints().iter().map(|j| j.kind == thermokin_chain::JointKind::Revolute).collect(),
            max_torque_nm: max_gravity_torques(robot),
            lever_mm,
            axis_lever_mm,
            times_min,
            sensor_reach,
            max_lateral_nm,
        }
    }
}

/// A fitted value the robot cannot have, and why.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Implausible {
    /// Beyond its bound: `what` fitted at `value`, the bound `bound` (both in `unit`), `scale` saying
    /// where the bound comes from.
    Beyond { what: &'static str, value: f64, bound: f64, unit: &'static str, scale: String },
    /// A compliance of the wrong sign: the joint would rise under its load (by `deflection_deg` at its
    /// largest gravity torque).
    Rising { k_deg_per_nm: f64, deflection_deg: f64 },
    /// An exponential drift over before all but `during` of the poses (those measured within three time
    /// constants of the cold start, where it is below 95 % of its end): fewer than its parameters, so
    /// that the data cannot tell its time law from a static deviation.
    Instant { tau_min: f64, during: usize },
    /// A gear-ratio or cyclic error whose slope (joint-value change per unit of joint motion) is beyond
    /// what a robot file's joint correction may have.
    Steep { slope: f64 },
}

/// How a value judged implausible was obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Judged {
    /// Fitted on all data, in the model it would join.
    Fitted,
    /// Fitted on every fold of the selection.
    FittedOnEveryFold,
    /// Forecast on every fold of the selection, by one Gauss–Newton step from the model's fit there
    /// (not fitted: [`crate::linearised`]).
    ForecastOnEveryFold,
}

impl Implausible {
    /// How far beyond its bound a value is (value / bound), for [`Implausible::Beyond`]; `None` for the
    /// others, which are wrong in kind rather than in size.
    pub(crate) fn excess(&self) -> Option<f64> {
        match self {
            Implausible::Beyond { value, bound, .. } => Some(value / bound),
            _ => None,
        }
    }

    /// The reason in words.
    pub(crate) fn reason(&self, judged: Judged) -> String {
        let (fitted, every) = match judged {
            Judged::Fitted => ("fitted", ""),
            Judged::FittedOnEveryFold => ("fitted", " in the fit of every fold"),
            Judged::ForecastOnEveryFold => ("forecast", " by one Gauss–Newton step on every fold from the model's fit"),
        };
        match self {
            Implausible::Beyond { what, value, bound, unit, scale } => {
                format!("{what} {fitted} at {value:.4}{unit}{every}, beyond the plausible {bound:.4}{unit} ({scale})")
            }
            Implausible::Rising { k_deg_per_nm, deflection_deg } => format!(
                "the compliance {fitted} at {k_deg_per_nm:.3e} °/N·m{every}: the joint would rise under its load, not sag ({deflection_deg:.2e}° at its largest gravity torque)"
            ),
            Implausible::Steep { slope } => format!(
                "its slope {fitted} at {slope:.3}{every} (the joint value would change by {:.0}% of the joint's own motion): not a correction of the joint — a robot model bounds one at {:.0}%",
                100.0 * slope,
                100.0 * MAX_CORRECTION_SLOPE
            ),
            Implausible::Instant { tau_min, during } => format!(
                "its time constant {fitted} at {tau_min:.3} min{every}: the drift is over (95 % of it) after {:.3} min, before all but {during} of the poses — indistinguishable from a static deviation in these data",
                3.0 * tau_min
            ),
        }
    }

    /// The refusal of `effect` for this value, with what was measured and what to do — and, for a value
    /// beyond its size, what the fit traded it with where that was measured ([`Trade`]).
    pub(crate) fn refused_trading(&self, effect: Effect, judged: Judged, trade: Option<&Trade>) -> Refusal {
        let mut r = self.refusal(effect, judged);
        if let (Some(t), Some(_)) = (trade, self.excess()) {
            r.reason = format!("{}; {}", r.reason, t.words());
        }
        r
    }

    /// The refusal of `effect` for this value, with what was measured and what to do.
    pub(crate) fn refusal(&self, effect: Effect, judged: Judged) -> Refusal {
        let remedy = match self {
            Implausible::Beyond { .. } => {
                "a value this large trades with another block or chases a few poses; if the robot truly deviates so much, raise the plausibility bound".into()
            }
            Implausible::Rising { .. } => {
                "no gravity compliance is seen here: what moves with the load is another effect".into()
            }
            Implausible::Instant { .. } => match effect.joint() {
                Some(j) => format!(
                    "the static row explains it: link_deviation[{n}] (or joint_offset[{n}]); measure more often early in the warm-up to see a fast drift",
                    n = j.number()
                ),
                None => "a static deviation explains it; measure more often early in the warm-up to see a fast drift".into(),
            },
            Implausible::Steep { .. } => {
                "the joint barely moves the measured point (typically a tool point near its axis): measure with a tool offset from the axis to see its errors".into()
            }
        };
        Refusal { effect: effect.label(), reason: self.reason(judged), remedy }
    }
}

/// What a fitted value beyond its size traded with: of the displacement the candidate's fitted values
/// give the measurements (`J_c (θ_c − θ_c⁰)` over the poses fitted), the share that lies in the
/// directions of the model's block most aligned with it (`‖P_b d‖² / ‖d‖²`), and in all the others
/// together ([`crate::scoring::Scorer::traded_with`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Trade {
    /// The block most aligned with the displacement.
    pub(crate) with: Effect,
    /// Its share of the displacement, 0–1.
    pub(crate) share: f64,
    /// The share of every other block together, 0–1.
    pub(crate) rest: f64,
    /// How many poses carry half of the displacement (`‖d‖²` summed over the poses it is largest at),
    /// and of how many.
    pub(crate) half_in: (usize, usize),
    /// The block's parameters.
    pub(crate) parameters: usize,
}

/// A share from which a block is said to be what a value traded with.
const TRADED: f64 = 0.5;

impl Trade {
    /// Whether a value beyond its size bound is the poses' own and stands: no block, nor the others
    /// together, spans half the displacement it gives the poses, and that displacement is not carried
    /// by a few poses — half of it in more poses than the block has parameters (a block of `p` can bend
    /// itself to any `p` poses; a gravity sag spreads over the workspace). The size bounds are an
    /// industrial arm's (a row, a deflection, a share of the arm's extent): an elastic robot's joints
    /// sag by degrees, and a value the fit did not trade with another block is what the poses show.
    pub(crate) fn stands(&self) -> bool {
        self.share < TRADED && self.rest < TRADED && !self.chases()
    }

    /// Whether half the displacement lies in no more poses than the block has parameters.
    fn chases(&self) -> bool {
        self.half_in.0 <= self.parameters
    }

    /// The trade in words: with one block, with several together, or with none (the value is the
    /// candidate's own).
    pub(crate) fn words(&self) -> String {
        let pct = |x: f64| 100.0 * x;
        if self.share >= TRADED {
            format!(
                "the fit traded it with {}: {:.0} % of the displacement its values give the poses lies in that block's directions",
                self.with.label(),
                pct(self.share)
            )
        } else if self.rest >= TRADED {
            format!(
                "the fit traded it with several blocks together: {:.0} % of the displacement its values give the poses lies in the model's other directions, at most {:.0} % in one ({})",
                pct(self.rest),
                pct(self.share),
                self.with.label()
            )
        } else if self.chases() {
            format!(
                "it traded with no block ({:.0} % at most of the displacement its values give the poses lies in the model's other directions), but half of that displacement lies in {} of the {} poses, no more than its {} parameters: it chases a few",
                pct(self.rest),
                self.half_in.0,
                self.half_in.1,
                self.parameters
            )
        } else {
            format!(
                "it traded with no block: {:.0} % at most of the displacement its values give the poses lies in the model's other directions — the poses show a displacement this large of this kind",
                pct(self.rest)
            )
        }
    }
}

/// What bounds a coupling (`v = [c]`) or a pair (`v = w`) of joint `a` and the next: the larger of the
/// two deflections it causes at the largest gravity torques, its name, and the lever it moves the tool
/// point at.
fn coupled_deflection(scale: &RobotScale, effect: Effect, a: usize, v: &[f64]) -> (&'static str, f64, f64) {
    let b = a + 1;
    if let Effect::CompliancePair(_) = effect {
        // Each joint's deflection `w_k (w_a τ_a + w_b τ_b)` at the largest torques of both, at its own
        // lever: the larger of the two.
        let load = (v[0] * scale.max_torque_nm[a]).abs() + (v[1] * scale.max_torque_nm[b]).abs();
        let (da, db) = ((v[0] * load).abs(), (v[1] * load).abs());
        let (la, lb) = (scale.axis_lever_mm[a].max(1.0), scale.axis_lever_mm[b].max(1.0));
        let (deflection, lever) = if da * la >= db * lb { (da, la) } else { (db, lb) };
        return ("the pair's deflection at the largest gravity torques", deflection, lever);
    }
    // A coupling: the larger of the two deflections it causes, each at its own joint's lever (no sign
    // rule: an off-diagonal compliance may take either).
    let what = "the coupled deflection at the largest gravity torque";
    let c = v[0];
    let moved = |from: usize, at: usize| (c * scale.max_torque_nm[from]).abs() * scale.axis_lever_mm[at].max(1.0);
    if moved(b, a) >= moved(a, b) {
        (what, c * scale.max_torque_nm[b], scale.axis_lever_mm[a].max(1.0))
    } else {
        (what, c * scale.max_torque_nm[a], scale.axis_lever_mm[b].max(1.0))
    }
}

/// The bound's test of [`implausible`]: `(what, value, moved mm, lever, unit)`.
type Over<'a> = dyn Fn(&'static str, f64, f64, f64, &'static str) -> Option<Implausible> + 'a;
/// What a bound on a row's six values (`v`, times `per`: a reading) says at `lever`: its translation
/// (mm) or its rotation (as the displacement at the lever), `words` naming each.
fn row_bound(v: &[f64], per: f64, lever: f64, words: [&'static str; 2], over: &Over<'_>) -> Option<Implausible> {
    let t = per * v[..3].iter().map(|x| x * x).sum::<f64>().sqrt();
    let r = per * v[3..6].iter().map(|x| x * x).sum::<f64>().sqrt();
    over(words[0], t, t, lever, " mm").or_else(|| over(words[1], units::degrees(r), r * lever, lever, "°"))
}

/// Whether the values `v` of `effect` (internal units) are implausible for a robot of `scale` under the
/// bound `p`, and why.
pub(crate) fn implausible(scale: &RobotScale, v: &[f64], effect: Effect, p: &Plausibility) -> Option<Implausible> {
    let allowed_mm = p.displacement_of_extent * scale.extent_mm;
    let why = |lever: f64| {
        format!(
            "{:.1} mm at the tool point, {:.0}% of the arm's {:.0} mm extent, at a {lever:.0} mm lever",
            allowed_mm,
            100.0 * p.displacement_of_extent,
            scale.extent_mm
        )
    };
    let over = |what: &'static str, value: f64, moved_mm: f64, lever: f64, unit: &'static str| {
        (moved_mm > allowed_mm).then(|| Implausible::Beyond {
            what,
            value,
            bound: value.abs() * allowed_mm / moved_mm,
            unit,
            scale: why(lever),
        })
    };
    let lever_of = |j: thermokin_identify::JointIndex| scale.lever_mm[j.index()].max(1.0);
    let deg = units::degrees;
    match effect {
        Effect::LinkDeviation(j) | Effect::ThermalDrift(j, _) => {
            if effect == Effect::ThermalDrift(j, DriftShape::Exponential) && !scale.times_min.is_empty() {
                let during = scale.times_min.partition_point(|&t| t < 3.0 * v[6]);
                if during < effect.len() {
                    return Some(Implausible::Instant { tau_min: v[6], during });
                }
            }
            row_bound(v, 1.0, lever_of(j), ["its translation", "its rotation"], &over)
        }
        Effect::SensorDrift(j, sensor) => {
            // Per unit of the reading: bounded as a row's deviation at the largest reading of the data.
            let most = scale.sensor_reach.get(sensor.index()).copied().unwrap_or(0.0);
            let words = ["its translation at the largest reading", "its rotation at the largest reading"];
            row_bound(v, most, lever_of(j), words, &over)
        }
        // A measured tilt has no gain to run away; its pivot does: the shift it gives the row at the
        // largest tilt of the data (its mounting yaw is any angle).
        Effect::Tilt(_, sensor, _) => {
            let reach = |c: usize| scale.sensor_reach.get(sensor.index() + c).copied().unwrap_or(0.0);
            let most = reach(0).hypot(reach(1)).hypot(reach(2));
            let pivot = v[1].hypot(v[2]).hypot(v[3]);
            over("the distance of its pivot from the row", pivot, pivot * most, scale.extent_mm.max(1.0), "mm")
        }
        // A knocked tracker or a moved base: bounded as a row's deviation at the arm's extent.
        Effect::FrameStep(_) => row_bound(v, 1.0, scale.extent_mm.max(1.0), ["its translation", "its rotation"], &over),
        Effect::ComplianceCoupling(j) | Effect::CompliancePair(j) => {
            let (what, deflection, lever) = coupled_deflection(scale, effect, j.index(), v);
            over(what, deg(deflection), deflection.abs() * lever, lever, "°")
        }
        Effect::LateralCompliance(j, n) => {
            let (tilt, moved) = lateral_reach(scale, j.index(), n, v);
            over("the tilt at the largest moment across the joint", deg(tilt), moved, lever_of(j), "°")
        }
        Effect::Straightness(j) => {
            // At the full extension the data reach: the turn (tilts and roll) at the row's lever, the bow
            // as it is.
            let d = scale.reach[j.index()];
            let turn = (v[0].hypot(v[1]) + v[2].abs()) * d;
            let moved = turn * lever_of(j) + v[3].hypot(v[4]) * d * d;
            over("the turn of the carriage at the full extension", deg(turn), moved, lever_of(j), "°")
        }
        Effect::LumpedLateralCompliance(j, _, support) => {
            // How far its tilt changes over the data's poses (a column's bend at each pose's extension
            // added, and its shift moving the row as it is), at the row's lever.
            let loads = scale.loads.get(j.index())?;
            let (tilt, moved) = loads.tilt_change(v, support.sets(), lever_of(j));
            over("the change of its tilt under gravity over the data", deg(tilt), moved, lever_of(j), "°")
        }
        Effect::LumpedCompliance(j, _) => {
            // How far its deflection changes over the data's poses, at the joint's axis lever.
            let lever = scale.axis_lever_mm[j.index()].max(1.0);
            let deflection = scale.loads.get(j.index())?.deflection_change(v);
            let what = "the change of its deflection under gravity over the data";
            over(what, deg(deflection), deflection * lever, lever, "°")
        }
        Effect::BranchLoad(j, _, at) => {
            branch_load_bound(scale, v, (j.index(), at.branch as usize, at.lateral), lever_of(j), &over)
        }
        Effect::JointOffset(j)
        | Effect::Backlash(j)
        | Effect::JointScale(j)
        | Effect::Periodic(j)
        | Effect::JointCompliance(j) => joint_level(scale, v, effect, j, &over),
        _ => None,
    }
}

/// A branch's load on joint `j` ([`Effect::BranchLoad`]): how far it moves the joint over the data's
/// poses, at the joint's axis lever — or, across the joint, how far it tilts the row (the two directions'
/// changes together), at the row's lever `row_lever`.
fn branch_load_bound(
    scale: &RobotScale,
    v: &[f64],
    (j, branch, across): (usize, usize, bool),
    row_lever: f64,
    over: &Over<'_>,
) -> Option<Implausible> {
    let (.., len, values) = scale.branch_loads.iter().find(|(k, b, a, ..)| *k == j && *b == branch && *a == across)?;
    if across {
        // The tilts along the two directions, each a half of the functions and the weights.
        let tilts: Vec<[f64; 2]> = values.chunks(*len).map(|f| thermokin_deform::lumped_tilts(f, v)).collect();
        let change = |k: usize| {
            let (lo, hi) = crate::stats::span(tilts.iter().map(|t| t[k]));
            if lo <= hi { hi - lo } else { 0.0 }
        };
        let tilt = change(0).hypot(change(1));
        let what = "the change of its tilt under the branch's load over the data";
        return over(what, units::degrees(tilt), tilt * row_lever, row_lever, "°");
    }
    let lever = scale.axis_lever_mm[j].max(1.0);
    let deflection = weighted_change(values, *len, v);
    let what = "the change of the joint under the branch's load over the data";
    over(what, units::degrees(deflection), deflection * lever, lever, "°")
}

/// The effects that move the joint value itself (an offset, a backlash, a scale, a cyclic error, a
/// compliance about the axis): the largest motion of the joint over the data at its lever.
fn joint_level(
    scale: &RobotScale,
    v: &[f64],
    effect: Effect,
    j: thermokin_identify::JointIndex,
    over: &Over<'_>,
) -> Option<Implausible> {
    let deg = units::degrees;
    let lever = scale.axis_lever_mm[j.index()].max(1.0);
    let revolute = scale.revolute[j.index()];
    // The largest joint motion the values cause over the data (radians, or mm for a prismatic
    // joint), and the value reported.
    let (what, value, unit, motion) = match effect {
        Effect::JointOffset(_) if revolute => ("the offset", deg(v[0]), "°", v[0].abs()),
        Effect::JointOffset(_) => ("the offset", v[0], " mm", v[0].abs()),
        Effect::Backlash(_) if revolute => ("the half play", deg(v[0]), "°", v[0].abs()),
        Effect::Backlash(_) => ("the half play", v[0], " mm", v[0].abs()),
        Effect::JointScale(_) => ("the scale error", v[0], "", (v[0] * scale.reach[j.index()]).abs()),
        Effect::Periodic(_) => {
            let amplitude = v[0].hypot(v[1]) + v[2].hypot(v[3]);
            ("a cyclic amplitude", deg(amplitude), "°", amplitude)
        }
        _ => {
            let deflection = v[0] * scale.max_torque_nm[j.index()];
            if v[0] < 0.0 {
                return Some(Implausible::Rising { k_deg_per_nm: deg(v[0]), deflection_deg: deg(deflection) });
            }
            ("the deflection at the largest gravity torque", deg(deflection), "°", deflection)
        }
    };
    // A gear-ratio or cyclic error changes the joint value by at most its slope per unit of motion
    // (`|s|`, and `2 Σ|aₖ|` bounding the twice-per-revolution terms' derivative as the robot model
    // does): beyond the robot model's bound it is not a correction of the joint but another joint,
    // whatever little it moves a tool point that sits near the axis.
    let slope = match effect {
        Effect::JointScale(_) => v[0].abs(),
        Effect::Periodic(_) => 2.0 * v[..4].iter().map(|a| a.abs()).sum::<f64>(),
        _ => 0.0,
    };
    if slope > MAX_CORRECTION_SLOPE {
        return Some(Implausible::Steep { slope });
    }
    let moved = if revolute { motion * lever } else { motion };
    over(what, value, moved, lever, unit)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use thermokin_chain::Robot;
    use thermokin_identify::{Effect, JointIndex};

    use super::{Implausible, RobotScale, implausible};
    use crate::config::Plausibility;

    /// A 1 m arm whose tool point sits 1 mm from joint 6's axis: a gear-ratio or cyclic error there moves
    /// the point by almost nothing, so only its slope can say that it is not a correction of the joint.
    #[test]
    fn a_joint_correction_steeper_than_a_robot_file_allows_is_refused_however_little_it_moves() {
        let robot = Robot::new("irb140", thermokin_testdata::irb140_table9());
        let scale = RobotScale { axis_lever_mm: vec![1000.0, 1000.0, 800.0, 500.0, 300.0, 1.0], ..metre_arm() };
        let j6 = JointIndex::of(&robot, 5).unwrap();
        let p = Plausibility::default();
        // A scale of 0.3 (30 % of the joint's motion) moves the point by ~1 mm over ±180°: within 2 % of
        // the extent, and still refused for its slope.
        let steep = implausible(&scale, &[0.3], Effect::JointScale(j6), &p);
        assert!(matches!(steep, Some(Implausible::Steep { slope }) if (slope - 0.3).abs() < 1e-12), "{steep:?}");
        // Cyclic terms bound by 2 Σ|a|: 0.03 + 0.03 rad → 0.12.
        let cyclic = implausible(&scale, &[0.03, -0.03, 0.0, 0.0], Effect::Periodic(j6), &p);
        assert!(matches!(cyclic, Some(Implausible::Steep { .. })), "{cyclic:?}");
        // A real gear-ratio error (1e-3) is a correction.
        assert_eq!(implausible(&scale, &[1e-3], Effect::JointScale(j6), &p), None);
        assert_eq!(implausible(&scale, &[0.02, 0.0, 0.0, 0.01], Effect::Periodic(j6), &p), None);
    }

    /// An exponential drift with τ = 0.1 min in a three-hour session whose poses came at irregular times
    /// (two of them a thousandth of a minute apart): over after 0.3 min, before all but one pose — a
    /// static row, whatever the smallest gap between two poses. A drift of τ = 30 min, under way for the
    /// first 90 minutes' poses, is a drift.
    #[test]
    fn a_drift_over_before_all_but_a_pose_is_static_however_close_two_poses_came() {
        let robot = Robot::new("irb140", thermokin_testdata::irb140_table9());
        let mut times: Vec<f64> = (0..300).map(|i| 0.6 * i as f64).collect();
        times[101] = times[100] + 0.001;
        let scale = RobotScale { times_min: times, ..metre_arm() };
        let drift =
            Effect::ThermalDrift(JointIndex::of(&robot, 2).unwrap(), thermokin_identify::DriftShape::Exponential);
        let p = Plausibility::default();
        let fast = implausible(&scale, &[0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1], drift, &p);
        assert_eq!(fast, Some(Implausible::Instant { tau_min: 0.1, during: 1 }));
        let refusal = fast.unwrap().refusal(drift, super::Judged::Fitted);
        assert!(refusal.remedy.contains("link_deviation[3]"), "{}", refusal.remedy);
        assert_eq!(implausible(&scale, &[0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 30.0], drift, &p), None);
    }

    /// A 6-joint arm of 1 m extent, every lever 1 m, no gravity, no time, no sensor.
    fn metre_arm() -> RobotScale {
        RobotScale {
            extent_mm: 1000.0,
            lever_mm: vec![1000.0; 6],
            axis_lever_mm: vec![1000.0; 6],
            max_torque_nm: vec![0.0; 6],
            reach: vec![std::f64::consts::PI; 6],
            revolute: vec![true; 6],
            times_min: Vec::new(),
            sensor_reach: Vec::new(),
            max_lateral_nm: vec![0.0; 6],
            loads: Vec::new(),
            branch_loads: Vec::new(),
        }
    }

    /// A compliance without masses is bounded by how far its deflection changes over the data's poses,
    /// not by the sum of its weights: on an IRB 140 without masses whose joint 2 moves over ±0.6 rad,
    /// joint 2's weights along the direction its functions are least excited over the data (the last
    /// right singular vector of their matrix, here), summing to 1 rad (57°), change its deflection by
    /// what the data's poses give them (computed here from the functions): plausible, where the sum alone
    /// is far beyond the bound. Scaled to 1.5× the bound over the data they are refused; to half, not.
    #[test]
    fn a_lumped_compliance_is_bounded_by_what_it_does_over_the_data() {
        use thermokin_chain::{Dataset, Measurement};
        let robot = Robot::new("irb140", thermokin_testdata::irb140_table9());
        let measurements = (0..50)
            .map(|i| Measurement {
                time_min: 0.0,
                q: vec![0.0, -0.6 + 1.2 * i as f64 / 49.0, 0.3 + 0.4 * (i % 3) as f64, 0.0, 0.4, 0.0],
                position_mm: nalgebra::Vector3::zeros(),
                orientation: None,
                position_std_mm: None,
                temps: Vec::new(),
            })
            .collect();
        let data = Dataset { measurements, ..Dataset::default() };
        let scale = RobotScale::of(&robot, &data);
        let j2 = JointIndex::of(&robot, 1).unwrap();
        let e = Effect::lumped_compliance(&robot, j2).unwrap();
        let down = -nalgebra::Vector3::z_axis();
        let (mut basis, mut rows) = (Vec::new(), Vec::new());
        for m in &data.measurements {
            thermokin_chain::gravity_load_basis_into(robot.chain(), &m.q, None, &down, 1, &mut basis).unwrap();
            rows.extend_from_slice(&basis);
        }
        let n = e.len();
        let a = nalgebra::DMatrix::from_row_slice(data.len(), n, &rows);
        let svd = a.clone().svd(false, true);
        let last = svd.singular_values.imin();
        let v: Vec<f64> = svd.v_t.unwrap().row(last).iter().copied().collect();
        let norm1 = v.iter().map(|x| x.abs()).sum::<f64>();
        let w: Vec<f64> = v.iter().map(|x| x / norm1).collect();
        // How far the deflection changes over the data (what an offset cannot take).
        let deflection = |w: &[f64]| {
            let d = &a * nalgebra::DVector::from_column_slice(w);
            d.max() - d.min()
        };
        let p = Plausibility::default();
        let allowed_rad = p.displacement_of_extent * scale.extent_mm / scale.axis_lever_mm[1];
        let small = deflection(&w);
        assert!(small < 0.1 * allowed_rad && allowed_rad < 0.1, "{small} {allowed_rad}");
        assert_eq!(implausible(&scale, &w, e, &p), None);
        let scaled = |k: f64| w.iter().map(|x| x * k * allowed_rad / small).collect::<Vec<f64>>();
        assert!(matches!(implausible(&scale, &scaled(1.5), e, &p), Some(Implausible::Beyond { .. })));
        assert_eq!(implausible(&scale, &scaled(0.5), e, &p), None);
    }

    #[test]
    fn a_sensors_row_is_bounded_at_the_largest_reading() {
        let robot = Robot::new("irb140", thermokin_testdata::irb140_table9());
        let scale = RobotScale { sensor_reach: vec![50.0], ..metre_arm() };
        let data = thermokin_chain::Dataset { sensor_names: vec!["acc".into()], ..Default::default() };
        let sensor = thermokin_identify::SensorId::of(&data, 0).unwrap();
        let e = Effect::SensorDrift(JointIndex::of(&robot, 1).unwrap(), sensor);
        let p = Plausibility::default();
        // 0.5 mm per unit is 25 mm at the largest reading: beyond 2 % of a 1 m arm (20 mm); 0.3 mm per
        // unit (15 mm) is not — whatever the per-unit value alone would say.
        let at = |v: f64| implausible(&scale, &[v, 0.0, 0.0, 0.0, 0.0, 0.0], e, &p);
        assert!(matches!(at(0.5), Some(Implausible::Beyond { .. })), "{:?}", at(0.5));
        assert_eq!(at(0.3), None);
    }
}
