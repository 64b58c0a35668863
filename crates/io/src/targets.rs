//! Target programs: the authors' CSV (`,X,Y,Z` then `P1,400,300,250`, mm), optionally with an
//! orientation in one of three conventions, told apart by the column names:
//! - `RX,RY,RZ`: X-Y-Z Euler angles in degrees, `R = Rx·Ry·Rz` (the paper's and CoppeliaSim's);
//! - `ROLL,PITCH,YAW`: ROS roll-pitch-yaw in degrees, `R = Rz(yaw)·Ry(pitch)·Rx(roll)`;
//! - `QW,QX,QY,QZ`: a unit quaternion.
//!
//! Without orientation columns every target gets X-Y-Z Euler (0, 90, 0), the orientation of Table 12.

use std::path::Path;

use nalgebra::{Isometry3, Translation3, Vector3};
pub use thermokin_chain::Target;

use crate::csvtext::{column, expect_fields, number, records};
use crate::{IoError, Orientation, read_text};

/// The orientation of every target of Table 12, degrees (X-Y-Z Euler: the tool Z axis along world +X).
pub const DEFAULT_ORIENTATION_DEG: [f64; 3] = [0.0, 90.0, 0.0];

/// Reads a targets CSV.
pub fn read_targets(path: &Path) -> Result<Vec<Target>, IoError> {
    let text = read_text(path)?;
    parse_targets(path, &text)
}

/// Parses a targets CSV's text.
pub fn parse_targets(path: &Path, text: &str) -> Result<Vec<Target>, IoError> {
    let recs = records(path, text)?;
    let Some((header, rows)) = recs.split_first() else {
        return Err(IoError::input(path, Some(1), "header", "empty file: expected the header ,X,Y,Z"));
    };
    let find = |name: &str| column(header, name);
    let pos: Vec<usize> = ["X", "Y", "Z"]
        .iter()
        .map(|n| find(n).ok_or_else(|| IoError::input(path, Some(header.line), *n, format!("missing column `{n}`"))))
        .collect::<Result<_, _>>()?;
    let conventions = [
        (Orientation::XyzEuler, &["RX", "RY", "RZ"][..]),
        (Orientation::Rpy, &["ROLL", "PITCH", "YAW"][..]),
        (Orientation::Quaternion, &["QW", "QX", "QY", "QZ"][..]),
    ];
    let mut orientation: Option<(Orientation, &[&str], Vec<usize>)> = None;
    for (convention, names) in conventions {
        let cols: Vec<Option<usize>> = names.iter().map(|n| find(n)).collect();
        if cols.iter().all(Option::is_none) {
            continue;
        }
        if cols.iter().any(Option::is_none) {
            return Err(IoError::input(
                path,
                Some(header.line),
                names.join(","),
                "give all the columns of an orientation or none",
            ));
        }
        if let Some((_, other, _)) = &orientation {
            return Err(IoError::input(
                path,
                Some(header.line),
                names.join(","),
                format!("two orientations given ({} and {})", other.join(","), names.join(",")),
            ));
        }
        orientation = Some((convention, names, cols.into_iter().flatten().collect()));
    }
    let orientation_cols: &[usize] = orientation.as_ref().map_or(&[], |(_, _, c)| c.as_slice());
    let label_col = (0..header.cells.len()).find(|i| !pos.contains(i) && !orientation_cols.contains(i));
    let mut out = Vec::with_capacity(rows.len());
    for r in rows {
        expect_fields(path, r, header.cells.len())?;
        let p = Vector3::new(
            number(path, r.line, "X", &r.cells[pos[0]])?,
            number(path, r.line, "Y", &r.cells[pos[1]])?,
            number(path, r.line, "Z", &r.cells[pos[2]])?,
        );
        let rotation = match &orientation {
            Some((convention, names, cols)) => {
                let values: Vec<f64> = names
                    .iter()
                    .zip(cols)
                    .map(|(n, &c)| number(path, r.line, n, &r.cells[c]))
                    .collect::<Result<_, _>>()?;
                convention.rotation(&values).map_err(|m| IoError::input(path, Some(r.line), names.join(","), m))?
            }
            None => Orientation::XyzEuler
                .rotation(&DEFAULT_ORIENTATION_DEG)
                .map_err(|m| IoError::input(path, Some(r.line), "RX,RY,RZ", m))?,
        };
        let label = label_col
            .map(|c| r.cells[c].clone())
            .filter(|s| !s.is_empty())
            .unwrap_or_else(|| format!("P{}", out.len() + 1));
        let pose = Isometry3::from_parts(Translation3::from(p), rotation);
        out.push(Target { label, pose, line: Some(r.line) });
    }
    if out.is_empty() {
        return Err(IoError::input(path, Some(header.line + 1), "rows", "no targets after the header"));
    }
    Ok(out)
}
