//! The one renderer every ray-answering method shares: a Whitted ray tracer (Whitted 1980) —
//! perfect mirror reflection, refraction with exact Fresnel weights, a recursion limit — lit
//! like the raster method. It is generic over what answers primary rays ([`RayQuery`]) and what
//! answers the rays mirrors and glass send out into the open ([`SecondaryQuery`]): the exact
//! BVH for both is the `trace` method; impostors for the second is paper 1 §6's method; the
//! environment alone is classic environment mapping. Rays that escape, or reach the depth limit,
//! take the environment's radiance.

use super::shading::{Side, albedo, lit, surface_radiance};
use super::{Progress, RenderError};
use crate::frame::Frame;
use crate::geom::Ray;
use crate::geom::optics::facing;
use crate::scene::{Lighting, RenderSettings, View};
use crate::trace::{Hit, RayQuery, SecondaryQuery};
use glam::{DVec2, Vec3};
use rayon::prelude::*;

/// A ray tracer over one view: primary rays (and rays that go into glass) answered by `P`,
/// rays mirrors and glass send out into the open answered by `S`.
pub struct Tracer<'a, P: RayQuery, S: SecondaryQuery + ?Sized> {
    /// Camera and surfaces.
    pub view: &'a View,
    /// What answers primary rays and rays that go into a glass object (the exact BVH for the
    /// ground truth).
    pub primary: &'a P,
    /// What answers every ray a mirror or glass object sends out into the open, given that
    /// object's id: a hit that carries its radiance (impostors of what the object reflects,
    /// paper 1 §6), or a hit without radiance on an object the tracer shades itself (one more
    /// bounce); a miss takes the environment's.
    pub secondary: &'a S,
    /// Environment and sun.
    pub lighting: &'a Lighting,
    /// Depth limit and ray offset.
    pub settings: &'a RenderSettings,
}

impl<P: RayQuery, S: SecondaryQuery + ?Sized> Tracer<'_, P, S> {
    /// Radiance arriving along `ray` after at most `max_depth − depth` more bounces.
    pub fn radiance(&self, ray: &Ray, depth: u32) -> Vec3 {
        match self.primary.closest_hit(ray, f32::INFINITY) {
            None => self.lighting.environment.radiance(ray.dir),
            Some(hit) => self.shade(ray, &hit, depth),
        }
    }

    /// Radiance leaving `hit` back along `ray`, at recursion depth `depth`.
    pub fn shade(&self, ray: &Ray, hit: &Hit, depth: u32) -> Vec3 {
        if let Some(l) = hit.radiance {
            return l;
        }
        let o = hit.object as usize;
        let (mesh, surface) = (&self.view.meshes[o], &self.view.surfaces[o]);
        let d = ray.dir;
        let (n, ng, front) = facing(d, hit.normal, hit.geometric_normal);
        let eps = self.settings.ray_epsilon;
        let last = depth + 1 >= self.settings.max_depth;
        surface_radiance(
            surface,
            d,
            (n, front),
            || albedo(mesh, surface, hit.triangle, hit.uv),
            self.lighting,
            // Hard shadows: the light is seen unless the scene blocks the shadow ray.
            |l| lit(self.primary, hit.position, ng, l, eps),
            |bounce| {
                let origin = match bounce.side {
                    Side::Near => hit.position + ng * eps,
                    Side::Far => hit.position - ng * eps,
                };
                let ray = Ray::new(origin, bounce.dir);
                if bounce.outward {
                    self.leaving(hit.object, &ray, depth)
                } else if last {
                    self.lighting.environment.radiance(bounce.dir)
                } else {
                    self.radiance(&ray, depth + 1)
                }
            },
        )
    }
}

impl<P: RayQuery, S: SecondaryQuery + ?Sized> Tracer<'_, P, S> {
    /// Radiance arriving along `ray`, which leaves object `object` into the open at recursion
    /// depth `depth`: what the secondary query answers (its radiance, or one more bounce on
    /// what it hit), the environment's when it answers nothing or the depth limit is reached
    /// — whatever answers, so every secondary query stops at the same depth.
    pub fn leaving(&self, object: u32, ray: &Ray, depth: u32) -> Vec3 {
        if depth + 1 >= self.settings.max_depth {
            return self.lighting.environment.radiance(ray.dir);
        }
        match self.secondary.secondary_hit(object, ray) {
            Some(Hit {
                radiance: Some(l), ..
            }) => l,
            Some(h) => self.shade(ray, &h, depth + 1),
            None => self.lighting.environment.radiance(ray.dir),
        }
    }
}

/// Traces one primary ray per pixel centre.
pub fn render_trace<P: RayQuery, S: SecondaryQuery + ?Sized>(
    tracer: &Tracer<'_, P, S>,
    progress: &dyn Progress,
) -> Result<Frame, RenderError> {
    // Each row's primary rays go to the primary query as one batch.
    let row_hits = |_: usize, rays: &[(Ray, f32)], hits: &mut Vec<Option<Hit>>| {
        tracer.primary.closest_hits(rays, hits)
    };
    shade_rows(tracer, progress, row_hits, |_, ray, hit| {
        tracer.shade(ray, hit, 0)
    })
}

/// Shades every pixel centre's primary hit, which `primary_hit(pixel index, ray)` gives — traced
/// ([`render_trace`]) or read from a G-buffer made beforehand.
pub fn shade_pixels<P: RayQuery, S: SecondaryQuery + ?Sized>(
    tracer: &Tracer<'_, P, S>,
    progress: &dyn Progress,
    primary_hit: impl Fn(usize, &Ray) -> Option<Hit> + Sync,
) -> Result<Frame, RenderError> {
    shade_pixels_with(tracer, progress, primary_hit, |_, ray, hit| {
        tracer.shade(ray, hit, 0)
    })
}

/// [`shade_pixels`] with the shading of each primary hit given (`shade(pixel index, ray, hit)`): a method
/// that answers some primary hits its own way (Wyman's refraction) and leaves the rest to
/// [`Tracer::shade`].
pub fn shade_pixels_with<P: RayQuery, S: SecondaryQuery + ?Sized>(
    tracer: &Tracer<'_, P, S>,
    progress: &dyn Progress,
    primary_hit: impl Fn(usize, &Ray) -> Option<Hit> + Sync,
    shade: impl Fn(usize, &Ray, &Hit) -> Vec3 + Sync,
) -> Result<Frame, RenderError> {
    let w = crate::camera::Projection::resolution(&tracer.view.camera).0 as usize;
    let row_hits = |y: usize, rays: &[(Ray, f32)], hits: &mut Vec<Option<Hit>>| {
        hits.clear();
        hits.extend((rays.iter().enumerate()).map(|(x, (ray, _))| primary_hit(y * w + x, ray)));
    };
    shade_rows(tracer, progress, row_hits, shade)
}

/// Shades every pixel centre, row by row in parallel: `row_hits(row, rays, hits)` answers a
/// row's primary rays at once (a batch of [`RayQuery::closest_hits`], or hits read from a
/// G-buffer), then `shade(pixel index, ray, hit)` shades each hit.
pub fn shade_rows<P: RayQuery, S: SecondaryQuery + ?Sized>(
    tracer: &Tracer<'_, P, S>,
    progress: &dyn Progress,
    row_hits: impl Fn(usize, &[(Ray, f32)], &mut Vec<Option<Hit>>) + Sync,
    shade: impl Fn(usize, &Ray, &Hit) -> Vec3 + Sync,
) -> Result<Frame, RenderError> {
    let camera = &tracer.view.camera;
    let (w, h) = crate::camera::Projection::resolution(camera);
    // A pixel looks along the pinhole's ray through where its lens sends it (the pinhole's
    // own pixel where there is no lens, or where undistortion does not converge, far outside
    // the lens's field).
    let lens = tracer.view.lens.as_deref();
    let through = |px: DVec2| lens.and_then(|l| l.undistorted_pixel_of(px)).unwrap_or(px);
    let mut frame = Frame::new(w, h)?;
    frame
        .par_rows_mut()
        .for_each(|(y, (color, depth, normal, id))| {
            let rays: Vec<(Ray, f32)> = (0..w as usize)
                .map(|x| {
                    let ray = camera.ray(through(crate::frame::pixel_centre(x as f64, y as f64)));
                    (ray, f32::INFINITY)
                })
                .collect();
            let mut hits = Vec::with_capacity(rays.len());
            row_hits(y, &rays, &mut hits);
            for (x, ((ray, _), hit)) in rays.iter().zip(&hits).enumerate() {
                match hit {
                    None => color[x] = tracer.lighting.environment.radiance(ray.dir).extend(1.0),
                    Some(hit) => {
                        color[x] = shade(y * w as usize + x, ray, hit).extend(1.0);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Pinhole;
    use crate::frame::envmap::EnvMap;
    use crate::scene::Surface;
    use crate::trace::{Bvh, Exact};
    use std::sync::Arc;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// Primary rays: the exact BVH, counted.
    struct CountedPrimary<'a>(&'a Bvh, AtomicU64);

    impl RayQuery for CountedPrimary<'_> {
        fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
            self.1.fetch_add(1, Ordering::Relaxed);
            self.0.closest_hit(ray, t_max)
        }
    }

    /// Secondary rays: a pure red image-based answer, counted, remembering who asked.
    struct RedSecondary(AtomicU64, AtomicU64);

    impl SecondaryQuery for RedSecondary {
        fn secondary_hit(&self, reflector: u32, ray: &Ray) -> Option<Hit> {
            self.0.fetch_add(1, Ordering::Relaxed);
            self.1
                .fetch_max(u64::from(reflector) + 1, Ordering::Relaxed);
            Some(Hit {
                t: 1.0,
                position: ray.at(1.0),
                normal: -ray.dir,
                geometric_normal: -ray.dir,
                uv: glam::Vec2::ZERO,
                bary: glam::Vec2::ZERO,
                object: 7,
                triangle: 0,
                radiance: Some(Vec3::X),
            })
        }
    }

    #[test]
    fn primary_and_secondary_rays_both_go_through_the_traits() {
        // A 4-unit mirror floor under a camera looking straight down at it: every pixel sees it.
        let floor =
            Arc::new(crate::geom::plane(1).transformed(&glam::Mat4::from_scale(Vec3::splat(4.0))));
        let (w, h) = (16u32, 12u32);
        let camera = Pinhole::look_at(Vec3::Y, Vec3::ZERO, Vec3::Z, 60.0, w, h).unwrap();
        let view = View {
            lens: None,
            camera,
            meshes: vec![floor],
            surfaces: vec![Surface::Mirror {
                tint: Vec3::splat(0.5),
            }],
        };
        let lighting = Lighting {
            environment: EnvMap::constant(Vec3::new(0.0, 0.0, 1.0)),
            light: None,
        };
        let settings = RenderSettings {
            max_depth: 4,
            time: 0.0,
            ray_epsilon: 1e-4,
        };
        let bvh = Bvh::build(view.meshes.clone()).unwrap();
        let primary = CountedPrimary(&bvh, AtomicU64::new(0));
        let secondary = RedSecondary(AtomicU64::new(0), AtomicU64::new(0));
        let tracer = Tracer {
            view: &view,
            primary: &primary,
            secondary: &secondary,
            lighting: &lighting,
            settings: &settings,
        };
        let frame = render_trace(&tracer, &()).unwrap();
        let pixels = u64::from(w * h);
        assert_eq!(primary.1.load(Ordering::Relaxed), pixels);
        assert_eq!(secondary.0.load(Ordering::Relaxed), pixels);
        // The mirror (object 0) asked, and its tint scales what the secondary query answered.
        assert_eq!(secondary.1.load(Ordering::Relaxed), 1);
        for c in frame.color.pixels() {
            assert!(
                (c.truncate() - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-6,
                "{c}"
            );
        }
        // Answered exactly instead, the floor reflects the blue sky.
        let exact = Tracer {
            view: &view,
            primary: &bvh,
            secondary: &Exact(&bvh),
            lighting: &lighting,
            settings: &settings,
        };
        let sky = render_trace(&exact, &()).unwrap();
        for c in sky.color.pixels() {
            assert!(
                (c.truncate() - Vec3::new(0.0, 0.0, 0.5)).length() < 1e-6,
                "{c}"
            );
        }
    }
}
