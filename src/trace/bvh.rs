//! The exact BVH over triangle meshes, built and traversed by `obvhs` (PLOC-built, 8-wide
//! compressed CWBVH with SIMD node tests), with trompe's own triangle test and hit record.
//!
//! Invariant: a build is checked against the memory budget before anything is allocated
//! ([`BUILD_BYTES_PER_TRIANGLE`] with what the process already holds), and the built hierarchy
//! holds its resident bytes in the account until it is dropped.

use super::{Hit, RayQuery};
use crate::geom::{Mesh, Ray, TriangleHit, intersect_triangle};
use crate::memory::{Held, OverBudget};
use glam::{Vec2, Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use std::sync::Arc;

/// Peak bytes a triangle costs while its hierarchy is built: the builder's input (48), its
/// working arrays and the result. Measured at 267–275 for 0.08–5.2 M triangles (peak resident
/// size around `Bvh::build`, one and two threads), rounded up.
pub const BUILD_BYTES_PER_TRIANGLE: u64 = 288;

/// Bytes a triangle costs in the built hierarchy: its corners (36), its source (8), its leaf
/// index (4) and its share of the wide nodes (80 bytes a node, about one node per ten
/// triangles), rounded up.
pub const RESIDENT_BYTES_PER_TRIANGLE: u64 = 64;

/// A bounding-volume hierarchy over the triangles of several meshes (object id = index).
pub struct Bvh {
    bvh: CwBvh,
    /// Triangle corners in BVH leaf order.
    corners: Vec<[Vec3; 3]>,
    /// `(object, triangle)` of each leaf-ordered triangle.
    source: Vec<(u32, u32)>,
    meshes: Vec<Arc<Mesh>>,
    /// The account's share for the arrays above.
    _held: Held,
}

impl Bvh {
    /// Builds the hierarchy (parallel where `obvhs` is), refusing before any allocation when
    /// the build and what the process holds would pass the memory budget
    /// ([`crate::memory::check`]); a refusal names the triangle count.
    pub fn build(meshes: Vec<Arc<Mesh>>) -> Result<Bvh, OverBudget> {
        let count: u64 = meshes.iter().map(|m| m.triangles.len() as u64).sum();
        let what = || match meshes.len() {
            1 => format!("a BVH of {count} triangles"),
            n => format!("a BVH of {count} triangles over {n} objects"),
        };
        crate::memory::check(what, crate::memory::times(count, BUILD_BYTES_PER_TRIANGLE))?;
        // Within the budget, an allocation that still fails (the machine's memory taken by
        // other processes) is reported as the same refusal rather than aborting.
        let refused = || OverBudget {
            what: what(),
            needed: crate::memory::times(count, BUILD_BYTES_PER_TRIANGLE),
            limit: crate::memory::limit(),
        };
        let capacity = usize::try_from(count).map_err(|_| refused())?;
        let mut tris = Vec::new();
        let mut source = Vec::new();
        tris.try_reserve_exact(capacity).map_err(|_| refused())?;
        source.try_reserve_exact(capacity).map_err(|_| refused())?;
        for (o, m) in meshes.iter().enumerate() {
            for t in 0..m.triangles.len() {
                let [a, b, c] = m.corners(t);
                tris.push(obvhs::triangle::Triangle {
                    v0: Vec3A::from(a),
                    v1: Vec3A::from(b),
                    v2: Vec3A::from(c),
                });
                source.push((o as u32, t as u32));
            }
        }
        if tris.is_empty() {
            return Ok(Bvh {
                bvh: CwBvh::default(),
                corners: Vec::new(),
                source: Vec::new(),
                meshes,
                _held: Held::new(0),
            });
        }
        let mut build_time = std::time::Duration::default();
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &tris,
            BvhBuildParams::medium_build(),
            &mut build_time,
        );
        let mut corners = Vec::new();
        let mut leaf_source = Vec::new();
        corners
            .try_reserve_exact(bvh.primitive_indices.len())
            .map_err(|_| refused())?;
        leaf_source
            .try_reserve_exact(bvh.primitive_indices.len())
            .map_err(|_| refused())?;
        for &i in &bvh.primitive_indices {
            let t = &tris[i as usize];
            corners.push([Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2)]);
            leaf_source.push(source[i as usize]);
        }
        Ok(Bvh {
            bvh,
            corners,
            source: leaf_source,
            meshes,
            _held: Held::new(crate::memory::times(count, RESIDENT_BYTES_PER_TRIANGLE)),
        })
    }

    /// The meshes, by object id.
    pub fn meshes(&self) -> &[Arc<Mesh>] {
        &self.meshes
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.corners.len()
    }

    /// The hierarchy's nodes, root first: obvhs's compressed wide nodes (80 bytes each, `Pod`),
    /// for walkers outside this crate (the GPU tracer uploads them as they are).
    pub fn wide_nodes(&self) -> &[obvhs::cwbvh::node::CwBvhNode] {
        &self.bvh.nodes
    }

    /// The triangles' corners in the order the nodes' leaves index them.
    pub fn leaf_corners(&self) -> &[[Vec3; 3]] {
        &self.corners
    }

    /// `(object, triangle)` of each leaf-ordered triangle.
    pub fn leaf_sources(&self) -> &[(u32, u32)] {
        &self.source
    }

    /// The hit of `ray` on leaf-ordered triangle `leaf` at distance `t` with barycentrics
    /// `(b1, b2)` of corners 1 and 2: the same surface point a query here would have made, for
    /// a hit found elsewhere (on the GPU). `None` when `leaf` is not a triangle of this BVH.
    pub fn hit_on_leaf(&self, leaf: u32, ray: &Ray, t: f32, bary: Vec2) -> Option<Hit> {
        let &(o, tri) = self.source.get(leaf as usize)?;
        Some(surface_hit(
            &self.meshes[o as usize],
            o,
            tri,
            ray,
            TriangleHit { t, bary },
        ))
    }

    fn obvhs_ray(ray: &Ray, t_max: f32) -> obvhs::ray::Ray {
        // `+ 0.0` turns −0.0 components into +0.0: obvhs 0.4 picks the traversal octant with
        // `d < 0.0` (so −0.0 counts as positive) but inverts −0.0 to −1/ε, and the two disagree:
        // a ray along −Z built as `-Vec3::Z` skipped every node. (Regression test:
        // `trace::tests::environment_answers_what_geometry_does_not`.)
        let dir = Vec3A::from(ray.dir) + Vec3A::ZERO;
        obvhs::ray::Ray::new(Vec3A::from(ray.origin), dir, 0.0, t_max)
    }
}

impl RayQuery for Bvh {
    fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if self.corners.is_empty() {
            return None;
        }
        let mut best: Option<(usize, TriangleHit)> = None;
        let mut rec = obvhs::ray::RayHit::none();
        self.bvh
            .ray_traverse(
                Self::obvhs_ray(ray, t_max),
                &mut rec,
                |r, id| match intersect_triangle(ray, self.corners[id], 0.0, r.tmax) {
                    Some(h) => {
                        best = Some((id, h));
                        h.t
                    }
                    None => f32::INFINITY,
                },
            );
        best.map(|(id, h)| {
            let (o, t) = self.source[id];
            surface_hit(&self.meshes[o as usize], o, t, ray, h)
        })
    }

    fn any_hit(&self, ray: &Ray, t_max: f32) -> bool {
        if self.corners.is_empty() {
            return false;
        }
        !self
            .bvh
            .ray_traverse_miss(Self::obvhs_ray(ray, t_max), |r, id| {
                intersect_triangle(ray, self.corners[id], 0.0, r.tmax)
                    .map_or(f32::INFINITY, |h| h.t)
            })
    }
}

/// The hit a ray found on `triangle` of `object` ([`surface_point`] at the ray's point).
pub(crate) fn surface_hit(
    mesh: &Mesh,
    object: u32,
    triangle: u32,
    ray: &Ray,
    h: TriangleHit,
) -> Hit {
    let (b1, b2) = (h.bary.x, h.bary.y);
    let bary = glam::Vec3::new(1.0 - b1 - b2, b1, b2);
    surface_point(mesh, (object, triangle), h.t, ray.at(h.t), bary)
}

/// The hit on `triangle` of `object` at barycentrics `bary` (of vertices 0, 1 and 2), at
/// distance `t` and `position` along the ray that found it (traced, or rasterized: paper 1
/// §6's primary pass): the shading normal interpolated, or the face normal where the vertex
/// normals cancel, and the texture coordinates interpolated. Every primary and secondary hit
/// is made here, so every way of finding a surface shades it the same.
pub(crate) fn surface_point(
    mesh: &Mesh,
    (object, triangle): (u32, u32),
    t: f32,
    position: Vec3,
    bary: glam::Vec3,
) -> Hit {
    let [i0, i1, i2] = mesh.triangles[triangle as usize].map(|i| i as usize);
    let (b0, b1, b2) = (bary.x, bary.y, bary.z);
    let n = mesh.normals[i0] * b0 + mesh.normals[i1] * b1 + mesh.normals[i2] * b2;
    let geometric_normal = mesh.face_normal(triangle as usize);
    let uv = mesh
        .uvs
        .as_ref()
        .map_or(Vec2::ZERO, |uv| uv[i0] * b0 + uv[i1] * b1 + uv[i2] * b2);
    Hit {
        t,
        position,
        normal: n.try_normalize().unwrap_or(geometric_normal),
        geometric_normal,
        uv,
        bary: Vec2::new(b1, b2),
        object,
        triangle,
        radiance: None,
    }
}

/// Tests every triangle: the oracle the BVH is checked against, and the peer it is timed with.
pub struct BruteForce {
    meshes: Vec<Arc<Mesh>>,
}

impl BruteForce {
    /// Wraps meshes (object id = index).
    pub fn new(meshes: Vec<Arc<Mesh>>) -> Self {
        Self { meshes }
    }
}

impl RayQuery for BruteForce {
    fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let mut best: Option<(u32, u32, TriangleHit)> = None;
        let mut limit = t_max;
        for (o, m) in self.meshes.iter().enumerate() {
            for t in 0..m.triangles.len() {
                if let Some(h) = intersect_triangle(ray, m.corners(t), 0.0, limit) {
                    limit = h.t;
                    best = Some((o as u32, t as u32, h));
                }
            }
        }
        best.map(|(o, t, h)| surface_hit(&self.meshes[o as usize], o, t, ray, h))
    }
}
