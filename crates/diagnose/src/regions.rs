//! Groups of poses by where they are: the workspace quadrant of the measured point (reach × height
//! against their medians), and the arm's branch (elbow × wrist) — for leave-one-group-out folds and for
//! the map of where residuals lie.

use thermokin_chain::Dataset;

/// The median of `v` (the upper one of an even count; 0 for none).
pub(crate) fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s.get(s.len() / 2).copied().unwrap_or(0.0)
}

/// Each pose's workspace quadrant: reach (distance from the base's Z axis) and height against their
/// medians — 0 near-low, 1 near-high, 2 far-low, 3 far-high.
pub(crate) fn workspace_quadrants(data: &Dataset) -> Vec<usize> {
    let reach: Vec<f64> = data.measurements.iter().map(|m| m.position_mm.xy().norm()).collect();
    let height: Vec<f64> = data.measurements.iter().map(|m| m.position_mm.z).collect();
    let (mr, mh) = (median(&reach), median(&height));
    (0..data.len()).map(|i| usize::from(reach[i] > mr) * 2 + usize::from(height[i] > mh)).collect()
}

/// Each pose's arm branch: the sign of each joint that decides one (elbow: joint 3 against its median;
/// wrist: joint 5's sign) — ABB's cfx bits for the arms of this project — 0…3 as elbow × 2 + wrist.
pub(crate) fn arm_branches(data: &Dataset) -> Vec<usize> {
    let elbow: Vec<f64> = data.measurements.iter().map(|m| m.q.get(2).copied().unwrap_or(0.0)).collect();
    let me = median(&elbow);
    let wrist = |i: usize| data.measurements[i].q.get(4).is_some_and(|&v| v > 0.0);
    (0..data.len()).map(|i| usize::from(elbow[i] > me) * 2 + usize::from(wrist(i))).collect()
}
