//! Convex polygons in 3-D space, as the graph camera builds its frusta's faces from them (paper 1
//! §5): clipping to a plane, area, Newell normal, the hull of coplanar points, shared edges.
//!
//! Invariant: every polygon is convex and planar, its corners in order around it.

use super::Plane;
use glam::{DVec2, DVec3};

/// Clips the convex polygon `poly` to the inside of `plane` ([`super::clip_polygon`]).
pub(crate) fn clip(poly: &[DVec3], plane: &Plane) -> Vec<DVec3> {
    super::clip_polygon(poly, |p| plane.eval(*p), |a, b, s| *a + (*b - *a) * s)
}

/// The area of the planar convex polygon `poly` with unit normal `n`.
pub(crate) fn polygon_area(poly: &[DVec3], n: DVec3) -> f64 {
    let mut sum = DVec3::ZERO;
    for i in 0..poly.len() {
        sum += poly[i].cross(poly[(i + 1) % poly.len()]);
    }
    0.5 * sum.dot(n).abs()
}

/// The convex hull of coplanar points (unit normal `n`).
pub(crate) fn convex_hull_in_plane(points: &[DVec3], n: DVec3) -> Vec<DVec3> {
    let t = n.any_orthonormal_vector();
    let b = n.cross(t);
    let flat: Vec<DVec2> = points
        .iter()
        .map(|p| DVec2::new(p.dot(t), p.dot(b)))
        .collect();
    super::convex_hull(&flat)
        .into_iter()
        .map(|i| points[i])
        .collect()
}

/// The unit normal of a planar polygon (Newell's method), if it has an area.
pub(crate) fn newell_normal(poly: &[DVec3]) -> Option<DVec3> {
    (0..poly.len())
        .map(|i| poly[i].cross(poly[(i + 1) % poly.len()]))
        .sum::<DVec3>()
        .try_normalize()
}

/// Whether two coplanar convex polygons share a stretch of an edge (collinear edges whose
/// overlap is longer than `tol`).
pub(crate) fn share_an_edge(a: &[DVec3], b: &[DVec3], tol: f64) -> bool {
    let edges = |p: &[DVec3]| {
        (0..p.len())
            .map(|i| (p[i], p[(i + 1) % p.len()]))
            .collect::<Vec<_>>()
    };
    edges(a).iter().any(|&(a0, a1)| {
        let Some(dir) = (a1 - a0).try_normalize() else {
            return false;
        };
        let off_line = |p: DVec3| (p - a0).reject_from_normalized(dir).length();
        edges(b).iter().any(|&(b0, b1)| {
            if off_line(b0) > tol || off_line(b1) > tol {
                return false;
            }
            let (s0, s1) = ((b0 - a0).dot(dir), (b1 - a0).dot(dir));
            let (lo, hi) = (s0.min(s1).max(0.0), s0.max(s1).min((a1 - a0).length()));
            hi - lo > tol
        })
    })
}
