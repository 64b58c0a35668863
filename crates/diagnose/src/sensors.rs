//! What a measurement column must be to be read as a sensor. Every numeric column the readers do not
//! read arrives as a sensor column ([`thermokin_chain::Dataset::sensor_names`]); the diagnosis takes it as
//! one only where it can be: a column that never changes over the session drives nothing, and a column
//! that is an affine function of a joint's value (a copy of the joint's angle, in any unit or offset: what
//! a controller's log repeats) is that joint, not a sensor — a row following it is a gear ratio, which the
//! catalogue already offers with its physics and its eligibility. Such columns are left out, and the
//! report says why (issue #59: a copy of joint 2's angle was chosen as a sensor in four outer folds).

use thermokin_chain::Dataset;

/// Each sensor column of `data` that is no sensor, with why.
pub fn not_sensors(data: &Dataset) -> Vec<(String, String)> {
    let column =
        |s: usize| -> Vec<f64> { data.sensor_values.iter().map(|r| r.get(s).copied().unwrap_or(f64::NAN)).collect() };
    let dof = data.measurements.first().map_or(0, |m| m.q.len());
    let mut out = Vec::new();
    if data.sensor_values.len() != data.len() || data.len() < 2 {
        return out;
    }
    // A declared accelerometer's tilt columns are its link's tilt, whatever they hold.
    // A declared accelerometer's tilt columns are its link's tilt, a branch's its joints, whatever they hold.
    let tilt = |s: usize| {
        data.tilt_sensors.iter().any(|t| (t.column..t.column + if t.below.is_some() { 6 } else { 3 }).contains(&s))
            || data.branch_columns.iter().any(|b| b.holds(s))
    };
    for (s, name) in data.sensor_names.iter().enumerate().filter(|(s, _)| !tilt(*s)) {
        let x = column(s);
        let (lo, hi) = crate::stats::span(x.iter().copied());
        if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
            out.push((name.clone(), "it does not change over the session".to_string()));
            continue;
        }
        let copy = (0..dof).find(|&j| {
            let q: Vec<f64> = data.measurements.iter().map(|m| m.q[j]).collect();
            affine(&q, &x)
        });
        if let Some(j) = copy {
            out.push((name.clone(), format!("it repeats joint {}'s value (an affine function of it)", j + 1)));
        }
    }
    out
}

/// Whether `y` is an affine function of `x` to rounding: the least-squares line leaves residuals below
/// 1e-9 of `y`'s spread (a log's six decimals of a degree are 1e-6 of a 1° spread: a copy printed
/// with fewer decimals than the joint column stays a copy; a sensor's noise does not pass).
fn affine(x: &[f64], y: &[f64]) -> bool {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
    let syy: f64 = y.iter().map(|v| (v - my).powi(2)).sum();
    if sxx <= 0.0 || syy <= 0.0 {
        return false;
    }
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let left = syy - sxy * sxy / sxx;
    left <= 1e-12 * syy
}

/// `data` without the columns of [`not_sensors`], and the sentences the report gives of them.
pub(crate) fn only_sensors(data: &Dataset) -> (std::borrow::Cow<'_, Dataset>, Vec<String>) {
    let dropped = not_sensors(data);
    if dropped.is_empty() {
        return (std::borrow::Cow::Borrowed(data), Vec::new());
    }
    let names: Vec<String> = dropped.iter().map(|(n, _)| n.clone()).collect();
    let kept = data.without_sensor_columns(&names);
    let said =
        dropped.into_iter().map(|(name, why)| format!("column `{name}` is not read as a sensor: {why}")).collect();
    (std::borrow::Cow::Owned(kept), said)
}

/// `holdout` (its sensor columns in `train`'s order) with each driver column — neither a declared
/// accelerometer's tilt nor a branch's joint — shifted so that its mean over the hold-out session is the
/// training session's: a column not declared has no known zero, so across sessions only its changes are
/// read (a remounted sensor, a base resting otherwise, shift its level without the robot changing). What
/// the refitted protocol scores, as it refits the registration: the session's own reference.
pub(crate) fn re_referenced(train: &Dataset, holdout: &Dataset) -> Dataset {
    let mut out = holdout.clone();
    let declared = |k: usize| {
        train.tilt_sensors.iter().any(|t| (t.column..t.column + if t.below.is_some() { 6 } else { 3 }).contains(&k))
            || train.branch_columns.iter().any(|b| b.holds(k))
    };
    let mean = |d: &Dataset, k: usize| {
        let v: Vec<f64> = d.sensor_values.iter().filter_map(|r| r.get(k).copied()).filter(|v| v.is_finite()).collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    for k in (0..train.sensor_names.len()).filter(|&k| !declared(k)) {
        if let (Some(a), Some(b)) = (mean(train, k), mean(holdout, k)) {
            for r in &mut out.sensor_values {
                if let Some(v) = r.get_mut(k) {
                    *v += a - b;
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use thermokin_chain::Measurement;

    #[test]
    fn a_copy_of_a_joint_or_a_constant_is_no_sensor_and_a_reading_is_one() {
        let n = 40;
        let measurements = (0..n)
            .map(|i| Measurement {
                time_min: 0.0,
                q: vec![0.1 * i as f64, (0.37 * i as f64).sin()],
                position_mm: Vector3::zeros(),
                orientation: None,
                position_std_mm: None,
                temps: Vec::new(),
            })
            .collect::<Vec<_>>();
        let sensor_values = measurements
            .iter()
            .enumerate()
            .map(|(i, m)| vec![m.q[1].to_degrees() + 3.0, 0.25, (1.3 * i as f64).cos()])
            .collect();
        let data = Dataset {
            measurements,
            sensor_names: vec!["q2_copy".into(), "flat".into(), "acc_x".into()],
            sensor_values,
            ..Dataset::default()
        };
        let said = not_sensors(&data);
        assert_eq!(said.len(), 2, "{said:?}");
        assert!(said[0].0 == "q2_copy" && said[0].1.contains("joint 2"), "{said:?}");
        assert!(said[1].0 == "flat" && said[1].1.contains("does not change"), "{said:?}");
        let (kept, sentences) = only_sensors(&data);
        assert_eq!(kept.sensor_names, ["acc_x"]);
        assert!(kept.sensor_values.iter().all(|r| r.len() == 1));
        assert_eq!(sentences.len(), 2);
    }
}
