//! Time profiles: operating time t (minutes) → the deviation table in force at t.
//!
//! Paper section 4: the IRB 140 warms up for about 180 minutes before it stabilises; the authors grew the
//! table linearly with time ("the maximum deformations … applied increasing linearly in each minute"), their
//! ref. \[26\] found a cubic regression best, and their transient file keeps growing after minute 180
//! (measured on the authors' transient file: docs/paper-reproduction.md), hence linear with and without a plateau.

use serde::{Deserialize, Serialize};

use crate::{DeformError, DeviationTable, Row};

/// What a linear warm-up does after the stabilization time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AfterStabilization {
    /// Hold the full table (the paper's description of thermal stabilization).
    Plateau,
    /// Keep growing at the same rate (what the authors' transient file does).
    KeepGrowing,
}

/// How a deviation table grows with operating time. Every time-dependent profile gives a zero table at
/// t = 0 (the cold robot); [`TimeProfile::Static`] gives the full table at every time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum TimeProfile {
    /// The full table at every time: a robot already in its deformed state.
    Static,
    /// `min(t / stabilization_min, 1) · table` with a plateau, `t / stabilization_min · table` without.
    Linear {
        /// Time to thermal stabilization, minutes (paper: 180).
        stabilization_min: f64,
        /// Plateau or keep growing after it.
        after: AfterStabilization,
    },
    /// First order: `(1 − e^(−t/τ)) · table`.
    Exponential {
        /// Time constant τ, minutes.
        tau_min: f64,
    },
    /// Cubic regression (the paper's ref. \[26\]): `(c1 t + c2 t² + c3 t³) · table`, t in minutes.
    Cubic {
        /// `[c1, c2, c3]` in 1/min, 1/min², 1/min³.
        coefficients: [f64; 3],
    },
    /// Temperature-driven: the table holds coefficients per kelvin, and joint `i`'s row is scaled by the
    /// temperature rise of its sensor, `T_sensor(t) − T_reference`. The base row follows joint 1's sensor,
    /// the tool row the last joint's. With no sensors named, every row follows the mean of all sensors.
    Temperature {
        /// The temperature log.
        log: TemperatureLog,
        /// For each joint, the log column (sensor name) that drives it; empty: the mean of all columns.
        sensors: Vec<String>,
        /// Reference temperature, °C; the log's first sample of each sensor when absent.
        reference_c: Option<f64>,
    },
}

/// A temperature log: sample times (minutes, strictly increasing) and one series per named sensor (°C).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TemperatureLog {
    /// Sample times, minutes.
    pub times_min: Vec<f64>,
    /// `(sensor name, temperatures)`, each as long as `times_min`.
    pub sensors: Vec<(String, Vec<f64>)>,
}

impl TemperatureLog {
    /// The series of a sensor.
    pub fn series(&self, name: &str) -> Option<&[f64]> {
        self.sensors.iter().find(|(n, _)| n == name).map(|(_, v)| v.as_slice())
    }

    /// Linear interpolation of a series at `t`; `None` outside the logged interval.
    pub fn interpolate(&self, values: &[f64], t: f64) -> Option<f64> {
        let times = &self.times_min;
        let first = *times.first()?;
        let last = *times.last()?;
        if !(first..=last).contains(&t) {
            return None;
        }
        let k = times.partition_point(|&x| x <= t);
        if k == 0 {
            return values.first().copied();
        }
        if k >= times.len() {
            return values.last().copied();
        }
        let (t0, t1) = (times[k - 1], times[k]);
        let w = (t - t0) / (t1 - t0);
        Some(values[k - 1] * (1.0 - w) + values[k] * w)
    }
}

/// Scale factors of one time step: base row, each joint row, tool row.
#[derive(Clone, Debug, PartialEq)]
pub struct RowFactors {
    /// Base row factor.
    pub base: f64,
    /// One factor per joint.
    pub joints: Vec<f64>,
    /// Tool row factor.
    pub tool: f64,
}

/// A profile as a command line names it ([`TimeProfile::parse_spec`]): a law with its parameters, or a
/// file to read (a TOML profile, a temperature log) — read at the I/O boundary
/// (`thermokin_io::read_profile_spec`), never while parsing.
#[derive(Clone, Debug, PartialEq)]
pub enum ProfileSpec {
    /// A law given inline.
    Law(TimeProfile),
    /// A TOML file holding a profile.
    TomlFile(std::path::PathBuf),
    /// A temperature log: every row scaled by the mean logged temperature rise.
    TemperatureLog(std::path::PathBuf),
}

impl TimeProfile {
    /// Parses `static`, `linear:180`, `linear-grow:180`, `exp:45`, `cubic:c1,c2,c3`, `temperature:LOG.csv`
    /// or `FILE.toml`; an inline law is checked by [`TimeProfile::validate`] (its rules, one place).
    pub fn parse_spec(s: &str) -> Result<ProfileSpec, DeformError> {
        let bad = |message: String| DeformError::BadProfile { field: "spec", message };
        if s.ends_with(".toml") {
            return Ok(ProfileSpec::TomlFile(s.into()));
        }
        let (kind, rest) = s.split_once(':').unwrap_or((s, ""));
        if kind == "temperature" {
            return Ok(ProfileSpec::TemperatureLog(rest.into()));
        }
        let num = |v: &str| -> Result<f64, DeformError> {
            if v.trim().is_empty() {
                return Err(bad(format!(
                    "`{kind}` needs a value after a colon, e.g. {kind}:180 (linear:T, linear-grow:T, exp:TAU, cubic:C1,C2,C3, temperature:LOG.csv)"
                )));
            }
            v.trim().parse().map_err(|_| bad(format!("`{v}` is not a number")))
        };
        let law = match kind {
            "static" if rest.is_empty() => TimeProfile::Static,
            "linear" => TimeProfile::Linear { stabilization_min: num(rest)?, after: AfterStabilization::Plateau },
            "linear-grow" => {
                TimeProfile::Linear { stabilization_min: num(rest)?, after: AfterStabilization::KeepGrowing }
            }
            "exp" => TimeProfile::Exponential { tau_min: num(rest)? },
            "cubic" => {
                let c: Vec<f64> = rest.split(',').map(num).collect::<Result<_, _>>()?;
                let [c1, c2, c3] = c[..] else {
                    return Err(bad("cubic takes three coefficients: cubic:C1,C2,C3".into()));
                };
                TimeProfile::Cubic { coefficients: [c1, c2, c3] }
            }
            _ => {
                return Err(bad(format!(
                    "unknown profile `{s}`: use static, linear:T, linear-grow:T, exp:TAU, cubic:C1,C2,C3, temperature:LOG.csv or a .toml file"
                )));
            }
        };
        // The law's own rules; a temperature profile (the only one that needs the joint count) is a file.
        law.validate(0)?;
        Ok(ProfileSpec::Law(law))
    }

    /// The paper's default: linear to 180 minutes, then a plateau.
    pub fn paper_linear() -> Self {
        TimeProfile::Linear { stabilization_min: 180.0, after: AfterStabilization::Plateau }
    }

    /// Checks the profile's own parameters (and, for a temperature profile, its log and sensor names
    /// against `dof` joints).
    pub fn validate(&self, dof: usize) -> Result<(), DeformError> {
        let bad = |field: &'static str, message: String| Err(DeformError::BadProfile { field, message });
        match self {
            TimeProfile::Static => Ok(()),
            TimeProfile::Linear { stabilization_min, .. } => {
                if !(stabilization_min.is_finite() && *stabilization_min > 0.0) {
                    return bad(
                        "stabilization_min",
                        format!("the stabilization time must be positive, got {stabilization_min} min"),
                    );
                }
                Ok(())
            }
            TimeProfile::Exponential { tau_min } => {
                if !(tau_min.is_finite() && *tau_min > 0.0) {
                    return bad("tau_min", format!("the time constant must be positive, got {tau_min} min"));
                }
                Ok(())
            }
            TimeProfile::Cubic { coefficients } => {
                if coefficients.iter().any(|c| !c.is_finite()) {
                    return bad("coefficients", "cubic coefficients must be finite".into());
                }
                Ok(())
            }
            TimeProfile::Temperature { log, sensors, reference_c } => {
                if !sensors.is_empty() && sensors.len() != dof {
                    return bad("sensors", format!("{} sensors named for {dof} joints", sensors.len()));
                }
                if log.sensors.is_empty() {
                    return bad("log", "the temperature log has no sensor columns".into());
                }
                if log.times_min.len() < 2 {
                    return bad("log", "the temperature log needs at least two samples".into());
                }
                if log.times_min.windows(2).any(|w| w[1] <= w[0]) || log.times_min.iter().any(|t| !t.is_finite()) {
                    return bad("log.times_min", "temperature log times must be finite and strictly increasing".into());
                }
                for (name, series) in &log.sensors {
                    if series.len() != log.times_min.len() || series.iter().any(|x| !x.is_finite()) {
                        return bad(
                            "log.sensors",
                            format!("sensor `{name}`: every sample must be a finite temperature"),
                        );
                    }
                }
                for s in sensors {
                    match log.series(s) {
                        None => return bad("sensors", format!("sensor `{s}` is not in the temperature log")),
                        Some(v) if v.len() != log.times_min.len() || v.iter().any(|x| !x.is_finite()) => {
                            return bad("sensors", format!("sensor `{s}`: every sample must be a finite temperature"));
                        }
                        Some(_) => {}
                    }
                }
                if reference_c.is_some_and(|r| !r.is_finite()) {
                    return bad("reference_c", "the reference temperature must be finite".into());
                }
                Ok(())
            }
        }
    }

    /// The one factor of a profile driven by time alone, at operating time `t` (minutes): the growth law
    /// that [`TimeProfile::row_factors`] applies to every row, and that the diagnosis's thermal drift
    /// fits. `None` for [`TimeProfile::Temperature`], whose factors come from its log, row by row.
    pub fn time_factor(&self, t: f64) -> Option<f64> {
        match self {
            TimeProfile::Static => Some(1.0),
            TimeProfile::Linear { stabilization_min, after } => {
                let f = t / stabilization_min;
                Some(match after {
                    AfterStabilization::Plateau => f.min(1.0),
                    AfterStabilization::KeepGrowing => f,
                })
            }
            TimeProfile::Exponential { tau_min } => Some(-(-t / tau_min).exp_m1()),
            TimeProfile::Cubic { coefficients: [c1, c2, c3] } => Some(t * (c1 + t * (c2 + t * c3))),
            TimeProfile::Temperature { .. } => None,
        }
    }

    /// `∂f/∂τ` of an exponential profile at `t`: `−e^(−t/τ) · t / τ²` (what a fit of τ needs); `None`
    /// for the other profiles, which have no τ.
    pub fn time_factor_dtau(&self, t: f64) -> Option<f64> {
        match self {
            TimeProfile::Exponential { tau_min } => Some(-(-t / tau_min).exp() * t / (tau_min * tau_min)),
            _ => None,
        }
    }

    /// The scale factor of each row at operating time `t` (minutes).
    pub fn row_factors(&self, t: f64, dof: usize) -> Result<RowFactors, DeformError> {
        if !(t.is_finite() && t >= 0.0) {
            return Err(DeformError::BadTime { time_min: t, reason: "time must be finite and ≥ 0".into() });
        }
        self.validate(dof)?;
        let uniform = |f: f64| RowFactors { base: f, joints: vec![f; dof], tool: f };
        Ok(match self {
            TimeProfile::Static
            | TimeProfile::Linear { .. }
            | TimeProfile::Exponential { .. }
            | TimeProfile::Cubic { .. } => uniform(self.time_factor(t).unwrap_or(1.0)),
            TimeProfile::Temperature { log, sensors, reference_c } => {
                let mut joints = Vec::with_capacity(dof);
                let mean: Vec<f64> = (0..log.times_min.len())
                    .map(|k| log.sensors.iter().map(|(_, v)| v[k]).sum::<f64>() / log.sensors.len() as f64)
                    .collect();
                let names: Vec<Option<&String>> =
                    if sensors.is_empty() { vec![None; dof] } else { sensors.iter().map(Some).collect() };
                for s in names {
                    // validate() guarantees the series exists.
                    let series = match s {
                        Some(s) => log.series(s).unwrap_or_default(),
                        None => &mean,
                    };
                    let now = log.interpolate(series, t).ok_or_else(|| DeformError::BadTime {
                        time_min: t,
                        reason: format!(
                            "outside the temperature log ({} to {} min)",
                            log.times_min[0],
                            log.times_min[log.times_min.len() - 1]
                        ),
                    })?;
                    let reference = reference_c.unwrap_or(series[0]);
                    joints.push(now - reference);
                }
                let base = joints.first().copied().unwrap_or(0.0);
                let tool = joints.last().copied().unwrap_or(0.0);
                RowFactors { base, joints, tool }
            }
        })
    }

    /// The table in force at time `t`: each row of `table` scaled by its factor.
    pub fn table_at(&self, table: &DeviationTable, t: f64) -> Result<DeviationTable, DeformError> {
        let f = self.row_factors(t, table.dof())?;
        Ok(table.scaled_rows(|row| match row {
            Row::Base => f.base,
            Row::Joint(i) => f.joints[i],
            Row::Tool => f.tool,
        }))
    }
}
