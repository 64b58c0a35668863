//! Deviation tables — the authors' CSV (`Dx,Dy,Dz,Dox,Doy,Doz`, one row per joint, mm and degrees, CRLF
//! or LF) and a TOML form — and temperature logs (`time_min,temp_<sensor>,…`).

use std::path::Path;

use serde::Deserialize;
use thermokin_chain::ErrorParams;
use thermokin_deform::{DeviationTable, TemperatureLog, TimeProfile};

use crate::csvtext::{column, expect_fields, number, records};
use crate::{IoError, line_of, read_text, units};

const HEADER: [&str; 6] = ["Dx", "Dy", "Dz", "Dox", "Doy", "Doz"];

/// Reads a deviation table from `.csv` (the authors' format) or `.toml`
/// (`joints = [[dx, dy, dz, dθx, dθy, dθz], …]`, optional `base` and `tool`; mm and degrees).
pub fn read_deviation_table(path: &Path) -> Result<DeviationTable, IoError> {
    let text = read_text(path)?;
    parse_deviation_table(path, &text)
}

/// Parses a deviation table's text; the format follows `path`'s extension (`.toml`, else CSV).
pub fn parse_deviation_table(path: &Path, text: &str) -> Result<DeviationTable, IoError> {
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("toml")) {
        parse_toml(path, text)
    } else {
        parse_csv(path, text)
    }
}

/// Reads a deviation table and checks it has one row per joint of a `dof`-joint robot.
pub fn read_deviation_table_for(path: &Path, dof: usize) -> Result<DeviationTable, IoError> {
    let table = read_deviation_table(path)?;
    if table.dof() != dof {
        return Err(IoError::input(
            path,
            None,
            "rows",
            format!("{} joint rows, but the robot has {dof} joints", table.dof()),
        ));
    }
    Ok(table)
}

fn parse_csv(path: &Path, text: &str) -> Result<DeviationTable, IoError> {
    let recs = records(path, text)?;
    let Some((header, rows)) = recs.split_first() else {
        return Err(IoError::input(path, Some(1), "header", "empty file: expected the header Dx,Dy,Dz,Dox,Doy,Doz"));
    };
    let mut index = [0usize; 6];
    for (k, name) in HEADER.iter().enumerate() {
        index[k] = column(header, name).ok_or_else(|| {
            IoError::input(
                path,
                Some(header.line),
                *name,
                format!("missing column `{name}` (header: {})", header.cells.join(",")),
            )
        })?;
    }
    if header.cells.len() != 6 {
        return Err(IoError::input(
            path,
            Some(header.line),
            "header",
            format!("expected 6 columns Dx,Dy,Dz,Dox,Doy,Doz, found {}", header.cells.len()),
        ));
    }
    if rows.is_empty() {
        return Err(IoError::input(path, Some(header.line + 1), "rows", "no joint rows after the header"));
    }
    let mut joints = Vec::with_capacity(rows.len());
    for r in rows {
        expect_fields(path, r, 6)?;
        let mut v = [0.0; 6];
        for k in 0..6 {
            v[k] = number(path, r.line, HEADER[k], &r.cells[index[k]])?;
        }
        joints.push(units::error_params_in(v));
    }
    Ok(DeviationTable::from_joint_rows(joints))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TableFile {
    joints: Vec<[f64; 6]>,
    base: Option<[f64; 6]>,
    tool: Option<[f64; 6]>,
}

fn parse_toml(path: &Path, text: &str) -> Result<DeviationTable, IoError> {
    let f: TableFile = toml::from_str(text)
        .map_err(|e| IoError::input(path, e.span().map(|s| line_of(text, s.start)), "toml", e.message().to_string()))?;
    let check = |name: String, v: &[f64; 6]| -> Result<ErrorParams, IoError> {
        if v.iter().all(|x| x.is_finite()) {
            Ok(units::error_params_in(*v))
        } else {
            Err(IoError::input(path, None, name, "values must be finite"))
        }
    };
    if f.joints.is_empty() {
        return Err(IoError::input(path, None, "joints", "no joint rows"));
    }
    let joints = f
        .joints
        .iter()
        .enumerate()
        .map(|(i, v)| check(format!("joints[{}]", i + 1), v))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(DeviationTable {
        base: f.base.as_ref().map(|v| check("base".into(), v)).transpose()?.unwrap_or_default(),
        joints,
        tool: f.tool.as_ref().map(|v| check("tool".into(), v)).transpose()?.unwrap_or_default(),
    })
}

/// The profile a [`thermokin_deform::ProfileSpec`] names, its file read: a TOML profile (`kind =
/// "exponential"`, `tau_min = 45.0`, checked by `TimeProfile::validate` for a robot of `dof` joints — a
/// temperature profile names one sensor per joint), a temperature log, or the law given inline.
pub fn read_profile_spec(spec: &thermokin_deform::ProfileSpec, dof: usize) -> Result<TimeProfile, IoError> {
    use thermokin_deform::ProfileSpec;
    let (profile, path) = match spec {
        ProfileSpec::Law(law) => (law.clone(), None),
        ProfileSpec::TemperatureLog(path) => (
            TimeProfile::Temperature { log: read_temperature_log(path)?, sensors: Vec::new(), reference_c: None },
            Some(path),
        ),
        ProfileSpec::TomlFile(path) => {
            let text = read_text(path)?;
            let profile: TimeProfile = toml::from_str(&text).map_err(|e| {
                let line = e.span().map(|s| line_of(&text, s.start));
                IoError::input(path, line, "profile", e.message())
            })?;
            (profile, Some(path))
        }
    };
    // An inline law was checked when its text was parsed (`TimeProfile::parse_spec`); a file's profile here,
    // against the robot's joints.
    if let Some(path) = path {
        profile.validate(dof).map_err(|e| IoError::input(path, None, "profile", e.to_string()))?;
    }
    Ok(profile)
}

/// Reads a temperature log: a `time_min` column and one column per sensor (°C); a `temp_` prefix is
/// dropped from sensor names.
pub fn read_temperature_log(path: &Path) -> Result<TemperatureLog, IoError> {
    let text = read_text(path)?;
    parse_temperature_log(path, &text)
}

/// Parses a temperature log's text.
pub fn parse_temperature_log(path: &Path, text: &str) -> Result<TemperatureLog, IoError> {
    let recs = records(path, text)?;
    let Some((header, rows)) = recs.split_first() else {
        return Err(IoError::input(path, Some(1), "header", "empty file: expected time_min and sensor columns"));
    };
    let t_col = column(header, "time_min")
        .ok_or_else(|| IoError::input(path, Some(header.line), "time_min", "missing column `time_min`"))?;
    let sensors: Vec<(usize, String)> = header
        .cells
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != t_col)
        .map(|(i, n)| (i, n.strip_prefix("temp_").unwrap_or(n).to_string()))
        .collect();
    if sensors.is_empty() {
        return Err(IoError::input(path, Some(header.line), "header", "no sensor columns"));
    }
    let mut times = Vec::with_capacity(rows.len());
    let mut series = vec![Vec::with_capacity(rows.len()); sensors.len()];
    for r in rows {
        expect_fields(path, r, header.cells.len())?;
        let t = number(path, r.line, "time_min", &r.cells[t_col])?;
        if let Some(&prev) = times.last()
            && t <= prev
        {
            return Err(IoError::input(
                path,
                Some(r.line),
                "time_min",
                format!("{t} does not increase (previous {prev})"),
            ));
        }
        times.push(t);
        for (k, (i, name)) in sensors.iter().enumerate() {
            series[k].push(number(path, r.line, &header.cells[*i], &r.cells[*i]).map_err(|e| match e {
                IoError::Input { path, line, message, .. } => {
                    IoError::Input { path, line, field: name.clone(), message }
                }
                other => other,
            })?);
        }
    }
    if times.len() < 2 {
        return Err(IoError::input(path, None, "rows", "a temperature log needs at least two samples"));
    }
    Ok(TemperatureLog { times_min: times, sensors: sensors.into_iter().map(|(_, n)| n).zip(series).collect() })
}
