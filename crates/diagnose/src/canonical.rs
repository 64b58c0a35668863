//! The same poses in any row order give the same diagnosis. A file's lines are the order the poses were
//! measured in only when the user says so ([`MeasuringOrder::File`]); otherwise only a time column orders
//! them. Everything the diagnosis draws from the order of its rows — the seeded shuffle of folds without
//! time, the k-means++ start of the neighbourhoods, the evenly spread subsets of the screen and the
//! scans, the order sums are taken in — is therefore taken from a canonical order that the poses
//! themselves define: by time where they span time, then by file line where the file is the order, then
//! by their content (joint values, measured position and orientation, sensor readings), the file line
//! last (it only separates exact copies of one pose, which weigh alike wherever they stand).
//!
//! The diagnosis runs on the set in that order; [`Report::in_given_order`] returns what the report lists
//! pose by pose (the gross errors, the blocks of flags, the residuals per measurement, the poses) to the
//! order the caller gave, so that "measurement 12" still names the twelfth row given.

use std::cmp::Ordering;

use thermokin_chain::{Dataset, Measurement, MeasuringOrder};

use crate::report::Report;

/// The canonical order of `data`'s poses under `by`: `perm[k]` is the given index of the `k`-th pose.
pub(crate) fn canonical_order(data: &Dataset, by: MeasuringOrder) -> Vec<usize> {
    let timed = data.time_span() > 0.0;
    let by_lines = by == MeasuringOrder::File;
    let line = |i: usize| data.line_of(i).unwrap_or(i + 1);
    let mut perm: Vec<usize> = (0..data.len()).collect();
    perm.sort_by(|&a, &b| {
        let (ma, mb) = (&data.measurements[a], &data.measurements[b]);
        let time = if timed { ma.time_min.total_cmp(&mb.time_min) } else { Ordering::Equal };
        let lines = if by_lines { line(a).cmp(&line(b)) } else { Ordering::Equal };
        time.then(lines)
            .then_with(|| content(ma, mb))
            .then_with(|| readings(data.sensor_values.get(a), data.sensor_values.get(b)))
            .then_with(|| line(a).cmp(&line(b)))
    });
    perm
}

/// Two poses compared by what was measured: joint values, position, orientation, stated deviations.
fn content(a: &Measurement, b: &Measurement) -> Ordering {
    let quaternion = |m: &Measurement| m.orientation.map(|q| q.coords.as_slice().to_vec()).unwrap_or_default();
    let std = |m: &Measurement| m.position_std_mm.map(|s| s.as_slice().to_vec()).unwrap_or_default();
    floats(&a.q, &b.q)
        .then_with(|| floats(a.position_mm.as_slice(), b.position_mm.as_slice()))
        .then_with(|| floats(&quaternion(a), &quaternion(b)))
        .then_with(|| floats(&std(a), &std(b)))
        .then_with(|| floats(&a.temps, &b.temps))
}

/// Two poses' sensor readings compared (a set without sensor columns: equal).
fn readings(a: Option<&Vec<f64>>, b: Option<&Vec<f64>>) -> Ordering {
    match (a, b) {
        (Some(x), Some(y)) => floats(x, y),
        _ => Ordering::Equal,
    }
}

/// Two lists of numbers in lexicographic total order (the shorter first where one begins the other).
fn floats(x: &[f64], y: &[f64]) -> Ordering {
    x.iter().zip(y).map(|(u, v)| u.total_cmp(v)).find(|o| o.is_ne()).unwrap_or(x.len().cmp(&y.len()))
}

/// `data` in its canonical order ([`canonical_order`]) with that order, or `data` itself where it is
/// already in it.
pub(crate) fn in_canonical_order(
    data: &Dataset,
    by: MeasuringOrder,
) -> (std::borrow::Cow<'_, Dataset>, Option<Vec<usize>>) {
    let perm = canonical_order(data, by);
    if perm.iter().enumerate().all(|(k, &i)| k == i) {
        return (std::borrow::Cow::Borrowed(data), None);
    }
    (std::borrow::Cow::Owned(data.subset(&perm)), Some(perm))
}

/// `report` of a diagnosis run on the poses in the order `perm`, if they were put in one, returned to the
/// given order ([`Report::in_given_order`]).
pub(crate) fn to_given_order(perm: Option<&[usize]>, kept: &[usize], report: Report) -> Report {
    match perm {
        Some(perm) => report.in_given_order(perm, kept),
        None => report,
    }
}

impl Report {
    /// The report of a diagnosis run on the poses in the order `perm` (`perm[k]` the given index of the
    /// `k`-th), with every pose-by-pose list returned to the given order: gross errors and the blocks of
    /// flags by their given measurement numbers, the residuals per measurement and the pose records (of
    /// the poses `kept`, canonical places) by the given place of each.
    pub(crate) fn in_given_order(mut self, perm: &[usize], kept: &[usize]) -> Report {
        let given = |m: usize| perm.get(m - 1).map_or(m, |&i| i + 1);
        for o in &mut self.outliers {
            o.measurement = given(o.measurement);
        }
        self.outliers.sort_by_key(|o| o.measurement);
        let kept_given: Vec<usize> = kept.iter().filter_map(|&k| perm.get(k).copied()).collect();
        let mut by_given: Vec<usize> = (0..kept_given.len()).collect();
        by_given.sort_by_key(|&k| kept_given[k]);
        let reorder = |v: &mut Vec<f64>| {
            if v.len() == by_given.len() {
                *v = by_given.iter().map(|&k| v[k]).collect();
            }
        };
        reorder(&mut self.residuals_before.per_measurement_mm);
        reorder(&mut self.residuals_after.per_measurement_mm);
        if self.poses.len() == by_given.len() {
            let mut poses: Vec<Option<crate::report::PoseRecord>> = self.poses.into_iter().map(Some).collect();
            self.poses = by_given.iter().filter_map(|&k| poses[k].take()).collect();
        }
        for c in &mut self.outlier_screen.clusters {
            let mut pairs: Vec<(usize, Option<usize>)> =
                c.measurements.iter().map(|&m| given(m)).zip(c.lines.iter().copied()).collect();
            pairs.sort_by_key(|p| p.0);
            (c.measurements, c.lines) = pairs.into_iter().unzip();
        }
        self
    }
}
