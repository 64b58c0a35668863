//! What the diagnosis reports: held-out statistics, the additive and leave-one-out tables (the DLR
//! format), each effect with its parameters, identifiability, refusals, and where the residuals lie.

use std::collections::BTreeMap;

use serde::Serialize;
use thermokin_chain::{Dataset, Robot};
use thermokin_identify::{CorrelatedPair, FixedParameter, Model, Observability, PoseTerms, norms, residuals};

use crate::error::DiagnoseError;
use crate::regions::{arm_branches, workspace_quadrants};
use crate::stats::Stats;

/// A measurement flagged as a gross error by the screen (the module `outliers` gives the rule).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Outlier {
    /// Its 1-based line in the measurements file (the header is line 1), when it was read from one.
    pub line: Option<usize>,
    /// Its 1-based position among the measurements.
    pub measurement: usize,
    /// Its residual against the screening model, mm (position and weighted rotation combined with a
    /// 6-D probe).
    pub residual_mm: f64,
}

/// Which model screened for gross errors.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum ScreenModel {
    /// The always-estimated blocks, every joint row and every loaded joint's gravity compliance.
    FullGeometry,
    /// The same, fitted with a prior toward the nominal robot strong enough for its effective
    /// parameters to leave the residual freedom its parameters would not (too few measurements for it
    /// unshrunk).
    ShrunkGeometry {
        /// Its effective parameters (the trace of its hat matrix).
        effective_parameters: f64,
        /// The prior's strength, in rows of data per parameter.
        prior_rows: f64,
    },
    /// The always-estimated blocks alone: too few measurements even for the shrunk geometry.
    FrameOnly,
}

/// Where the screen's residual scale comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum ScaleSource {
    /// Estimated from the screening model's residuals (robustly).
    Residuals,
    /// The stated noise, larger than the residuals' robust scale.
    StatedNoise,
}

/// The gravity compliance of the screen's model ([`OutlierScreen::compliance`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum ScreenCompliance {
    /// On the robot file's masses.
    FileMasses,
    /// Its loads lumped and fitted from the data: the robot file gives no masses (or they are not trusted).
    Lumped,
    /// None: gravity loads no joint in these poses.
    NotLoaded,
    /// None: the robot file gives no masses, and the poses are too few to fit the loads lumped beside the
    /// geometry (four residual rows per parameter).
    TooFewPoses,
}

/// How the screen for gross errors judged.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OutlierScreen {
    /// The model whose residuals were judged.
    pub model: ScreenModel,
    /// Which gravity compliance that model holds.
    pub compliance: ScreenCompliance,
    /// The residual scale per axis, mm: robust (`1.4826 · median |r|`) over every measurement, or
    /// the stated noise where that is larger. With the tracker's per-point standard deviations, the
    /// residuals are first divided by each point's over their mean: the scale is then the mean point's.
    pub scale_mm: f64,
    /// Where the scale comes from.
    pub scale_from: ScaleSource,
    /// The residual beyond which a measurement is flagged, mm.
    pub threshold_mm: f64,
    /// Whether the flagged measurements were left out of everything else in the report.
    pub excluded: bool,
    /// Flagged measurements that gather — in consecutive lines, in time, in one part of a joint's range,
    /// of a sensor's, or in one neighbourhood of arm configurations — beyond what independent gross
    /// errors do: a systematic effect, whose poses are kept (a scan statistic over each ordering, bounded
    /// by the screen's false-alarm rate).
    pub clusters: Vec<Cluster>,
}

/// What the poses of a [`Cluster`] gather along.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Along {
    /// Consecutive lines of the measurements file (its order: the order they were measured in).
    Lines,
    /// A span of the measurements' time, minutes (when the file is not in time order).
    Time,
    /// One part of a joint's range, degrees (mm for a prismatic joint: an extension).
    Joint {
        /// The joint, numbered from 1.
        joint: usize,
        /// Whether its values are millimetres.
        prismatic: bool,
    },
    /// One range of a sensor column's values.
    Sensor {
        /// The column's name.
        column: String,
    },
    /// One neighbourhood of arm configurations (a k-means block of the joint values, as the folds use).
    Configurations,
    /// Wherever they lie, each pose's departure is a motion of one joint, by its own amount (the range:
    /// degrees, mm for a prismatic joint).
    JointMotion {
        /// The joint, numbered from 1.
        joint: usize,
        /// Whether its amounts are millimetres.
        prismatic: bool,
    },
}

/// Flagged measurements that gather ([`OutlierScreen::clusters`]): a systematic effect the screening
/// model lacks, kept in the data for the selection to explain.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Cluster {
    /// What they gather along.
    pub along: Along,
    /// Their extent along it, `[lowest, highest]`: lines, minutes, degrees or mm, the sensor's unit
    /// (lines for a neighbourhood of configurations).
    pub range: [f64; 2],
    /// Their joint ranges, degrees (mm for a prismatic joint), per joint `[lowest, highest]`.
    pub joint_ranges: Vec<[f64; 2]>,
    /// How many were flagged there and are kept.
    pub kept: usize,
    /// Which: 1-based measurement numbers, and their file lines where read from a file.
    pub measurements: Vec<usize>,
    /// Their file lines.
    pub lines: Vec<Option<usize>>,
    /// How far they depart from the screening model, mm, `[least, most]`.
    pub residual_mm: [f64; 2],
    /// The chance that independent gross errors gather so anywhere (Bonferroni over the places looked).
    pub chance: f64,
    /// How far they depart from the chosen model, mm, `[least, most]` (filled once the selection has
    /// chosen; `None` where they were not in its data).
    pub after_mm: Option<[f64; 2]>,
}

impl Cluster {
    /// Where the block lies, in words: `in lines 152–300`, `with joint 2 between 65.0° and 80.2°`.
    pub fn place(&self) -> String {
        let [lo, hi] = self.range;
        match &self.along {
            Along::Lines if self.lines.iter().all(Option::is_some) => {
                format!("in lines {lo:.0}–{hi:.0} (measured one after the other)")
            }
            Along::Lines => format!("among measurements {lo:.0}–{hi:.0} (taken one after the other)"),
            Along::Time => format!("measured between {lo:.1} and {hi:.1} min"),
            Along::Joint { joint, prismatic: true } => format!("with joint {joint} extended {lo:.1}–{hi:.1} mm"),
            Along::Joint { joint, prismatic: false } => format!("with joint {joint} between {lo:.1}° and {hi:.1}°"),
            Along::Sensor { column } => format!("with {column} between {lo:.3} and {hi:.3}"),
            Along::Configurations => {
                let ranges: Vec<String> = self
                    .joint_ranges
                    .iter()
                    .enumerate()
                    .map(|(j, [lo, hi])| format!("q{} {lo:.0}…{hi:.0}", j + 1))
                    .collect();
                format!("in one neighbourhood of arm configurations ({})", ranges.join(", "))
            }
            Along::JointMotion { joint, prismatic } => {
                let unit = if *prismatic { " mm" } else { "°" };
                format!("whose departures are each a motion of joint {joint} alone (by {lo:.4}{unit} … {hi:.4}{unit})")
            }
        }
    }

    /// The block as the report's warnings say it, with what the chosen model made of it when it was in
    /// the selection's data (`threshold_mm`: the screen's threshold, the line between explained or not).
    pub fn sentence(&self, threshold_mm: f64) -> String {
        let [r_lo, r_hi] = self.residual_mm;
        let head = format!(
            "{} poses {} depart from the screening model by {r_lo:.2}–{r_hi:.2} mm together (independent gross errors gather so with a chance of {:.1e}): kept as a systematic effect, not gross errors",
            self.kept,
            self.place(),
            self.chance
        );
        match self.after_mm {
            Some([_, hi]) if hi <= threshold_mm => {
                format!(
                    "{head}; the chosen effects explain them (now {:.2}–{hi:.2} mm)",
                    self.after_mm.map_or(0.0, |a| a[0])
                )
            }
            Some([lo, hi]) => {
                let look = match self.along {
                    Along::JointMotion { joint, .. } => format!(
                        "joint {joint} stands off by a different amount at each pose — its play by the direction it was approached from (a backlash: measure with a time column, or say the file lists the poses as measured with --order file), or a slipping joint or encoder"
                    ),
                    _ => {
                        "look for what changes there — a moved tracker or base, a load, a joint's end stop".to_string()
                    }
                };
                format!("{head}; no effect of the catalogue explains them (still {lo:.2}–{hi:.2} mm): {look}")
            }
            None => head,
        }
    }
}

/// A candidate the data cannot pin down: not selectable, reported with what to measure.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Refusal {
    /// The candidate's label.
    pub effect: String,
    /// Why the data cannot pin it down.
    pub reason: String,
    /// What to measure so that they could.
    pub remedy: String,
}

/// A candidate skipped because it adds nothing identifiable to the model.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Skipped {
    /// The candidate's label.
    pub effect: String,
    /// Why: the block a parameter duplicates, or that it moves nothing.
    pub reason: String,
}

/// A row of the additive or leave-one-out table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TableRow {
    /// The model of this row, e.g. `nominal + joint_offset[2]`.
    pub model: String,
    /// Its held-out errors.
    #[serde(flatten)]
    pub stats: Stats,
}

/// A fitted parameter in report units (mm, degrees, minutes, degrees per N·m).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParameterValue {
    /// Value: the fitted one, or for a parameter fixed as unidentifiable its starting value (0, or an
    /// exponential drift's starting τ).
    pub value: f64,
    /// One standard deviation; `None` when the parameter is fixed.
    pub std: Option<f64>,
    /// Why the parameter was fixed instead of fitted (the block it duplicates, or that the data do not
    /// move it); `None` when it was fitted.
    pub fixed: Option<String>,
}

/// One effect of the final model.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EffectReport {
    /// The effect's kind name (`joint_offset`, …).
    pub effect: String,
    /// Label with joint and shape (`joint_offset[2]`).
    pub label: String,
    /// Joints, 1-based.
    pub joints: Vec<usize>,
    /// Held-out RMS before this effect was added, mm (none for an effect that joined in a replacement,
    /// beside the block it replaced).
    pub heldout_rms_before_mm: Option<f64>,
    /// Held-out RMS after it was added, mm.
    pub heldout_rms_after_mm: Option<f64>,
    /// The phase of the selection it joined in: "forward step", "replacing …" (parsimony), "geometry
    /// completion", "replacing … (physics first)".
    pub joined: String,
    /// Held-out RMS of the final model without this effect, mm (the leave-one-out table).
    pub heldout_rms_without_mm: f64,
    /// Fitted parameters.
    pub parameters: BTreeMap<String, ParameterValue>,
    /// Blocks that span the same parameter directions on these data (rank test on the Jacobians).
    pub equivalent: Vec<String>,
    /// Larger blocks that contain this one's directions on these data: they would explain the same and
    /// more; this one was preferred as the smaller.
    pub contained_in: Vec<String>,
    /// Smaller blocks whose directions this one contains on these data (a joint-6 offset inside a tool
    /// rotation): what they would explain, this one does too.
    pub contains: Vec<String>,
}

/// Identifiability of the final model.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Identifiability {
    /// Observability indices and condition number.
    pub observability: Option<Observability>,
    /// Parameters fixed as unidentifiable, with the reason.
    pub fixed: Vec<FixedParameter>,
    /// Candidates skipped because they add nothing identifiable to the model.
    pub skipped_candidates: Vec<Skipped>,
    /// Candidates the data cannot pin down (too little of the joint's travel, of the load, of the
    /// temperature; a near re-description of the tracker frame or probe): not selectable, each with what
    /// to measure ([`crate::config::Eligibility`]).
    pub not_identifiable: Vec<Refusal>,
    /// Nearly unidentifiable combinations of the final model: pairs of parameters whose estimates are
    /// correlated above 0.99 (their combination is determined, not each).
    pub correlated: Vec<CorrelatedPair>,
}

/// Residual RMS broken down by groups of measurements, mm.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Breakdown {
    /// Per joint: RMS in the four quartiles of that joint's angle.
    pub by_joint: Vec<[f64; 4]>,
    /// Workspace: near-low, near-high, far-low, far-high (reach and height against their medians); none
    /// for a region without poses.
    pub by_workspace_region: [Option<f64>; 4],
    /// Joint space: elbow (joint 3 below/above its median) × wrist (joint 5 negative/positive); none for
    /// a region without poses.
    pub by_joint_space_region: [Option<f64>; 4],
    /// Time quartiles (empty without a time column).
    pub by_time: Vec<f64>,
    /// |residual| of every measurement, in file order (model fitted on all data), mm.
    pub per_measurement_mm: Vec<f64>,
}

/// The held-out error of the whole procedure by nested cross-validation: selection rerun on each outer
/// fold's training part, the chosen model scored on its test part.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Nested {
    /// Outer folds.
    pub outer_folds: usize,
    /// The nominal model (always-estimated blocks only) on the outer test parts.
    pub nominal: Stats,
    /// The model each outer selection chose, on its outer test part.
    pub selected: Stats,
    /// What each outer selection chose (how stable the choice is).
    pub selections: Vec<Vec<String>>,
    /// Each outer fold on its own.
    pub folds: Vec<OuterFold>,
    /// Outer folds (1-based) whose chosen model predicts its test poses worse than the nominal one, by
    /// more than twice the standard error of the fold's own paired difference (a fold whose error rose
    /// within its scatter is shown among the folds, not listed here).
    pub worse_than_nominal: Vec<usize>,
    /// The outer fold (1-based) holding more than half of the squared held-out error, if one does.
    pub dominated_by: Option<usize>,
    /// The outer fold (1-based) that carries the gain over the nominal model, if one does: the gain over
    /// all folds is beyond twice its standard error, and without that fold's poses it is not — a region
    /// of the poses (the folds are blocks of neighbouring configurations, or of time) that the claim
    /// rests on alone.
    pub carried_by: Option<usize>,
    /// The mean over the outer folds' test poses of (selected − nominal) error, mm, and its standard
    /// error (paired, over the poses): how far the procedure is from the nominal model, and how well
    /// these poses can tell.
    pub mean_difference_mm: f64,
    /// The standard error of [`Nested::mean_difference_mm`], mm.
    pub mean_difference_se_mm: f64,
    /// The completed geometry on the outer test parts: in each outer fold the model its completion
    /// judged (the chosen effects and every determined row, shrunk toward the nominal robot as its folds
    /// ask), whether the selection took it or not — the model a small set falls back to.
    pub complete: Stats,
    /// The mean over the outer folds' test poses of (selected − complete) error, mm, and its standard
    /// error: whether the selection beats the completed geometry.
    pub versus_complete_mm: f64,
    /// The standard error of [`Nested::versus_complete_mm`], mm.
    pub versus_complete_se_mm: f64,
}

/// One outer fold of the nested validation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OuterFold {
    /// 1-based.
    pub fold: usize,
    /// Test poses.
    pub poses: usize,
    /// The nominal model on them.
    pub nominal: Stats,
    /// The model this fold's selection chose, on them.
    pub selected: Stats,
    /// What it chose.
    pub effects: Vec<String>,
}

/// The diagnosis's prediction at the poses of use ([`crate::Report::at_use`], computed by `crate::at_use`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AtUse {
    /// How many poses of use.
    pub poses: usize,
    /// Frame parameters a test fits again there (registration, unknown tool).
    pub refitted: usize,
    /// The final model's residual scale on all measurements, mm per coordinate (`√(SSR / (rows − free))`).
    pub residual_scale_mm: f64,
    /// The model's own share of the predicted error there, mm RMS per pose (`√trace(W Σ)`).
    pub model_rms_mm: f64,
    /// The predicted held-out RMS per pose of use, mm.
    pub predicted_rms_mm: f64,
    /// The standard error of a held-out RMS measured there, as a fraction of it.
    pub resolution: f64,
    /// The hold-out set's RMS (registration and tool refitted on it), when its poses are the poses of
    /// use, mm.
    pub measured_rms_mm: Option<f64>,
    /// What the plan of these poses promised there ([`crate::Config::promised`]), restated at the
    /// residual scale this fit found: the plan's figure times `residual_scale_mm / its noise` (the
    /// promise scales with the noise it was stated at), mm.
    pub promised_rms_mm: Option<f64>,
    /// Of the poses of use, how many the plan's promise took at their nearest candidate
    /// ([`crate::Promised::at_nearest`]).
    pub promised_at_nearest: usize,
}

/// The final model (fitted on all measurements) and the nominal one on an explicit hold-out set.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HoldoutStats {
    /// The nominal model, its always-estimated blocks refitted on the hold-out file.
    pub nominal: Stats,
    /// The selected model, its always-estimated blocks refitted on the hold-out file, the effects kept
    /// as fitted on the training file.
    pub selected: Stats,
    /// The blocks refitted on the hold-out file for `nominal` and `selected` (its own tracker frame, its
    /// own probe); empty when none is estimated, and then both protocols are one.
    pub refitted: Vec<String>,
    /// Both models exactly as fitted on the training file — registration and tool point included, the
    /// model the export carries — nothing refitted: the fair use-test when the two files share one tracker
    /// frame and probe mount (a calibrated robot is used as exported).
    pub same_frame: HoldoutPair,
}

/// The nominal and the selected model's errors on a hold-out file under one protocol.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HoldoutPair {
    /// The nominal model.
    pub nominal: Stats,
    /// The selected model.
    pub selected: Stats,
}

/// The diagnosis.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// Measurements flagged as gross errors, in file order (empty when none was).
    pub outliers: Vec<Outlier>,
    /// How they were found.
    pub outlier_screen: OutlierScreen,
    /// The nominal model (with the always-estimated blocks), the selection's cross-validation.
    pub nominal: Stats,
    /// The held-out error of the whole procedure, by nested cross-validation (the honest figure; `None`
    /// with [`crate::Validation::SelectionOnly`]).
    pub nested: Option<Nested>,
    /// Nominal and selected model on an explicit hold-out set, when one was given (it never influences
    /// the selection).
    pub holdout: Option<HoldoutStats>,
    /// The final model's predicted held-out error at the poses of use ([`crate::Config::poses_of_use`]),
    /// beside what a hold-out set of those poses measured; `None` without poses of use.
    pub at_use: Option<AtUse>,
    /// The chain of the identified robot: its static effects (frames, registration in the base row, tool,
    /// offsets, link deviations), fitted on all measurements.
    #[serde(skip)]
    pub calibrated: thermokin_chain::Chain,
    /// The identified robot with every chosen effect — the chain above, gear-ratio, cyclic and compliance
    /// terms, thermal drift rows each with its law: the model the report scores and `--export` writes.
    #[serde(skip)]
    pub identified: thermokin_deform::RobotModel,
    /// Said first when the chosen model does not beat the nominal one on data it never saw (nested
    /// validation, the hold-out set): `--export` then refuses unless forced.
    pub honest_end: Option<String>,
    /// How held-out errors were obtained.
    pub validation: String,
    /// `Some(lever)` when measured orientations were fitted (6-D probe): every error of this report
    /// then combines position and rotation, `√(|Δp|² + (lever · |δφ|)²)` mm.
    pub orientation_lever_mm: Option<f64>,
    /// The diagnosed effects of the final model (the selection's choice), main cause first.
    pub effects: Vec<EffectReport>,
    /// The joint rows and compliances the completion added beside the diagnosed effects, main first: not causes
    /// found, but what the identified robot needs to be used in its training frame (a partial geometry
    /// leans on the registration and the tool point, which only holds where those are refitted). Part of
    /// the model every score, table and export of this report is of. Empty when the completion was off,
    /// had no row to add or was significantly worse.
    pub completed: Vec<EffectReport>,
    /// The strength of the Gaussian prior toward the nominal robot the model is fitted with, in rows of
    /// data per parameter ([`crate::Shrinkage`]): 0 when cross-validation preferred none, or it was off.
    /// The values, scores and export of this report are those of the shrunk fit.
    pub shrinkage: f64,
    /// Held-out errors as effects are added, in the order chosen.
    pub additive: Vec<TableRow>,
    /// Held-out errors of the final model with each effect left out.
    pub leave_one_out: Vec<TableRow>,
    /// Observability and fixed parameters of the final model.
    pub identifiability: Identifiability,
    /// Where the nominal model's residuals lie.
    pub residuals_before: Breakdown,
    /// Where the final model's residuals lie.
    pub residuals_after: Breakdown,
    /// Bayesian information criterion of each model in the additive table (full-data fits).
    pub bic: Vec<f64>,
    /// The always-estimated blocks as fitted on all measurements: the registration (the measurement
    /// frame's pose of the robot base) and the tool point, where they were estimated.
    pub frames: FittedFrames,
    /// What the data look like they got wrong (units, frame), said rather than absorbed.
    pub warnings: Vec<String>,
    /// Whether the effects found explain the data, against the measurement noise when it is stated.
    pub verdict: String,
    /// Every measurement the diagnosis kept (the gross errors left out), in file order: where it was
    /// measured and its residual vector before and after — what the report's pictures are drawn from.
    pub poses: Vec<PoseRecord>,
}

/// One measurement as the report's pictures show it, in report units (mm, degrees).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseRecord {
    /// Its 1-based line in the measurements file, when it was read from one.
    pub line: Option<usize>,
    /// When it was measured, minutes (0 without a time column).
    pub time_min: f64,
    /// Its joint values, degrees (mm for a prismatic joint).
    pub joints: Vec<f64>,
    /// The measured position, mm, in the measurement frame.
    pub measured_mm: [f64; 3],
    /// Measured − predicted by the nominal model (the always-estimated blocks fitted on all
    /// measurements), mm.
    pub before_mm: [f64; 3],
    /// Measured − predicted by the final model fitted on all measurements, mm.
    pub after_mm: [f64; 3],
    /// The nested validation's outer fold (1-based) it was a test pose of, with its held-out error there
    /// under the nominal and the selected model, mm; `None` without nested validation.
    pub heldout: Option<PoseHeldOut>,
}

/// One measurement's held-out error in the nested validation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PoseHeldOut {
    /// The outer fold (1-based) it was a test pose of.
    pub fold: usize,
    /// Its error under the nominal model fitted on the fold's training part, mm.
    pub nominal_mm: f64,
    /// Its error under the model the fold's selection chose, mm.
    pub selected_mm: f64,
}

/// A pose for reports: position (mm) and X-Y-Z Euler angles (degrees).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseReport {
    /// Position, mm.
    pub position_mm: [f64; 3],
    /// X-Y-Z Euler angles (`R = Rx·Ry·Rz`), degrees.
    pub xyz_euler_deg: [f64; 3],
}

/// The fitted registration and tool point.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FittedFrames {
    /// `measurement_frame_from_base`, when the measurements are in a tracker frame.
    pub registration: Option<PoseReport>,
    /// The tool point in the robot's tip frame (its last link as loaded: the frame a user names the
    /// tool in), mm, when it was unknown.
    pub tool_point_mm: Option<[f64; 3]>,
    /// The same point in the last joint's same-orientation frame (the paper's, where the tool row's
    /// translation lives), mm.
    pub tool_point_joint_frame_mm: Option<[f64; 3]>,
    /// The unknown probe's rotation, when orientations were measured: the tool row's error angles
    /// (X-Y-Z, degrees, eq. 19 — about the axes of the flange's same-orientation frame, before the
    /// row's nominal rotation).
    pub tool_rotation_deg: Option<[f64; 3]>,
}

/// The position residual (measured − predicted, mm) of every measurement of `data` under `model` at
/// `theta`.
pub(crate) fn residual_vectors(
    robot: &Robot,
    data: &Dataset,
    model: &Model,
    theta: &[f64],
    terms: &PoseTerms,
) -> Result<Vec<[f64; 3]>, DiagnoseError> {
    let all: Vec<usize> = (0..data.len()).collect();
    let r = residuals(robot, model, theta, data, &all, terms)?;
    Ok(r.chunks(terms.stride()).map(|c| [c[0], c[1], c[2]]).collect())
}

/// Where the residuals of `model` at `theta` lie on `data`: RMS by quartile of each joint's angle, by
/// workspace quadrant and arm branch ([`crate::regions`]), by time quartile, and per measurement.
pub(crate) fn breakdown(
    robot: &Robot,
    data: &Dataset,
    model: &Model,
    theta: &[f64],
    terms: &PoseTerms,
) -> Result<Breakdown, DiagnoseError> {
    let all: Vec<usize> = (0..data.len()).collect();
    let r = residuals(robot, model, theta, data, &all, terms)?;
    let e: Vec<f64> = norms(&r, terms.stride()).iter().map(|x| x * x).collect();
    let rms_of = |sel: &[usize]| -> Option<f64> {
        (!sel.is_empty()).then(|| (sel.iter().map(|&i| e[i]).sum::<f64>() / sel.len() as f64).sqrt())
    };
    // Quartiles of at least four poses are never empty (a diagnosis needs four poses at the least).
    let quartiles = |key: &dyn Fn(usize) -> f64| -> [f64; 4] {
        let mut idx = all.clone();
        idx.sort_by(|&a, &b| key(a).total_cmp(&key(b)));
        let n = idx.len();
        [0, 1, 2, 3].map(|k| rms_of(&idx[k * n / 4..(k + 1) * n / 4]).unwrap_or(0.0))
    };
    let n = robot.chain().dof();
    let by_joint = (0..n).map(|j| quartiles(&|i| data.measurements[i].q[j])).collect();
    let region = |labels: &[usize]| -> [Option<f64>; 4] {
        [0, 1, 2, 3].map(|k| rms_of(&all.iter().copied().filter(|&i| labels[i] == k).collect::<Vec<_>>()))
    };
    let by_workspace_region = region(&workspace_quadrants(data));
    let by_joint_space_region = region(&arm_branches(data));
    let by_time =
        if data.time_span() > 0.0 { quartiles(&|i| data.measurements[i].time_min).to_vec() } else { Vec::new() };
    let per_measurement_mm = e.iter().map(|x| x.sqrt()).collect();
    Ok(Breakdown { by_joint, by_workspace_region, by_joint_space_region, by_time, per_measurement_mm })
}

impl Report {
    /// The effects refused for what the poses cover — a joint's arc, a gravity-torque range: more poses,
    /// planned, would let them be told.
    pub fn refused_for_coverage(&self) -> Vec<&str> {
        let coverage = |r: &&Refusal| r.remedy.starts_with("measure joint") || r.remedy.starts_with("measure poses");
        self.identifiability.not_identifiable.iter().filter(coverage).map(|r| r.effect.as_str()).collect()
    }

    /// Whether the identified robot may be exported: refused ([`DiagnoseError::DoesNotTransfer`]) when the
    /// chosen model does not beat the nominal one on data it never saw, unless `force`d.
    pub fn check_export(&self, force: bool) -> Result<(), DiagnoseError> {
        match &self.honest_end {
            Some(why) if !force => Err(DiagnoseError::DoesNotTransfer { reason: why.clone() }),
            _ => Ok(()),
        }
    }

    /// The identified robot as a robot file carries it ([`Report::identified`], the model scored), on
    /// `file_robot` — the robot as its file describes it: its own link masses and name, here renamed
    /// `"<name> (calibrated on <source>)"` — with `payload`, the load the measurements were taken with,
    /// kept as the robot's default payload (a later operating state's payload replaces it).
    pub fn export_model(
        &self,
        file_robot: &Robot,
        payload: Option<thermokin_chain::LinkMass>,
        source: &str,
    ) -> Result<thermokin_deform::RobotModel, DiagnoseError> {
        let named = file_robot
            .with_chain(self.identified.robot().chain().clone())?
            .renamed(format!("{} (calibrated on {source})", file_robot.name()));
        Ok(self.identified.clone().with_robot(named)?.with_payload(payload)?)
    }
}
