//! The paper's printed result tables (Tables 13, 15, 17 and 18: minimum and maximum residual deviations)
//! as data, kept as printed — strings, so that each figure's printed precision is known — and compared
//! with the authors' own files and with their angles evaluated on the replayed scene.
//!
//! Printed precision: the print truncates rather than rounds (Table 15 prints −0.0099978 as −0.0099 and
//! 0.0092997 as 0.00929), so a printed figure `p` with `d` decimals stands for a value within one unit of
//! its last digit, `|v − p| < 10⁻ᵈ`. That is the tolerance of every comparison with print here.

use nalgebra::Vector3;
use serde::Serialize;
use thermokin_chain::Chain;
use thermokin_io::PaperResultRow;

use crate::PaperError;

/// Minimum and maximum per axis, as printed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrintedMinMax {
    /// Table number.
    pub table: u8,
    /// What it holds.
    pub quantity: &'static str,
    /// Minimum per axis (X, Y, Z), as printed.
    pub min: [&'static str; 3],
    /// Maximum per axis, as printed.
    pub max: [&'static str; 3],
}

/// Table 15: static case, programmed − reached position, mm (its third column is labelled ΔX; it is ΔZ).
pub const TABLE_15: PrintedMinMax = PrintedMinMax {
    table: 15,
    quantity: "static position deviation, mm",
    min: ["-0.0053", "-0.0099", "-0.0047"],
    max: ["0.0084", "0.00929", "0.005"],
};
/// Table 13: static case, orientation deviation ΔθX, ΔθY, ΔθZ, degrees.
pub const TABLE_13: PrintedMinMax = PrintedMinMax {
    table: 13,
    quantity: "static orientation deviation, deg",
    min: ["0", "0", "-0.002"],
    max: ["0", "0.02", "0.005"],
};
/// Table 17: transient case, position deviation, mm (third column labelled ΔX; it is ΔZ).
pub const TABLE_17: PrintedMinMax = PrintedMinMax {
    table: 17,
    quantity: "transient position deviation, mm",
    min: ["-0.199", "-0.198", "-0.199"],
    max: ["0.1", "0.1", "0.1"],
};
/// Table 18: transient case, orientation deviation, degrees.
pub const TABLE_18: PrintedMinMax = PrintedMinMax {
    table: 18,
    quantity: "transient orientation deviation, deg",
    min: ["0", "0", "-0.007"],
    max: ["0", "0.1", "0.004"],
};

/// A printed figure's value and the unit of its last digit.
pub fn printed_value(text: &str) -> (f64, f64) {
    let value = text.parse::<f64>().unwrap_or(f64::NAN);
    let decimals = text.split_once('.').map_or(0, |(_, d)| d.len());
    (value, 10f64.powi(-(decimals as i32)))
}

/// One printed figure against a value computed from data.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Figure {
    /// Table number.
    pub table: u8,
    /// `min` or `max`.
    pub bound: &'static str,
    /// Axis 0, 1, 2 (X, Y, Z).
    pub axis: usize,
    /// As printed.
    pub printed: &'static str,
    /// Computed.
    pub computed: f64,
    /// Unit of the printed last digit.
    pub unit: f64,
}

impl Figure {
    /// `true` when the computed value is what the print says, to its precision.
    pub fn agrees(&self) -> bool {
        (self.computed - printed_value(self.printed).0).abs() < self.unit
    }
}

/// Min and max per axis of a set of vectors.
fn min_max(values: impl Iterator<Item = Vector3<f64>>) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for v in values {
        for k in 0..3 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    (lo, hi)
}

/// The six figures of a printed table against computed minima and maxima.
pub fn compare(printed: &PrintedMinMax, min: [f64; 3], max: [f64; 3]) -> Vec<Figure> {
    let mut out = Vec::with_capacity(6);
    for (bound, texts, values) in [("min", printed.min, min), ("max", printed.max, max)] {
        for axis in 0..3 {
            out.push(Figure {
                table: printed.table,
                bound,
                axis,
                printed: texts[axis],
                computed: values[axis],
                unit: printed_value(texts[axis]).1,
            });
        }
    }
    out
}

/// Min/max of the authors' own position deviations (programmed − reached, from their coordinates).
pub fn file_position_deviation(rows: &[PaperResultRow]) -> ([f64; 3], [f64; 3]) {
    min_max(rows.iter().map(|r| r.programmed_mm - r.reached_mm))
}

/// Min/max of the authors' own orientation deviations (programmed − reached X-Y-Z Euler angles, degrees,
/// as their file and tables give them).
pub fn file_orientation_deviation(rows: &[PaperResultRow]) -> ([f64; 3], [f64; 3]) {
    min_max(rows.iter().map(|r| (r.programmed_xyz_rad - r.reached_xyz_rad).map(thermokin_io::units::degrees)))
}

/// Min/max of programmed − FK(their published angles) on `replayed` (the scene, deformed as their script
/// did): the authors' residual deviations, recomputed from their angles by our model.
pub fn replayed_position_deviation(
    replayed: &Chain,
    rows: &[PaperResultRow],
) -> Result<([f64; 3], [f64; 3]), PaperError> {
    let mut deviations = Vec::with_capacity(rows.len());
    for r in rows {
        deviations.push(r.programmed_mm - replayed.tool_pose(&r.joints)?.translation.vector);
    }
    Ok(min_max(deviations.into_iter()))
}
