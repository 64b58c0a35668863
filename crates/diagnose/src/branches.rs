//! Robots with branches (issue #59): a torso carrying two arms, measured at one arm's tool while the
//! robot logs the other's joints. A measurement column named exactly as a joint of one of the robot's
//! branches ([`thermokin_chain::Branch`], the rest of its tree beside the measured chain) is that joint's
//! position (degrees; mm for a slide), not a sensor to drive rows with a gain: what hangs from the branch
//! loads the links it shares with the measured chain, and the catalogue offers that load on each
//! revolute joint below it ([`thermokin_identify::Effect::BranchLoad`], lumped without masses as a
//! compliance is). A branch is read whole or not at all: its load needs every one of its joints.

use thermokin_chain::{BranchColumns, Dataset, Robot};

use crate::error::DiagnoseError;

/// `data` with each branch of `robot` whose joints it logs moved to consecutive sensor columns at the
/// end (in the branch's joint order), [`Dataset::branch_columns`] filled; unchanged when it logs none.
/// A branch logged in part is refused by name.
pub(crate) fn with_branches(robot: &Robot, data: &Dataset) -> Result<Option<Dataset>, DiagnoseError> {
    let mut logged = Vec::new();
    for (b, branch) in robot.branches().iter().enumerate() {
        let place: Vec<Option<usize>> =
            branch.joints.iter().map(|j| data.sensor_names.iter().position(|n| *n == j.name)).collect();
        if place.iter().all(Option::is_none) {
            continue;
        }
        let missing: Vec<&str> =
            branch.joints.iter().zip(&place).filter(|(_, p)| p.is_none()).map(|(j, _)| j.name.as_str()).collect();
        if !missing.is_empty() {
            return Err(DiagnoseError::Branch {
                name: branch.name.clone(),
                reason: format!(
                    "the measurements log some of its joints but not {}: what it carries loads the measured chain by all of them — give every joint of the branch, or none",
                    missing.join(", ")
                ),
            });
        }
        logged.push((b, place.into_iter().flatten().collect::<Vec<usize>>()));
    }
    if logged.is_empty() {
        return Ok(None);
    }
    let taken: Vec<usize> = logged.iter().flat_map(|(_, p)| p.iter().copied()).collect();
    let order: Vec<usize> =
        (0..data.sensor_names.len()).filter(|k| !taken.contains(k)).chain(taken.iter().copied()).collect();
    let mut out = data.clone();
    out.sensor_names = order.iter().map(|&k| data.sensor_names[k].clone()).collect();
    out.sensor_values = data
        .sensor_values
        .iter()
        .map(|r| order.iter().map(|&k| r.get(k).copied().unwrap_or(f64::NAN)).collect())
        .collect();
    let mut column = data.sensor_names.len() - logged.iter().map(|(_, p)| p.len()).sum::<usize>();
    out.branch_columns = logged
        .iter()
        .map(|(b, p)| {
            let at = BranchColumns { branch: *b, column, len: p.len() };
            column += p.len();
            at
        })
        .collect();
    for t in &mut out.tilt_sensors {
        t.column = order.iter().position(|&k| k == t.column).unwrap_or(t.column);
    }
    Ok(Some(out))
}
