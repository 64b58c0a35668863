//! Python arguments into library values shared by the classes and functions: a table semantics' name, a
//! profile spec, an operating state.

use std::collections::HashMap;

use pyo3::prelude::*;
use thermokin_chain::OperatingState;
use thermokin_deform::{SemanticsKind, TableSemantics, TimeProfile};

use crate::errors::{input, io};

/// A setting with named values (the library's `CHOICES`), given as the keyword argument `what`: the
/// library's default when `None`.
pub fn choice<T: std::str::FromStr<Err = thermokin_chain::UnknownChoice>>(
    what: &str,
    given: Option<&str>,
    default: T,
) -> PyResult<T> {
    match given {
        None => Ok(default),
        Some(name) => name.parse().map_err(|e| input(format!("{what}: {e}"))),
    }
}

/// A table semantics by name (`"canonical"`, `"coppeliasim"`: the authors' scene, edited at home).
pub fn semantics_of(name: Option<&str>, dof: usize) -> PyResult<TableSemantics> {
    Ok(choice("semantics", name, SemanticsKind::default())?.at_home(dof))
}

/// A profile spec (`static`, `linear:180`, `linear-grow:180`, `exp:45`, `cubic:c1,c2,c3`,
/// `temperature:LOG.csv`, `FILE.toml`), its file read and checked against `dof` joints.
pub fn profile_of(spec: &str, dof: usize) -> PyResult<TimeProfile> {
    let spec = TimeProfile::parse_spec(spec).map_err(|e| input(format!("profile: {e}")))?;
    thermokin_io::read_profile_spec(&spec, dof).map_err(io)
}

/// The directions of approach a call takes: one list for every row (`[1, -1, 0, …]`, per joint), or one
/// list per row of a batch (`(N, n)`).
#[derive(FromPyObject)]
pub enum Approaches {
    /// One list per row of the batch.
    PerRow(Vec<Vec<i64>>),
    /// One list for every row.
    One(Vec<i64>),
}

/// The operating states of a batch of `rows`: [`state`] once when `approach` is one list (or none), once
/// per row when it gives one list per row — an error naming the counts when they differ.
pub fn states(
    time_min: Option<f64>,
    temps: Option<HashMap<String, f64>>,
    approach: Option<Approaches>,
    rows: usize,
) -> PyResult<Vec<OperatingState>> {
    match approach {
        None => Ok(vec![state(time_min, temps, None)?]),
        Some(Approaches::One(a)) => Ok(vec![state(time_min, temps, Some(a))?]),
        Some(Approaches::PerRow(per)) => {
            if per.len() != rows {
                return Err(input(format!(
                    "approach: {} rows of directions for {rows} rows (give one list for all, or one per row)",
                    per.len()
                )));
            }
            per.into_iter()
                .enumerate()
                .map(|(i, a)| {
                    state(time_min, temps.clone(), Some(a)).map_err(|e| input(format!("approach row {i}: {e}")))
                })
                .collect()
        }
    }
}

/// The state of row `i` of a batch whose states [`states`] gave.
pub fn state_of(states: &[OperatingState], i: usize) -> &OperatingState {
    if states.len() == 1 { &states[0] } else { &states[i] }
}

/// The operating state of `time_min` (minutes of the warm-up), `temps` (°C by sensor name; the
/// `temp_` prefix added when left out) and `approach` (per joint the direction it last moved in: 1 rising,
/// -1 falling, 0 not known — what a backlash follows).
pub fn state(
    time_min: Option<f64>,
    temps: Option<HashMap<String, f64>>,
    approach: Option<Vec<i64>>,
) -> PyResult<OperatingState> {
    if let Some(t) = time_min
        && !t.is_finite()
    {
        return Err(input(format!("time_min: {t} is not a time in minutes")));
    }
    let mut temperatures_c: Vec<(String, f64)> = Vec::new();
    for (name, value) in temps.unwrap_or_default() {
        if !value.is_finite() {
            return Err(input(format!("temps[{name}]: {value} is not a temperature in °C")));
        }
        temperatures_c.push((thermokin_io::sensor_name(&name), value));
    }
    temperatures_c.sort_by(|a, b| a.0.cmp(&b.0));
    let approach = approach
        .unwrap_or_default()
        .iter()
        .enumerate()
        .map(|(k, &v)| match v {
            1 => Ok(thermokin_chain::Approach::Rising),
            -1 => Ok(thermokin_chain::Approach::Falling),
            0 => Ok(thermokin_chain::Approach::Unknown),
            _ => Err(input(format!("approach[{k}]: {v}; give 1 (rising), -1 (falling) or 0 (not known) per joint"))),
        })
        .collect::<PyResult<Vec<_>>>()?;
    Ok(OperatingState { time_min, temperatures_c, approach, ..OperatingState::default() })
}
