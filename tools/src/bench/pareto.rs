//! The Pareto front of (cost, error) points, both to be made small, where errors nearer each
//! other than a tolerance (three times the reference's own noise) are not told apart.

/// Whether each point is on the front, taken by rising cost: a point is on it when its error
/// is lower by more than `tolerance` than that of every cheaper point on it, and not higher by
/// more than `tolerance` than the best of its own cost. So a cheaper point hides a dearer one
/// whose lower error the reference cannot resolve, and each step of the front buys an error
/// it can. With no tolerance this is the usual front (no point at most as costly and at most
/// as wrong, strictly better in one); equal points are all on it. Points with a NaN coordinate
/// are never on it.
pub(crate) fn front(points: &[(f64, f64)], tolerance: f64) -> Vec<bool> {
    let mut order: Vec<usize> = (0..points.len()).filter(|&i| !points[i].0.is_nan() && !points[i].1.is_nan()).collect();
    order.sort_by(|&a, &b| points[a].0.total_cmp(&points[b].0));
    let mut on = vec![false; points.len()];
    // None before the cheapest group: it is on the front whatever its errors (infinite ones too).
    let mut best: Option<f64> = None;
    for same_cost in order.chunk_by(|&a, &b| points[a].0 == points[b].0) {
        let resolved: Vec<usize> = same_cost.iter().copied().filter(|&i| best.is_none_or(|b| points[i].1 < b - tolerance)).collect();
        let Some(lowest) = resolved.iter().map(|&i| points[i].1).min_by(f64::total_cmp) else { continue };
        for &i in resolved.iter().filter(|&&i| points[i].1 <= lowest + tolerance) {
            on[i] = true;
        }
        best = Some(best.map_or(lowest, |b| b.min(lowest)));
    }
    on
}

/// The indices of the front's points, by rising cost: the staircase a chart draws.
pub(crate) fn front_in_cost_order(points: &[(f64, f64)], tolerance: f64) -> Vec<usize> {
    let on = front(points, tolerance);
    let mut indices: Vec<usize> = (0..points.len()).filter(|&i| on[i]).collect();
    indices.sort_by(|&a, &b| points[a].0.total_cmp(&points[b].0).then(points[b].1.total_cmp(&points[a].1)));
    indices
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_front_keeps_exactly_the_undominated_points() {
        let points = [(1.0, 5.0), (2.0, 3.0), (3.0, 4.0), (4.0, 1.0), (2.0, 3.0), (5.0, 1.0), (0.5, 9.0), (f64::NAN, 0.0)];
        assert_eq!(front(&points, 0.0), [true, true, false, true, true, false, true, false]);
        assert_eq!(front_in_cost_order(&points, 0.0), [6, 0, 1, 4, 3]);
    }

    #[test]
    fn one_point_and_none() {
        assert_eq!(front(&[(1.0, 1.0)], 0.0), [true]);
        // A black reference makes every error infinite: the cheapest stay on the front.
        assert_eq!(front(&[(2.0, f64::INFINITY), (1.0, f64::INFINITY), (1.0, f64::INFINITY)], 0.1), [false, true, true]);
        assert!(front(&[], 0.1).is_empty());
    }

    #[test]
    fn brute_force_agrees_on_a_grid() {
        // Every point of a 4 x 4 grid with error falling as cost rises along one diagonal.
        let points: Vec<(f64, f64)> = (0..16).map(|i| ((i % 4) as f64, ((i / 4) as f64 - (i % 4) as f64).abs())).collect();
        let on = front(&points, 0.0);
        for (i, p) in points.iter().enumerate() {
            let beaten = points.iter().any(|q| q.0 <= p.0 && q.1 <= p.1 && q != p);
            assert_eq!(on[i], !beaten, "point {p:?}");
        }
    }

    #[test]
    fn an_error_lower_by_less_than_the_tolerance_buys_no_place_on_the_front() {
        // Costs rise; errors fall by 0.03, then 0.03 (0.06 from the first), then 0.2.
        let points = [(1.0, 0.30), (2.0, 0.27), (3.0, 0.24), (4.0, 0.04)];
        assert_eq!(front(&points, 0.0), [true, true, true, true]);
        assert_eq!(front(&points, 0.05), [true, false, true, true], "0.27 is not told from 0.30; 0.24 is");
        assert_eq!(front(&points, 0.1), [true, false, false, true]);
        assert_eq!(front_in_cost_order(&points, 0.05), [0, 2, 3]);
        // Equally costly: only an error lower by more than the tolerance hides another.
        assert_eq!(front(&[(1.0, 0.30), (1.0, 0.27)], 0.05), [true, true]);
        assert_eq!(front(&[(1.0, 0.30), (1.0, 0.20)], 0.05), [false, true]);
        // A cheaper point a little worse still hides the dearer one.
        assert_eq!(front(&[(1.0, 0.31), (2.0, 0.30)], 0.05), [true, false]);
    }
}
