//! The authors' results files (`results-static-case-study.csv`, `results-transient-case-study.csv`):
//! two header rows, one row per target (with a leading `time_min` column in the transient file), then
//! `MIN`/`MAX` trailer rows.

use std::path::Path;

use nalgebra::Vector3;

use thermokin_chain::JointKind;

use crate::csvtext::{number, records};
use crate::{IoError, read_text, units};

/// One row of an authors' results file.
#[derive(Clone, Debug, PartialEq)]
pub struct PaperResultRow {
    /// Operating time, minutes (0 in the static file).
    pub time_min: f64,
    /// Target label.
    pub label: String,
    /// Programmed position, mm.
    pub programmed_mm: Vector3<f64>,
    /// Position reached in CoppeliaSim, mm.
    pub reached_mm: Vector3<f64>,
    /// Programmed orientation: the file's X-Y-Z Euler angles (RX, RY, RZ), in radians. Kept as the
    /// three angles, not a rotation: Tables 13 and 18 are differences of these angles, and every
    /// target sits at the Euler singularity (RY = 90°), where a rotation does not give them back.
    pub programmed_xyz_rad: Vector3<f64>,
    /// Orientation reached, the file's X-Y-Z Euler angles in radians.
    pub reached_xyz_rad: Vector3<f64>,
    /// Joint values A1..A6 in radians (the authors' IRB 140 has revolute joints only).
    pub joints: Vec<f64>,
}

/// Reads either results file (the transient one is recognised by its leading time column).
pub fn read_paper_results(path: &Path) -> Result<Vec<PaperResultRow>, IoError> {
    let text = read_text(path)?;
    parse_paper_results(path, &text)
}

/// Parses an authors' results file's text.
pub fn parse_paper_results(path: &Path, text: &str) -> Result<Vec<PaperResultRow>, IoError> {
    let recs = records(path, text)?;
    if recs.len() < 3 {
        return Err(IoError::input(path, None, "rows", "expected two header rows and data rows"));
    }
    let transient = recs[1].cells.first().is_some_and(|c| c.to_ascii_lowercase().starts_with("time"));
    let shift = usize::from(transient);
    let mut out = Vec::new();
    for r in &recs[2..] {
        let label = r.cells.get(shift).cloned().unwrap_or_default();
        if label.is_empty() || !label.starts_with('P') {
            continue; // MIN / MAX trailer rows
        }
        let need = shift + 25;
        if r.cells.len() < need {
            return Err(IoError::input(
                path,
                Some(r.line),
                "row",
                format!("{} fields, expected {need}", r.cells.len()),
            ));
        }
        let n = |k: usize, name: &str| number(path, r.line, name, &r.cells[shift + k]);
        let v3 = |k: usize, name: &str| -> Result<Vector3<f64>, IoError> {
            Ok(Vector3::new(n(k, name)?, n(k + 1, name)?, n(k + 2, name)?))
        };
        let joints = (19..25)
            .map(|k| n(k, &format!("A{}", k - 18)).map(|v| units::joint_value_in(JointKind::Revolute, v)))
            .collect::<Result<Vec<_>, _>>()?;
        let angles = |k: usize, name: &str| v3(k, name).map(|v| v.map(units::radians));
        out.push(PaperResultRow {
            time_min: if transient { number(path, r.line, "Time (min)", &r.cells[0])? } else { 0.0 },
            label,
            programmed_mm: v3(1, "programmed X,Y,Z")?,
            reached_mm: v3(4, "CoppeliaSim X,Y,Z")?,
            programmed_xyz_rad: angles(10, "programmed RX,RY,RZ")?,
            reached_xyz_rad: angles(13, "CoppeliaSim RX,RY,RZ")?,
            joints,
        });
    }
    Ok(out)
}
