//! Accelerometers and inclinometers as what they measure (issue #59). A sensor declared on a link
//! ([`Accelerometer`]) reads gravity in its own axes; the change of that direction from its reference
//! is the link's tilt — a rotation with a physical gain of one, not a number a row follows with a gain
//! to fit (a column's accelerometers fitted as free drivers learned, on one session, how its base
//! happened to rest). So the three raw columns `NAME_x`, `NAME_y`, `NAME_z` become three tilt columns
//! (`NAME.tilt_x`, …: radians, the sensor's axes, [`TiltSensor::tilt`] from the training session's mean
//! direction), followed, where a declared sensor sits below it on the chain, by that sensor's three: the
//! base's sensor gives the tilt of everything above it, a column top's what the column bends beyond the
//! base. The diagnosis offers [`thermokin_identify::Effect::Tilt`] for each — the row of the joint the
//! link carries turned by it, only the sensors' mounting yaws and the pivot fitted — judged held out
//! like any effect.
//!
//! A sensor on a link that a revolute joint below it turns would read that joint's motion as tilt:
//! refused, as is one on the last link (it carries no joint's row) and a reading of no length.

use nalgebra::Vector3;
use thermokin_chain::{Dataset, JointKind, Robot, TiltSensor};

use crate::config::Accelerometer;
use crate::error::DiagnoseError;

/// The accelerometers the diagnosis reads as tilts: those `config` declares, and those the robot file
/// declares on its links that `config` does not name (the command line's word over the file's).
pub(crate) fn declared(robot: &Robot, config: &crate::Config) -> Vec<Accelerometer> {
    declared_accelerometers(robot, &config.accelerometers)
}

/// The accelerometers a diagnosis with these `flags` reads as tilts: the flags', and those `robot`'s file
/// declares on its links that the flags do not name (what a front end says of the columns it reads).
pub fn declared_accelerometers(robot: &Robot, flags: &[Accelerometer]) -> Vec<Accelerometer> {
    let mut all = flags.to_vec();
    for s in robot.accelerometers() {
        if !all.iter().any(|a| a.name == s.name) {
            all.push(Accelerometer { name: s.name.clone(), link: s.link });
        }
    }
    all
}

/// The three column names of sensor `name`'s raw readings.
fn raw_columns(name: &str) -> [String; 3] {
    ["x", "y", "z"].map(|a| format!("{name}_{a}"))
}

/// `data` with each declared accelerometer's raw columns replaced by its tilt columns (at the end of its
/// sensor columns), its [`Dataset::tilt_sensors`] filled. `references`: the sensors as the training set
/// declared them (their reference directions), for a hold-out set; `None` for the training set, whose
/// own mean directions are the references.
pub(crate) fn with_tilts(
    robot: &Robot,
    data: &Dataset,
    declared: &[Accelerometer],
    references: Option<&[TiltSensor]>,
) -> Result<Dataset, DiagnoseError> {
    if declared.is_empty() {
        return Ok(data.clone());
    }
    let mut sorted = declared.to_vec();
    sorted.sort_by_key(|a| a.link);
    let refuse = |name: &str, reason: String| DiagnoseError::Accelerometer { name: name.to_string(), reason };
    let chain = robot.chain();
    let mut out = data.clone();
    // Each sensor's tilt per pose, in the order declared by link.
    let mut tilts: Vec<Vec<Vector3<f64>>> = Vec::new();
    let mut sensors: Vec<TiltSensor> = Vec::new();
    for a in &sorted {
        if a.link >= chain.dof() {
            return Err(refuse(
                &a.name,
                format!(
                    "link {} carries no joint's row (the robot has {} joints): declare it on a link from 0 (the base) to {}",
                    a.link,
                    chain.dof(),
                    chain.dof() - 1
                ),
            ));
        }
        if let Some(j) = chain.joints()[..a.link].iter().position(|j| j.kind != JointKind::Prismatic) {
            return Err(refuse(
                &a.name,
                format!(
                    "joint {} below link {} turns it: the sensor would read that joint's motion as a tilt — declare it on a link no revolute joint moves",
                    j + 1,
                    a.link
                ),
            ));
        }
        let columns = raw_columns(&a.name);
        let place: Vec<usize> =
            columns.iter().map(|c| data.sensor_names.iter().position(|n| n == c)).collect::<Option<_>>().ok_or_else(
                || {
                    refuse(
                        &a.name,
                        format!(
                            "{} need its columns {}, {} and {}",
                            if references.is_some() { "the hold-out set's measurements" } else { "the measurements" },
                            columns[0],
                            columns[1],
                            columns[2]
                        ),
                    )
                },
            )?;
        let readings: Vec<[f64; 3]> =
            data.sensor_values.iter().map(|r| [r[place[0]], r[place[1]], r[place[2]]]).collect();
        let reference = match references.and_then(|r| r.iter().find(|t| t.name == a.name)) {
            Some(t) => t.reference,
            None => mean_direction(&readings)
                .ok_or_else(|| refuse(&a.name, "its readings have no mean direction (all of no length)".into()))?,
        };
        let tilt: Vec<Vector3<f64>> = readings
            .iter()
            .enumerate()
            .map(|(i, r)| {
                TiltSensor::tilt(*r, reference).ok_or_else(|| {
                    let at = data.line_of(i).map_or(format!("measurement {}", i + 1), |l| format!("line {l}"));
                    refuse(&a.name, format!("{at}: the reading {r:?} has no direction"))
                })
            })
            .collect::<Result<_, _>>()?;
        // Its own tilt's columns, then the nearest declared sensor's below it on the chain.
        let column = out.sensor_names.len();
        let below = sensors.iter().zip(&tilts).rev().find(|(s, _)| s.link < a.link);
        out.sensor_names.extend(["x", "y", "z"].map(|c| format!("{}.tilt_{c}", a.name)));
        if below.is_some() {
            out.sensor_names.extend(["x", "y", "z"].map(|c| format!("{}.below_tilt_{c}", a.name)));
        }
        for (i, (row, t)) in out.sensor_values.iter_mut().zip(&tilt).enumerate() {
            row.extend([t.x, t.y, t.z]);
            if let Some((_, under)) = below {
                row.extend([under[i].x, under[i].y, under[i].z]);
            }
        }
        let below = below.map(|(s, _)| s.name.clone());
        sensors.push(TiltSensor { name: a.name.clone(), link: a.link, column, reference, below });
        tilts.push(tilt);
    }
    // The raw columns are no drivers: taken out, the tilt columns moved to their places.
    out.tilt_sensors = sensors;
    let raw: Vec<String> = sorted.iter().flat_map(|a| raw_columns(&a.name)).collect();
    Ok(out.without_sensor_columns(&raw))
}

/// The unit mean of the readings' directions.
fn mean_direction(readings: &[[f64; 3]]) -> Option<[f64; 3]> {
    let sum: Vector3<f64> = readings
        .iter()
        .map(|r| Vector3::from(*r))
        .filter(|v| v.norm().is_finite() && v.norm() > 0.0)
        .map(|v| v.normalize())
        .sum();
    let n = sum.norm();
    (n.is_finite() && n > 0.0).then(|| (sum / n).into())
}
