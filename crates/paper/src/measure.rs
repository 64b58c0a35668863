//! What a reproduction measures, as typed values: the compensation runs summarised, Table 16's angles
//! and Table 14's coordinates row by row, and — when the authors' files are present — their files on
//! our models, the replayed scene and the print compared figure by figure. [`Measurements::report`]
//! renders them (`crate::render`); [`Measurements::golden_json`] is the drift check's format. Nothing
//! here formats text.

use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use serde::Serialize;
use serde_json::{Value, json};
use thermokin_chain::Chain;
use thermokin_compensate::{RunOutput, SummaryOut};
use thermokin_io::{PaperResultRow, read_deviation_table, read_paper_results};

use crate::PaperError;
use crate::print::{Figure, PrintedMinMax, TABLE_13, TABLE_15, TABLE_17, TABLE_18};
use crate::scene::{Hypothesis, Residuals, SinglePrecisionEvidence, TransientCandidate, Verdict};

/// FK of joint values against published coordinates, over a set of rows.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FkResidual {
    /// Rows compared (every row: a row FK refuses is an error).
    pub rows: usize,
    /// RMS of the 3-D difference, mm.
    pub rms_mm: f64,
    /// The same per coordinate (`rms / √3`), mm.
    pub rms_per_coordinate_mm: f64,
    /// Mean difference FK − published, mm.
    pub mean_mm: [f64; 3],
    /// Largest 3-D difference, mm.
    pub max_mm: f64,
}

/// RMS (3-D) and mean of FK(joint values, radians) − published coordinates; a row FK refuses (a
/// non-finite value) is an error, never a row left out.
pub(crate) fn fk_residual(chain: &Chain, rows: &[(Vec<f64>, Vector3<f64>)]) -> Result<FkResidual, PaperError> {
    let errs: Vec<Vector3<f64>> =
        rows.iter().map(|(q, p)| Ok(chain.tool_pose(q)?.translation.vector - p)).collect::<Result<_, PaperError>>()?;
    let n = errs.len().max(1) as f64;
    let rms = (errs.iter().map(Vector3::norm_squared).sum::<f64>() / n).sqrt();
    let mean = errs.iter().sum::<Vector3<f64>>() / n;
    let max = errs.iter().map(|e| e.norm()).fold(0.0, f64::max);
    Ok(FkResidual {
        rows: errs.len(),
        rms_mm: rms,
        rms_per_coordinate_mm: rms / 3f64.sqrt(),
        mean_mm: [mean.x, mean.y, mean.z],
        max_mm: max,
    })
}

/// Joint values of a file or a table (degrees, mm) in the chain's radians (mm), per joint kind, through
/// the unit boundary; a row of the wrong length is an error naming `what`.
pub(crate) fn to_internal(chain: &Chain, v: &[f64], what: &'static str) -> Result<Vec<f64>, PaperError> {
    thermokin_io::units::joints_to_internal(chain, v).ok_or(PaperError::Shape {
        what,
        expected: chain.dof(),
        got: v.len(),
    })
}

/// Joint values of a run's row (radians, mm) in degrees (mm), per joint kind.
fn to_external(run: &RunOutput, q: &[f64]) -> Vec<f64> {
    run.kinds.iter().zip(q).map(|(&k, &v)| thermokin_io::units::joint_value_out(k, v)).collect()
}

/// One target of Table 16 (the authors' compensated joint angles) beside ours and Table 14.
#[derive(Clone, Debug, PartialEq)]
pub struct Table16Row {
    /// Target label (Table 12).
    pub label: String,
    /// A1..A6 as printed, degrees.
    pub published_deg: Vec<f64>,
    /// A1..A6 of our static compensation (CoppeliaSim semantics), degrees.
    pub ours_deg: Vec<f64>,
    /// Largest |ours − published| over the joints, degrees.
    pub max_diff_deg: f64,
    /// Table 14's coordinates reached, mm.
    pub table14_mm: Vector3<f64>,
    /// FK of the printed angles on our deformed model − Table 14, mm.
    pub fk_minus_table14_mm: Vector3<f64>,
}

/// Table 16 against our static compensation and, through FK on our deformed model, against Table 14.
#[derive(Clone, Debug, PartialEq)]
pub struct Table16Comparison {
    /// The targets present in Table 16, Table 14 and our run, in Table 16's order.
    pub rows: Vec<Table16Row>,
    /// Largest |ours − published| per joint, degrees.
    pub max_joint_diff_deg: [f64; 6],
    /// FK of the printed angles on our deformed model (CoppeliaSim semantics) vs Table 14.
    pub on_our_model: FkResidual,
    /// The same on the canonical reading of the table.
    pub on_canonical_model: FkResidual,
}

/// One target of Table 14 (the authors' reached coordinates) beside the program and ours.
#[derive(Clone, Debug, PartialEq)]
pub struct Table14Row {
    /// Target label.
    pub label: String,
    /// Programmed position (Table 12), mm.
    pub programmed_mm: Vector3<f64>,
    /// Published reached position (Table 14), mm.
    pub published_mm: Vector3<f64>,
    /// Our reached position, mm.
    pub ours_mm: Vector3<f64>,
}

/// The authors' scene identified from their minute-0 rows and replayed (see `crate::scene`).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneReplay {
    /// The tool point identified in joint 6's frame, mm.
    pub tool_point_mm: Vector3<f64>,
    /// Rank of the scene-geometry step (of 18).
    pub rank: usize,
    /// The nominal scene on its own minute-0 rows: the floor candidates are judged against.
    pub floor: Residuals,
    /// The candidate explanations of the static gap, judged on the 50 static rows.
    pub hypotheses: Vec<Hypothesis>,
    /// Candidate replays of the transient file.
    pub candidates: Vec<TransientCandidate>,
    /// Whether the authors' scene computed in single precision.
    pub precision: SinglePrecisionEvidence,
}

impl SceneReplay {
    /// The first hypothesis kept, if any.
    pub fn kept(&self) -> Option<&Hypothesis> {
        self.hypotheses.iter().find(|h| h.verdict == Verdict::Kept)
    }
}

/// One printed figure beside the authors' file, their angles replayed, and ours.
#[derive(Clone, Debug, PartialEq)]
pub struct PrintRow {
    /// The printed figure and the value from the authors' file.
    pub figure: Figure,
    /// From their published angles on the replayed scene (static positions only).
    pub replayed: Option<f64>,
    /// From our compensation (rotation vectors for orientations, shown for scale).
    pub ours: f64,
}

/// Tables 13, 15, 17 and 18 figure by figure.
#[derive(Clone, Debug, PartialEq)]
pub struct PrintComparison {
    /// Six figures per table, in the order 15, 13, 17, 18.
    pub rows: Vec<PrintRow>,
    /// Largest |figure| printed in Table 15 (static positions), mm.
    pub largest_static_printed_mm: f64,
    /// Largest |figure| printed in Table 17 (transient positions), mm.
    pub largest_transient_printed_mm: f64,
}

impl PrintComparison {
    /// The figures where the authors' file and the print disagree, named.
    pub fn disagreements(&self) -> Vec<String> {
        const AXIS: [&str; 3] = ["X", "Y", "Z"];
        self.rows
            .iter()
            .map(|r| &r.figure)
            .filter(|f| !f.agrees())
            .map(|f| {
                format!("Table {} {} Δ{}: printed {}, file {}", f.table, f.bound, AXIS[f.axis], f.printed, f.computed)
            })
            .collect()
    }
}

/// The authors' full files on our models.
#[derive(Clone, Debug, PartialEq)]
pub struct AuthorsComparison {
    /// FK of their 50 static angles on our deformed model vs their coordinates.
    pub static_on_our_model: FkResidual,
    /// Largest |ours − theirs| over the static rows and joints, degrees.
    pub static_max_joint_diff_deg: f64,
    /// FK of their minute-0 angles on our nominal model vs their coordinates.
    pub transient_minute0_on_nominal: FkResidual,
    /// Rows of their transient file.
    pub transient_rows: usize,
    /// Largest |ours − theirs| over the transient rows and joints, degrees.
    pub transient_max_joint_diff_deg: f64,
    /// Their scene replayed.
    pub scene: SceneReplay,
    /// The print against their files.
    pub print: PrintComparison,
}

/// Everything a reproduction measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurements {
    /// Our static compensation on the scene (CoppeliaSim semantics), mm and degrees.
    pub static_case: SummaryOut,
    /// Our static compensation on Table 9 with the canonical reading of the table.
    pub static_canonical: SummaryOut,
    /// Our transient compensation, mm and degrees.
    pub transient: SummaryOut,
    /// Table 16 row by row.
    pub table16: Table16Comparison,
    /// Table 14 row by row.
    pub table14: Vec<Table14Row>,
    /// Where the authors' files were looked for.
    pub authors_dir: PathBuf,
    /// The authors' files compared, when present.
    pub authors: Option<AuthorsComparison>,
}

impl Measurements {
    /// The measured numbers in the golden file's format (`fixtures/golden/paper-reproduction.json`).
    pub fn golden_json(&self) -> Value {
        let summary = |s: &SummaryOut| serde_json::to_value(s).unwrap_or(Value::Null);
        let mut j = json!({
            "static": summary(&self.static_case),
            "static_canonical": summary(&self.static_canonical),
            "transient": summary(&self.transient),
            "table16_max_joint_diff_deg": self.table16.max_joint_diff_deg,
            "table16_on_our_model_vs_table14": &self.table16.on_our_model,
            "table16_on_canonical_model_vs_table14": &self.table16.on_canonical_model,
        });
        if let Some(a) = &self.authors {
            j["authors_static_on_our_model"] = json!(a.static_on_our_model);
            j["authors_static_max_joint_diff_deg"] = json!(a.static_max_joint_diff_deg);
            j["authors_transient_minute0_on_nominal"] = json!(a.transient_minute0_on_nominal);
            j["authors_transient_rows"] = json!(a.transient_rows);
            j["authors_transient_max_joint_diff_deg"] = json!(a.transient_max_joint_diff_deg);
            if let Some(k) = a.scene.kept() {
                j["scene_static_rms_mm"] = json!(k.residuals.rms_mm);
                j["scene_static_worst_mm"] = json!(k.residuals.worst_mm);
            }
            j["scene_minute0_floor_rms_mm"] = json!(a.scene.floor.rms_mm);
            j["transient_single_precision_angles"] = json!(a.scene.precision.angles);
            j["transient_single_precision_worst_fraction"] = json!(a.scene.precision.worst_fraction_of_spacing);
            j["print_disagreements"] = json!(a.print.disagreements());
        }
        j
    }
}

/// The chains and the three runs a reproduction measures.
pub(crate) struct Runs<'a> {
    pub nominal: &'a Chain,
    pub deformed: &'a Chain,
    pub deformed_canonical: &'a Chain,
    pub static_run: &'a RunOutput,
    pub canonical_run: &'a RunOutput,
    pub transient_run: &'a RunOutput,
}

/// Measures the runs against the printed tables and, when present in `authors`, the authors' files.
pub(crate) fn measure(
    runs: &Runs<'_>,
    table14: &[(String, Vec<f64>)],
    table16: &[(String, Vec<f64>)],
    authors: &Path,
) -> Result<Measurements, PaperError> {
    Ok(Measurements {
        static_case: SummaryOut::of(&runs.static_run.summary),
        static_canonical: SummaryOut::of(&runs.canonical_run.summary),
        transient: SummaryOut::of(&runs.transient_run.summary),
        table16: table16_comparison(runs, table14, table16)?,
        table14: table14_rows(runs.static_run, table14),
        authors_dir: authors.to_path_buf(),
        authors: authors_comparison(runs, authors)?,
    })
}

fn table16_comparison(
    runs: &Runs<'_>,
    table14: &[(String, Vec<f64>)],
    table16: &[(String, Vec<f64>)],
) -> Result<Table16Comparison, PaperError> {
    let mut max_joint_diff_deg = [0.0f64; 6];
    let mut rows = Vec::new();
    let mut fk_rows = Vec::new();
    for (label, q_pub) in table16 {
        let Some(ours) = runs.static_run.rows.iter().find(|r| &r.label == label) else { continue };
        let Some((_, p14)) = table14.iter().find(|(l, _)| l == label) else { continue };
        let ours_deg = to_external(runs.static_run, &ours.joints);
        let d: Vec<f64> = q_pub.iter().zip(&ours_deg).map(|(a, b)| b - a).collect();
        for (k, v) in d.iter().enumerate() {
            max_joint_diff_deg[k] = max_joint_diff_deg[k].max(v.abs());
        }
        let p14 = Vector3::new(p14[0], p14[1], p14[2]);
        let q = to_internal(runs.deformed, q_pub, "Table 16 row")?;
        let fk_minus_table14_mm = runs.deformed.tool_pose(&q)?.translation.vector - p14;
        fk_rows.push((q, p14));
        rows.push(Table16Row {
            label: label.clone(),
            published_deg: q_pub.clone(),
            max_diff_deg: d.iter().fold(0.0f64, |m, v| m.max(v.abs())),
            ours_deg,
            table14_mm: p14,
            fk_minus_table14_mm,
        });
    }
    Ok(Table16Comparison {
        rows,
        max_joint_diff_deg,
        on_our_model: fk_residual(runs.deformed, &fk_rows)?,
        on_canonical_model: fk_residual(runs.deformed_canonical, &fk_rows)?,
    })
}

fn table14_rows(static_run: &RunOutput, table14: &[(String, Vec<f64>)]) -> Vec<Table14Row> {
    table14
        .iter()
        .filter_map(|(label, p14)| {
            let ours = static_run.rows.iter().find(|r| &r.label == label)?;
            Some(Table14Row {
                label: label.clone(),
                programmed_mm: ours.programmed.translation.vector,
                published_mm: Vector3::new(p14[0], p14[1], p14[2]),
                ours_mm: ours.reached.translation.vector,
            })
        })
        .collect()
}

fn authors_comparison(runs: &Runs<'_>, authors: &Path) -> Result<Option<AuthorsComparison>, PaperError> {
    let static_file = authors.join("results-static-case-study.csv");
    let transient_file = authors.join("results-transient-case-study.csv");
    if !(thermokin_io::file_exists(&static_file) && thermokin_io::file_exists(&transient_file)) {
        return Ok(None);
    }
    let authors_static = read_paper_results(&static_file)?;
    let rows: Vec<(Vec<f64>, Vector3<f64>)> = authors_static.iter().map(|r| (r.joints.clone(), r.reached_mm)).collect();
    let authors_transient = read_paper_results(&transient_file)?;
    let minute0: Vec<(Vec<f64>, Vector3<f64>)> =
        authors_transient.iter().filter(|r| r.time_min == 0.0).map(|r| (r.joints.clone(), r.reached_mm)).collect();
    Ok(Some(AuthorsComparison {
        static_on_our_model: fk_residual(runs.deformed, &rows)?,
        static_max_joint_diff_deg: max_joint_diff(&authors_static, runs.static_run),
        transient_minute0_on_nominal: fk_residual(runs.nominal, &minute0)?,
        transient_rows: authors_transient.len(),
        transient_max_joint_diff_deg: max_joint_diff(&authors_transient, runs.transient_run),
        scene: scene_replay(runs.nominal, authors, &authors_static, &authors_transient)?,
        print: print_comparison(runs, &authors_static, &authors_transient)?,
    }))
}

/// The authors' scene replayed: the static gap explained, the candidates judged, the transient file's
/// state (see `crate::scene`).
fn scene_replay(
    table9: &Chain,
    authors: &Path,
    authors_static: &[PaperResultRow],
    authors_transient: &[PaperResultRow],
) -> Result<SceneReplay, PaperError> {
    let table = read_deviation_table(&authors.join("deformations-case-study.csv"))?;
    let minute0: Vec<&PaperResultRow> = authors_transient.iter().filter(|r| r.time_min == 0.0).collect();
    let (floor, hypotheses) = crate::static_hypotheses(table9, &table, &minute0, authors_static)?;
    let tool_point_mm = crate::identify_tool_point(table9, &minute0)?;
    let (scene, rank) = crate::identify_scene_geometry(&crate::scene_chain(table9, tool_point_mm)?, &minute0)?;
    Ok(SceneReplay {
        tool_point_mm,
        rank,
        floor,
        hypotheses,
        candidates: crate::transient_candidates(&scene, &table, authors_transient)?,
        precision: crate::single_precision_evidence(authors_transient),
    })
}

/// Tables 13, 15, 17 and 18 figure by figure: as printed, from the authors' files, from their angles on
/// the replayed scene (static positions), and ours (see `crate::print`).
fn print_comparison(
    runs: &Runs<'_>,
    authors_static: &[PaperResultRow],
    authors_transient: &[PaperResultRow],
) -> Result<PrintComparison, PaperError> {
    use crate::print::{
        compare, file_orientation_deviation, file_position_deviation, printed_value, replayed_position_deviation,
    };
    let largest = |t: &PrintedMinMax| t.min.iter().chain(&t.max).map(|p| printed_value(p).0.abs()).fold(0.0, f64::max);
    let (static_run, transient_run) = (runs.static_run, runs.transient_run);
    let replay = replayed_position_deviation(runs.deformed, authors_static)?;
    let cases = [
        (TABLE_15, file_position_deviation(authors_static), Some(replay), static_run.summary.position_mm),
        (
            TABLE_13,
            file_orientation_deviation(authors_static),
            None,
            SummaryOut::of(&static_run.summary).orientation_deg,
        ),
        (TABLE_17, file_position_deviation(authors_transient), None, transient_run.summary.position_mm),
        (
            TABLE_18,
            file_orientation_deviation(authors_transient),
            None,
            SummaryOut::of(&transient_run.summary).orientation_deg,
        ),
    ];
    let mut rows = Vec::new();
    for (printed, (lo, hi), replay, ours) in cases {
        for figure in compare(&printed, lo, hi) {
            let is_min = figure.bound == "min";
            let replayed = replay.map(|(rl, rh)| if is_min { rl[figure.axis] } else { rh[figure.axis] });
            let ours = if is_min { ours.min[figure.axis] } else { ours.max[figure.axis] };
            rows.push(PrintRow { figure, replayed, ours });
        }
    }
    Ok(PrintComparison {
        rows,
        largest_static_printed_mm: largest(&TABLE_15),
        largest_transient_printed_mm: largest(&TABLE_17),
    })
}

fn max_joint_diff(authors: &[PaperResultRow], ours: &RunOutput) -> f64 {
    authors
        .iter()
        .filter_map(|a| {
            ours.rows.iter().find(|o| o.label == a.label && o.time_min == a.time_min).map(|o| {
                let (theirs, ours) = (to_external(ours, &a.joints), to_external(ours, &o.joints));
                theirs.iter().zip(&ours).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
            })
        })
        .fold(0.0, f64::max)
}
