//! The trace method: a Whitted ray tracer (Whitted 1980) over any [`RayQuery`] — perfect mirror
//! reflection, refraction with exact Fresnel weights, a recursion limit — lit like the raster
//! method. Rays that escape, or reach the depth limit, take the environment's radiance.

use super::shading::{albedo, facing, fresnel, lambert, reflect, refract};
use super::{Progress, RenderError};
use crate::frame::Frame;
use crate::geom::Ray;
use crate::scene::{Lighting, RenderSettings, Surface, View};
use crate::trace::{Hit, RayQuery};
use glam::{DVec2, Vec3};
use rayon::prelude::*;

/// A ray tracer over one view and one scene representation.
pub struct Tracer<'a, Q: RayQuery> {
    /// Camera and surfaces.
    pub view: &'a View,
    /// What answers the rays (the exact BVH for the ground truth).
    pub scene: &'a Q,
    /// Environment and sun.
    pub lighting: &'a Lighting,
    /// Depth limit and ray offset.
    pub settings: &'a RenderSettings,
    /// When set, answers instead of `scene` every ray a mirror or glass object sends out into
    /// the open — given that object's id — with a hit that carries its radiance (impostors of
    /// what the object reflects, paper 1 §6), or a hit without radiance on an object the
    /// tracer shades itself (one more bounce); a miss takes the environment's. Rays that go
    /// into a glass object still follow `scene`.
    pub secondary: Option<&'a SecondaryRays<'a>>,
}

/// Answers the rays a mirror or glass object (its id) sends out: see [`Tracer::secondary`].
pub type SecondaryRays<'a> = dyn Fn(u32, &Ray) -> Option<Hit> + Sync + 'a;

impl<Q: RayQuery> Tracer<'_, Q> {
    /// Radiance arriving along `ray` after at most `max_depth − depth` more bounces.
    pub fn radiance(&self, ray: &Ray, depth: u32) -> Vec3 {
        match self.scene.closest_hit(ray, f32::INFINITY) {
            None => self.lighting.environment.radiance(ray.dir),
            Some(hit) => self.shade(ray, &hit, depth),
        }
    }

    fn shade(&self, ray: &Ray, hit: &Hit, depth: u32) -> Vec3 {
        if let Some(l) = hit.radiance {
            return l;
        }
        let o = hit.object as usize;
        let (mesh, surface) = (&self.view.meshes[o], &self.view.surfaces[o]);
        let d = ray.dir;
        let (n, ng, front) = facing(d, hit.normal, hit.geometric_normal);
        let eps = self.settings.ray_epsilon;
        let env = &self.lighting.environment;
        let last = depth + 1 >= self.settings.max_depth;
        // `outward`: the ray leaves the object into the open (not into the glass).
        let follow = |origin: Vec3, dir: Vec3, outward: bool| {
            let ray = Ray::new(origin, dir);
            match self.secondary {
                Some(answer) if outward => match answer(hit.object, &ray) {
                    Some(Hit {
                        radiance: Some(l), ..
                    }) => l,
                    Some(h) if !last => self.shade(&ray, &h, depth + 1),
                    _ => env.radiance(dir),
                },
                _ if last => env.radiance(dir),
                _ => self.radiance(&ray, depth + 1),
            }
        };
        match surface {
            Surface::Diffuse(_) => lambert(
                albedo(mesh, surface, hit.triangle, hit.uv),
                n,
                self.lighting,
            ),
            Surface::Mirror { tint } => {
                *tint * follow(hit.position + ng * eps, reflect(d, n), true)
            }
            Surface::Glass { ior, tint } => {
                let eta = if front { 1.0 / ior } else { *ior };
                let kr = fresnel((-d.dot(n)).max(0.0), eta);
                let reflected = follow(hit.position + ng * eps, reflect(d, n), front);
                let transmitted = match refract(d, n, eta) {
                    Some(t) if kr < 1.0 => *tint * follow(hit.position - ng * eps, t, !front),
                    _ => Vec3::ZERO,
                };
                kr * reflected + (1.0 - kr) * transmitted
            }
        }
    }
}

/// Traces one primary ray per pixel centre.
pub fn render_trace<Q: RayQuery>(
    tracer: &Tracer<'_, Q>,
    progress: &dyn Progress,
) -> Result<Frame, RenderError> {
    let camera = &tracer.view.camera;
    let (w, h) = crate::camera::Projection::resolution(camera);
    let mut frame = Frame::new(w, h)?;
    frame
        .par_rows_mut()
        .for_each(|(y, (color, depth, normal, id))| {
            for x in 0..w as usize {
                let ray = camera.ray(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
                match tracer.scene.closest_hit(&ray, f32::INFINITY) {
                    None => color[x] = tracer.lighting.environment.radiance(ray.dir).extend(1.0),
                    Some(hit) => {
                        color[x] = tracer.shade(&ray, &hit, 0).extend(1.0);
                        depth[x] = hit.t;
                        normal[x] = facing(ray.dir, hit.normal, hit.geometric_normal).0;
                        id[x] = hit.object;
                    }
                }
            }
            progress.advance(1);
        });
    Ok(frame)
}
