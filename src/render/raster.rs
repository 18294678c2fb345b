//! The raster method: the tracer ([`super::Tracer`]) with its primary hits read from the
//! rasterizer's visibility buffer ([`primary_hits`]) and every ray a mirror or glass sends out
//! answered by the environment alone, at depth 1 — classic environment mapping, shaded by the
//! one shading path every method shares. The light's shadows are shadow rays through the
//! scene's BVH, built only when the scene has a light.

use super::trace::shade_pixels;
use super::{Progress, RenderError, Timings, Tracer};
use crate::frame::Frame;
use crate::geom::Ray;
use crate::raster::{StoreFragment, rasterize};
use crate::scene::{Lighting, RenderSettings, View};
use crate::trace::{Bvh, EnvironmentOnly, Hit, RayQuery};
use rayon::prelude::*;

/// What blocks the light in a raster frame: the scene's BVH when the scene has a light. Without
/// a light no shadow ray is cast, and no BVH is built.
struct Occluders(Option<Bvh>);

impl RayQuery for Occluders {
    fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.0.as_ref()?.closest_hit(ray, t_max)
    }

    fn any_hit(&self, ray: &Ray, t_max: f32) -> bool {
        self.0.as_ref().is_some_and(|b| b.any_hit(ray, t_max))
    }
}

/// Renders `view` by rasterization.
pub fn render_raster(
    view: &View,
    lighting: &Lighting,
    settings: &RenderSettings,
    progress: &dyn Progress,
    timings: &mut Timings,
) -> Result<Frame, RenderError> {
    let occluders = Occluders(match lighting.light {
        Some(_) => Some(timings.time("build BVH (shadows)", || Bvh::build(view.meshes.clone()))?),
        None => None,
    });
    let hits = timings.time("rasterize", || primary_hits(view))?;
    // Depth 1: what mirrors and glass send out is looked up in the environment.
    let settings = RenderSettings {
        max_depth: 1,
        ..*settings
    };
    let tracer = Tracer {
        view,
        primary: &occluders,
        secondary: &EnvironmentOnly,
        lighting,
        settings: &settings,
    };
    timings.time("shade", || shade_pixels(&tracer, progress, |i, _| hits[i]))
}

/// What the camera sees at every pixel centre, by rasterization rather than by tracing (the
/// primary pass of paper 1 §6, which rasterizes it): per pixel, row-major, the hit the
/// primary ray would report, or `None`. It differs from the traced hits only where the
/// rasterizer's coverage rule and the ray-triangle test disagree (silhouette pixels).
pub fn primary_hits(view: &View) -> Result<Vec<Option<crate::trace::Hit>>, RenderError> {
    let meshes = view.mesh_refs();
    let (target, _) = rasterize(&view.camera, &meshes, &StoreFragment, None)?;
    let (w, _) = target.gd.size();
    Ok(target
        .attributes
        .pixels()
        .par_iter()
        .enumerate()
        .map(|(i, f)| {
            let f = f.as_ref()?;
            let (x, y) = (i % w as usize, i / w as usize);
            let ray = view
                .camera
                .ray(crate::frame::pixel_centre(x as f64, y as f64));
            let mesh = &view.meshes[f.item.object as usize];
            let c = mesh.corners(f.item.triangle as usize);
            let b = f.bary;
            let position = c[0] * b.x + c[1] * b.y + c[2] * b.z;
            let t = (position - ray.origin).dot(ray.dir);
            let id = (f.item.object, f.item.triangle);
            Some(crate::trace::surface_point(mesh, id, t, position, b))
        })
        .collect())
}
