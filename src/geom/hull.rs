//! The convex hull of points in the plane (Andrew's monotone chain), used to outline and
//! check planar polygons (graph-camera faces, their top views).
//!
//! Invariant: the hull is returned counter-clockwise (for a right-handed `x`, `y`), without
//! collinear points, as indices into the input.

use glam::DVec2;

/// Indices of the convex hull of `points`, counter-clockwise. Fewer than three distinct
/// points give what remains of them.
pub fn convex_hull(points: &[DVec2]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        let (p, q) = (points[a], points[b]);
        p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y))
    });
    order.dedup_by(|a, b| points[*a] == points[*b]);
    if order.len() < 3 {
        return order;
    }
    let turn =
        |o: usize, a: usize, b: usize| (points[a] - points[o]).perp_dot(points[b] - points[o]);
    let mut hull: Vec<usize> = Vec::with_capacity(2 * order.len());
    // The lower chain left to right, then the upper chain right to left.
    for reverse in [false, true] {
        let start = hull.len();
        for k in 0..order.len() {
            let i = order[if reverse { order.len() - 1 - k } else { k }];
            while hull.len() >= start + 2
                && turn(hull[hull.len() - 2], hull[hull.len() - 1], i) <= 0.0
            {
                hull.pop();
            }
            hull.push(i);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_a_square_with_inner_and_edge_points() {
        let pts = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(0.5, 0.5),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.5, 0.0),
            DVec2::new(0.0, 1.0),
            DVec2::new(1.0, 1.0),
        ];
        let h = convex_hull(&pts);
        assert_eq!(h.len(), 4, "{h:?}");
        let area: f64 = (0..4)
            .map(|i| pts[h[i]].perp_dot(pts[h[(i + 1) % 4]]))
            .sum::<f64>()
            / 2.0;
        assert!(
            (area - 1.0).abs() < 1e-12,
            "counter-clockwise, area 1: {area}"
        );
        assert!(convex_hull(&pts[..2]).len() == 2);
    }
}
