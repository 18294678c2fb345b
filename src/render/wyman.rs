//! Wyman's image-space refraction ("An Approximate Image-Space Approach for Interactive
//! Refraction", SIGGRAPH 2005; paper 1 §2.3 uses it for refractors in front of impostors;
//! docs/conventions.md §1.5): what the eye sees through a glass object after two refractions,
//! with the second interface found in images rather than by tracing inside the object.
//!
//! Pass 1 draws the back faces of the glass objects (those facing away from the eye) through the
//! eye's camera: per pixel, the nearest back face's distance and outward normal. Per vertex, `d_N`
//! is the distance along the inward normal to the opposite surface (one ray each). At a front
//! hit `P₁` (normal `N₁`, eye direction `V`): `T₁ = refract(V, N₁, 1/η)`, `d_V` the distance from
//! `P₁` to the back face along `V` at this pixel, `r = θt/θi` (`1/η` as `θi → 0`),
//! `d = r·d_V + (1 − r)·d_N`, `P₂ = P₁ + d·T₁`; `N₂` is the back-face normal at `P₂`'s pixel and
//! the ray leaves along `T₂ = refract(T₁, −N₂, η)`, or `reflect(T₁, −N₂)` under total internal
//! reflection. The leaving ray is answered like any ray a glass object sends out (the exact
//! scene, impostors or the environment).
//!
//! Invariants: only the eye's first refraction into a glass object is approximated — the
//! reflection at the front face and everything after the leaving ray are the tracer's; a pixel
//! whose back face is missing (`P₂` off the object's image) leaves along `T₁` from `P₂`; along a
//! sphere's centre line the exit is exact.

use super::RenderError;
use super::trace::{Tracer, shade_pixels_with};
use crate::camera::{Pinhole, Projection};
use crate::frame::Frame;
use crate::geom::optics::{facing, fresnel, reflect, refract};
use crate::geom::{Mesh, Ray};
use crate::progress::Progress;
use crate::raster::{StoreFragment, rasterize};
use crate::scene::{Surface, View};
use crate::trace::{Bvh, Hit, RayQuery, SecondaryQuery};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::Arc;

/// Pass 1 and the per-vertex distances: what Wyman's second pass reads.
pub struct BackFaces {
    camera: Pinhole,
    width: u32,
    /// Per pixel: the glass object, the distance from the eye along the pixel's ray and the
    /// outward unit normal of its nearest back face.
    pixels: Vec<Option<(u32, f32, Vec3)>>,
    /// Per object (empty for non-glass objects): `d_N` at each vertex.
    d_n: Vec<Vec<f32>>,
}

impl BackFaces {
    /// Draws the back faces of `view`'s glass objects through its camera and casts the
    /// per-vertex rays.
    pub fn build(view: &View) -> Result<BackFaces, RenderError> {
        let camera = view.camera.clone();
        let eye = camera.position().as_vec3();
        let glass: Vec<usize> = (0..view.surfaces.len())
            .filter(|&o| matches!(view.surfaces[o], Surface::Glass { .. }))
            .collect();
        // Back-facing triangles only (front faces culled), one mesh a glass object.
        let backs: Vec<Mesh> = glass
            .iter()
            .map(|&o| {
                let m = &view.meshes[o];
                let mut b = (**m).clone();
                let (tris, mats): (Vec<[u32; 3]>, Vec<u32>) = (0..m.triangle_count())
                    .filter(|&t| {
                        let c = m.corners(t);
                        m.face_normal(t).dot((c[0] + c[1] + c[2]) / 3.0 - eye) > 0.0
                    })
                    .map(|t| (m.triangles[t], m.face_material.get(t).copied().unwrap_or(0)))
                    .unzip();
                b.triangles = tris;
                b.face_material = mats;
                b
            })
            .collect();
        let refs: Vec<&Mesh> = backs.iter().collect();
        let (target, _) = rasterize(&camera, &refs, &StoreFragment, None)?;
        let (width, _) = camera.resolution();
        let pixels = target
            .attributes
            .pixels()
            .par_iter()
            .enumerate()
            .map(|(i, f)| {
                let f = (*f)?;
                let m = &backs[f.item.object as usize];
                let [a, b, c] = m.triangles[f.item.triangle as usize].map(|k| k as usize);
                let n =
                    (m.normals[a] * f.bary.x + m.normals[b] * f.bary.y + m.normals[c] * f.bary.z)
                        .normalize_or(m.face_normal(f.item.triangle as usize));
                let uv = crate::frame::pixel_centre(
                    (i % width as usize) as f64,
                    (i / width as usize) as f64,
                );
                let t = camera.distance(uv, f64::from(f.gd)) as f32;
                Some((glass[f.item.object as usize] as u32, t, n))
            })
            .collect();
        let d_n = vertex_distances(view)?;
        Ok(BackFaces {
            camera,
            width,
            pixels,
            d_n,
        })
    }

    /// The back face seen at pixel index `i` — its distance from the eye along the pixel's ray
    /// and its outward normal — if it belongs to `object`.
    pub fn at(&self, i: usize, object: u32) -> Option<(f32, Vec3)> {
        match self.pixels.get(i).copied().flatten() {
            Some((o, t, n)) if o == object => Some((t, n)),
            _ => None,
        }
    }

    /// The back face of `object` at the pixel `p` projects to.
    pub fn at_point(&self, p: Vec3, object: u32) -> Option<(f32, Vec3)> {
        let ip = self.camera.project(p.as_dvec3())?;
        let (w, h) = self.camera.resolution();
        let (x, y) = (ip.uv.x.floor(), ip.uv.y.floor());
        if x < 0.0 || y < 0.0 || x >= f64::from(w) || y >= f64::from(h) {
            return None;
        }
        self.at(y as usize * self.width as usize + x as usize, object)
    }

    /// `d_N` of `object` at a hit on triangle `triangle` with barycentrics `bary` (corners 1, 2).
    pub fn d_n_at(&self, mesh: &Mesh, object: u32, triangle: u32, bary: glam::Vec2) -> f32 {
        let Some(d) = self.d_n.get(object as usize).filter(|d| !d.is_empty()) else {
            return 0.0;
        };
        let [a, b, c] = mesh.triangles[triangle as usize].map(|k| d[k as usize]);
        a * (1.0 - bary.x - bary.y) + b * bary.x + c * bary.y
    }
}

/// Per object of `view`, `d_N` at each vertex of a glass object (empty for other objects): the
/// per-vertex distances Wyman's second pass interpolates, one ray each.
///
/// # Errors
/// A glass object whose BVH exceeds the memory budget.
pub fn vertex_distances(view: &View) -> Result<Vec<Vec<f32>>, crate::memory::OverBudget> {
    let mut d_n = vec![Vec::new(); view.meshes.len()];
    for (o, surface) in view.surfaces.iter().enumerate() {
        if let (Surface::Glass { .. }, Some(mesh)) = (surface, view.meshes.get(o)) {
            d_n[o] = opposite_distances(mesh)?;
        }
    }
    Ok(d_n)
}

/// Per vertex of a closed mesh, the distance along its inward normal to the mesh's opposite
/// surface (0 where the ray leaves an open mesh).
fn opposite_distances(mesh: &Arc<Mesh>) -> Result<Vec<f32>, crate::memory::OverBudget> {
    let bvh = Bvh::build(vec![mesh.clone()])?;
    let eps = mesh.bounds().radius() * 1e-4;
    Ok(mesh
        .positions
        .par_iter()
        .zip(&mesh.normals)
        .map(|(&p, &n)| {
            let ray = Ray::new(p - n * eps, -n);
            bvh.closest_hit(&ray, f32::INFINITY)
                .map_or(0.0, |h| h.t + eps)
        })
        .collect())
}

/// Wyman's leaving ray for an eye ray of direction `v` entering glass of index `ior` at `p1`
/// (unit normal `n1` facing the eye), with `d_v` the distance to the back face along `v` and `d_n`
/// the interpolated per-vertex distance; `back(p2)` is the back face's outward normal at `p2`'s
/// pixel. Returns the exit point and the leaving direction.
pub fn exit_ray(
    p1: Vec3,
    n1: Vec3,
    v: Vec3,
    ior: f32,
    d_v: f32,
    d_n: f32,
    back: impl Fn(Vec3) -> Option<Vec3>,
) -> Option<(Vec3, Vec3)> {
    let t1 = refract(v, n1, 1.0 / ior)?;
    let theta_i = (-v.dot(n1)).clamp(-1.0, 1.0).acos();
    let theta_t = (-t1.dot(n1)).clamp(-1.0, 1.0).acos();
    let r = if theta_i > 1e-4 {
        theta_t / theta_i
    } else {
        1.0 / ior
    };
    let d = r * d_v + (1.0 - r) * d_n;
    let p2 = p1 + t1 * d;
    let Some(n2) = back(p2) else {
        return Some((p2, t1));
    };
    let t2 = refract(t1, -n2, ior).unwrap_or_else(|| reflect(t1, -n2));
    Some((p2, t2))
}

/// Renders with the tracer, the eye's refractions into glass by Wyman's approximation.
pub fn render<P: RayQuery, S: SecondaryQuery + ?Sized>(
    tracer: &Tracer<'_, P, S>,
    backs: &BackFaces,
    progress: &dyn Progress,
    primary_hit: impl Fn(usize, &Ray) -> Option<crate::trace::Hit> + Sync,
) -> Result<Frame, RenderError> {
    let view = tracer.view;
    let eps = tracer.settings.ray_epsilon;
    shade_pixels_with(tracer, progress, primary_hit, |pixel, ray, hit| {
        let Surface::Glass { ior, tint } = view.surfaces[hit.object as usize] else {
            return tracer.shade(ray, hit, 0);
        };
        let v = ray.dir;
        let (n1, ng, front) = facing(v, hit.normal, hit.geometric_normal);
        if !front {
            return tracer.shade(ray, hit, 0);
        }
        let mesh = &view.meshes[hit.object as usize];
        let d_v = backs
            .at(pixel, hit.object)
            .map_or(0.0, |(t, _)| (t - hit.t).max(0.0));
        let d_n = backs.d_n_at(mesh, hit.object, hit.triangle, hit.bary);
        let kr = fresnel((-v.dot(n1)).max(0.0), 1.0 / ior);
        let reflected = tracer.leaving(
            hit.object,
            &Ray::new(hit.position + ng * eps, reflect(v, n1)),
            0,
        );
        let transmitted = exit_ray(hit.position, n1, v, ior, d_v, d_n, |p| {
            backs.at_point(p, hit.object).map(|(_, n)| n)
        })
        .map_or(Vec3::ZERO, |(p2, t2)| {
            tint * tint * tracer.leaving(hit.object, &Ray::new(p2 + t2 * eps, t2), 0)
        });
        kr * reflected + (1.0 - kr) * transmitted
    })
}

/// The exact leaving ray for comparison: the eye ray refracted at `hit`, traced inside the
/// object through `inside` (a BVH of the object alone), refracted out (or reflected under total
/// internal reflection, once).
pub fn exact_exit(inside: &Bvh, hit: &Hit, v: Vec3, ior: f32, eps: f32) -> Option<(Vec3, Vec3)> {
    let (n1, ng, _) = facing(v, hit.normal, hit.geometric_normal);
    let t1 = refract(v, n1, 1.0 / ior)?;
    let h2 = inside.closest_hit(&Ray::new(hit.position - ng * eps, t1), f32::INFINITY)?;
    let (n2, _, _) = facing(t1, h2.normal, h2.geometric_normal);
    let t2 = refract(t1, n2, ior).unwrap_or_else(|| reflect(t1, n2));
    Some((h2.position, t2))
}
