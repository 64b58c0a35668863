//! The diagnosis's settings, each with its default and its rule ([`Config::validate`]): folds and how
//! poses are grouped into them, the gate, parsimony, the measurement setup, noise, and the thresholds of
//! eligibility, plausibility and the screen.

use serde::Serialize;
use thermokin_identify::{FrameMode, Setup, ToolMode};

use crate::error::DiagnoseError;

/// Diagnosis settings.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Config {
    /// Cross-validation folds.
    pub folds: usize,
    /// Measurement frame.
    pub frame: FrameMode,
    /// Tool point.
    pub tool: ToolMode,
    /// A candidate is accepted only if it lowers the held-out mean squared error by more than this many
    /// standard errors of the paired per-measurement difference (1: the one-standard-error rule). The
    /// same rule keeps a linear drift where the exponential is not significantly better.
    pub gate_standard_errors: f64,
    /// Among candidates within this fraction of the best improvement, the smallest block wins.
    pub parsimony: f64,
    /// Most effects added.
    pub max_effects: usize,
    /// Seed of the fold assignment.
    pub seed: u64,
    /// How the reported held-out error of the whole procedure is obtained.
    pub validation: Validation,
    /// How measurements are grouped into folds, for the selection and for the nested validation.
    pub folds_by: FoldGrouping,
    /// The measurement noise per axis (standard deviation, mm), when known — a tracker's specification:
    /// the verdict compares the held-out error with it. `None`: the verdict says it cannot.
    pub noise_mm: Option<f64>,
    /// The weight of measured orientations (6-D probes), as a lever: a rotation error of δφ radians
    /// counts as the displacement `lever · δφ` mm it causes that far from the tool point, next to the
    /// position error. 0 ignores orientations. The default, 100 mm, weighs 0.01° like 0.017 mm — the
    /// ratio of a 6-D tracker probe's orientation and position accuracy. Every held-out error of a
    /// diagnosis with orientations combines both: `√(|Δp|² + (lever · |δφ|)²)`.
    pub orientation_lever_mm: f64,
    /// The orientation noise per axis of a 6-D probe (standard deviation, radians), when known: with
    /// orientations fitted, the verdict's noise floor is `√(3σ² + 3(lever · σ_rot)²)`.
    pub orientation_noise_rad: Option<f64>,
    /// What the data must show before an effect may be selected ([`Eligibility`]).
    pub eligibility: Eligibility,
    /// Bounds on fitted values beyond which a candidate is refused as implausible ([`Plausibility`]).
    pub plausibility: Plausibility,
    /// How many candidates a forward step fits in full after ranking all by a linearised step
    /// ([`Screen`]; `keep: 0` fits every one).
    pub screen: Screen,
    /// Whether the selection ends by completing the geometry ([`Completion`]).
    pub completion: Completion,
    /// What becomes of measurements flagged as gross errors ([`Outliers`]).
    pub outliers: Outliers,
    /// Whether the chosen model is shrunk toward the nominal robot ([`Shrinkage`]).
    pub shrinkage: Shrinkage,
    /// Whether a chosen function of a joint's angle or load must hold beyond the poses it was fitted on
    /// ([`Extrapolation`]).
    pub extrapolation: Extrapolation,
    /// Whether the robot file's link masses are trusted ([`Masses`]).
    pub masses: Masses,
    /// Which joints' lateral compliance is a candidate ([`thermokin_identify::Lateral`]): a column's by
    /// default, every joint's bearing when the user says the joints are elastic.
    pub lateral: thermokin_identify::Lateral,
    /// Where the order the poses were measured in comes from, for what only that order shows — a
    /// backlash (the direction each joint last moved in), a step of the measurement frame, flagged poses
    /// gathered in one stretch of the session: their times, or also the file's lines when the user says
    /// the file lists them as measured ([`thermokin_chain::MeasuringOrder`]). Without either the poses
    /// have no order, and the diagnosis is the same whatever the order of its rows
    /// (`crate::canonical`).
    #[serde(serialize_with = "by_name")]
    pub order: thermokin_chain::MeasuringOrder,
    /// The accelerometers (or inclinometers) on the robot's links, each read as the tilt of its link
    /// ([`Accelerometer`]); empty: every sensor column is a free driver of rows.
    pub accelerometers: Vec<Accelerometer>,
    /// Where the robot will work (radians; mm for a prismatic joint): the report predicts the final
    /// model's held-out error there from its own fit and sets it beside a hold-out set of those poses
    /// ([`crate::AtUse`]). Empty: no prediction. Never used to choose.
    #[serde(skip)]
    pub poses_of_use: Vec<Vec<f64>>,
    /// What the plan of the measured poses promised at the poses of use (`thermokin plan --json`'s
    /// `promise`): the report restates it at the residual scale its fit found, beside its own prediction
    /// and the hold-out set's measured error ([`crate::AtUse::promised_rms_mm`]).
    pub promised: Option<Promised>,
}

/// A plan's promise at the poses of use ([`crate::Config::promised`]): its predicted held-out RMS and the
/// tracker noise it was stated at.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Promised {
    /// The predicted held-out RMS per pose of use, mm.
    pub rms_mm: f64,
    /// The noise per axis it was stated at, mm.
    pub noise_mm: f64,
    /// How many poses of use it was made for: [`crate::Config::poses_of_use`] must hold as many (the
    /// promise is of those poses, not of others).
    pub poses: usize,
    /// Of them, how many the plan took at their nearest candidate (beyond the candidates' arcs:
    /// `thermokin_planner::BeyondArcs`): its promise is stated at those stand-ins.
    pub at_nearest: usize,
}

/// An accelerometer or inclinometer declared on a link (`--accelerometer NAME=LINK`): its columns
/// `NAME_x`, `NAME_y`, `NAME_z` (any unit proportional to g) measure the link's tilt — read as a
/// rotation with its physical gain (`crate::tilts`), not as a driver whose gain is fitted.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Accelerometer {
    /// The sensor's name: its columns are `NAME_x`, `NAME_y`, `NAME_z`.
    pub name: String,
    /// The link it sits on: 0 the robot's base, `k` the link joint `k` moves.
    pub link: usize,
}

/// A setting serialized by its name (a type of a crate without serde).
fn by_name<T: std::fmt::Display, S: serde::Serializer>(value: &T, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&value.to_string())
}

/// What the diagnosis makes of the robot file's link masses ([`crate::Config::masses`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum Masses {
    /// The default: a gravity compliance is the file's masses' torque times one stiffness per joint; a
    /// file with no masses gets each joint's loads lumped and identified from the data.
    #[default]
    FromFile,
    /// The masses are not trusted (CAD masses without cables and grease, a file copied from another
    /// arm): every compliance has its loads lumped and identified from the data, as for a file without
    /// masses, and the exported robot carries none.
    Ignored,
}

thermokin_chain::choices!(
    Masses,
    "robot masses",
    [
        (
            "from-file",
            "gravity compliance on the robot file's masses (lumped from the data where it has none)",
            Masses::FromFile
        ),
        (
            "ignore",
            "the file's masses not trusted: every compliance's loads lumped and identified from the data",
            Masses::Ignored
        ),
    ]
);

/// The selection's check beyond the measured poses ([`crate::Config::extrapolation`]; the module
/// `extrapolation` gives the why).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum Extrapolation {
    /// The default: a chosen scale, cyclic error, compliance or coupling leaves when, fitted on one half
    /// of a joint's measured arc and scored on the other, the model is significantly worse with it, by
    /// more than it gains among neighbouring poses.
    #[default]
    HalfArcs,
    /// The effects as the neighbourhood folds chose them (for comparisons: the selection before it).
    Off,
}

thermokin_chain::choices!(
    Extrapolation,
    "extrapolation check",
    [
        (
            "half-arcs",
            "a chosen angle- or load-dependent effect must hold from one half of each joint's measured arc to the other",
            Extrapolation::HalfArcs
        ),
        ("off", "the effects as the neighbourhood folds chose them", Extrapolation::Off),
    ]
);

/// What becomes of measurements the screen for gross errors flags (the module `outliers` gives the rule).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum Outliers {
    /// The default: listed in the report and kept out of every fit, score and table.
    #[default]
    Exclude,
    /// Listed in the report, and kept in the data as measured.
    Keep,
}

thermokin_chain::choices!(
    Outliers,
    "outlier handling",
    [
        ("exclude", "flagged gross errors are listed and left out of every fit and figure", Outliers::Exclude),
        ("keep", "flagged gross errors are listed and kept in the data", Outliers::Keep),
    ]
);

/// The selection's last phase ([`crate::Config::completion`]; the module `completion` gives the why).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum Completion {
    /// The default: every eligible joint row and gravity compliance joins the chosen effects unless the
    /// selected model is significantly better held out (reported apart from them:
    /// [`crate::Report::completed`]).
    #[default]
    GeometryAndCompliance,
    /// The selected effects as chosen (for comparisons: the selection before issue #36).
    Off,
}

/// The selection's shrinkage phase ([`crate::Config::shrinkage`]; the module `shrinkage` gives the why).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum Shrinkage {
    /// The default: a Gaussian prior toward the nominal robot on the chosen static effects, as strong
    /// as cross-validation on the selection's folds asks (none where none predicts best).
    #[default]
    CrossValidated,
    /// The least-squares fit as it is (for comparisons: the selection before it).
    Off,
}

thermokin_chain::choices!(
    Shrinkage,
    "shrinkage",
    [
        (
            "cross-validated",
            "the chosen model shrunk toward the nominal robot as far as the folds ask, where it passes the gate",
            Shrinkage::CrossValidated
        ),
        ("off", "the least-squares fit as it is", Shrinkage::Off),
    ]
);

/// How measurements are grouped into cross-validation folds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum FoldGrouping {
    /// The default: `folds` folds grouped in time when the data span time (neighbours in time share a
    /// thermal state); otherwise grouped by neighbourhood in joint space — `4 · folds` blocks of
    /// neighbouring arm configurations (k-means), every `folds`-th block in one fold, so that each
    /// candidate is scored on poses unlike those it was fitted on while every fold spans the workspace.
    /// The gate's standard error is taken over the blocks.
    #[default]
    Neighbourhood,
    /// `folds` folds grouped in time when the data span time, a seeded shuffle of single poses
    /// otherwise.
    Time,
    /// One fold per workspace quadrant (reach × height against their medians): held-out poses lie in a
    /// region the fit never saw.
    WorkspaceRegion,
    /// One fold per arm configuration (elbow against its median × wrist sign): held-out poses are on a
    /// branch the fit never saw.
    JointConfiguration,
}

thermokin_chain::choices!(
    FoldGrouping,
    "fold grouping",
    [
        (
            "neighbourhood",
            "grouped in time when the data span time; otherwise blocks of neighbouring arm configurations (4 per fold, k-means in joint space; single poses below 10 per block)",
            FoldGrouping::Neighbourhood
        ),
        ("time", "grouped in time, or single poses shuffled", FoldGrouping::Time),
        ("region", "leave one workspace quadrant out (reach × height)", FoldGrouping::WorkspaceRegion),
        ("configuration", "leave one arm branch out (elbow × wrist)", FoldGrouping::JointConfiguration),
    ]
);

/// How the diagnosis's own held-out error is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Validation {
    /// Nested cross-validation: the whole selection (the ladder, with its inner folds) is rerun on the
    /// training part of each of `outer` folds, and the model it picks is scored on that fold's test part,
    /// which the selection never saw. The default.
    Nested {
        /// Outer folds.
        outer: usize,
    },
    /// Only the selection's own cross-validation (optimistic: the same scores chose the effects). Faster.
    SelectionOnly,
}

impl Config {
    /// The measurement setup these settings describe: frame, tool, orientation lever.
    pub fn setup(&self) -> Setup {
        Setup {
            frame: self.frame,
            tool: self.tool,
            orientation_lever_mm: self.orientation_lever_mm,
            lateral: self.lateral,
        }
    }

    /// The RMS a model at the measurement noise leaves (3-D, or position and orientation combined with
    /// `lever_mm` when orientations are fitted), from the stated noise: `√3 · σ`, or
    /// `√(3σ² + 3(lever · σ_rot)²)`. `None` when the noise is not stated (or, with orientations fitted,
    /// the orientation noise is not).
    pub fn noise_floor_mm(&self, lever_mm: Option<f64>) -> Option<f64> {
        match (self.noise_mm, lever_mm, self.orientation_noise_rad) {
            (None, ..) | (Some(_), Some(_), None) => None,
            (Some(sigma), None, _) => Some(sigma * 3f64.sqrt()),
            (Some(sigma), Some(lever), Some(rot)) => Some((3.0 * sigma * sigma + 3.0 * (lever * rot).powi(2)).sqrt()),
        }
    }

    /// Whether a held-out RMS is at the stated noise: within 1.5× its floor ([`Config::noise_floor_mm`];
    /// the 3-D RMS of Gaussian noise scatters by ~10 % over 100 poses, a model error shows as more).
    /// `None` when the noise is not stated.
    pub fn at_the_noise(&self, heldout_rms_mm: f64, lever_mm: Option<f64>) -> Option<bool> {
        self.noise_floor_mm(lever_mm).map(|floor| heldout_rms_mm <= 1.5 * floor)
    }

    /// The fewest poses a diagnosis with these folds can run on: two per fold.
    pub fn minimum_poses(&self) -> usize {
        2 * self.folds.max(2)
    }

    /// Checks every setting against its domain, one rule each: at least 2 folds (and 2 outer folds), a
    /// stated noise a positive standard deviation, a non-negative orientation lever, a gate, parsimony
    /// fraction and effect count that can select something.
    pub fn validate(&self) -> Result<(), DiagnoseError> {
        let bad = |setting, value: f64, rule| Err(DiagnoseError::BadSetting { setting, value, rule });
        if self.folds < 2 {
            return bad("folds", self.folds as f64, "must be at least 2");
        }
        if let Validation::Nested { outer } = self.validation
            && outer < 2
        {
            return bad("validation.outer", outer as f64, "must be at least 2");
        }
        if let Some(p) = self.promised {
            if self.poses_of_use.is_empty() {
                return bad("promised", p.rms_mm, "needs the poses of use it was stated at (poses_of_use)");
            }
            for (setting, v) in [("promised.rms_mm", p.rms_mm), ("promised.noise_mm", p.noise_mm)] {
                if !(v.is_finite() && v > 0.0) {
                    return bad(setting, v, "must be a positive number of millimetres");
                }
            }
            if p.poses != self.poses_of_use.len() {
                return bad(
                    "promised.poses",
                    p.poses as f64,
                    "must be the number of poses of use given: the promise is of the poses the plan was made for",
                );
            }
        }
        if let Some(n) = self.noise_mm
            && !(n.is_finite() && n > 0.0)
        {
            return bad("noise_mm", n, "must be a positive standard deviation");
        }
        if !(self.orientation_lever_mm.is_finite() && self.orientation_lever_mm >= 0.0) {
            return bad("orientation_lever_mm", self.orientation_lever_mm, "must be ≥ 0");
        }
        if let Some(n) = self.orientation_noise_rad
            && !(n.is_finite() && n > 0.0)
        {
            return bad("orientation_noise_rad", n, "must be a positive standard deviation");
        }
        if !(self.gate_standard_errors.is_finite() && self.gate_standard_errors >= 0.0) {
            return bad("gate_standard_errors", self.gate_standard_errors, "must be ≥ 0");
        }
        if !(self.parsimony.is_finite() && (0.0..=1.0).contains(&self.parsimony)) {
            return bad("parsimony", self.parsimony, "must be a fraction in [0, 1]");
        }
        Ok(())
    }
}

impl Default for Config {
    fn default() -> Self {
        Self {
            folds: 5,
            frame: FrameMode::Base,
            tool: ToolMode::Known,
            gate_standard_errors: 1.0,
            parsimony: 0.9,
            max_effects: 8,
            seed: 0xd1a6,
            validation: Validation::Nested { outer: 5 },
            noise_mm: None,
            folds_by: FoldGrouping::Neighbourhood,
            orientation_lever_mm: 100.0,
            orientation_noise_rad: None,
            eligibility: Eligibility::default(),
            plausibility: Plausibility::default(),
            screen: Screen::default(),
            completion: Completion::default(),
            outliers: Outliers::default(),
            shrinkage: Shrinkage::default(),
            extrapolation: Extrapolation::default(),
            masses: Masses::default(),
            lateral: thermokin_identify::Lateral::default(),
            order: thermokin_chain::MeasuringOrder::default(),
            accelerometers: Vec::new(),
            poses_of_use: Vec::new(),
            promised: None,
        }
    }
}

/// The thresholds of eligibility ([`crate::Config::eligibility`]): `thermokin-identify`'s, which the
/// measurement planner plans by too.
pub use thermokin_identify::Eligibility;

/// The bound beyond which a fitted value is not a property of a working robot but a fit running away
/// (trading against another block, or chasing a few poses), in the robot's own scale: every effect is
/// judged by the largest displacement it causes at the tool point over the data, against the arm's
/// extent over the data — so that a cable-driven research arm's real millimetres and a small arm's real
/// degrees pass, and a robot at half the size with half the deviation is judged as the same robot. A
/// candidate whose values exceed it in the fit it would join is refused, with the values measured.
///
/// The displacement of each kind: a joint row's (or drift's, at its factor 1) translation, and its
/// rotation times the row's lever (the largest distance from the joint to the tool point over the data);
/// a zero offset's angle times the lever (a prismatic joint's offset itself); a gear-ratio error's
/// largest angle `|s|·max|q|` over the data times the lever; a cyclic error's largest angle `√(a1²+b1²) +
/// √(a2²+b2²)` times the lever; a compliance's largest deflection `k·τ_max` (the joint's largest gravity
/// torque) times the lever.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Plausibility {
    /// Largest displacement at the tool point of any one effect, as a fraction of the arm's extent over
    /// the data (the largest distance from joint 1 to the tool point). Default 0.02: 20 mm on a 1 m arm —
    /// a hundred times what an industrial arm is calibrated to, a few times a cable-driven arm's real
    /// wrist errors; a 90 % gear-ratio error or a 60° cyclic term of a wrist joint trading with the tool
    /// point moves it by a hundred millimetres or more.
    pub displacement_of_extent: f64,
}

impl Default for Plausibility {
    fn default() -> Self {
        Self { displacement_of_extent: 0.02 }
    }
}

/// How many candidates a forward step fits in full after the linearised ranking.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Screen {
    /// Candidates kept for the full scoring, best linearised held-out error first; 0 keeps every
    /// candidate (the exhaustive selection, for comparisons).
    pub keep: usize,
    /// Which of those are fitted on every fold.
    pub fitted: Fitted,
}

/// Which of a forward step's shortlisted candidates are fitted in full on every fold.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum Fitted {
    /// Those a forecast from the current model's own fold fits puts within reach of the step's choice
    /// (one Gauss–Newton step per fold, `thermokin_diagnose`'s `linearised` module): the others could
    /// not be chosen. Every one when the forecast does not exist.
    #[default]
    InReach,
    /// Every one (the selection before forecasts, for comparisons).
    Every,
}

impl Default for Screen {
    /// Four. Measured over the whole diagnosis test suite with eight kept (391 forward steps on simulated,
    /// Rokae and UR10 sets): the candidate finally chosen — after the step's parsimony, which prefers a
    /// smaller block within reach of the best — stood at linearised rank 1 in 329 steps, 2 in 44, 3 in 17,
    /// 4 in one, never lower (9 were exponential drifts, scored outside the screen). Four keeps them all;
    /// three would have changed one step.
    fn default() -> Self {
        Self { keep: 4, fitted: Fitted::InReach }
    }
}
