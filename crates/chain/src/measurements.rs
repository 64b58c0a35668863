//! Measured poses: plain data, read from files by `thermokin-io` and fitted by `thermokin-diagnose`. They
//! live in the core so that the readers sit below the algorithms that use them.

use nalgebra::{UnitQuaternion, Vector3};

/// One measured pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// Operating time, minutes (0 when the file has none).
    pub time_min: f64,
    /// Joint values, radians (mm for prismatic joints).
    pub q: Vec<f64>,
    /// Measured TCP position, mm.
    pub position_mm: Vector3<f64>,
    /// Measured tool orientation in the same frame, when the probe measures one (a 6-D probe: T-Mac,
    /// three reflectors); `None` for a position-only reflector.
    pub orientation: Option<UnitQuaternion<f64>>,
    /// The tracker's stated standard deviation of this position per axis, mm, when it reports one
    /// (`std_x, std_y, std_z`): the fit weighs each axis by it.
    pub position_std_mm: Option<Vector3<f64>>,
    /// Temperatures, °C, in the order of [`Dataset::temperature_names`].
    pub temps: Vec<f64>,
}

/// A set of measurements.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Dataset {
    /// The measurements.
    pub measurements: Vec<Measurement>,
    /// Names of the temperature columns.
    pub temperature_names: Vec<String>,
    /// Where each measurement was read: its 1-based line in the measurements file (the header is line
    /// 1; of the poses file when joints and poses are kept apart), one per measurement — empty when the
    /// set was not read from a file. What a report names a measurement by ([`Dataset::line_of`]).
    pub source_lines: Vec<usize>,
    /// Names of the sensor columns (an accelerometer's or inclinometer's tilt, a load): the readings a
    /// row's error may follow linearly; empty when the set has none.
    pub sensor_names: Vec<String>,
    /// Per measurement, its reading of each sensor column (in [`Dataset::sensor_names`]' order); empty
    /// when the set has no sensor columns.
    pub sensor_values: Vec<Vec<f64>>,
}

impl Dataset {
    /// The measurements at `rows` (in that order), with the same temperature columns.
    pub fn subset(&self, rows: &[usize]) -> Dataset {
        Dataset {
            measurements: rows.iter().filter_map(|&i| self.measurements.get(i).cloned()).collect(),
            temperature_names: self.temperature_names.clone(),
            source_lines: if self.source_lines.len() == self.measurements.len() {
                rows.iter().filter_map(|&i| self.source_lines.get(i).copied()).collect()
            } else {
                Vec::new()
            },
            sensor_names: self.sensor_names.clone(),
            sensor_values: if self.sensor_values.len() == self.measurements.len() {
                rows.iter().filter_map(|&i| self.sensor_values.get(i).cloned()).collect()
            } else {
                Vec::new()
            },
        }
    }

    /// The file line measurement `i` (0-based) was read from, when the set was read from a file.
    pub fn line_of(&self, i: usize) -> Option<usize> {
        (self.source_lines.len() == self.measurements.len()).then(|| self.source_lines.get(i).copied()).flatten()
    }

    /// Number of measurements.
    pub fn len(&self) -> usize {
        self.measurements.len()
    }
    /// `true` when there are none.
    pub fn is_empty(&self) -> bool {
        self.measurements.is_empty()
    }
    /// `true` when every measurement carries an orientation (the diagnosis then fits 6-D poses).
    pub fn has_orientation(&self) -> bool {
        !self.measurements.is_empty() && self.measurements.iter().all(|m| m.orientation.is_some())
    }
    /// `true` when every measurement carries the tracker's stated standard deviations.
    pub fn has_position_std(&self) -> bool {
        !self.measurements.is_empty() && self.measurements.iter().all(|m| m.position_std_mm.is_some())
    }
    /// The time span covered, minutes.
    pub fn time_span(&self) -> f64 {
        let (lo, hi) = self
            .measurements
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), m| (l.min(m.time_min), h.max(m.time_min)));
        if lo.is_finite() { hi - lo } else { 0.0 }
    }
}
