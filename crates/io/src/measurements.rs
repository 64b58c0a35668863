//! Measurement sets for identification and diagnosis: `time_min` (optional), `q1..qn` (degrees, or radians
//! with [`JointUnits::Radians`]), `x,y,z` (mm), optional `rx,ry,rz` (the measured tool orientation, X-Y-Z Euler
//! angles in degrees as everywhere in the project: a 6-D probe; all three or none), optional `temp_<name>` (°C). Comma-separated, semicolon-separated
//! with decimal commas, or whitespace-separated, as tracker software exports them. The authors' results
//! files are accepted too (their joints and reached coordinates).

use std::path::Path;

use nalgebra::Vector3;
use thermokin_chain::{Dataset, JointKind, Measurement};

use crate::csvtext::{column, expect_fields, number, records_any_dialect};
use crate::units::{joint_value_in, joint_value_out, xyz_euler_deg, xyz_rotation_deg};
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

/// Reads a measurement set whose revolute joints are in `units`.
pub fn read_measurements_with(path: &Path, kinds: &[JointKind], units: JointUnits) -> Result<Dataset, IoError> {
    let text = read_text(path)?;
    parse_measurements_with(path, &text, kinds, units)
}

/// Parses a measurement set's text for a robot whose joints are of `kinds` (one per joint): joint columns
/// are degrees for revolute joints and mm for prismatic ones.
pub fn parse_measurements(path: &Path, text: &str, kinds: &[JointKind]) -> Result<Dataset, IoError> {
    parse_measurements_with(path, text, kinds, JointUnits::Degrees)
}

/// As [`parse_measurements`], revolute joint columns in `units`.
pub fn parse_measurements_with(
    path: &Path,
    text: &str,
    kinds: &[JointKind],
    units: JointUnits,
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
                temps: Vec::new(),
            })
            .collect();
        return Ok(Dataset { measurements, temperature_names: Vec::new() });
    }
    let recs = records_any_dialect(path, text)?;
    let Some((header, rows)) = recs.split_first() else {
        return Err(IoError::input(path, Some(1), "header", "empty file: expected q1..qn,x,y,z"));
    };
    let need = |name: &str| {
        column(header, name)
            .ok_or_else(|| IoError::input(path, Some(header.line), name, format!("missing column `{name}`")))
    };
    let q_cols: Vec<usize> = (1..=dof).map(|i| need(&format!("q{i}"))).collect::<Result<_, _>>()?;
    if column(header, &format!("q{}", dof + 1)).is_some() {
        return Err(IoError::input(
            path,
            Some(header.line),
            format!("q{}", dof + 1),
            format!("more joint columns than the robot's {dof} joints"),
        ));
    }
    let p_cols: Vec<usize> = ["x", "y", "z"].iter().map(|n| need(n)).collect::<Result<_, _>>()?;
    let t_col = column(header, "time_min");
    let temp_cols: Vec<(usize, String)> = header
        .cells
        .iter()
        .enumerate()
        .filter_map(|(i, c)| c.strip_prefix("temp_").map(|n| (i, n.to_string())))
        .collect();
    let r_cols: Vec<Option<usize>> = ["rx", "ry", "rz"].iter().map(|n| column(header, n)).collect();
    let r_cols: Option<Vec<usize>> = match r_cols.iter().filter(|c| c.is_some()).count() {
        0 => None,
        3 => Some(r_cols.into_iter().flatten().collect()),
        _ => {
            let missing: Vec<&str> =
                ["rx", "ry", "rz"].iter().zip(&r_cols).filter(|(_, c)| c.is_none()).map(|(n, _)| *n).collect();
            return Err(IoError::input(
                path,
                Some(header.line),
                missing.join(","),
                "an orientation needs all three of rx, ry, rz (X-Y-Z Euler angles, degrees)",
            ));
        }
    };
    let mut measurements = Vec::with_capacity(rows.len());
    for r in rows {
        expect_fields(path, r, header.cells.len())?;
        let q = q_cols
            .iter()
            .enumerate()
            .map(|(k, &c)| {
                let kind = kinds.get(k).copied().unwrap_or(JointKind::Revolute);
                number(path, r.line, &format!("q{}", k + 1), &r.cells[c]).map(|v| match (kind, units) {
                    (JointKind::Revolute, JointUnits::Radians) => v,
                    _ => joint_value_in(kind, v),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let p = Vector3::new(
            number(path, r.line, "x", &r.cells[p_cols[0]])?,
            number(path, r.line, "y", &r.cells[p_cols[1]])?,
            number(path, r.line, "z", &r.cells[p_cols[2]])?,
        );
        let orientation = match &r_cols {
            Some(c) => {
                let angles = [
                    number(path, r.line, "rx", &r.cells[c[0]])?,
                    number(path, r.line, "ry", &r.cells[c[1]])?,
                    number(path, r.line, "rz", &r.cells[c[2]])?,
                ];
                Some(xyz_rotation_deg(angles))
            }
            None => None,
        };
        let time_min = match t_col {
            Some(c) => {
                let t = number(path, r.line, "time_min", &r.cells[c])?;
                if t < 0.0 {
                    return Err(IoError::input(path, Some(r.line), "time_min", format!("{t} is negative")));
                }
                t
            }
            None => 0.0,
        };
        let temps = temp_cols
            .iter()
            .map(|(c, n)| number(path, r.line, &format!("temp_{n}"), &r.cells[*c]))
            .collect::<Result<Vec<_>, _>>()?;
        measurements.push(Measurement { time_min, q, position_mm: p, orientation, temps });
    }
    if measurements.is_empty() {
        return Err(IoError::input(path, Some(header.line + 1), "rows", "no measurements after the header"));
    }
    Ok(Dataset { measurements, temperature_names: temp_cols.into_iter().map(|(_, n)| n).collect() })
}

/// Writes a measurement set in the format [`read_measurements`] reads (degrees or mm per joint kind, mm).
pub fn write_measurements(out: &mut impl std::io::Write, data: &Dataset, kinds: &[JointKind]) -> std::io::Result<()> {
    let n = data.measurements.first().map_or(0, |m| m.q.len());
    let qs: Vec<String> = (1..=n).map(|i| format!("q{i}")).collect();
    let temps: Vec<String> = data.temperature_names.iter().map(|t| format!(",temp_{t}")).collect();
    let oriented = data.has_orientation();
    let r_head = if oriented { ",rx,ry,rz" } else { "" };
    writeln!(out, "time_min,{},x,y,z{r_head}{}", qs.join(","), temps.concat())?;
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
        writeln!(
            out,
            "{:?},{},{:?},{:?},{:?}{r}{}",
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
