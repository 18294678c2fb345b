//! The software shader of paper 3 (§1, §4, §6): a CPU ray tracer that lights what a raster
//! pipeline cannot — hard shadows from the scene's light and mirror and glass bounces through
//! the whole scene — and produces relief impostors from it: an orthographic colour +
//! displacement image of one object, perpendicular to the direction of the eye (paper Fig. 2).
//! It also renders the true frame a warped impostor stands for, through the view camera.
//!
//! Invariants: generation is single-threaded and deterministic (it runs on the pipeline's
//! rendering thread, beside the warping loop); it reads only its own copy of the scene, so it
//! can run while the caller renders.

use super::{DepthEncoding, Displacements, ReliefError, ReliefFrame, ReliefImpostor};
use crate::camera::{Pinhole, Projection};
use crate::frame::{Frame, pixel_centre};
use crate::geom::Ray;
use crate::geom::optics::facing;
use crate::render::Tracer;
use crate::scene::{Lighting, RenderSettings, View};
use crate::trace::{Bvh, Exact, Hit, RayQuery};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::sync::Arc;

/// An object's own BVH and bounding sphere.
struct Object {
    bvh: Bvh,
    centre: DVec3,
    radius: f64,
}

/// The ray tracer that makes relief impostors of a scene's objects.
pub struct SoftwareShader {
    view: View,
    lighting: Lighting,
    settings: RenderSettings,
    scene: Bvh,
    objects: Vec<Object>,
}

impl SoftwareShader {
    /// A shader over the scene `view` (its camera is not used), lit by `lighting`; refused
    /// when its BVHs (one over the scene, one an object) would pass the memory budget.
    pub fn new(
        view: &View,
        lighting: &Lighting,
        settings: &RenderSettings,
    ) -> Result<Arc<Self>, crate::memory::OverBudget> {
        let objects = view
            .meshes
            .iter()
            .map(|m| {
                let centre = m.bounds().center().as_dvec3();
                // The farthest vertex from the box's centre, padded so that no surface touches
                // the base plane.
                let radius = m
                    .positions
                    .iter()
                    .map(|p| (p.as_dvec3() - centre).length())
                    .fold(0.0, f64::max)
                    * 1.001;
                Ok(Object {
                    bvh: Bvh::build(vec![m.clone()])?,
                    centre,
                    radius,
                })
            })
            .collect::<Result<_, crate::memory::OverBudget>>()?;
        Ok(Arc::new(Self {
            view: view.clone(),
            lighting: lighting.clone(),
            settings: *settings,
            scene: Bvh::build(view.meshes.clone())?,
            objects,
        }))
    }

    /// Objects in the scene.
    pub fn object_count(&self) -> usize {
        self.objects.len()
    }

    /// Bounding sphere `(centre, radius)` of object `object`.
    pub fn bounds(&self, object: usize) -> Result<(DVec3, f64), ReliefError> {
        let o = self.objects.get(object).ok_or(ReliefError::NoObject {
            object,
            count: self.objects.len(),
        })?;
        if !(o.radius > 0.0 && o.radius.is_finite()) {
            return Err(ReliefError::Empty { object });
        }
        Ok((o.centre, o.radius))
    }

    /// The frame a relief impostor of `object` made for `eye` has.
    pub fn frame(
        &self,
        object: usize,
        eye: DVec3,
        resolution: u32,
    ) -> Result<ReliefFrame, ReliefError> {
        let (c, r) = self.bounds(object)?;
        if (eye - c).length() <= r {
            return Err(ReliefError::EyeInside {
                object,
                eye: eye.as_vec3().to_array(),
            });
        }
        ReliefFrame::facing(c, r, eye, resolution)
    }

    /// A relief impostor of `object` facing `eye`, `resolution²` texels, ray traced row by row;
    /// `cancel` is asked between rows and stops the work (`Ok(None)`).
    pub fn impostor(
        &self,
        object: usize,
        eye: DVec3,
        resolution: u32,
        encoding: DepthEncoding,
        cancel: &dyn Fn() -> bool,
    ) -> Result<Option<ReliefImpostor>, ReliefError> {
        let frame = self.frame(object, eye, resolution)?;
        let n = resolution as usize;
        crate::memory::check(
            || format!("a {n} × {n} relief impostor"),
            (n * n * 24) as u64,
        )?;
        let bvh = &self.objects[object].bvh;
        // Rays start just in front of the base plane; a hit `t` along them is `top − d`.
        let top = frame.max_depth * 1e-4;
        let mut color = vec![[0u8; 4]; n * n];
        let mut heights = vec![0.0f64; n * n];
        for v in 0..n {
            if cancel() {
                return Ok(None);
            }
            for u in 0..n {
                let start = {
                    let c = pixel_centre(u as f64, v as f64);
                    frame.point(c.x, c.y, top)
                };
                let ray = Ray::new(start.as_vec3(), (-frame.f).as_vec3());
                let Some(hit) = bvh.closest_hit(&ray, (frame.max_depth * 1.0002) as f32) else {
                    continue;
                };
                let d = (top - hit.t as f64).clamp(-frame.max_depth, 0.0);
                let mut hit = hit;
                hit.object = object as u32;
                color[v * n + u] = super::encode(self.shade(&ray, &hit, 0).extend(1.0));
                heights[v * n + u] = d;
            }
        }
        let depth = match encoding {
            DepthEncoding::U8 => Displacements::U8(
                heights
                    .iter()
                    .map(|&d| (-d / frame.max_depth * 255.0).round().clamp(0.0, 255.0) as u8)
                    .collect(),
            ),
            DepthEncoding::F32 => Displacements::F32(heights.iter().map(|&d| d as f32).collect()),
        };
        Ok(Some(ReliefImpostor {
            frame,
            eye,
            color,
            depth,
        }))
    }

    /// The radiance arriving along `ray` through the whole scene.
    pub fn radiance(&self, ray: &Ray, depth: u32) -> Vec3 {
        self.with_tracer(|t| t.radiance(ray, depth))
    }

    /// Shades `hit` as trompe's Whitted tracer does over the exact scene: Lambert under the
    /// light with a shadow ray and the environment's irradiance, mirrors and glass followed
    /// through the scene up to the scene's depth limit.
    fn shade(&self, ray: &Ray, hit: &Hit, depth: u32) -> Vec3 {
        self.with_tracer(|t| t.shade(ray, hit, depth))
    }

    /// `f` of the Whitted tracer over this shader's copy of the scene, every ray answered
    /// exactly.
    fn with_tracer<R>(&self, f: impl FnOnce(&Tracer<'_, Bvh, Exact<'_, Bvh>>) -> R) -> R {
        let exact = Exact(&self.scene);
        f(&Tracer {
            view: &self.view,
            primary: &self.scene,
            secondary: &exact,
            lighting: &self.lighting,
            settings: &self.settings,
        })
    }

    /// The true frame through `camera`: every pixel ray traced by this shader, the objects in
    /// `only` (all when empty) shaded, the others' pixels left to the environment behind them.
    pub fn render(&self, camera: &Pinhole, only: &[usize]) -> Result<Frame, ReliefError> {
        let (w, h) = camera.resolution();
        let mut frame = Frame::new(w, h)?;
        frame
            .par_rows_mut()
            .for_each(|(y, (color, depth, normal, id))| {
                for x in 0..w as usize {
                    let ray = camera.ray(crate::frame::pixel_centre(x as f64, y as f64));
                    let hit = self
                        .scene
                        .closest_hit(&ray, f32::INFINITY)
                        .filter(|h| only.is_empty() || only.contains(&(h.object as usize)));
                    match hit {
                        None => color[x] = self.lighting.environment.radiance(ray.dir).extend(1.0),
                        Some(hit) => {
                            color[x] = self.shade(&ray, &hit, 0).extend(1.0);
                            depth[x] = hit.t;
                            normal[x] = facing(ray.dir, hit.normal, hit.geometric_normal).0;
                            id[x] = hit.object;
                        }
                    }
                }
            });
        Ok(frame)
    }

    /// The scene this shader lights (for the fallback rasterizer).
    pub fn view(&self) -> &View {
        &self.view
    }

    /// Its lighting.
    pub fn lighting(&self) -> &Lighting {
        &self.lighting
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::frame::envmap::EnvMap;
    use crate::scene::{Light, Surface};

    /// A sphere of radius 0.5 above a floor, lit from straight above: the floor under it is in shadow.
    pub(crate) fn sphere_on_floor() -> (View, Lighting, RenderSettings) {
        let floor = crate::geom::plane(1).transformed(&glam::Mat4::from_scale(Vec3::splat(8.0)));
        let ball = crate::geom::icosphere(3)
            .transformed(&glam::Mat4::from_translation(Vec3::new(0.0, 1.5, 0.0)));
        let grey = Surface::Diffuse(Some(crate::scene::DiffuseOverride {
            color: Vec3::splat(0.5),
            texture: None,
        }));
        let camera =
            Pinhole::look_at(Vec3::new(0.0, 2.0, 6.0), Vec3::Y, Vec3::Y, 40.0, 64, 48).unwrap();
        let view = View {
            lens: None,
            camera,
            meshes: vec![Arc::new(floor), Arc::new(ball)],
            surfaces: vec![grey.clone(), grey],
        };
        let lighting = Lighting {
            environment: EnvMap::constant(Vec3::splat(0.1)),
            light: Some(Light {
                direction: Vec3::Y,
                irradiance: Vec3::splat(std::f32::consts::PI),
            }),
        };
        let settings = RenderSettings {
            max_depth: 4,
            time: 0.0,
            ray_epsilon: 1e-4,
        };
        (view, lighting, settings)
    }

    #[test]
    fn the_floor_under_the_ball_is_in_shadow_and_the_rest_is_lit() {
        let (view, lighting, settings) = sphere_on_floor();
        let shader = SoftwareShader::new(&view, &lighting, &settings).unwrap();
        let down = |x: f32| Ray::new(Vec3::new(x, 5.0, 0.3), Vec3::NEG_Y);
        // Straight above the floor beside the ball: lit (0.5 · (0.1·π-free ambient + 1)).
        let lit = shader.radiance(&down(3.0), 0);
        // Under the ball the floor is reached only from below... trace upward from it instead:
        // a ray hitting the floor at x = 0.3 from the side, where the ball shadows it.
        let side = Ray::new(
            Vec3::new(0.3, 0.2, 5.0),
            Vec3::new(0.0, -0.2, -5.0).normalize(),
        );
        let shadowed = shader.radiance(&side, 0);
        let ambient = 0.5 * lighting.environment.irradiance(Vec3::Y);
        assert!(
            (lit - (ambient + Vec3::splat(0.5))).length() < 1e-4,
            "{lit}"
        );
        assert!((shadowed - ambient).length() < 1e-4, "{shadowed}");
    }

    #[test]
    fn an_impostor_holds_the_object_at_its_heights() {
        let (view, lighting, settings) = sphere_on_floor();
        let shader = SoftwareShader::new(&view, &lighting, &settings).unwrap();
        let eye = DVec3::new(0.0, 1.5, 6.0);
        let imp = shader
            .impostor(1, eye, 64, DepthEncoding::F32, &|| false)
            .unwrap()
            .unwrap();
        let fr = imp.frame;
        // Every covered texel's 3-D point lies on the sphere of radius 0.5 (facets aside).
        let mut covered = 0;
        for v in 0..64 {
            for u in 0..64 {
                let i = v * 64 + u;
                if imp.covered(i) {
                    covered += 1;
                    let p = fr.point(u as f64 + 0.5, v as f64 + 0.5, imp.displacement(i));
                    let r = (p - DVec3::new(0.0, 1.5, 0.0)).length();
                    assert!((r - 0.5).abs() < 0.01, "{r}");
                }
            }
        }
        // The sphere covers π/4 of its square.
        let share = covered as f64 / 4096.0;
        assert!(
            (share - std::f64::consts::FRAC_PI_4).abs() < 0.02,
            "{share}"
        );
        // Cancelled: no impostor.
        assert!(
            shader
                .impostor(1, eye, 64, DepthEncoding::U8, &|| true)
                .unwrap()
                .is_none()
        );
    }
}
