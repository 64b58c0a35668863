//! The parameterised model: effects as parameter blocks on top of a chain, the prediction of a measured
//! TCP position and its analytic Jacobian (from [`Chain::parameter_jacobian`]).

use nalgebra::{Isometry3, Matrix3xX, Vector3};
use serde::Serialize;
use thermokin_chain::{Chain, ErrorParams, JointKind, LinkMass};

use crate::{Dataset, DiagnoseError, Measurement};

/// How a thermal drift grows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, PartialOrd, Ord)]
pub enum DriftShape {
    /// `δ · t / 180 min`.
    Linear,
    /// `δ · (1 − e^(−t/τ)) / (1 − e^(−180/τ))` with τ fitted: δ is the deviation at 180 minutes.
    Exponential,
    /// `δ · (T(t) − T(0))` per kelvin of the mean logged temperature rise.
    Temperature,
}

/// A kind of effect: a block of parameters that can be added to the model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, PartialOrd, Ord)]
pub enum EffectKind {
    /// The tracker registration (tracker frame): always estimated, never reported as an effect.
    Registration,
    /// An unknown tool point: always estimated, never reported as an effect.
    ToolPoint,
    /// A base misalignment (6).
    BaseFrame,
    /// A tool-point error (3: positions carry no tool orientation).
    ToolFrame,
    /// A joint's zero offset (1).
    JointOffset,
    /// The paper's six error parameters of a joint (6).
    LinkDeviation,
    /// Gravity compliance of a joint: Δq = k · τ_gravity(q) (1).
    JointCompliance,
    /// A link deviation growing with operating time or temperature (6, +1 for τ).
    ThermalDrift(DriftShape),
}

/// An effect: a kind, on a joint where it has one (0-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Effect {
    /// The kind.
    pub kind: EffectKind,
    /// The joint (0-based) for per-joint kinds.
    pub joint: Option<usize>,
}

impl Effect {
    /// A whole-robot effect.
    pub fn global(kind: EffectKind) -> Self {
        Self { kind, joint: None }
    }
    /// A per-joint effect.
    pub fn at(kind: EffectKind, joint: usize) -> Self {
        Self { kind, joint: Some(joint) }
    }

    /// Number of parameters.
    pub fn len(&self) -> usize {
        match self.kind {
            EffectKind::Registration | EffectKind::BaseFrame | EffectKind::LinkDeviation => 6,
            EffectKind::ThermalDrift(DriftShape::Exponential) => 7,
            EffectKind::ThermalDrift(_) => 6,
            EffectKind::ToolPoint | EffectKind::ToolFrame => 3,
            EffectKind::JointOffset | EffectKind::JointCompliance => 1,
        }
    }

    /// Never empty.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The name used in reports: `joint_offset` etc.
    pub fn kind_name(&self) -> &'static str {
        match self.kind {
            EffectKind::Registration => "registration",
            EffectKind::ToolPoint => "tool_point",
            EffectKind::BaseFrame => "base_frame",
            EffectKind::ToolFrame => "tool_frame",
            EffectKind::JointOffset => "joint_offset",
            EffectKind::LinkDeviation => "link_deviation",
            EffectKind::JointCompliance => "joint_compliance",
            EffectKind::ThermalDrift(_) => "thermal_drift",
        }
    }

    /// Checks the effect against a robot of `dof` joints: a per-joint kind (offset, link deviation,
    /// compliance, thermal drift) needs a joint in `0..dof`, a whole-robot kind none. An effect that fails
    /// this would index past the chain.
    pub fn validate(&self, dof: usize) -> Result<(), DiagnoseError> {
        let per_joint = matches!(
            self.kind,
            EffectKind::JointOffset
                | EffectKind::LinkDeviation
                | EffectKind::JointCompliance
                | EffectKind::ThermalDrift(_)
        );
        match (per_joint, self.joint) {
            (true, Some(j)) if j < dof => Ok(()),
            (false, None) => Ok(()),
            (true, Some(j)) => {
                Err(DiagnoseError::Input(format!("{}: joint {} is not in 1..={dof}", self.kind_name(), j + 1)))
            }
            (true, None) => Err(DiagnoseError::Input(format!("{} needs a joint", self.kind_name()))),
            (false, Some(_)) => {
                Err(DiagnoseError::Input(format!("{} acts on the whole robot, not a joint", self.kind_name())))
            }
        }
    }

    /// `joint_offset[3]`, `thermal_drift[2] (exponential)`, `base_frame`.
    pub fn label(&self) -> String {
        let shape = match self.kind {
            EffectKind::ThermalDrift(DriftShape::Linear) => " (linear)",
            EffectKind::ThermalDrift(DriftShape::Exponential) => " (exponential)",
            EffectKind::ThermalDrift(DriftShape::Temperature) => " (temperature)",
            _ => "",
        };
        match self.joint {
            Some(j) => format!("{}[{}]{shape}", self.kind_name(), j + 1),
            None => format!("{}{shape}", self.kind_name()),
        }
    }

    /// The names of this effect's parameters, with units.
    pub fn parameter_names(&self) -> Vec<String> {
        let six = ["dx_mm", "dy_mm", "dz_mm", "rx_deg", "ry_deg", "rz_deg"];
        let base = self.label();
        match self.kind {
            EffectKind::ToolPoint | EffectKind::ToolFrame => six[..3].iter().map(|n| format!("{base}.{n}")).collect(),
            EffectKind::JointOffset => vec![format!("{base}.offset_deg")],
            EffectKind::JointCompliance => vec![format!("{base}.k_deg_per_Nm")],
            EffectKind::ThermalDrift(DriftShape::Exponential) => {
                let mut v: Vec<String> = six.iter().map(|n| format!("{base}.{n}")).collect();
                v.push(format!("{base}.tau_min"));
                v
            }
            _ => six.iter().map(|n| format!("{base}.{n}")).collect(),
        }
    }

    /// Time-dependent effects are judged with forward-chained cross-validation too.
    pub fn is_time_dependent(&self) -> bool {
        matches!(self.kind, EffectKind::ThermalDrift(_))
    }

    /// Reported to the user as a cause (not a nuisance block).
    pub fn is_reported(&self) -> bool {
        !matches!(self.kind, EffectKind::Registration | EffectKind::ToolPoint)
    }

    /// Internal parameter units → report units (mm, degrees, minutes, degrees per N·m).
    pub fn to_report_units(&self, k: usize, v: f64) -> f64 {
        match self.kind {
            EffectKind::JointOffset => v.to_degrees(),
            EffectKind::JointCompliance => v.to_degrees(),
            EffectKind::ToolPoint | EffectKind::ToolFrame => v,
            EffectKind::ThermalDrift(DriftShape::Exponential) if k == 6 => v,
            _ if k >= 3 => v.to_degrees(),
            _ => v,
        }
    }
}

/// Reference time of the linear drift: the parameters are the deviation at 180 minutes (section 4).
pub const LINEAR_DRIFT_REFERENCE_MIN: f64 = 180.0;
/// Largest time constant considered, minutes: beyond it the exponential is indistinguishable from the
/// linear drift over any warm-up a user measures.
const MAX_TAU_MIN: f64 = 1e4;
/// Initial time constant of an exponential drift, minutes.
const INITIAL_TAU_MIN: f64 = 60.0;

/// The fixed parts of a model: the chain the effects act on, link masses, and the initial registration.
#[derive(Clone, Debug)]
pub struct Base {
    /// The robot, known deviations included.
    pub chain: Chain,
    /// Link masses for gravity compliance.
    pub masses: Vec<Option<LinkMass>>,
}

/// A model: the base plus a list of effects, and the parameter vector's layout.
#[derive(Clone, Debug)]
pub struct Model {
    /// Effects in parameter order.
    pub effects: Vec<Effect>,
    /// First parameter of each effect.
    pub offsets: Vec<usize>,
    /// Total parameters.
    pub len: usize,
    /// The tracker registration's starting pose (identity in the base frame).
    pub registration: Isometry3<f64>,
}

impl Model {
    /// A model with these effects.
    pub fn new(effects: Vec<Effect>, registration: Isometry3<f64>) -> Self {
        let mut offsets = Vec::with_capacity(effects.len());
        let mut len = 0;
        for e in &effects {
            offsets.push(len);
            len += e.len();
        }
        Self { effects, offsets, len, registration }
    }

    /// The initial parameter vector (zeros, τ at its starting value).
    pub fn initial(&self) -> Vec<f64> {
        let mut theta = vec![0.0; self.len];
        for (e, &o) in self.effects.iter().zip(&self.offsets) {
            if e.kind == EffectKind::ThermalDrift(DriftShape::Exponential) {
                theta[o + 6] = INITIAL_TAU_MIN;
            }
        }
        theta
    }

    /// Names of all parameters.
    pub fn parameter_names(&self) -> Vec<String> {
        self.effects.iter().flat_map(Effect::parameter_names).collect()
    }

    fn drift_factor(shape: DriftShape, m: &Measurement, temp_rise: f64, tau: f64) -> (f64, f64) {
        match shape {
            DriftShape::Linear => (m.time_min / LINEAR_DRIFT_REFERENCE_MIN, 0.0),
            DriftShape::Exponential => {
                // Normalised at the reference time: s(t) = A(t) / A(180) with A(x) = 1 − e^(−x/τ), so that
                // the six amplitudes are the deviation reached at 180 minutes (as for the linear drift) and
                // a very slow exponential tends to the linear drift instead of trading a huge amplitude
                // against a huge τ.
                let tau = tau.clamp(1e-3, MAX_TAU_MIN);
                let a = |x: f64| -(-x / tau).exp_m1();
                let da = |x: f64| -(-x / tau).exp() * x / (tau * tau);
                let (at, ar) = (a(m.time_min), a(LINEAR_DRIFT_REFERENCE_MIN));
                let ds = (da(m.time_min) * ar - at * da(LINEAR_DRIFT_REFERENCE_MIN)) / (ar * ar);
                (at / ar, ds)
            }
            DriftShape::Temperature => (temp_rise, 0.0),
        }
    }

    /// Predicted TCP position of one measurement and, if asked, its 3 × len Jacobian.
    pub fn predict(
        &self,
        base: &Base,
        theta: &[f64],
        m: &Measurement,
        temp_rise: f64,
        torques: &[f64],
        jacobian: Option<&mut Matrix3xX<f64>>,
        cache: &mut Option<Chain>,
    ) -> Result<Vector3<f64>, DiagnoseError> {
        let chain = &base.chain;
        let mut base_err = chain.base().error;
        let mut tool_err = chain.tool().error;
        let mut joint_err: Vec<ErrorParams> = chain.joints().iter().map(|j| j.error).collect();
        let mut zeros: Vec<f64> = chain.joints().iter().map(|j| j.zero).collect();
        let mut q = m.q.clone();
        let mut drift_scale: Vec<(usize, f64, f64)> = Vec::new(); // (effect index, s, ds/dτ)
        let six = |o: usize| {
            ErrorParams::from_array([theta[o], theta[o + 1], theta[o + 2], theta[o + 3], theta[o + 4], theta[o + 5]])
        };
        for (k, (e, &o)) in self.effects.iter().zip(&self.offsets).enumerate() {
            match e.kind {
                EffectKind::Registration | EffectKind::BaseFrame => base_err = base_err.add(&six(o)),
                EffectKind::ToolPoint | EffectKind::ToolFrame => {
                    tool_err.translation += Vector3::new(theta[o], theta[o + 1], theta[o + 2]);
                }
                EffectKind::JointOffset => zeros[e.joint.unwrap_or(0)] += theta[o],
                EffectKind::LinkDeviation => {
                    let j = e.joint.unwrap_or(0);
                    joint_err[j] = joint_err[j].add(&six(o));
                }
                EffectKind::JointCompliance => {
                    let j = e.joint.unwrap_or(0);
                    q[j] += theta[o] * torques[j];
                }
                EffectKind::ThermalDrift(shape) => {
                    let j = e.joint.unwrap_or(0);
                    let tau = if shape == DriftShape::Exponential { theta[o + 6] } else { 0.0 };
                    let (s, ds) = Self::drift_factor(shape, m, temp_rise, tau);
                    joint_err[j] = joint_err[j].add(&six(o).scaled(s));
                    drift_scale.push((k, s, ds));
                }
            }
        }
        // Without a drift the deformed chain is the same for every measurement: build it once per
        // parameter vector (the caller keeps the cache for one evaluation).
        let per_measurement = !drift_scale.is_empty();
        let built;
        let registered: &Chain = match cache {
            Some(c) if !per_measurement => c,
            _ => {
                let mut c = chain.with_errors_and_zeros(base_err, &joint_err, tool_err, &zeros)?;
                if self.registration != Isometry3::identity() {
                    // The registration's large rotation sits in the base row's nominal pose; its
                    // parameters are small corrections on top.
                    let mut row = c.base().clone();
                    let nominal = self.registration * row.nominal();
                    row.translation = nominal.translation.vector;
                    row.rotation = nominal.rotation;
                    c = c.with_base(row)?;
                }
                if per_measurement {
                    built = c;
                    &built
                } else {
                    cache.insert(c)
                }
            }
        };
        let p = registered.tool_position_rotation(&q)?.0;
        if let Some(jac) = jacobian {
            let pj = registered.parameter_jacobian(&q)?;
            let layout = registered.parameter_layout();
            jac.fill(0.0);
            let mut drift = drift_scale.iter();
            for (k, (e, &o)) in self.effects.iter().zip(&self.offsets).enumerate() {
                let mut copy = |dst: usize, src: usize, scale: f64| {
                    for r in 0..3 {
                        jac[(r, dst)] = pj[(r, src)] * scale;
                    }
                };
                match e.kind {
                    EffectKind::Registration | EffectKind::BaseFrame => {
                        (0..6).for_each(|c| copy(o + c, layout.base() + c, 1.0))
                    }
                    EffectKind::ToolPoint | EffectKind::ToolFrame => {
                        (0..3).for_each(|c| copy(o + c, layout.tool() + c, 1.0))
                    }
                    EffectKind::JointOffset => copy(o, layout.zero(e.joint.unwrap_or(0)), 1.0),
                    EffectKind::LinkDeviation => {
                        (0..6).for_each(|c| copy(o + c, layout.joint(e.joint.unwrap_or(0)) + c, 1.0))
                    }
                    EffectKind::JointCompliance => {
                        let j = e.joint.unwrap_or(0);
                        let scale = if chain.joints()[j].kind == JointKind::Revolute { torques[j] } else { 0.0 };
                        copy(o, layout.zero(j), scale);
                    }
                    EffectKind::ThermalDrift(shape) => {
                        let j = e.joint.unwrap_or(0);
                        let &(_, s, ds) = drift.next().filter(|d| d.0 == k).unwrap_or(&(k, 0.0, 0.0));
                        (0..6).for_each(|c| copy(o + c, layout.joint(j) + c, s));
                        if shape == DriftShape::Exponential {
                            for r in 0..3 {
                                let mut v = 0.0;
                                for c in 0..6 {
                                    v += pj[(r, layout.joint(j) + c)] * theta[o + c] * ds;
                                }
                                jac[(r, o + 6)] = v;
                            }
                        }
                    }
                }
            }
        }
        Ok(p)
    }
}

/// Gravity torque about each joint's axis at configuration `q`, N·m, from the link masses (gravity along
/// the base's −Z): `τ_j = z_j · Σ_{l ≥ j} (c_l − o_j) × m_l g`.
pub fn gravity_torques(chain: &Chain, masses: &[Option<LinkMass>], q: &[f64]) -> Vec<f64> {
    let n = chain.dof();
    let Ok(frames) = chain.joint_frames(q) else { return vec![0.0; n] };
    let g = Vector3::new(0.0, 0.0, -9.81);
    let coms: Vec<Option<(f64, Vector3<f64>)>> = (0..n)
        .map(|l| {
            masses.get(l).copied().flatten().map(|m| (m.mass_kg, (frames[l] * nalgebra::Point3::from(m.com_mm)).coords))
        })
        .collect();
    (0..n)
        .map(|j| {
            let z = frames[j].rotation * chain.joints()[j].axis.into_inner();
            let o = frames[j].translation.vector;
            let mut moment = Vector3::zeros();
            for (m, c) in coms.iter().skip(j).flatten() {
                moment += (c - o).cross(&(g * *m));
            }
            z.dot(&moment) / 1000.0 // N·mm → N·m
        })
        .collect()
}

/// Per-measurement quantities that do not depend on the parameters: gravity torques and temperature rise.
pub(crate) fn prepare(base: &Base, data: &Dataset) -> (Vec<Vec<f64>>, Vec<f64>) {
    let torques = data.measurements.iter().map(|m| gravity_torques(&base.chain, &base.masses, &m.q)).collect();
    let first: Option<Vec<f64>> =
        data.measurements.iter().min_by(|a, b| a.time_min.total_cmp(&b.time_min)).map(|m| m.temps.clone());
    let rise = data
        .measurements
        .iter()
        .map(|m| match &first {
            Some(t0) if !m.temps.is_empty() => {
                m.temps.iter().zip(t0).map(|(a, b)| a - b).sum::<f64>() / m.temps.len() as f64
            }
            _ => 0.0,
        })
        .collect();
    (torques, rise)
}
