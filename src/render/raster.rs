//! The raster method: rasterize a visibility buffer through the view camera, then shade each
//! pixel from its fragment (deferred, so each pixel is shaded once); the light's shadows are
//! shadow rays through the scene's BVH, built only when the scene has a light.

use super::shading::{Shadows, albedo, lambert};
use super::{Progress, RenderError, Timings};
use crate::frame::Frame;
use crate::geom::optics::{facing, fresnel, reflect, refract};
use crate::raster::{Fragment, StoreFragment, rasterize};
use crate::scene::{Lighting, RenderSettings, Surface, View};
use crate::trace::Bvh;
use glam::{DVec2, Vec2, Vec3};
use rayon::prelude::*;

/// Renders `view` by rasterization.
pub fn render_raster(
    view: &View,
    lighting: &Lighting,
    settings: &RenderSettings,
    progress: &dyn Progress,
    timings: &mut Timings,
) -> Result<Frame, RenderError> {
    let meshes = view.mesh_refs();
    let occluders = lighting
        .light
        .as_ref()
        .map(|_| timings.time("build BVH (shadows)", || Bvh::build(view.meshes.clone())));
    let shadows = occluders.as_ref().map(|b| Shadows {
        occluders: b,
        epsilon: settings.ray_epsilon,
    });
    let (target, _stats) = timings.time("rasterize", || {
        rasterize(&view.camera, &meshes, &StoreFragment, None)
    })?;
    let (w, h) = target.gd.size();
    let mut frame = Frame::new(w, h)?;
    let fragments = target.attributes.pixels();
    timings.time("shade", || {
        frame
            .par_rows_mut()
            .for_each(|(y, (color, depth, normal, id))| {
                for x in 0..w as usize {
                    let uv = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                    let ray = view.camera.ray(uv);
                    match fragments[y * w as usize + x] {
                        None => color[x] = lighting.environment.radiance(ray.dir).extend(1.0),
                        Some(f) => {
                            let s = shade_fragment(view, lighting, shadows, &f, ray.dir);
                            color[x] = s.color.extend(1.0);
                            depth[x] = view.camera.distance(uv, f.gd as f64) as f32;
                            normal[x] = s.normal;
                            id[x] = f.item.object;
                        }
                    }
                }
                progress.advance(1);
            });
    });
    Ok(frame)
}

struct Shaded {
    color: Vec3,
    normal: Vec3,
}

fn shade_fragment(
    view: &View,
    lighting: &Lighting,
    shadows: Option<Shadows<'_>>,
    f: &Fragment,
    d: Vec3,
) -> Shaded {
    let mesh = &view.meshes[f.item.object as usize];
    let surface = &view.surfaces[f.item.object as usize];
    let tri = f.item.triangle as usize;
    let [i0, i1, i2] = mesh.triangles[tri].map(|i| i as usize);
    let b = f.bary;
    let n = (mesh.normals[i0] * b.x + mesh.normals[i1] * b.y + mesh.normals[i2] * b.z)
        .normalize_or_zero();
    let uv = mesh
        .uvs
        .as_ref()
        .map_or(Vec2::ZERO, |uv| uv[i0] * b.x + uv[i1] * b.y + uv[i2] * b.z);
    let (n, ng, front) = facing(d, n, mesh.face_normal(tri));
    let env = &lighting.environment;
    let color = match surface {
        Surface::Diffuse(_) => {
            let c = mesh.corners(tri);
            let p = c[0] * b.x + c[1] * b.y + c[2] * b.z;
            lambert(
                albedo(mesh, surface, f.item.triangle, uv),
                n,
                lighting,
                |l| shadows.is_none_or(|s| s.lit(p, ng, l)),
            )
        }
        Surface::Mirror { tint } => *tint * env.radiance(reflect(d, n)),
        Surface::Glass { ior, tint } => {
            let eta = if front { 1.0 / ior } else { *ior };
            let cos_i = (-d.dot(n)).max(0.0);
            let kr = fresnel(cos_i, eta);
            let reflected = env.radiance(reflect(d, n));
            let transmitted = refract(d, n, eta).map_or(Vec3::ZERO, |t| *tint * env.radiance(t));
            kr * reflected + (1.0 - kr) * transmitted
        }
    };
    Shaded { color, normal: n }
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
            let ray = view.camera.ray(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
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
