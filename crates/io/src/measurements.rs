//! Measurement sets for identification and diagnosis: `time_min` (optional), `q1..qn` (degrees, or radians
//! with [`JointUnits::Radians`]), `x,y,z` (mm), optional `rx,ry,rz` (the measured tool orientation, X-Y-Z Euler
//! angles in degrees as everywhere in the project: a 6-D probe; all three or none), optional `temp_<name>` (°C). Comma-separated, semicolon-separated
//! with decimal commas, or whitespace-separated, as tracker software exports them. The authors' results
//! files are accepted too (their joints and reached coordinates).

use std::path::Path;

use nalgebra::{UnitQuaternion, Vector3};
use thermokin_chain::{Dataset, JointKind, Measurement, OperatingState};

use crate::csvtext::{Record, column, expect_fields, number, records_any_dialect};
use crate::targets::sensor_name;
use crate::units::{Orientation, joint_value_in, joint_value_out, xyz_euler_deg};
use crate::{IoError, parse_paper_results, read_text};

/// Reads a measurement set for a robot with `dof` joints (revolute joints in degrees).
pub fn read_measurements(path: &Path, kinds: &[JointKind]) -> Result<Dataset, IoError> {
    let text = read_text(path)?;
    parse_measurements(path, &text, kinds)
}

/// The unit of a measurement file's revolute joint columns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum JointUnits {
    /// Degrees (the paper's, and this project's files).
    #[default]
    Degrees,
    /// Radians (what ROS and many robot SDKs log).
    Radians,
}

thermokin_chain::choices!(
    JointUnits,
    "joint unit",
    [
        ("deg", "degrees (this project's files)", JointUnits::Degrees),
        ("rad", "radians (ROS, robot SDKs)", JointUnits::Radians),
    ]
);

/// The unit of a measurement file's positions (and their standard deviations).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PositionUnits {
    /// Millimetres (this project's files, most tracker software).
    #[default]
    Millimetres,
    /// Metres (ROS, some tracker exports): converted to millimetres on reading.
    Metres,
}

thermokin_chain::choices!(
    PositionUnits,
    "position unit",
    [
        ("mm", "millimetres (this project's files)", PositionUnits::Millimetres),
        ("m", "metres (ROS, some tracker exports), converted on reading", PositionUnits::Metres),
    ]
);

/// A unit the numbers of a file contradict, when the file's unit was not stated: refused rather than
/// absorbed into hundreds of millimetres of "error".
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UnitsUnclear {
    /// Every revolute joint value lies within ±2π when read as degrees (±6.28°): radians, most likely.
    JointsLookLikeRadians {
        /// The largest magnitude read, degrees.
        largest_deg: f64,
    },
    /// Every coordinate lies within ±5 when read as millimetres: a robot's workspace in metres.
    PositionsLookLikeMetres {
        /// The largest magnitude read.
        largest: f64,
    },
}

impl std::fmt::Display for UnitsUnclear {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            UnitsUnclear::JointsLookLikeRadians { largest_deg } => write!(
                f,
                "every revolute joint value lies within ±{largest_deg:.3}: read as degrees, the arm would hardly move; these look like radians"
            ),
            UnitsUnclear::PositionsLookLikeMetres { largest } => write!(
                f,
                "every coordinate lies within ±{largest:.4}: read as millimetres, the whole workspace would fit in a 1 cm cube; these look like metres"
            ),
        }
    }
}

/// How a measurement file writes what is not fixed by its columns' names: the unit of revolute joints
/// and of positions, and the convention of the measured orientation. A unit left unstated (`None`) is
/// the default one, checked against the numbers ([`UnitsUnclear`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MeasurementFormat {
    /// Revolute joint columns in degrees or radians; `None`: degrees, refused if the values look like
    /// radians.
    pub joint_units: Option<JointUnits>,
    /// Positions in millimetres or metres; `None`: millimetres, refused if they look like metres.
    pub position_units: Option<PositionUnits>,
    /// The orientation columns: `rx,ry,rz` as X-Y-Z Euler angles (`R = Rx·Ry·Rz`, the default and this
    /// project's convention) or as roll, pitch, yaw (`R = Rz(rz)·Ry(ry)·Rx(rx)`, ROS and many trackers),
    /// degrees; or `qw,qx,qy,qz`, a unit quaternion.
    pub orientation: Orientation,
}

/// Fewest measurements from which a unit is judged by the numbers ([`UnitsUnclear`]).
const UNIT_EVIDENCE: usize = 10;

/// The units of `data` (read with `format`) settled: positions given in metres scaled to millimetres;
/// units left unstated that the numbers contradict refused ([`IoError::UnitsUnclear`]). Readers call it;
/// a front end that builds a data set from arrays calls it too.
pub fn settle_units(
    path: &Path,
    mut data: Dataset,
    kinds: &[JointKind],
    format: MeasurementFormat,
) -> Result<Dataset, IoError> {
    let unclear = |unclear| Err(IoError::UnitsUnclear { path: path.to_path_buf(), unclear });
    if format.position_units == Some(PositionUnits::Metres) {
        for m in &mut data.measurements {
            m.position_mm = m.position_mm.map(crate::units::millimetres);
            m.position_std_mm = m.position_std_mm.map(|s| s.map(crate::units::millimetres));
        }
    }
    if data.len() < UNIT_EVIDENCE {
        return Ok(data);
    }
    let revolute: Vec<usize> = (0..kinds.len()).filter(|&j| kinds[j] == JointKind::Revolute).collect();
    if format.joint_units.is_none() && !revolute.is_empty() {
        let largest = data.measurements.iter().flat_map(|m| revolute.iter().map(|&j| m.q[j].abs())).fold(0.0, f64::max);
        // 2π read as degrees is 0.11 rad: joints that never leave ±6.3° were most likely written in radians.
        if largest < crate::units::radians(std::f64::consts::TAU) {
            return unclear(UnitsUnclear::JointsLookLikeRadians { largest_deg: crate::units::degrees(largest) });
        }
    }
    if format.position_units.is_none() {
        let largest = data.measurements.iter().map(|m| m.position_mm.amax()).fold(0.0, f64::max);
        if largest <= 5.0 {
            return unclear(UnitsUnclear::PositionsLookLikeMetres { largest });
        }
    }
    Ok(data)
}

/// Reads a measurement set written in `format`.
pub fn read_measurements_with(path: &Path, kinds: &[JointKind], format: MeasurementFormat) -> Result<Dataset, IoError> {
    let text = read_text(path)?;
    parse_measurements_with(path, &text, kinds, format)
}

/// Parses a measurement set's text for a robot whose joints are of `kinds` (one per joint): joint columns
/// are degrees for revolute joints and mm for prismatic ones.
pub fn parse_measurements(path: &Path, text: &str, kinds: &[JointKind]) -> Result<Dataset, IoError> {
    parse_measurements_with(path, text, kinds, MeasurementFormat::default())
}

/// As [`parse_measurements`], written in `format`.
pub fn parse_measurements_with(
    path: &Path,
    text: &str,
    kinds: &[JointKind],
    format: MeasurementFormat,
) -> Result<Dataset, IoError> {
    let dof = kinds.len();
    if text.lines().next().is_some_and(|l| l.contains("Programmed coordinate")) {
        // The authors' results files hold the six joint angles of a revolute arm.
        if kinds.len() != 6 || kinds.iter().any(|&k| k != JointKind::Revolute) {
            return Err(IoError::input(
                path,
                Some(1),
                "A1..A6",
                format!(
                    "an authors' results file holds six revolute joints; the robot has {dof} joints of kinds {kinds:?}"
                ),
            ));
        }
        let rows = parse_paper_results(path, text)?;
        let measurements = rows
            .into_iter()
            .map(|r| Measurement {
                time_min: r.time_min,
                q: r.joints,
                position_mm: r.reached_mm,
                orientation: None,
                position_std_mm: None,
                temps: Vec::new(),
            })
            .collect();
        return Ok(Dataset { measurements, ..Dataset::default() });
    }
    let recs = records_any_dialect(path, text)?;
    let Some((header, rows)) = recs.split_first() else {
        return Err(IoError::input(path, Some(1), "header", "empty file: expected q1..qn,x,y,z"));
    };
    let joints = JointColumns::find(path, header, kinds, format.joint_units.unwrap_or_default())?;
    let poses = PoseColumns::find(path, header, format.orientation)?;
    let pairs = rows.iter().map(|r| expect_fields(path, r, header.cells.len()).map(|()| (r, r)));
    let mut data = assemble(
        &joints,
        &poses,
        pairs,
        IoError::input(path, Some(header.line + 1), "rows", "no measurements after the header"),
    )?;
    (data.sensor_names, data.sensor_values) = sensor_columns(header, rows, &read_columns(&joints, &poses));
    settle_units(path, data, kinds, format)
}

/// The columns of a measurements file that [`read_measurements_with`] does not read (an accelerometer's,
/// a load cell's, a comment), by their header names: a front end says them, so that no column is ignored
/// in silence. Empty for the authors' results files.
pub fn unread_columns(path: &Path, kinds: &[JointKind], format: MeasurementFormat) -> Result<Vec<String>, IoError> {
    let text = read_text(path)?;
    if text.lines().next().is_some_and(|l| l.contains("Programmed coordinate")) {
        return Ok(Vec::new());
    }
    let recs = records_any_dialect(path, &text)?;
    let Some(header) = recs.first() else { return Ok(Vec::new()) };
    let joints = JointColumns::find(path, header, kinds, format.joint_units.unwrap_or_default())?;
    let poses = PoseColumns::find(path, header, format.orientation)?;
    let mut read = read_columns(&joints, &poses);
    let (sensors, _) = sensor_columns(header, &recs[1..], &read);
    read.extend(header.cells.iter().enumerate().filter(|(_, n)| sensors.contains(n)).map(|(c, _)| c));
    Ok(header.cells.iter().enumerate().filter(|(c, _)| !read.contains(c)).map(|(_, name)| name.clone()).collect())
}

/// The columns a measurement set's joint and pose readers read.
fn read_columns(joints: &JointColumns<'_>, poses: &PoseColumns<'_>) -> Vec<usize> {
    let mut read: Vec<usize> = joints.q.clone();
    read.extend(joints.time);
    read.extend(joints.temps.iter().map(|(c, _)| *c));
    read.extend(&poses.p);
    read.extend(poses.r.iter().flatten().map(|(c, _)| *c));
    read.extend(poses.std.iter().flatten());
    read
}

/// The sensor columns of a measurement set — the rule: every column the readers do not read whose every
/// cell is a finite number (an accelerometer's or inclinometer's tilt, a load, a current) — by name,
/// and each row's readings in that order. A column with any other cell (a point's name) is not a sensor.
fn sensor_columns(header: &Record, rows: &[Record], read: &[usize]) -> (Vec<String>, Vec<Vec<f64>>) {
    let numeric = |c: usize| {
        rows.iter().all(|r| r.cells.get(c).and_then(|v| v.trim().parse::<f64>().ok()).is_some_and(f64::is_finite))
    };
    let columns: Vec<usize> =
        (0..header.cells.len()).filter(|c| !read.contains(c) && !rows.is_empty() && numeric(*c)).collect();
    if columns.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let names = columns.iter().map(|&c| header.cells[c].clone()).collect();
    let values = rows
        .iter()
        .map(|r| columns.iter().map(|&c| r.cells[c].trim().parse::<f64>().unwrap_or(f64::NAN)).collect())
        .collect();
    (names, values)
}

/// Reads a measurement set kept in two files, as tracker and robot software often write them: the
/// joints (`q1..qn`, optional `time_min` and `temp_<name>`) in one, the measured poses (`x,y,z`, optional
/// `rx,ry,rz`) in the other, joined by the column `key` present in both (a point name, a timestamp) or,
/// without a key, row by row. Every row must find its partner; errors name the file, line and field.
pub fn read_measurements_joined(
    joints_path: &Path,
    poses_path: &Path,
    key: Option<&str>,
    kinds: &[JointKind],
    format: MeasurementFormat,
) -> Result<Dataset, IoError> {
    let (jt, pt) = (read_text(joints_path)?, read_text(poses_path)?);
    let (jr, pr) = (records_any_dialect(joints_path, &jt)?, records_any_dialect(poses_path, &pt)?);
    let Some((jh, jrows)) = jr.split_first() else {
        return Err(IoError::input(joints_path, Some(1), "header", "empty file: expected q1..qn"));
    };
    let Some((ph, prows)) = pr.split_first() else {
        return Err(IoError::input(poses_path, Some(1), "header", "empty file: expected x,y,z"));
    };
    let joints = JointColumns::find(joints_path, jh, kinds, format.joint_units.unwrap_or_default())?;
    let poses = PoseColumns::find(poses_path, ph, format.orientation)?;
    for r in jrows {
        expect_fields(joints_path, r, jh.cells.len())?;
    }
    for r in prows {
        expect_fields(poses_path, r, ph.cells.len())?;
    }
    let pairs: Vec<(&Record, &Record)> = match key {
        None => {
            if jrows.len() != prows.len() {
                return Err(IoError::input(
                    poses_path,
                    None,
                    "rows",
                    format!(
                        "{} joint rows in {} but {} poses here: joined row by row they must match (or join by a key column)",
                        jrows.len(),
                        joints_path.display(),
                        prows.len()
                    ),
                ));
            }
            jrows.iter().zip(prows).collect()
        }
        Some(key) => {
            let col = |path: &Path, h: &Record| {
                column(h, key).ok_or_else(|| {
                    IoError::input(
                        path,
                        Some(h.line),
                        key,
                        format!("missing key column `{key}` (the join needs it in both files)"),
                    )
                })
            };
            let (jk, pk) = (col(joints_path, jh)?, col(poses_path, ph)?);
            let mut by_key: std::collections::HashMap<&str, &Record> = std::collections::HashMap::new();
            for r in prows {
                if let Some(first) = by_key.insert(r.cells[pk].as_str(), r) {
                    return Err(IoError::input(
                        poses_path,
                        Some(r.line),
                        key,
                        format!("`{}` again (first on line {})", r.cells[pk], first.line),
                    ));
                }
            }
            let mut pairs = Vec::with_capacity(jrows.len());
            for r in jrows {
                let pose = by_key.remove(r.cells[jk].as_str()).ok_or_else(|| {
                    IoError::input(
                        joints_path,
                        Some(r.line),
                        key,
                        format!("`{}` has no pose in {}", r.cells[jk], poses_path.display()),
                    )
                })?;
                pairs.push((r, pose));
            }
            if let Some(r) = by_key.values().min_by_key(|r| r.line) {
                return Err(IoError::input(
                    poses_path,
                    Some(r.line),
                    key,
                    format!("`{}` has no joints in {}", r.cells[pk], joints_path.display()),
                ));
            }
            pairs
        }
    };
    let empty = IoError::input(joints_path, Some(jh.line + 1), "rows", "no measurements after the header");
    let data = assemble(&joints, &poses, pairs.into_iter().map(Ok), empty)?;
    settle_units(poses_path, data, kinds, format)
}

/// One data row of a joints file: its 1-based line, and its joint values (internal units) with the
/// operating state its `time_min` and `temp_*` columns give — or why the row cannot be read.
#[derive(Debug)]
pub struct JointRow {
    /// The row's line in the file.
    pub line: usize,
    /// The joint values and the state, or the row's error.
    pub values: Result<(Vec<f64>, OperatingState), IoError>,
}

/// Reads a file of joint values, `q1..qn` (degrees, or radians with [`JointUnits::Radians`]; mm for a
/// prismatic joint) with optional `time_min` and `temp_<name>` columns, in any of the measurement files'
/// dialects, row by row: a bad header is an error; a bad row is that row's error, the others are read.
pub fn read_joint_rows(path: &Path, kinds: &[JointKind], units: JointUnits) -> Result<Vec<JointRow>, IoError> {
    let text = read_text(path)?;
    let recs = records_any_dialect(path, &text)?;
    let Some((header, rows)) = recs.split_first() else {
        return Err(IoError::input(path, Some(1), "header", "empty file: expected q1..qn"));
    };
    let joints = JointColumns::find(path, header, kinds, units)?;
    let names: Vec<String> = joints.temperature_names().iter().map(|n| sensor_name(n)).collect();
    let has_time = joints.time.is_some();
    let out: Vec<JointRow> = rows
        .iter()
        .map(|r| {
            let values =
                expect_fields(path, r, header.cells.len()).and_then(|()| joints.read(r)).map(|(t, q, temps)| {
                    let temperatures_c = names.iter().cloned().zip(temps).collect();
                    (q, OperatingState { time_min: has_time.then_some(t), temperatures_c, ..OperatingState::default() })
                });
            JointRow { line: r.line, values }
        })
        .collect();
    if out.is_empty() {
        return Err(IoError::input(path, Some(header.line + 1), "rows", "no rows after the header"));
    }
    Ok(out)
}

/// The measurements of paired rows (joint side, pose side: the same record for a single file), in order;
/// `empty` when there are none.
fn assemble<'r>(
    joints: &JointColumns,
    poses: &PoseColumns,
    pairs: impl Iterator<Item = Result<(&'r Record, &'r Record), IoError>>,
    empty: IoError,
) -> Result<Dataset, IoError> {
    let mut measurements = Vec::new();
    // The measured pose's line: where a gross error of the tracker is found in its file.
    let mut source_lines = Vec::new();
    for pair in pairs {
        let (j, p) = pair?;
        let (time_min, q, temps) = joints.read(j)?;
        let (position_mm, orientation, position_std_mm) = poses.read(p)?;
        measurements.push(Measurement { time_min, q, position_mm, orientation, position_std_mm, temps });
        source_lines.push(p.line);
    }
    if measurements.is_empty() {
        return Err(empty);
    }
    Ok(Dataset { measurements, temperature_names: joints.temperature_names(), source_lines, ..Dataset::default() })
}

/// Where a file's joint-side columns are: `q1..qn`, `time_min`, `temp_<name>`.
struct JointColumns<'a> {
    path: &'a Path,
    kinds: &'a [JointKind],
    units: JointUnits,
    q: Vec<usize>,
    time: Option<usize>,
    temps: Vec<(usize, String)>,
}

impl<'a> JointColumns<'a> {
    fn find(path: &'a Path, header: &Record, kinds: &'a [JointKind], units: JointUnits) -> Result<Self, IoError> {
        let dof = kinds.len();
        let need = |name: &str| {
            column(header, name).ok_or_else(|| {
                let found = header.cells.join(", ");
                IoError::input(
                    path,
                    Some(header.line),
                    name,
                    format!("missing column `{name}` (the header has {found})"),
                )
            })
        };
        let q: Vec<usize> = (1..=dof).map(|i| need(&format!("q{i}"))).collect::<Result<_, _>>()?;
        if column(header, &format!("q{}", dof + 1)).is_some() {
            return Err(IoError::input(
                path,
                Some(header.line),
                format!("q{}", dof + 1),
                format!("more joint columns than the robot's {dof} joints"),
            ));
        }
        let temps = header
            .cells
            .iter()
            .enumerate()
            .filter_map(|(i, c)| c.strip_prefix("temp_").map(|n| (i, n.to_string())))
            .collect();
        Ok(Self { path, kinds, units, q, time: column(header, "time_min"), temps })
    }

    /// Time (minutes), joint values (internal units), temperatures of one row.
    fn read(&self, r: &Record) -> Result<(f64, Vec<f64>, Vec<f64>), IoError> {
        let path = self.path;
        let q = self
            .q
            .iter()
            .enumerate()
            .map(|(k, &c)| {
                let kind = self.kinds.get(k).copied().unwrap_or(JointKind::Revolute);
                number(path, r.line, &format!("q{}", k + 1), &r.cells[c]).map(|v| match (kind, self.units) {
                    (JointKind::Revolute, JointUnits::Radians) => v,
                    _ => joint_value_in(kind, v),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let time_min = match self.time {
            Some(c) => {
                let t = number(path, r.line, "time_min", &r.cells[c])?;
                if t < 0.0 {
                    return Err(IoError::input(path, Some(r.line), "time_min", format!("{t} is negative")));
                }
                t
            }
            None => 0.0,
        };
        let temps = self
            .temps
            .iter()
            .map(|(c, n)| number(path, r.line, &format!("temp_{n}"), &r.cells[*c]))
            .collect::<Result<Vec<_>, _>>()?;
        Ok((time_min, q, temps))
    }

    fn temperature_names(&self) -> Vec<String> {
        self.temps.iter().map(|(_, n)| n.clone()).collect()
    }
}

/// Columns that come all together or not at all: their indices in `names` order, `None` when none is
/// present, and an error naming the missing ones (with `message`) when only some are.
fn column_group(path: &Path, header: &Record, names: &[&str], message: &str) -> Result<Option<Vec<usize>>, IoError> {
    let found: Vec<Option<usize>> = names.iter().map(|n| column(header, n)).collect();
    match found.iter().filter(|c| c.is_some()).count() {
        0 => Ok(None),
        k if k == names.len() => Ok(Some(found.into_iter().flatten().collect())),
        _ => {
            let missing: Vec<&str> = names.iter().zip(&found).filter(|(_, c)| c.is_none()).map(|(n, _)| *n).collect();
            Err(IoError::input(path, Some(header.line), missing.join(","), message.to_string()))
        }
    }
}

/// One row's pose side: position, orientation, stated standard deviations.
type PoseRow = (Vector3<f64>, Option<UnitQuaternion<f64>>, Option<Vector3<f64>>);

/// Where a file's pose-side columns are: `x,y,z`, optional orientation columns.
struct PoseColumns<'a> {
    path: &'a Path,
    p: Vec<usize>,
    convention: Orientation,
    /// The orientation columns with their names, when present.
    r: Option<Vec<(usize, &'static str)>>,
    /// `std_x, std_y, std_z`, when present.
    std: Option<[usize; 3]>,
}

impl<'a> PoseColumns<'a> {
    fn find(path: &'a Path, header: &Record, convention: Orientation) -> Result<Self, IoError> {
        let need = |name: &str| {
            column(header, name).ok_or_else(|| {
                let found = header.cells.join(", ");
                IoError::input(
                    path,
                    Some(header.line),
                    name,
                    format!("missing column `{name}` (the header has {found})"),
                )
            })
        };
        let p: Vec<usize> = ["x", "y", "z"].iter().map(|n| need(n)).collect::<Result<_, _>>()?;
        let names: &'static [&'static str] = match convention {
            Orientation::Quaternion => &["qw", "qx", "qy", "qz"],
            _ => &["rx", "ry", "rz"],
        };
        let r = column_group(
            path,
            header,
            names,
            &format!("an orientation needs all of {} ({convention:?})", names.join(", ")),
        )?
        .map(|cols| cols.into_iter().zip(names.iter().copied()).collect());
        let std = column_group(
            path,
            header,
            &["std_x", "std_y", "std_z"],
            "the tracker's standard deviations need all of std_x, std_y, std_z (mm)",
        )?
        .map(|cols| [cols[0], cols[1], cols[2]]);
        Ok(Self { path, p, convention, r, std })
    }

    /// Position (mm), orientation and stated standard deviations (mm) of one row.
    fn read(&self, r: &Record) -> Result<PoseRow, IoError> {
        let path = self.path;
        let p = Vector3::new(
            number(path, r.line, "x", &r.cells[self.p[0]])?,
            number(path, r.line, "y", &r.cells[self.p[1]])?,
            number(path, r.line, "z", &r.cells[self.p[2]])?,
        );
        let orientation = match &self.r {
            Some(cols) => {
                let values = cols
                    .iter()
                    .map(|&(c, name)| number(path, r.line, name, &r.cells[c]))
                    .collect::<Result<Vec<_>, _>>()?;
                let field = cols.iter().map(|(_, n)| *n).collect::<Vec<_>>().join(",");
                Some(self.convention.rotation(&values).map_err(|m| IoError::input(path, Some(r.line), field, m))?)
            }
            None => None,
        };
        let std = match self.std {
            Some(cols) => {
                let mut v = [0.0; 3];
                for (k, name) in ["std_x", "std_y", "std_z"].iter().enumerate() {
                    v[k] = number(path, r.line, name, &r.cells[cols[k]])?;
                    if v[k] <= 0.0 {
                        return Err(IoError::input(
                            path,
                            Some(r.line),
                            *name,
                            format!("{} is not a positive standard deviation (mm)", v[k]),
                        ));
                    }
                }
                Some(Vector3::from(v))
            }
            None => None,
        };
        Ok((p, orientation, std))
    }
}

/// The configurations of a joints file ([`read_joint_rows`]: `q1..qn`, other columns ignored), each with
/// its line; the first bad row is the error (a plan's candidates must all be usable).
pub fn read_configurations(
    path: &Path,
    kinds: &[JointKind],
    units: JointUnits,
) -> Result<(Vec<Vec<f64>>, Vec<usize>), IoError> {
    let rows = read_joint_rows(path, kinds, units)?;
    let mut joints = Vec::with_capacity(rows.len());
    let mut lines = Vec::with_capacity(rows.len());
    for r in rows {
        joints.push(r.values?.0);
        lines.push(r.line);
    }
    Ok((joints, lines))
}

/// [`read_configurations`] with the unit of revolute joints stated, or `None`: degrees, refused as a
/// measurement file is ([`UnitsUnclear::JointsLookLikeRadians`]) where every revolute value of ten or
/// more rows stays within ±2π read as degrees.
pub fn read_configurations_checked(
    path: &Path,
    kinds: &[JointKind],
    units: Option<JointUnits>,
) -> Result<(Vec<Vec<f64>>, Vec<usize>), IoError> {
    let (joints, lines) = read_configurations(path, kinds, units.unwrap_or_default())?;
    let revolute: Vec<usize> = (0..kinds.len()).filter(|&j| kinds[j] == JointKind::Revolute).collect();
    if units.is_none() && joints.len() >= UNIT_EVIDENCE && !revolute.is_empty() {
        let largest = joints.iter().flat_map(|q| revolute.iter().map(|&j| q[j].abs())).fold(0.0, f64::max);
        if largest < crate::units::radians(std::f64::consts::TAU) {
            let unclear = UnitsUnclear::JointsLookLikeRadians { largest_deg: crate::units::degrees(largest) };
            return Err(IoError::UnitsUnclear { path: path.to_path_buf(), unclear });
        }
    }
    Ok((joints, lines))
}

/// Writes a measurement set in the format [`read_measurements`] reads (degrees or mm per joint kind, mm).
pub fn write_measurements(out: &mut impl std::io::Write, data: &Dataset, kinds: &[JointKind]) -> std::io::Result<()> {
    let n = data.measurements.first().map_or(0, |m| m.q.len());
    let qs: Vec<String> = (1..=n).map(|i| format!("q{i}")).collect();
    let temps: Vec<String> = data.temperature_names.iter().map(|t| format!(",temp_{t}")).collect();
    let oriented = data.has_orientation();
    let r_head = if oriented { ",rx,ry,rz" } else { "" };
    let with_std = data.has_position_std();
    let s_head = if with_std { ",std_x,std_y,std_z" } else { "" };
    writeln!(out, "time_min,{},x,y,z{r_head}{s_head}{}", qs.join(","), temps.concat())?;
    for m in &data.measurements {
        let q: Vec<String> = m
            .q
            .iter()
            .enumerate()
            .map(|(k, &v)| format!("{:?}", joint_value_out(kinds.get(k).copied().unwrap_or(JointKind::Revolute), v)))
            .collect();
        let t: Vec<String> = m.temps.iter().map(|v| format!(",{v:?}")).collect();
        let r = match (oriented, &m.orientation) {
            (true, Some(o)) => {
                let [a, b, c] = xyz_euler_deg(o);
                format!(",{a:?},{b:?},{c:?}")
            }
            _ => String::new(),
        };
        let sd = match (with_std, &m.position_std_mm) {
            (true, Some(v)) => format!(",{:?},{:?},{:?}", v.x, v.y, v.z),
            _ => String::new(),
        };
        writeln!(
            out,
            "{:?},{},{:?},{:?},{:?}{r}{sd}{}",
            m.time_min,
            q.join(","),
            m.position_mm.x,
            m.position_mm.y,
            m.position_mm.z,
            t.concat()
        )?;
    }
    Ok(())
}
