//! The plan as a value: the poses in measuring order, what they are predicted to give against random
//! poses of the same pool, and what stays unidentifiable — in report units (mm, degrees), serialisable,
//! and as text ([`Plan::text`]).

use serde::Serialize;
use thermokin_identify::{FixedParameter, Observability};

use crate::params::Criterion;

/// A measurement plan.
#[derive(Clone, Debug, Serialize)]
pub struct Plan {
    /// What the poses optimise.
    pub criterion: Criterion,
    /// Candidates the plan chose from (distinct).
    pub candidates: usize,
    /// The lines (or indices) of the candidates set aside as exact copies of an earlier one.
    pub copies: Vec<usize>,
    /// Poses already measured.
    pub measured: usize,
    /// The tracker noise the predictions are stated at, mm.
    pub noise_mm: f64,
    /// The model's effects (always-estimated blocks first), by label.
    pub effects: Vec<String>,
    /// The planned poses, in measuring order.
    pub poses: Vec<PlannedPose>,
    /// The criterion after each pose in measuring order (the first value: the measured poses alone): the
    /// log det, which never decreases (D-optimal), or the mean predicted variance `trace(W B)`, which never
    /// increases (I-optimal).
    pub criterion_by_pose: Vec<f64>,
    /// The plan against random poses of the same pool.
    pub comparison: Comparison,
    /// The predicted held-out error at the poses of use, planned and random.
    pub promise: Promise,
    /// Why an automatic count of poses stopped where it did (`--poses auto`); `None` for a given count.
    pub count: Option<CountRule>,
    /// The joints along which the poses of use leave every candidate's (and measured pose's) arc: there
    /// the promise is an extrapolation of the model, which no variance bounds.
    pub beyond_candidates: Vec<Beyond>,
    /// Every parameter's predicted standard deviation, planned and random.
    pub parameters: Vec<ParameterPrecision>,
    /// Parameters the candidates can identify but the planned poses (with the measured ones) cannot.
    pub not_identifiable: Vec<FixedParameter>,
    /// Parameters no candidate (with the measured poses) can identify, whatever is chosen.
    pub never_identifiable: Vec<FixedParameter>,
    /// Catalogue effects not planned for: the diagnosis refuses them on any choice of these candidates
    /// (the arc of their joint over every candidate and measured pose is shorter than they need).
    pub left_out: Vec<LeftOut>,
    /// The arc each joint covers over the planned and measured poses.
    pub coverage: Vec<JointCoverage>,
    /// The largest-joint motion along the measuring order, and along the order the poses were chosen in,
    /// degrees (mm for a prismatic joint).
    pub motion: Motion,
}

/// One planned pose.
#[derive(Clone, Debug, Serialize)]
pub struct PlannedPose {
    /// The candidate's 0-based index.
    pub candidate: usize,
    /// Its 1-based line in the candidates file (none when sampled).
    pub line: Option<usize>,
    /// Joint values, degrees (mm for a prismatic joint) — the candidate's values.
    pub joints: Vec<f64>,
    /// Joint values in the library's units, radians (mm for a prismatic joint).
    #[serde(skip)]
    pub joints_rad: Vec<f64>,
    /// Where the tracker should see the tool, on the nominal robot in its base frame, mm.
    pub nominal_position_mm: [f64; 3],
    /// The effects whose remaining variance this pose halves or more, measured in this order after the
    /// poses before it (reported effects only: not the registration or an unknown tool).
    pub helps: Vec<String>,
}

/// The plan against random poses.
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    /// Random draws of the same size from the same pool (with the same measured poses).
    pub random_draws: usize,
    /// The D-criterion `log det(δI + MᵀM)` of the plan (whichever criterion chose it).
    pub planned_criterion: f64,
    /// The median D-criterion of the random draws.
    pub random_criterion: f64,
    /// The observability indices of the plan.
    pub planned: Option<Observability>,
    /// The median of each index over the random draws.
    pub random: Option<Observability>,
}

/// What the plan promises where the robot will work ([`crate::Region`]): the predicted held-out RMS
/// error per pose of use (3-D, mm) at the stated noise, if the model planned for were the robot — the
/// model's prediction error there, with the frame a test re-measures (registration, unknown tool)
/// fitted on those poses, plus what the test's own noise leaves after that fit:
/// `σ √(trace(W B) + 3 − k/u)` ([`thermokin_identify::frame_refitted_weight`],
/// [`thermokin_identify::heldout_rms`]).
/// Its error scales with the noise: a diagnosis whose residuals are wider than the tracker (a model
/// that is not the robot) measures more, in proportion.
#[derive(Clone, Debug, Serialize)]
pub struct Promise {
    /// What the poses of use are: the candidates, or the poses given (`--for`).
    pub region: PosesOfUse,
    /// How many poses of use.
    pub poses_of_use: usize,
    /// Of them, how many reach beyond the candidates' arcs and were planned for at their nearest candidate
    /// or measured pose ([`crate::BeyondArcs::Nearest`]): the figures here are then at those stand-ins,
    /// where a measurement can check them.
    pub planned_at_nearest: usize,
    /// With stand-ins, the planned poses' predicted held-out RMS at the poses of use as given, mm: the
    /// model planned for taken as the robot beyond the candidates' arcs too.
    pub planned_as_given_rms_mm: Option<f64>,
    /// Frame parameters fitted again on the poses of use (registration, unknown tool).
    pub refitted: usize,
    /// The noise the figures are stated at, mm per axis.
    pub noise_mm: f64,
    /// The planned poses' predicted held-out RMS, mm.
    pub planned_rms_mm: f64,
    /// Of which the model's prediction error alone (`σ √trace(W B)`), mm.
    pub planned_model_rms_mm: f64,
    /// The median over the random draws of their predicted held-out RMS, mm (`None`: most draws cannot
    /// identify the model).
    pub random_rms_mm: Option<f64>,
    /// The standard error of a held-out RMS measured at the poses of use, as a fraction of it
    /// (`1/√(2(3u − k))`): differences below it a test there cannot show.
    pub resolution: f64,
}

/// Where a plan's poses of use came from ([`Promise::region`]; `"candidates"` or `"given"` in JSON).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PosesOfUse {
    /// The candidates themselves ([`crate::Region::Candidates`]).
    Candidates,
    /// The poses given ([`crate::Region::Poses`], `--for`).
    Given,
}

/// A joint along which the poses of use leave the candidates' arc.
#[derive(Clone, Debug, Serialize)]
pub struct Beyond {
    /// 1-based joint.
    pub joint: usize,
    /// The poses of use's lowest and highest value, degrees (mm for a prismatic joint).
    pub use_arc: [f64; 2],
    /// The candidates' and measured poses', the same units.
    pub candidates_arc: [f64; 2],
}

impl std::fmt::Display for Beyond {
    /// `q3 -125…125 (candidates 0…133)`: degrees, mm for a prismatic joint.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "q{} {:.0}…{:.0} (candidates {:.0}…{:.0})",
            self.joint, self.use_arc[0], self.use_arc[1], self.candidates_arc[0], self.candidates_arc[1]
        )
    }
}

/// Why `--poses auto` planned the count it did.
#[derive(Clone, Debug, Serialize)]
pub struct CountRule {
    /// The most poses allowed.
    pub at_most: usize,
    /// The fall of the predicted held-out RMS (mm) the next pose would have given, and the standard
    /// error (mm) of a held-out RMS at the poses of use it fell below; `None`: the count reached
    /// `at_most`.
    pub stopped: Option<[f64; 2]>,
}

/// A parameter's predicted standard deviation, report units.
#[derive(Clone, Debug, Serialize)]
pub struct ParameterPrecision {
    /// The parameter, with its unit (`joint_offset[2].offset_deg`).
    pub parameter: String,
    /// From the planned poses; `None` when they cannot identify it.
    pub planned: Option<f64>,
    /// The median over the random draws; `None` when most cannot identify it.
    pub random: Option<f64>,
}

/// A catalogue effect the plan is not made for, and why.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LeftOut {
    /// The effect's label (`joint_scale[1]`).
    pub effect: String,
    /// What the candidates cover against what it needs.
    pub reason: String,
}

/// The arc a joint covers.
#[derive(Clone, Debug, Serialize)]
pub struct JointCoverage {
    /// 1-based joint.
    pub joint: usize,
    /// Lowest and highest value, degrees (mm for a prismatic joint).
    pub arc: [f64; 2],
    /// Fraction of the joint's travel between its limits (of a revolution without limits).
    pub fraction_of_travel: f64,
}

/// Joint motion along the plan.
#[derive(Clone, Debug, Serialize)]
pub struct Motion {
    /// In measuring order.
    pub ordered: f64,
    /// In the order chosen.
    pub as_chosen: f64,
}

/// One observability index, read from the indices.
type Index = fn(&Observability) -> f64;

/// A number in a table: `—` when absent, three significant digits otherwise.
fn cell(x: Option<f64>) -> String {
    match x {
        None => "—".into(),
        Some(v) if v == 0.0 || !v.is_finite() => format!("{v}"),
        Some(v) if v.abs() >= 1e4 || v.abs() < 1e-3 => format!("{v:.2e}"),
        Some(v) => {
            let decimals = (2 - v.abs().log10().floor() as i32).max(0) as usize;
            format!("{v:.decimals$}")
        }
    }
}

impl Plan {
    /// The plan as the command line prints it.
    pub fn text(&self) -> String {
        let mut out = self.head();
        out.push_str(&self.pose_table());
        out.push_str(&self.promise_text());
        out.push_str(&self.comparison_table());
        out.push_str(&self.parameter_table());
        if !self.left_out.is_empty() {
            out.push_str("\nNot planned for (the diagnosis refuses them on any choice of these candidates):\n");
            for l in &self.left_out {
                out.push_str(&format!("  {} — {}\n", l.effect, l.reason));
            }
        }
        for (title, list) in [
            (
                "Not identifiable from the planned poses (more poses, or candidates that move these):",
                &self.not_identifiable,
            ),
            ("Not identifiable from any candidate, whatever is chosen:", &self.never_identifiable),
        ] {
            if !list.is_empty() {
                out.push_str(&format!("\n{title}\n"));
                for f in list {
                    out.push_str(&format!("  {} — {}\n", f.parameter, f.reason));
                }
            }
        }
        out
    }

    fn head(&self) -> String {
        let after = if self.measured > 0 { format!(" after {} measured", self.measured) } else { String::new() };
        let mut out = format!(
            "PLAN: {} poses of {} candidates{after}, chosen for the {} ({}) of {}\n",
            self.poses.len(),
            self.candidates,
            self.criterion,
            match self.criterion {
                Criterion::Prediction => "I-optimal",
                Criterion::Parameters => "D-optimal",
            },
            self.effects.join(", ")
        );
        if !self.copies.is_empty() {
            let shown: Vec<String> = self.copies.iter().take(10).map(ToString::to_string).collect();
            let more = if self.copies.len() > 10 { ", …" } else { "" };
            out.push_str(&format!(
                "{} candidates repeat an earlier one exactly and were set aside (lines {}{more}): a pose measured twice pins down nothing it did not\n",
                self.copies.len(),
                shown.join(", ")
            ));
        }
        out.push_str(&format!(
            "Measuring order: {:.0}° of largest-joint motion, a slide's mm counted as degrees (as chosen: {:.0}°)\nCoverage: {}\n\n",
            self.motion.ordered,
            self.motion.as_chosen,
            self.coverage
                .iter()
                .map(|c| format!(
                    "q{} {:.0}…{:.0} ({:.0} %)",
                    c.joint,
                    c.arc[0],
                    c.arc[1],
                    100.0 * c.fraction_of_travel
                ))
                .collect::<Vec<_>>()
                .join(", ")
        ));
        out
    }

    fn promise_text(&self) -> String {
        let p = &self.promise;
        let region = match p.region {
            PosesOfUse::Given if p.planned_at_nearest > 0 => format!(
                "the {} poses of use given ({} taken at their nearest candidate: below)",
                p.poses_of_use, p.planned_at_nearest
            ),
            PosesOfUse::Given => format!("the {} poses of use given", p.poses_of_use),
            PosesOfUse::Candidates => format!("the {} candidates (the poses of use: no --for)", p.poses_of_use),
        };
        let frame = if p.refitted > 0 {
            format!(", the {} frame parameters a test fits there refitted", p.refitted)
        } else {
            String::new()
        };
        let random = p.random_rms_mm.map_or("not identifiable in most draws".into(), |r| format!("{r:.4} mm"));
        let mut out = format!(
            "\nPredicted held-out RMS at {region} (noise {} mm per axis{frame}; the model planned for taken as the robot):\n  planned {:.4} mm (the model's own share {:.4}), random ({} draws, median) {random}; a test there resolves {:.1} % of it\n",
            p.noise_mm,
            p.planned_rms_mm,
            p.planned_model_rms_mm,
            self.comparison.random_draws,
            100.0 * p.resolution
        );
        if !self.beyond_candidates.is_empty() {
            let joints: Vec<String> = self.beyond_candidates.iter().map(ToString::to_string).collect();
            out.push_str(&format!(
                "warning: the poses of use leave the candidates' arcs — {}: there the model is extrapolated, its error there is not what any variance promises, and a model that is not the robot may do worse than the promise; candidates that cover those arcs would measure it\n",
                joints.join(", ")
            ));
            if p.planned_at_nearest > 0 {
                out.push_str(&format!(
                    "  {} of the {} poses of use reach beyond those arcs: planned for, and the figures above stated, at the nearest candidate each, where a measurement can check the prediction (--beyond-arcs as-given plans for them as given); at the poses as given, the model planned for taken as the robot there, the planned poses would promise {}\n",
                    p.planned_at_nearest,
                    p.poses_of_use,
                    p.planned_as_given_rms_mm.map_or("nothing finite".into(), |r| format!("{r:.4} mm"))
                ));
            }
        }
        if let Some(c) = &self.count {
            match c.stopped {
                Some([gain, resolution]) => out.push_str(&format!(
                    "Poses: {} — one more would lower that RMS by {:.2e} mm, below the {:.2e} mm a test at the poses of use can show (at most {})\n",
                    self.poses.len(),
                    gain,
                    resolution,
                    c.at_most
                )),
                None => out.push_str(&format!(
                    "Poses: {} — the most allowed; each still lowered the predicted RMS by more than a test at the poses of use can show\n",
                    self.poses.len()
                )),
            }
        }
        out
    }

    fn pose_table(&self) -> String {
        let mut out =
            String::from("   #   line  joints                                          nominal x, y, z (mm)  helps\n");
        for (k, p) in self.poses.iter().enumerate() {
            let joints: Vec<String> = p.joints.iter().map(|v| format!("{v:.2}")).collect();
            let [x, y, z] = p.nominal_position_mm;
            out.push_str(&format!(
                "{:>4}  {:>5}  {:<46}  {x:>8.1} {y:>8.1} {z:>8.1}  {}\n",
                k + 1,
                p.line.map_or("—".into(), |l| l.to_string()),
                joints.join(" "),
                p.helps.join(", ")
            ));
        }
        out
    }

    fn comparison_table(&self) -> String {
        let c = &self.comparison;
        let mut out = format!(
            "\nIdentifiability            planned     random ({} draws, median)\n  criterion (log det)  {:>12.2}  {:>12.2}\n",
            c.random_draws, c.planned_criterion, c.random_criterion
        );
        let index = |o: &Option<Observability>, f: fn(&Observability) -> f64| o.as_ref().map(f);
        let rows: [(&str, Index); 6] = [
            ("condition number", |o| o.condition_number),
            ("O1 (geometric mean)", |o| o.o1),
            ("O2 (1 / condition)", |o| o.o2),
            ("O3 (smallest σ)", |o| o.o3),
            ("O4 (noise amplification)", |o| o.o4),
            ("O5", |o| o.o5),
        ];
        for (name, f) in rows {
            out.push_str(&format!(
                "  {name:<20} {:>12}  {:>12}\n",
                cell(index(&c.planned, f)),
                cell(index(&c.random, f))
            ));
        }
        out
    }

    fn parameter_table(&self) -> String {
        let mut out = format!("\nPredicted standard deviation at {} mm noise     planned      random\n", self.noise_mm);
        for p in &self.parameters {
            out.push_str(&format!("  {:<44} {:>10}  {:>10}\n", p.parameter, cell(p.planned), cell(p.random)));
        }
        out
    }
}

impl Plan {
    /// Writes the plan as CSV, one row per pose in measuring order: `pose` (1, 2, …), `line` (the
    /// candidate's line in its file, empty when sampled), `q1..qn` (degrees, mm for a prismatic joint —
    /// the candidate's values, written in full precision), and `x_expected,y_expected,z_expected`: where
    /// the tracker should see the tool on the nominal robot, in its base frame, mm. The file reads back as
    /// candidates or as `--measured` poses (the other columns are ignored).
    pub fn write_csv(&self, out: &mut impl std::io::Write) -> std::io::Result<()> {
        let n = self.poses.first().map_or(0, |p| p.joints.len());
        let q: Vec<String> = (1..=n).map(|i| format!("q{i}")).collect();
        writeln!(out, "pose,line,{},x_expected,y_expected,z_expected", q.join(","))?;
        for (k, p) in self.poses.iter().enumerate() {
            let joints: Vec<String> = p.joints.iter().map(|v| format!("{v}")).collect();
            let [x, y, z] = p.nominal_position_mm;
            let line = p.line.map_or(String::new(), |l| l.to_string());
            writeln!(out, "{},{line},{},{x:.4},{y:.4},{z:.4}", k + 1, joints.join(","))?;
        }
        Ok(())
    }
}
