//! The Pareto front of (cost, error) points, both to be made small.

/// Whether each point is on the front: no other point is at most as costly and at most as
/// wrong while strictly better in one of the two. Equal points are all on the front.
/// Points with a NaN coordinate are never on it.
pub(crate) fn front(points: &[(f64, f64)]) -> Vec<bool> {
    let dominates = |a: (f64, f64), b: (f64, f64)| a.0 <= b.0 && a.1 <= b.1 && (a.0 < b.0 || a.1 < b.1);
    points
        .iter()
        .map(|&p| !p.0.is_nan() && !p.1.is_nan() && !points.iter().any(|&q| !q.0.is_nan() && !q.1.is_nan() && dominates(q, p)))
        .collect()
}

/// The indices of the front's points, by rising cost: the staircase a chart draws.
pub(crate) fn front_in_cost_order(points: &[(f64, f64)]) -> Vec<usize> {
    let on = front(points);
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
        assert_eq!(front(&points), [true, true, false, true, true, false, true, false]);
        assert_eq!(front_in_cost_order(&points), [6, 0, 1, 4, 3]);
    }

    #[test]
    fn one_point_and_none() {
        assert_eq!(front(&[(1.0, 1.0)]), [true]);
        assert!(front(&[]).is_empty());
    }

    #[test]
    fn brute_force_agrees_on_a_grid() {
        // Every point of a 4 x 4 grid with error falling as cost rises along one diagonal.
        let points: Vec<(f64, f64)> = (0..16).map(|i| ((i % 4) as f64, ((i / 4) as f64 - (i % 4) as f64).abs())).collect();
        let on = front(&points);
        for (i, p) in points.iter().enumerate() {
            let beaten = points.iter().any(|q| q.0 <= p.0 && q.1 <= p.1 && q != p);
            assert_eq!(on[i], !beaten, "point {p:?}");
        }
    }
}
