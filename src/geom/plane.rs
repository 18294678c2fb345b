//! Oriented planes and the one convex-polygon clipper (Sutherland–Hodgman) every module uses:
//! the rasterizer's near-plane and guard-band clipping, the graph camera cutting its frusta's
//! faces, the impostor builder cutting triangles to a frustum (paper 1 §5).
//!
//! Invariant: an edge crossing the boundary is cut from its inside end toward its outside end,
//! so the two polygons sharing it are cut at the same point whichever way round they list it.

use glam::DVec3;

/// An oriented plane `n·X + e = 0`; the inside is where `n·X + e ≥ 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Normal (pointing inside).
    pub n: DVec3,
    /// Offset.
    pub e: f64,
}

impl Plane {
    /// The plane through `p` with normal `n` (inside along `n`).
    pub fn through(p: DVec3, n: DVec3) -> Plane {
        Plane { n, e: -n.dot(p) }
    }
    /// Signed distance (scaled by `|n|`).
    pub fn eval(&self, x: DVec3) -> f64 {
        self.n.dot(x) + self.e
    }
    /// The same plane, inside and outside swapped.
    pub fn flipped(&self) -> Plane {
        Plane {
            n: -self.n,
            e: -self.e,
        }
    }
}

/// Sutherland–Hodgman: the part of the convex polygon `poly` where `dist ≥ 0` (`dist` affine
/// along every edge: a plane's [`Plane::eval`], a camera's clip distance, an image-space bound).
/// Where an edge is cut, the new corner is `lerp(inside, outside, s)`, always from the inside
/// corner toward the outside one.
pub fn clip_polygon<V: Copy>(
    poly: &[V],
    dist: impl Fn(&V) -> f64,
    lerp: impl Fn(&V, &V, f64) -> V,
) -> Vec<V> {
    let mut out = Vec::with_capacity(poly.len() + 2);
    for i in 0..poly.len() {
        let (a, b) = (&poly[i], &poly[(i + 1) % poly.len()]);
        let (da, db) = (dist(a), dist(b));
        if da >= 0.0 {
            out.push(*a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            let (inside, outside, di, dout) = if da >= 0.0 {
                (a, b, da, db)
            } else {
                (b, a, db, da)
            };
            out.push(lerp(inside, outside, di / (di - dout)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_cut_through_its_middle_keeps_the_inside_half_and_its_payloads() {
        let sq = [
            (DVec3::new(0.0, 0.0, 0.0), 0.0),
            (DVec3::new(2.0, 0.0, 0.0), 2.0),
            (DVec3::new(2.0, 2.0, 0.0), 2.0),
            (DVec3::new(0.0, 2.0, 0.0), 0.0),
        ];
        let plane = Plane::through(DVec3::new(1.0, 0.0, 0.0), DVec3::X);
        let cut = |p: &Plane| {
            clip_polygon(
                &sq,
                |c: &(DVec3, f64)| p.eval(c.0),
                |a, b, s| (a.0 + (b.0 - a.0) * s, a.1 + (b.1 - a.1) * s),
            )
        };
        let half = cut(&plane);
        assert_eq!(half.len(), 4);
        for (p, x) in &half {
            assert!(p.x >= 1.0 - 1e-12 && (p.x - x).abs() < 1e-12, "{p} {x}");
        }
        // Listed the other way round, the cut points are the same.
        let mut rev = sq;
        rev.reverse();
        let other = clip_polygon(
            &rev,
            |c| plane.eval(c.0),
            |a, b, s| (a.0 + (b.0 - a.0) * s, a.1 + (b.1 - a.1) * s),
        );
        for (p, _) in &half {
            assert!(other.iter().any(|(q, _)| q == p), "{p}");
        }
        assert_eq!(cut(&plane.flipped()).len(), 4);
        assert!(cut(&Plane::through(DVec3::new(5.0, 0.0, 0.0), DVec3::X)).is_empty());
    }
}
