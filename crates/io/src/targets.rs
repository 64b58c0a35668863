//! Target programs: the authors' CSV (`,X,Y,Z` then `P1,400,300,250`, mm), optionally with `RX,RY,RZ`
//! (degrees, CoppeliaSim X-Y-Z Euler). Without orientation columns every target gets (0, 90, 0), the
//! orientation of Table 12.

use std::path::Path;

use nalgebra::Vector3;

use crate::csvtext::{column, expect_fields, number, records};
use crate::{IoError, read_text};

/// The orientation of every target of Table 12, degrees (X-Y-Z Euler: the tool Z axis along world +X).
pub const DEFAULT_ORIENTATION_DEG: [f64; 3] = [0.0, 90.0, 0.0];

/// One programmed target.
#[derive(Clone, Debug, PartialEq)]
pub struct Target {
    /// Label from the first column (`P1`, …).
    pub label: String,
    /// Position, mm.
    pub position_mm: Vector3<f64>,
    /// Orientation, degrees, X-Y-Z Euler (`R = Rx Ry Rz`).
    pub rotation_xyz_deg: Vector3<f64>,
    /// Line in the file.
    pub line: usize,
}

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
    let rot: Vec<Option<usize>> = ["RX", "RY", "RZ"].iter().map(|n| find(n)).collect();
    if rot.iter().any(Option::is_some) && rot.iter().any(Option::is_none) {
        return Err(IoError::input(path, Some(header.line), "RX,RY,RZ", "give all three orientation columns or none"));
    }
    let label_col = (0..header.cells.len()).find(|i| !pos.contains(i) && !rot.contains(&Some(*i)));
    let mut out = Vec::with_capacity(rows.len());
    for r in rows {
        expect_fields(path, r, header.cells.len())?;
        let p = Vector3::new(
            number(path, r.line, "X", &r.cells[pos[0]])?,
            number(path, r.line, "Y", &r.cells[pos[1]])?,
            number(path, r.line, "Z", &r.cells[pos[2]])?,
        );
        let o = match (rot[0], rot[1], rot[2]) {
            (Some(a), Some(b), Some(c)) => Vector3::new(
                number(path, r.line, "RX", &r.cells[a])?,
                number(path, r.line, "RY", &r.cells[b])?,
                number(path, r.line, "RZ", &r.cells[c])?,
            ),
            _ => Vector3::from(DEFAULT_ORIENTATION_DEG),
        };
        let label = label_col
            .map(|c| r.cells[c].clone())
            .filter(|s| !s.is_empty())
            .unwrap_or_else(|| format!("P{}", out.len() + 1));
        out.push(Target { label, position_mm: p, rotation_xyz_deg: o, line: r.line });
    }
    if out.is_empty() {
        return Err(IoError::input(path, Some(header.line + 1), "rows", "no targets after the header"));
    }
    Ok(out)
}
