//! The reproduction of the paper's two case studies (section 4, Tables 10–18): rerun with our model and
//! IK from the transcribed tables in `fixtures/paper/`, the authors' scene replayed, and everything
//! compared side by side — with the print ([`crate::print`]), with the authors' own files, and with our
//! compensation. [`reproduce`] returns the measured numbers (typed, [`Measurements`]; measured in
//! `crate::measure`, rendered to Markdown in `crate::render`) and the report; the CLI and `cargo xtask`
//! only call it and write what it returns.

use std::path::{Path, PathBuf};

use serde_json::{Value, json};
use thermokin_chain::Chain;
use thermokin_chain::Target;
use thermokin_compensate::{
    Accumulation, Cycle, RunOutput, RunSettings, SummaryOut, compensate_static, compensate_transient,
};
use thermokin_deform::{AfterStabilization, TableSemantics, TimeProfile};
use thermokin_ik::Params;
use thermokin_io::{read_deviation_table, read_robot, read_targets};

use crate::PaperError;
use crate::measure::{Measurements, Runs, measure, to_internal};

/// Where the inputs are.
#[derive(Clone, Debug, PartialEq)]
pub struct Inputs {
    /// The transcribed tables (`fixtures/paper`).
    pub fixtures: PathBuf,
    /// Table 9's IRB 140 (`configs/irb140.toml`): the canonical run and the scene's identification.
    pub robot: PathBuf,
    /// The scene's IRB 140 (`configs/irb140-scene.toml`): the CoppeliaSim-semantics runs.
    pub scene_robot: PathBuf,
    /// The authors' files (`fixtures/paper/authors`); compared when present.
    pub authors: PathBuf,
}

/// The figures a reproduction's one-screen summary gives ([`Headline::text`]): typed, not read back from
/// the JSON.
#[derive(Clone, Debug, PartialEq)]
pub struct Headline {
    /// The static case on the authors' scene (Tables 13, 15), mm and degrees.
    pub static_case: SummaryOut,
    /// The transient case (Tables 17, 18), mm and degrees.
    pub transient: SummaryOut,
    /// FK of Table 16's printed angles on our deformed model against Table 14's coordinates, RMS (3-D), mm.
    pub table16_rms_mm: f64,
}

impl Headline {
    /// The summary `thermokin reproduce-paper` prints.
    pub fn text(&self) -> String {
        let (s, t) = (&self.static_case, &self.transient);
        format!(
            "static case (50 targets): largest compensated error {:.3e} mm, {:.3e}°; uncompensated {:.3e} mm\n\
             transient case (10,050 solves): largest compensated error {:.3e} mm, {:.3e}°; uncompensated {:.3e} mm\n\
             published Table 16 angles on our deformed model vs Table 14: RMS {:.3e} mm",
            s.max_position_error_mm,
            s.max_orientation_error_deg,
            s.max_uncompensated_error_mm,
            t.max_position_error_mm,
            t.max_orientation_error_deg,
            t.max_uncompensated_error_mm,
            self.table16_rms_mm,
        )
    }
}

/// What a reproduction measured.
pub struct Reproduction {
    /// The measured numbers, typed ([`Measurements::golden_json`] is the golden file's format).
    pub measurements: Measurements,
    /// The one-screen summary's figures.
    pub headline: Headline,
    /// The Markdown report.
    pub report: String,
    /// The static compensation on the scene.
    pub static_run: RunOutput,
    /// The transient compensation on the scene.
    pub transient_run: RunOutput,
    /// The scene's nominal robot.
    pub scene: Chain,
    /// The scene deformed by the case-study table (the authors' semantics).
    pub deformed: Chain,
}

/// A labelled row of numbers from a fixture CSV (`label,v1,…`).
fn labelled_rows(path: &Path) -> Result<Vec<(String, Vec<f64>)>, PaperError> {
    let text = thermokin_io::read_text(path)?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') || line.starts_with(',') {
            continue;
        }
        let mut cells = line.split(',');
        let label = cells.next().unwrap_or_default().to_string();
        let values = cells
            .map(|c| {
                c.trim().parse::<f64>().map_err(|_| PaperError::Fixture {
                    path: path.to_path_buf(),
                    line: i + 1,
                    message: format!("`{c}` is not a number"),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        out.push((label, values));
    }
    Ok(out)
}

/// Reruns both case studies and compares them with print, with the authors' files and with the
/// replayed scene. `progress` is called after each transient step with (steps done, steps in all).
///
/// ```
/// use std::path::PathBuf;
/// use thermokin_paper::{Inputs, reproduce};
///
/// let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
/// let inputs = Inputs {
///     fixtures: root.join("fixtures/paper"),
///     robot: root.join("configs/irb140.toml"),
///     scene_robot: root.join("configs/irb140-scene.toml"),
///     authors: root.join("fixtures/paper/authors"),
/// };
/// let r = reproduce(&inputs, |_, _| {}).unwrap();
/// // 50 static targets and 10,050 transient solves, all reached to the solver's tolerance.
/// assert_eq!(r.static_run.rows.len(), 50);
/// assert_eq!(r.transient_run.rows.len(), 10_050);
/// assert!(r.measurements.transient.max_position_error_mm < 1e-9);
/// assert_eq!(r.measurements.golden_json()["transient"]["failures"], 0);
/// assert!(r.report.contains("Tables 13, 15, 17 and 18 against print"));
/// ```
pub fn reproduce(inputs: &Inputs, progress: impl FnMut(usize, usize)) -> Result<Reproduction, PaperError> {
    let a = inputs;
    let robot = read_robot(&a.robot)?;
    let chain = robot.chain().clone();
    let scene = read_robot(&a.scene_robot)?.chain().clone();
    let f = |name: &str| a.fixtures.join(name);
    let prog: Vec<Target> = read_targets(&f("table12-targets.csv"))?;
    let table = read_deviation_table(&f("deformations-case-study.toml"))?;
    let table14 = labelled_rows(&f("table14-reached-static.csv"))?;
    let table16 = labelled_rows(&f("table16-joints-static.csv"))?;
    let coppelia = TableSemantics::coppeliasim_at_home(chain.dof());
    // The authors' IK ran in CoppeliaSim from the robot's current pose; a seed with the wrist bent down
    // (A5 = −45°) puts every target on the branch of their Table 16 (A5 < 0).
    let start = to_internal(&scene, &[0.0, 20.0, 20.0, 0.0, -45.0, 0.0], "the start configuration")?;
    let settings = RunSettings {
        semantics: coppelia.clone(),
        accumulation: Accumulation::FromNominal,
        ik: Params::default(),
        start,
    };

    let static_run = compensate_static(&scene, &table, &prog, &settings)?;
    let canonical_run = compensate_static(
        &chain,
        &table,
        &prog,
        &RunSettings { semantics: TableSemantics::Canonical, ..settings.clone() },
    )?;
    let profile = TimeProfile::Linear { stabilization_min: 180.0, after: AfterStabilization::KeepGrowing };
    let transient_run = compensate_transient(&scene, &table, &profile, Cycle::PAPER, &prog, &settings, progress)?;

    let deformed = table.apply(&scene, &coppelia)?;
    let deformed_canonical = table.apply(&chain, &TableSemantics::Canonical)?;
    let runs = Runs {
        nominal: &chain,
        deformed: &deformed,
        deformed_canonical: &deformed_canonical,
        static_run: &static_run,
        canonical_run: &canonical_run,
        transient_run: &transient_run,
    };
    let measurements = measure(&runs, &table14, &table16, &a.authors)?;
    let headline = Headline {
        static_case: SummaryOut::of(&static_run.summary),
        transient: SummaryOut::of(&transient_run.summary),
        table16_rms_mm: measurements.table16.on_our_model.rms_mm,
    };
    let report = measurements.report()?;
    Ok(Reproduction { measurements, report, headline, static_run, transient_run, scene, deformed })
}

/// Compares the measured numbers with the golden file. Keys ending in `_error_mm` or `_error_deg` under
/// `static`/`transient` are bounds: ≤ 1e-6 (the compensation must stay exact); every other number must
/// match the golden value within 1e-6 (absolute, mm or degrees) — the runs are deterministic, so any
/// larger change is a change of the model. A key present in only one of the two is drift.
pub fn check(g: &Value, measured: &Value) -> Vec<String> {
    check_values(g, measured)
}

/// [`check`] against the golden JSON file at `path` (read from disk, or bundled).
pub fn check_file(path: &std::path::Path, measured: &Value) -> Result<Vec<String>, crate::PaperError> {
    let text = thermokin_io::read_text(path)?;
    let golden: Value = serde_json::from_str(&text).map_err(|e| crate::PaperError::Fixture {
        path: path.to_path_buf(),
        line: e.line(),
        message: format!("not the golden JSON: {e}"),
    })?;
    Ok(check_values(&golden, measured))
}

fn check_values(g: &Value, measured: &Value) -> Vec<String> {
    let mut drift = Vec::new();
    for case in ["static", "static_canonical", "transient"] {
        for key in ["max_position_error_mm", "max_orientation_error_deg"] {
            let v = measured[case][key].as_f64().unwrap_or(f64::INFINITY);
            if v > 1e-6 {
                drift.push(format!("{case}.{key} = {v:.3e} exceeds the 1e-6 bound"));
            }
        }
        if measured[case]["failures"] != json!(0) {
            drift.push(format!("{case}: {} failed targets", measured[case]["failures"]));
        }
    }
    compare("", g, measured, &mut drift);
    drift
}

fn compare(path: &str, g: &Value, m: &Value, drift: &mut Vec<String>) {
    match (g, m) {
        (Value::Object(go), Value::Object(mo)) => {
            // A key on one side only is drift too: a number that disappeared, or one that was never blessed.
            for k in mo.keys().filter(|k| !go.contains_key(*k)) {
                drift.push(format!("{path}.{k}: measured but not in the golden file (bless it)"));
            }
            for (k, gv) in go {
                let Some(mv) = mo.get(k) else {
                    drift.push(format!("{path}.{k}: in the golden file but no longer measured"));
                    continue;
                };
                {
                    // The min/max of compensated deviations are rounding noise (~1e-10); bounded above.
                    if matches!(
                        k.as_str(),
                        "position_mm" | "orientation_deg" | "max_position_error_mm" | "max_orientation_error_deg"
                    ) {
                        continue;
                    }
                    compare(&format!("{path}.{k}"), gv, mv, drift);
                }
            }
        }
        (Value::Array(ga), Value::Array(ma)) => {
            if ga.len() != ma.len() {
                drift.push(format!("{path}: {} values, golden {}", ma.len(), ga.len()));
            }
            for (i, (gv, mv)) in ga.iter().zip(ma).enumerate() {
                compare(&format!("{path}[{i}]"), gv, mv, drift);
            }
        }
        (Value::Number(gn), Value::Number(mn)) => {
            let (a, b) = (gn.as_f64().unwrap_or(f64::NAN), mn.as_f64().unwrap_or(f64::NAN));
            if (a - b).abs() > 1e-6 || a.is_nan() != b.is_nan() {
                drift.push(format!("{path} = {b}, golden {a}"));
            }
        }
        (gv, mv) if gv != mv => drift.push(format!("{path} = {mv}, golden {gv}")),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;
    use crate::measure::fk_residual;

    fn two_joint_chain() -> Chain {
        use thermokin_chain::{FixedRow, Joint};
        let joints = vec![
            Joint::revolute("j1", Vector3::new(0.0, 0.0, 100.0), Vector3::z_axis()),
            Joint::revolute("j2", Vector3::new(0.0, 0.0, 200.0), Vector3::y_axis()),
        ];
        Chain::new(FixedRow::identity(), joints, FixedRow::identity()).expect("a valid chain")
    }

    #[test]
    fn a_row_fk_refuses_is_an_error_not_a_perfect_match() {
        // Before: the row was left out (filter_map) or became a zero deviation (unwrap_or_default),
        // which read as a perfect match.
        let chain = two_joint_chain();
        let good = (vec![0.0, 0.0], Vector3::new(0.0, 0.0, 300.0));
        let bad = (vec![f64::NAN, 0.0], Vector3::new(0.0, 0.0, 300.0));
        let fine = fk_residual(&chain, std::slice::from_ref(&good)).expect("a finite row");
        assert_eq!(fine.rows, 1);
        assert!(fine.rms_mm < 1e-9);
        assert!(fk_residual(&chain, &[good, bad]).is_err());
    }

    #[test]
    fn a_joint_row_of_the_wrong_length_is_an_error() {
        let chain = two_joint_chain();
        let err = to_internal(&chain, &[1.0, 2.0, 3.0], "Table 16 row").expect_err("three values for two joints");
        assert!(matches!(err, PaperError::Shape { what: "Table 16 row", expected: 2, got: 3 }), "{err}");
        assert_eq!(to_internal(&chain, &[90.0, 0.0], "row").expect("two values").len(), 2);
    }

    #[test]
    fn without_the_authors_files_the_measurements_say_so_and_the_report_renders_them() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let missing = root.join("fixtures/paper/no-such-directory");
        let inputs = Inputs {
            fixtures: root.join("fixtures/paper"),
            robot: root.join("configs/irb140.toml"),
            scene_robot: root.join("configs/irb140-scene.toml"),
            authors: missing.clone(),
        };
        let r = reproduce(&inputs, |_, _| {}).expect("the printed tables alone reproduce");
        let m = &r.measurements;
        assert!(m.authors.is_none());
        // Table 16 prints 25 targets, each in Table 14 and in our run.
        assert_eq!(m.table16.rows.len(), 25);
        assert_eq!(m.table16.on_our_model.rows, 25);
        // The golden format has only the printed-table keys, and the report names the missing directory.
        let keys: Vec<String> = m.golden_json().as_object().expect("an object").keys().cloned().collect();
        assert_eq!(keys.len(), 6, "{keys:?}");
        assert!(!keys.iter().any(|k| k.starts_with("authors_") || k.starts_with("scene_")), "{keys:?}");
        assert!(r.report.contains(&format!("were not found at `{}`", missing.display())));
        assert_eq!(r.report, m.report().expect("renders"));
    }
}
