//! Geometry: rays, boxes, triangles, meshes and transforms (all papers).
//!
//! World space is right-handed, `y` up, in metres. Geometry is `f32` (mesh payloads); cameras do
//! their projection arithmetic in `f64` (`crate::camera`). Loaders for OBJ + MTL, PLY and glTF
//! live in [`io`]; each returns a validated [`Mesh`] plus the survivable problems it met.
//!
//! Invariants of a [`Mesh`]: every index is in range, every position and normal is finite, every
//! normal has unit length, and no triangle is degenerate (zero area).

mod hull;
pub mod io;
mod mesh;
pub mod optics;
mod plane;
pub(crate) mod polygon;
mod primitives;
mod sampling;

/// Object ids: said in [`crate::frame`], the lowest layer, where frames first store them.
pub use crate::frame::{ENVIRONMENT, NO_OBJECT};

/// The largest coordinate magnitude trompe accepts, in scene units. The BVH builder multiplies
/// box spans (surface areas) and sums those products; spans up to `2 × 10¹⁸` keep every product
/// below `4 × 10³⁶`, far from `f32::MAX` (`3.4 × 10³⁸`), where a coordinate merely finite (a
/// cube at `x = 3 × 10³⁸`) overflows to infinity and the builder fails. Mesh files and scenes
/// placed at a time are refused past it, naming the vertex or object.
pub const MAX_COORDINATE: f32 = 1e18;

/// Whether a coordinate magnitude is past [`MAX_COORDINATE`] or not a number.
pub fn out_of_range(magnitude: f32) -> bool {
    magnitude.is_nan() || magnitude > MAX_COORDINATE
}
pub use hull::convex_hull;
pub use mesh::{Material, Mesh, MeshError, SourceCounts, Texture, Warning};
pub use plane::{Plane, clip_polygon};
pub use primitives::{cube, icosphere, plane};
pub use sampling::{SplitMix64, sample_surface, sphere_rays};

use glam::{Mat4, Vec2, Vec3};

/// A ray `origin + t · dir`, `t ≥ 0`. Renderers keep `dir` unit length so `t` is a distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts.
    pub origin: Vec3,
    /// Its direction.
    pub dir: Vec3,
}

impl Ray {
    /// A ray from `origin` along `dir`.
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self { origin, dir }
    }
    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// An axis-aligned box; empty when `min > max` on some axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (the identity of [`Aabb::grow`]).
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };
    /// The smallest box holding every point.
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.grow(p))
    }
    /// This box grown to hold `p`.
    pub fn grow(self, p: Vec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }
    /// The smallest box holding both.
    pub fn union(self, o: Aabb) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    /// True when the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }
    /// Centre point.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    /// Edge lengths.
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }
    /// Radius of the bounding sphere centred at [`Aabb::center`].
    pub fn radius(&self) -> f32 {
        self.extent().length() * 0.5
    }
    /// The box of this box's eight corners after `m`.
    pub fn transformed(&self, m: &Mat4) -> Self {
        let mut out = Self::EMPTY;
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            );
            out = out.grow(m.transform_point3(c));
        }
        out
    }
    /// Slab test: the parameter interval `[t0, t1]` of `ray` inside the box, if any.
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32)> {
        let inv = ray.dir.recip();
        let ta = (self.min - ray.origin) * inv;
        let tb = (self.max - ray.origin) * inv;
        let t0 = ta.min(tb).max_element().max(0.0);
        let t1 = ta.max(tb).min_element().min(t_max);
        (t0 <= t1).then_some((t0, t1))
    }
}

/// A ray–triangle hit: distance and barycentrics `(b1, b2)` of vertices 1 and 2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter.
    pub t: f32,
    /// Barycentric weights of vertices 1 and 2 (vertex 0 has `1 − b1 − b2`).
    pub bary: Vec2,
}

/// Watertight ray–triangle intersection (Woop, Benthin and Wald 2013, "Watertight
/// Ray/Triangle Intersection", JCGT 2(1)), two-sided, for hits with `t_min < t < t_max`.
///
/// The triangle is sheared into a frame where the ray runs along `+z` from the origin; the 2-D
/// edge functions `U`, `V`, `W` are then exact in sign for rays through shared edges and vertices
/// (recomputed in `f64` when one is exactly zero), so a ray never slips between two triangles.
#[inline]
pub fn intersect_triangle(ray: &Ray, p: [Vec3; 3], t_min: f32, t_max: f32) -> Option<TriangleHit> {
    let d = ray.dir;
    // kz: the dimension where the direction is largest; kx, ky follow, swapped to keep winding.
    let ad = d.abs();
    let kz = if ad.x >= ad.y && ad.x >= ad.z {
        0
    } else if ad.y >= ad.z {
        1
    } else {
        2
    };
    let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
    if d[kz] < 0.0 {
        std::mem::swap(&mut kx, &mut ky);
    }
    if d[kz] == 0.0 || !d[kz].is_finite() {
        return None;
    }
    let (sx, sy, sz) = (d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
    let [a, b, c] = p.map(|v| v - ray.origin);
    let shear = |v: Vec3| (v[kx] - sx * v[kz], v[ky] - sy * v[kz]);
    let ((ax, ay), (bx, by), (cx, cy)) = (shear(a), shear(b), shear(c));
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    if u == 0.0 || v == 0.0 || w == 0.0 {
        let (ax, ay, bx, by, cx, cy) = (
            ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
        );
        u = (cx * by - cy * bx) as f32;
        v = (ax * cy - ay * cx) as f32;
        w = (bx * ay - by * ax) as f32;
    }
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let t = (u * (sz * a[kz]) + v * (sz * b[kz]) + w * (sz * c[kz])) / det;
    (t > t_min && t < t_max).then_some(TriangleHit {
        t,
        bary: Vec2::new(v / det, w / det),
    })
}

/// Möller–Trumbore ray–triangle intersection (Möller & Trumbore 1997): fewer operations than
/// [`intersect_triangle`] but not watertight — a ray through a shared vertex or edge can miss
/// every triangle around it. Kept as the peer the watertight test is measured against.
#[inline]
pub fn intersect_triangle_mt(
    ray: &Ray,
    p: [Vec3; 3],
    t_min: f32,
    t_max: f32,
) -> Option<TriangleHit> {
    let e1 = p[1] - p[0];
    let e2 = p[2] - p[0];
    let pv = ray.dir.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let tv = ray.origin - p[0];
    let b1 = tv.dot(pv) * inv_det;
    if !(0.0..=1.0).contains(&b1) {
        return None;
    }
    let qv = tv.cross(e1);
    let b2 = ray.dir.dot(qv) * inv_det;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return None;
    }
    let t = e2.dot(qv) * inv_det;
    (t > t_min && t < t_max).then_some(TriangleHit {
        t,
        bary: Vec2::new(b1, b2),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_hit_returns_distance_and_barycentrics() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let ray = Ray::new(Vec3::new(0.25, 0.5, 2.0), -Vec3::Z);
        let hit = intersect_triangle(&ray, tri, 0.0, f32::INFINITY).unwrap();
        assert!((hit.t - 2.0).abs() < 1e-6);
        assert!((hit.bary - Vec2::new(0.25, 0.5)).length() < 1e-6);
        assert!(intersect_triangle(&ray, tri, 0.0, 1.5).is_none());
        let miss = Ray::new(Vec3::new(0.8, 0.8, 2.0), -Vec3::Z);
        assert!(intersect_triangle(&miss, tri, 0.0, f32::INFINITY).is_none());
        // Both windings, any axis.
        let flipped = [tri[0], tri[2], tri[1]];
        let h = intersect_triangle(&ray, flipped, 0.0, f32::INFINITY).unwrap();
        assert!((h.bary - Vec2::new(0.5, 0.25)).length() < 1e-6);
        let mt = intersect_triangle_mt(&ray, tri, 0.0, f32::INFINITY).unwrap();
        assert!((mt.t - hit.t).abs() < 1e-6 && (mt.bary - hit.bary).length() < 1e-6);
    }

    #[test]
    fn rays_through_shared_vertices_and_edges_always_hit() {
        // A fan of triangles around a vertex, and rays aimed exactly at the vertex and at
        // points on the shared edges: each must hit at least one triangle.
        let k = 7;
        let centre = Vec3::new(0.3, -0.2, 0.0);
        let rim: Vec<Vec3> = (0..k)
            .map(|i| {
                let a = i as f32 / k as f32 * std::f32::consts::TAU + 0.1;
                centre + Vec3::new(a.cos(), a.sin(), 0.0) * 0.7
            })
            .collect();
        let tris: Vec<[Vec3; 3]> = (0..k).map(|i| [centre, rim[i], rim[(i + 1) % k]]).collect();
        let origins = [
            Vec3::new(0.1, 0.3, 5.0),
            Vec3::new(-3.0, 1.0, 2.0),
            Vec3::new(0.7, -0.9, -4.0),
        ];
        for o in origins {
            let mut targets = vec![centre];
            for r in &rim {
                for s in [0.25f32, 0.5, 0.75] {
                    targets.push(centre + (*r - centre) * s);
                }
            }
            for t in targets {
                let ray = Ray::new(o, (t - o).normalize());
                let hits = tris
                    .iter()
                    .filter(|p| intersect_triangle(&ray, **p, 0.0, f32::INFINITY).is_some())
                    .count();
                assert!(hits >= 1, "ray from {o} to {t} slipped through");
            }
        }
    }

    #[test]
    fn slab_test_clips_to_the_box() {
        let b = Aabb::from_points([Vec3::ZERO, Vec3::ONE]);
        let r = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z);
        let (t0, t1) = b.intersect(&r, 10.0).unwrap();
        assert!((t0 - 1.0).abs() < 1e-6 && (t1 - 2.0).abs() < 1e-6);
        assert!(
            b.intersect(&Ray::new(Vec3::new(2.0, 0.5, -1.0), Vec3::Z), 10.0)
                .is_none()
        );
    }
}
