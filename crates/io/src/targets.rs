//! Target programs: the authors' CSV (`,X,Y,Z` then `P1,400,300,250`, mm), optionally with an
//! orientation in one of three conventions, told apart by the column names:
//! - `RX,RY,RZ`: X-Y-Z Euler angles in degrees, `R = Rx·Ry·Rz` (the paper's and CoppeliaSim's);
//! - `ROLL,PITCH,YAW`: ROS roll-pitch-yaw in degrees, `R = Rz(yaw)·Ry(pitch)·Rx(roll)`;
//! - `QW,QX,QY,QZ`: a unit quaternion.
//!
//! Without orientation columns every target gets X-Y-Z Euler (0, 90, 0), the orientation of Table 12.
//!
//! Optional state columns say when each target is reached: `time_min` (operating time of a warm-up,
//! minutes) and `temp_<name>` (a sensor's reading, °C, named as in measurement files: `temp_j2`); read
//! for a robot ([`read_target_rows_for`]), also every column named as one of its sensors (an
//! accelerometer's `acc_top_x`, a branch's joint). A robot with thermal drift or a sensor row is solved as
//! it is at that moment ([`Target::state`]).

use std::io::BufRead;
use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Translation3, Vector3};
use thermokin_chain::Target;

use crate::csvtext::{Record, check_delimiter, column, expect_fields, number, record, records};
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
    parse_target_rows(path, text)?.rows.into_iter().collect()
}

/// A targets file read row by row: each data row's target or its error, and the columns the header has
/// that nothing reads (ignored, to be said).
#[derive(Debug)]
pub struct TargetRows {
    /// Each data row: its target (its line in [`Target::line`]) or its error.
    pub rows: Vec<Result<Target, IoError>>,
    /// Columns the header names that no target reads (beside the label column).
    pub ignored_columns: Vec<String>,
}

impl TargetRows {
    /// The targets' positions in `units`: metres scaled to millimetres; left unstated (`None`), refused
    /// when ten or more targets all lie within ±5 of the origin — a program written in metres, whose every
    /// target read in millimetres would sit inside the robot's base ([`crate::UnitsUnclear`], as for
    /// measurements).
    pub fn settle_units(mut self, path: &Path, units: Option<crate::PositionUnits>) -> Result<Self, IoError> {
        if units == Some(crate::PositionUnits::Metres) {
            for t in self.rows.iter_mut().flatten() {
                t.pose.translation.vector = t.pose.translation.vector.map(crate::units::millimetres);
            }
            return Ok(self);
        }
        let read: Vec<&Target> = self.rows.iter().flatten().collect();
        let largest = read.iter().map(|t| t.pose.translation.vector.amax()).fold(0.0, f64::max);
        if units.is_none() && read.len() >= 10 && largest <= 5.0 {
            let unclear = crate::UnitsUnclear::PositionsLookLikeMetres { largest };
            return Err(IoError::UnitsUnclear { path: path.to_path_buf(), unclear });
        }
        Ok(self)
    }
}

/// Reads a targets CSV row by row ([`TargetRows`]): a bad header is an error, a bad row that row's.
pub fn read_target_rows(path: &Path) -> Result<TargetRows, IoError> {
    read_target_rows_for(path, &[])
}

/// [`read_target_rows`] for a robot that reads the sensors `sensors` (the names its model carries, as
/// the measurement files named them: `acc_top_x`, a branch's joint `b1`): a column of that name (any
/// case) is that sensor's reading at the target, as a `temp_` column is — so that a program gives a
/// reading under the name the diagnosis read it by, the name an error about a missing reading quotes.
pub fn read_target_rows_for(path: &Path, sensors: &[String]) -> Result<TargetRows, IoError> {
    let text = read_text(path)?;
    parse_target_rows_for(path, &text, sensors)
}

/// Parses a targets CSV's text row by row.
pub fn parse_target_rows(path: &Path, text: &str) -> Result<TargetRows, IoError> {
    parse_target_rows_for(path, text, &[])
}

/// Parses a targets CSV's text row by row, the columns named as `sensors` read as their readings
/// ([`read_target_rows_for`]).
pub fn parse_target_rows_for(path: &Path, text: &str, sensors: &[String]) -> Result<TargetRows, IoError> {
    let recs = records(path, text)?;
    let Some((header, rows)) = recs.split_first() else {
        return Err(IoError::input(path, Some(1), "header", "empty file: expected the header ,X,Y,Z"));
    };
    let layout = Layout::of(path, header, sensors)?;
    let out: Vec<Result<Target, IoError>> = rows.iter().enumerate().map(|(i, r)| layout.target(path, r, i)).collect();
    if out.is_empty() {
        return Err(IoError::input(path, Some(header.line + 1), "rows", "no targets after the header"));
    }
    Ok(TargetRows { rows: out, ignored_columns: layout.ignored.clone() })
}

/// A targets CSV read in chunks, for programs too large to hold: memory stays that of one chunk whatever
/// the file's length. The same columns, conventions and errors as [`read_targets`].
pub struct TargetReader<R> {
    path: PathBuf,
    lines: std::io::Lines<R>,
    line: usize,
    layout: Layout,
    count: usize,
}

impl<R: BufRead> TargetReader<R> {
    /// Reads the header of `input` (named `path` in messages).
    pub fn new(path: &Path, input: R) -> Result<Self, IoError> {
        let mut lines = input.lines();
        let mut line = 0;
        let mut checked = false;
        let header = loop {
            line += 1;
            let Some(raw) = lines.next() else {
                return Err(IoError::input(path, Some(line), "header", "empty file: expected the header ,X,Y,Z"));
            };
            let raw = raw.map_err(|e| IoError::input(path, Some(line), "file", e.to_string()))?;
            if !checked && !raw.trim().is_empty() {
                check_delimiter(path, &raw)?;
                checked = true;
            }
            if let Some(r) = record(path, line, &raw)? {
                break r;
            }
        };
        let layout = Layout::of(path, &header, &[])?;
        Ok(Self { path: path.to_path_buf(), lines, line, layout, count: 0 })
    }

    /// The next at most `max` targets; empty at the end of the file. A file with a header and no target
    /// is an error, as for [`read_targets`].
    pub fn next_chunk(&mut self, max: usize) -> Result<Vec<Target>, IoError> {
        let mut out = Vec::with_capacity(max.min(1 << 16));
        while out.len() < max {
            let Some(raw) = self.lines.next() else { break };
            self.line += 1;
            let raw = raw.map_err(|e| IoError::input(&self.path, Some(self.line), "file", e.to_string()))?;
            if let Some(r) = record(&self.path, self.line, &raw)? {
                out.push(self.layout.target(&self.path, &r, self.count)?);
                self.count += 1;
            }
        }
        if out.is_empty() && self.count == 0 {
            return Err(IoError::input(&self.path, Some(self.line + 1), "rows", "no targets after the header"));
        }
        Ok(out)
    }

    /// Targets read so far.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Columns the header names that no target reads (beside the label column).
    pub fn ignored_columns(&self) -> &[String] {
        &self.layout.ignored
    }
}

/// Where a targets file keeps its columns, from its header.
struct Layout {
    columns: usize,
    position: [usize; 3],
    orientation: Option<(Orientation, &'static [&'static str], Vec<usize>)>,
    label: Option<usize>,
    /// `time_min`: the operating time at the target.
    time: Option<usize>,
    /// `temp_<name>` columns: sensor readings at the target, °C (named with the prefix, `temp_j2`); and
    /// the columns named as a sensor the robot reads, by the robot's name for it.
    temps: Vec<(usize, String)>,
    /// Columns nothing reads: besides the label, only when an orientation is given (else refused).
    ignored: Vec<String>,
}

impl Layout {
    fn of(path: &Path, header: &Record, sensors: &[String]) -> Result<Self, IoError> {
        let find = |name: &str| column(header, name);
        let mut position = [0; 3];
        for (slot, n) in position.iter_mut().zip(["X", "Y", "Z"]) {
            *slot =
                find(n).ok_or_else(|| IoError::input(path, Some(header.line), n, format!("missing column `{n}`")))?;
        }
        const CONVENTIONS: [(Orientation, &[&str]); 3] = [
            (Orientation::XyzEuler, &["RX", "RY", "RZ"]),
            (Orientation::Rpy, &["ROLL", "PITCH", "YAW"]),
            (Orientation::Quaternion, &["QW", "QX", "QY", "QZ"]),
        ];
        let mut orientation: Option<(Orientation, &'static [&'static str], Vec<usize>)> = None;
        for (convention, names) in CONVENTIONS {
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
        let time = find("time_min");
        let robots = |c: &str| sensors.iter().find(|s| s.eq_ignore_ascii_case(c.trim())).cloned();
        let temps: Vec<(usize, String)> = header
            .cells
            .iter()
            .enumerate()
            .filter_map(|(i, c)| match sensor_suffix(c) {
                Some(_) => Some((i, sensor_name(c))),
                None => robots(c).map(|name| (i, name)),
            })
            .collect();
        let state_col = |i: &usize| time == Some(*i) || temps.iter().any(|(c, _)| c == i);
        let unread: Vec<usize> = (0..header.cells.len())
            .filter(|i| !position.contains(i) && !orientation_cols.contains(i) && !state_col(i))
            .collect();
        let label = unread.first().copied();
        let ignored: Vec<String> = unread.iter().skip(1).map(|&i| header.cells[i].clone()).collect();
        // Unknown columns beside a file without an orientation would leave every target at the default
        // orientation — they may be an orientation under other names: refused, not guessed.
        if orientation.is_none() && !ignored.is_empty() {
            return Err(IoError::input(
                path,
                Some(header.line),
                ignored.join(","),
                format!(
                    "unknown column{} {}: an orientation is read from RX,RY,RZ (X-Y-Z Euler degrees), ROLL,PITCH,YAW or QW,QX,QY,QZ; without one every target is at ({}, {}, {}) — name the columns, or drop them",
                    if ignored.len() > 1 { "s" } else { "" },
                    ignored.iter().map(|c| format!("`{c}`")).collect::<Vec<_>>().join(", "),
                    DEFAULT_ORIENTATION_DEG[0],
                    DEFAULT_ORIENTATION_DEG[1],
                    DEFAULT_ORIENTATION_DEG[2]
                ),
            ));
        }
        Ok(Self { columns: header.cells.len(), position, orientation, label, time, temps, ignored })
    }

    /// Row `r`, the `index`-th target of the file (0-based, for the default label `P{index + 1}`).
    fn target(&self, path: &Path, r: &Record, index: usize) -> Result<Target, IoError> {
        expect_fields(path, r, self.columns)?;
        let [x, y, z] = self.position;
        let p = Vector3::new(
            number(path, r.line, "X", &r.cells[x])?,
            number(path, r.line, "Y", &r.cells[y])?,
            number(path, r.line, "Z", &r.cells[z])?,
        );
        let rotation = match &self.orientation {
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
        let label = self
            .label
            .map(|c| r.cells[c].clone())
            .filter(|s| !s.is_empty())
            .unwrap_or_else(|| format!("P{}", index + 1));
        let pose = Isometry3::from_parts(Translation3::from(p), rotation);
        let mut state = thermokin_chain::OperatingState::default();
        if let Some(c) = self.time {
            let t = number(path, r.line, "time_min", &r.cells[c])?;
            if t < 0.0 {
                return Err(IoError::input(path, Some(r.line), "time_min", format!("{t} is negative")));
            }
            state.time_min = Some(t);
        }
        for (c, name) in &self.temps {
            state.temperatures_c.push((name.clone(), number(path, r.line, name, &r.cells[*c])?));
        }
        Ok(Target { label, pose, line: Some(r.line), state })
    }
}

/// The part of `name` after a `temp_` prefix (any case), if it has one and something follows.
fn sensor_suffix(name: &str) -> Option<&str> {
    (name.len() > 5 && name.is_char_boundary(5) && name[..5].eq_ignore_ascii_case("temp_")).then(|| &name[5..])
}

/// A temperature sensor's name as files and robot models carry it: `temp_<name>`, the prefix written in
/// lower case and added when left out (`J2` → `temp_J2`, `TEMP_j2` → `temp_j2`).
pub fn sensor_name(name: &str) -> String {
    format!("temp_{}", sensor_suffix(name).unwrap_or(name))
}
