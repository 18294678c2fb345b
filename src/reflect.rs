//! Reflections through ray queries (paper 1 §1, Fig. 1): primary rays see the exact scene; the
//! rays reflected off a mirror are answered by any [`RayQuery`] — the exact BVH, an impostor, or
//! the environment alone — so the methods differ only in how they answer secondary rays.

use crate::camera::{Pinhole, Projection};
use crate::frame::envmap::EnvMap;
use crate::frame::{FrameError, Image, Rgba};
use crate::geom::Ray;
use crate::render::shading::reflect;
use crate::trace::{Bvh, Hit, RayQuery};
use glam::{DVec2, Vec3};
use rayon::prelude::*;

/// The mirror ray of `ray` at `hit`: reflected about the shading normal turned toward the
/// viewer ([`crate::render::shading::facing`]), starting `epsilon` off the surface.
pub fn mirror_ray(ray: &Ray, hit: &Hit, epsilon: f32) -> Ray {
    let (n, ng, _) = crate::render::shading::facing(ray.dir, hit.normal, hit.geometric_normal);
    Ray::new(hit.position + ng * epsilon, reflect(ray.dir, n).normalize())
}

/// What a mirror frame needs besides the secondary-ray answerer.
pub struct MirrorScene<'a> {
    /// The viewer.
    pub camera: &'a Pinhole,
    /// The exact scene, for primary rays.
    pub primary: &'a Bvh,
    /// Object id of the mirror in `primary`.
    pub mirror: u32,
    /// Radiance at infinity.
    pub environment: &'a EnvMap,
    /// Colour of a geometry hit that carries no radiance of its own.
    pub shade: &'a (dyn Fn(&Hit) -> Vec3 + Sync),
    /// Offset of reflected rays along the normal.
    pub epsilon: f32,
}

/// Renders the view; also returns the mask of pixels that show the mirror.
pub fn mirror_frame<Q: RayQuery>(
    scene: &MirrorScene,
    secondary: &Q,
) -> Result<(Image<Rgba>, Image<bool>), FrameError> {
    let (w, h) = scene.camera.resolution();
    let mut color = Image::new(w, h, Rgba::ZERO)?;
    let mut mask = Image::new(w, h, false)?;
    color
        .pixels_mut()
        .par_chunks_mut(w as usize)
        .zip(mask.pixels_mut().par_chunks_mut(w as usize))
        .enumerate()
        .for_each(|(y, (row, mrow))| {
            for x in 0..w as usize {
                let ray = scene.camera.ray(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
                let c = match scene.primary.closest_hit(&ray, f32::INFINITY) {
                    None => scene.environment.radiance(ray.dir),
                    Some(hit) if hit.object == scene.mirror => {
                        mrow[x] = true;
                        let r = mirror_ray(&ray, &hit, scene.epsilon);
                        match secondary.closest_hit(&r, f32::INFINITY) {
                            Some(h2) => h2.radiance.unwrap_or_else(|| (scene.shade)(&h2)),
                            None => scene.environment.radiance(r.dir),
                        }
                    }
                    Some(hit) => (scene.shade)(&hit),
                };
                row[x] = c.extend(1.0);
            }
        });
    Ok((color, mask))
}

/// Answers no ray: with it, reflections show only the environment.
pub struct Nothing;

impl RayQuery for Nothing {
    fn closest_hit(&self, _: &Ray, _: f32) -> Option<Hit> {
        None
    }
}
