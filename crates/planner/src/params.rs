//! The settings of a plan.

use nalgebra::Vector3;
use serde::Serialize;
use thermokin_identify::{Effect, Eligibility, FrameMode, Lateral, ToolMode};

use crate::error::PlanError;

/// What the chosen poses optimise ([`crate::plan`]; the choice and its reasons are in the `select`
/// module's documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum Criterion {
    /// D-optimal: the smallest volume of the parameters' confidence ellipsoid (`log det` of the
    /// information, as FIGAROH and most of the literature): for pinning parameters down (the poses
    /// `diagnose` suggests after a refusal).
    Parameters,
    /// I-optimal: the smallest mean variance of the predicted tool position over the poses of use
    /// ([`Params::region`]; the candidates without one) — the accuracy the calibrated model would have
    /// where the robot works if the model were the robot, after the frame a test re-measures
    /// (registration, unknown tool) is fitted there. The default: what a calibration is used for.
    #[default]
    Prediction,
}

thermokin_chain::choices!(
    Criterion,
    "criterion",
    [
        ("parameters", "D-optimal: the largest log det of the parameters' information", Criterion::Parameters),
        (
            "prediction",
            "I-optimal: the smallest mean variance of the predicted tool position over the poses of use (--for; the candidates without it)",
            Criterion::Prediction
        ),
    ]
);

/// What a plan for prediction makes of a pose of use that reaches beyond the candidates' arcs (by more
/// than a degree on some joint, a millimetre on a slide; the candidates' arcs with the measured poses').
/// There the model is extrapolated: its predicted variance assumes the model is the robot beyond
/// anything measured, and a design that lowers it spends poses on the extrapolation's leverage (a gear
/// ratio pinned down at the far end of an arc). On the real UR10 (60 of series C for series B, which
/// leaves C's arcs on four joints; docs/planner.md) the poses so planned reached B at 0.608 mm, worse than
/// random draws (median 0.470) and than the plan over the candidates (0.437).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum BeyondArcs {
    /// Planned for at its nearest candidate or measured pose (joint by joint, each in fractions of its
    /// travel): the nearest configuration a measurement can check a prediction at. The default. The
    /// promise is stated there too ([`crate::Promise::planned_at_nearest`]), and beside it what the plan
    /// would promise at the poses as given ([`crate::Promise::planned_as_given_rms_mm`]).
    #[default]
    Nearest,
    /// Planned for as given: the model planned for taken as the robot there too.
    AsGiven,
}

thermokin_chain::choices!(
    BeyondArcs,
    "beyond_arcs",
    [
        (
            "nearest",
            "a pose of use beyond the candidates' arcs is planned for at its nearest candidate (a prediction there can be checked)",
            BeyondArcs::Nearest
        ),
        (
            "as-given",
            "planned for as given: the model extrapolated beyond the candidates' arcs, taken as the robot there",
            BeyondArcs::AsGiven
        ),
    ]
);

/// Where the robot will work: the poses whose predicted error a plan for prediction lowers and every
/// plan's promise is stated at ([`crate::Promise`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Region {
    /// The candidates themselves: the whole reachable space the user gave (or the sampled one).
    #[default]
    Candidates,
    /// These configurations (radians; mm for a prismatic joint): the program the robot will run, or any
    /// poses of its work. Only their joints are used, never a measurement.
    Poses(Vec<Vec<f64>>),
}

/// How many poses to plan.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Poses {
    /// Exactly this many (after the measured ones).
    Exactly(usize),
    /// As many as lower the predicted error at the poses of use by more than a test there could show,
    /// at most this many: the greedy choice stops at the first pose whose fall of the predicted held-out
    /// RMS is below that RMS's own standard error over the poses of use ([`crate::Promise`]; the rule
    /// in `select`'s documentation).
    Auto {
        /// The most poses planned.
        at_most: usize,
    },
}

impl std::fmt::Display for Poses {
    /// As the command line takes it: the count, or `auto`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Poses::Exactly(n) => write!(f, "{n}"),
            Poses::Auto { .. } => f.write_str("auto"),
        }
    }
}

impl Poses {
    /// The largest count this setting may plan.
    pub fn at_most(self) -> usize {
        match self {
            Poses::Exactly(n) | Poses::Auto { at_most: n } => n,
        }
    }
}

/// The settings of a plan ([`crate::plan`]), with the diagnosis' defaults where they mean the same thing.
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    /// Poses to plan (after the measured ones). Default: exactly 30.
    pub poses: Poses,
    /// Where the robot will work: the poses the plan's promise is stated at, and those a plan for
    /// prediction chooses for. Default: the candidates.
    pub region: Region,
    /// What a plan for prediction makes of poses of use beyond the candidates' arcs. Default: each is
    /// planned for at its nearest candidate.
    pub beyond_arcs: BeyondArcs,
    /// What the poses optimise. Default: the predicted error at the poses of use (I-optimal).
    pub criterion: Criterion,
    /// The tracker's noise, mm (one standard deviation per coordinate): the predicted standard deviation
    /// of every parameter is stated at it. Default 0.02 mm — a laser tracker's repeatability at a few
    /// metres. The choice of poses does not depend on it.
    pub noise_mm: f64,
    /// The frame the poses will be measured in: a tracker's registration is estimated with every model,
    /// so the plan makes it identifiable too. Default: the robot's base frame, as `diagnose`.
    pub frame: FrameMode,
    /// Whether the tool point is known; an unknown one is estimated with every model. Default: known.
    pub tool: ToolMode,
    /// Which joints' lateral compliance the catalogue offers, as the diagnosis' (`thermokin_identify::Lateral`,
    /// the same default: a column's).
    pub lateral: Lateral,
    /// The effects to plan for; `None`: the catalogue's for the robot (every pose-dependent effect the
    /// diagnosis considers — base and tool frames where not estimated anyway, per joint its offset and
    /// link deviation, a gravity compliance where the joint carries mass, a gear-ratio scale and a
    /// cyclic error of a revolute joint).
    pub effects: Option<Vec<Effect>>,
    /// Seed of every random choice (sampled candidates, the random poses the plan is compared with).
    pub seed: u64,
    /// How many random sets of the same size the plan is compared with (their median is reported).
    pub random_draws: usize,
    /// The diagnosis' coverage rule (`thermokin_identify::Eligibility`, the same default): a catalogue
    /// effect of a joint's angle whose arc no choice of the candidates (with the measured poses) can
    /// cover is not planned for — the diagnosis would refuse it whatever is measured — and is reported
    /// as left out ([`crate::Plan::left_out`]). Effects given in [`Params::effects`] are planned for as
    /// given.
    pub eligibility: Eligibility,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            poses: Poses::Exactly(30),
            region: Region::Candidates,
            beyond_arcs: BeyondArcs::Nearest,
            criterion: Criterion::Prediction,
            noise_mm: 0.02,
            frame: FrameMode::Base,
            tool: ToolMode::Known,
            lateral: Lateral::default(),
            effects: None,
            seed: 0x91a7,
            random_draws: 5,
            eligibility: Eligibility::default(),
        }
    }
}

impl Params {
    /// Checks the settings: at least one pose, a positive finite noise, at least one random draw, no
    /// effect that poses cannot plan for.
    pub fn validate(&self) -> Result<(), PlanError> {
        if self.poses.at_most() == 0 {
            return Err(PlanError::NoPoses);
        }
        if let Region::Poses(p) = &self.region
            && p.is_empty()
        {
            return Err(PlanError::Setting {
                setting: "region",
                value: "no poses".into(),
                rule: "give at least one pose of use",
            });
        }
        if !(self.noise_mm.is_finite() && self.noise_mm > 0.0) {
            return Err(PlanError::Setting {
                setting: "noise_mm",
                value: self.noise_mm.to_string(),
                rule: "must be a positive number of millimetres",
            });
        }
        if self.random_draws == 0 {
            return Err(PlanError::Setting { setting: "random_draws", value: "0".into(), rule: "must be at least 1" });
        }
        if let Some(e) = self.effects.iter().flatten().find(|e| e.is_time_dependent()) {
            return Err(PlanError::TimeDependent { effect: e.label() });
        }
        if let Some(e) = self.effects.iter().flatten().find(|e| matches!(e, Effect::Backlash(_))) {
            return Err(PlanError::OrderDependent { effect: e.label() });
        }
        Ok(())
    }
}

/// A box of the robot's base frame the tool point must stay in, mm: where candidates are sampled when
/// the user gives none (a cell's free space, a tracker's line of sight).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct WorkspaceBox {
    /// The lowest x, y, z, mm.
    pub min_mm: Vector3<f64>,
    /// The highest x, y, z, mm.
    pub max_mm: Vector3<f64>,
}

impl WorkspaceBox {
    /// The box between two corners (in any order per axis); every coordinate finite.
    pub fn new(a: Vector3<f64>, b: Vector3<f64>) -> Result<Self, PlanError> {
        if !(a.iter().chain(b.iter()).all(|v| v.is_finite())) {
            return Err(PlanError::Setting {
                setting: "box",
                value: format!("{a:?} {b:?}"),
                rule: "every corner coordinate must be a finite number of millimetres",
            });
        }
        Ok(Self { min_mm: a.inf(&b), max_mm: a.sup(&b) })
    }

    /// The box of six numbers `x0, y0, z0, x1, y1, z1` (two corners, mm), as flags and scripts give it.
    pub fn from_corners(values: &[f64]) -> Result<Self, PlanError> {
        match values {
            [x0, y0, z0, x1, y1, z1] => Self::new(Vector3::new(*x0, *y0, *z0), Vector3::new(*x1, *y1, *z1)),
            _ => Err(PlanError::Setting {
                setting: "box",
                value: format!("{} numbers", values.len()),
                rule: "six numbers: x0,y0,z0,x1,y1,z1 (two corners, mm)",
            }),
        }
    }

    /// Whether `p` (base frame, mm) is inside.
    pub fn contains(&self, p: &Vector3<f64>) -> bool {
        (0..3).all(|k| p[k] >= self.min_mm[k] && p[k] <= self.max_mm[k])
    }
}
