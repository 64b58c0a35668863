//! The measuring order: a short joint-space path through the chosen poses.
//!
//! A joint move takes as long as its largest joint motion (the joints move together), so the distance
//! between two poses is `max_j |qᵃⱼ − qᵇⱼ|`. The path starts at the last measured pose when there is one
//! (else at the first pose chosen), visits the nearest unvisited pose next, then is shortened by 2-opt
//! (reversing any stretch that makes it shorter) until no reversal does.

/// The largest joint motion between two configurations, radians (mm for a prismatic joint).
pub(crate) fn motion(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// Passes of 2-opt at most (each pass is O(n²); a path of 60 poses settles in a handful).
const MAX_PASSES: usize = 100;

/// The order to visit `poses` in, starting from `from` (not itself visited) or from `poses[0]`.
pub(crate) fn measuring_order(poses: &[Vec<f64>], from: Option<&[f64]>) -> Vec<usize> {
    let n = poses.len();
    if n == 0 {
        return Vec::new();
    }
    // Nearest neighbour.
    let mut order = Vec::with_capacity(n);
    let mut left: Vec<usize> = (0..n).collect();
    let mut at: Vec<f64> = match from {
        Some(q) => q.to_vec(),
        None => {
            left.remove(0);
            order.push(0);
            poses[0].clone()
        }
    };
    while !left.is_empty() {
        let (k, _) = left
            .iter()
            .enumerate()
            .map(|(k, &i)| (k, motion(&at, &poses[i])))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((0, 0.0));
        let i = left.remove(k);
        at.clone_from(&poses[i]);
        order.push(i);
    }
    two_opt(poses, from, &mut order);
    order
}

/// Total motion of the path through `order` (from `from` when given).
pub(crate) fn path_length(poses: &[Vec<f64>], from: Option<&[f64]>, order: &[usize]) -> f64 {
    let head = match (from, order.first()) {
        (Some(q), Some(&i)) => motion(q, &poses[i]),
        _ => 0.0,
    };
    head + order.windows(2).map(|w| motion(&poses[w[0]], &poses[w[1]])).sum::<f64>()
}

/// 2-opt on an open path whose start is fixed (`from`, or the first pose when there is none).
fn two_opt(poses: &[Vec<f64>], from: Option<&[f64]>, order: &mut [usize]) {
    let n = order.len();
    // Position 0 of the path is `from` when given: reversals may then start at the first pose.
    let first = usize::from(from.is_none());
    let point = |order: &[usize], k: usize| -> Option<&[f64]> {
        if k == usize::MAX { from } else { order.get(k).map(|&i| poses[i].as_slice()) }
    };
    let d = |a: Option<&[f64]>, b: Option<&[f64]>| match (a, b) {
        (Some(a), Some(b)) => motion(a, b),
        _ => 0.0,
    };
    for _ in 0..MAX_PASSES {
        let mut improved = false;
        for i in first..n {
            for k in i + 1..n {
                let before = point(order, i.wrapping_sub(1));
                let after = point(order, k + 1);
                let (a, b) = (point(order, i), point(order, k));
                let delta = d(before, b) + d(a, after) - d(before, a) - d(b, after);
                // Strictly shorter by more than rounding: no cycling between equal paths.
                if delta < -1e-12 {
                    order[i..=k].reverse();
                    improved = true;
                }
            }
        }
        if !improved {
            break;
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use super::{measuring_order, path_length};

    /// Poses on a line visited out of order come back in line order, from either end.
    #[test]
    fn poses_on_a_line_are_visited_in_order() {
        let poses: Vec<Vec<f64>> = [0.0, 5.0, 1.0, 4.0, 2.0, 3.0].iter().map(|&x| vec![x, -x]).collect();
        let order = measuring_order(&poses, None);
        assert_eq!(order.iter().map(|&i| poses[i][0]).collect::<Vec<_>>(), [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        assert!((path_length(&poses, None, &order) - 5.0).abs() < 1e-12);
        let from_end = measuring_order(&poses, Some(&[6.0, -6.0]));
        assert_eq!(from_end.iter().map(|&i| poses[i][0]).collect::<Vec<_>>(), [5.0, 4.0, 3.0, 2.0, 1.0, 0.0]);
        assert!((path_length(&poses, Some(&[6.0, -6.0]), &from_end) - 6.0).abs() < 1e-12);
    }
}
