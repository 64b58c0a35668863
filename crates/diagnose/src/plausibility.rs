//! Physical plausibility of fitted values: a candidate whose values exceed the bounds of
//! [`Plausibility`] is a fit running away (trading against another block, or chasing a few poses), not a
//! property of a working robot.

use thermokin_chain::{Robot, units};
use thermokin_identify::{Effect, max_gravity_torque};

use crate::config::Plausibility;
use crate::report::Refusal;

/// A fitted value beyond its bound.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Implausible {
    /// What exceeded its bound ("its translation", "the offset", …).
    what: &'static str,
    /// The value, in `unit`.
    value: f64,
    /// The bound, in `unit`.
    bound: f64,
    /// The unit of both ("mm", "°", or none).
    unit: &'static str,
}

/// How a value judged implausible was obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Judged {
    /// Fitted on all data.
    Fitted,
    /// Fitted on every fold of the selection.
    FittedOnEveryFold,
    /// Predicted by one linearised step on all data (the screen).
    LinearisedStep,
}

impl Implausible {
    /// The reason in words.
    pub(crate) fn reason(&self, judged: Judged) -> String {
        let Self { what, value, bound, unit } = self;
        let beyond = format!("(beyond the plausible {bound} {unit})");
        match judged {
            Judged::Fitted => format!("{what} fitted at {value:.4} {unit} {beyond}"),
            Judged::FittedOnEveryFold => {
                format!("{what} fitted at {value:.4} {unit} {beyond} in the fit of every fold")
            }
            Judged::LinearisedStep => {
                format!("one linearised step on all data puts {what} at {value:.4} {unit} {beyond}")
            }
        }
    }

    /// The refusal of `effect` for this value.
    pub(crate) fn refusal(&self, effect: Effect, judged: Judged) -> Refusal {
        Refusal {
            effect: effect.label(),
            reason: self.reason(judged),
            remedy: "check the robot description (masses, link lengths) and the units of the data".into(),
        }
    }
}

/// Whether the values `v` of `effect` (internal units) exceed the bounds `p`, and which.
pub(crate) fn implausible(robot: &Robot, v: &[f64], effect: Effect, p: &Plausibility) -> Option<Implausible> {
    let deg = units::degrees;
    let over = |what: &'static str, value: f64, bound: f64, unit: &'static str| {
        (value.abs() > bound).then_some(Implausible { what, value, bound, unit })
    };
    match effect {
        Effect::LinkDeviation(_) | Effect::ThermalDrift(..) => {
            let t = v[..3].iter().map(|x| x * x).sum::<f64>().sqrt();
            let r = deg(v[3..6].iter().map(|x| x * x).sum::<f64>().sqrt());
            over("its translation", t, p.link_translation_mm, "mm")
                .or_else(|| over("its rotation", r, p.link_rotation_deg, "°"))
        }
        Effect::JointOffset(_) => over("the offset", deg(v[0]), p.joint_offset_deg, "°"),
        Effect::JointScale(_) => over("the scale error", v[0], p.joint_scale, ""),
        Effect::Periodic(_) => {
            let a = v.iter().map(|x| deg(*x).abs()).fold(0.0, f64::max);
            over("a cyclic amplitude", a, p.periodic_deg, "°")
        }
        Effect::JointCompliance(j) => {
            let bound = max_gravity_torque(robot, j.index());
            over("the deflection at the largest gravity torque", deg(v[0] * bound), p.compliance_deflection_deg, "°")
        }
        _ => None,
    }
}
