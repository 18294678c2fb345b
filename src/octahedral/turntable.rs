//! A turntable of an atlas against the exact render: views all around the object — a full turn
//! whose elevation swings from the horizon to 60°, then straight down and straight up, where
//! octahedral bakers' frames are sparsest in screen terms — each rendered from the atlas with
//! and without parallax and scored by FLIP against the Whitted tracer's frame of the mesh, lit
//! as the atlas is (an atlas carries no occluders, so neither casts shadow rays).

use super::bake::OctahedralAtlas;
use crate::camera::Pinhole;
use crate::frame::{Frame, FrameError, metrics};
use crate::geom::Mesh;
use crate::geom::Ray;
use crate::render::{RenderError, Tracer, render_trace};
use crate::scene::{Lighting, RenderSettings, Surface, View};
use crate::trace::{Bvh, Exact, Hit, RayQuery};
use glam::{DVec3, Vec3};
use std::sync::Arc;

/// One view of a turntable.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TurntableView {
    /// Degrees about `+y`.
    pub azimuth: f64,
    /// Degrees above the horizon.
    pub elevation: f64,
    /// Mean FLIP against exact, with parallax.
    pub flip: f64,
    /// Mean FLIP against exact, without parallax (the frames' planes through the centre).
    pub flip_flat: f64,
}

/// `views` views round the object at 4 bounding radii, `size` pixels square, 30° field of view.
pub fn turntable(
    atlas: &OctahedralAtlas,
    mesh: &Mesh,
    surface: &Surface,
    lighting: &Lighting,
    views: u32,
    size: u32,
) -> Result<Vec<TurntableView>, RenderError> {
    let settings = RenderSettings {
        max_depth: 2,
        time: 0.0,
        ray_epsilon: atlas.radius * 1e-4,
    };
    let mut out = Vec::new();
    let mut directions: Vec<(f64, f64)> = (0..views)
        .map(|k| {
            let turn = f64::from(k) / f64::from(views.max(1));
            (
                360.0 * turn,
                30.0 - 30.0 * (std::f64::consts::TAU * 2.0 * turn).cos(),
            )
        })
        .collect();
    directions.extend([(0.0, 89.0), (0.0, -89.0)]);
    for (azimuth, elevation) in directions {
        let (a, e) = (azimuth.to_radians(), elevation.to_radians());
        let dir = DVec3::new(e.cos() * a.cos(), e.sin(), e.cos() * a.sin());
        let eye = atlas.centre + (dir * f64::from(atlas.radius) * 4.0).as_vec3();
        let up = if elevation.abs() > 80.0 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        let view = View {
            lens: None,
            camera: Pinhole::look_at(eye, atlas.centre, up, 30.0, size, size)?,
            meshes: vec![Arc::new(mesh.clone())],
            surfaces: vec![surface.clone()],
        };
        let exact = exact_unshadowed(&view, lighting, &settings)?;
        let score = |parallax: u32| -> Result<f64, FrameError> {
            metrics::flip(
                &exact.color,
                &atlas.render(&view.camera, lighting, parallax),
                None,
            )
        };
        out.push(TurntableView {
            azimuth,
            elevation,
            flip: score(super::render::PARALLAX_STEPS)?,
            flip_flat: score(0)?,
        });
    }
    Ok(out)
}

/// The Whitted tracer's frame of `view` lit as an atlas is: an atlas carries no occluders, so
/// the light is not shadowed here either — what a comparison scores is the bake, not the
/// lighting model.
pub fn exact_unshadowed(
    view: &View,
    lighting: &Lighting,
    settings: &RenderSettings,
) -> Result<Frame, RenderError> {
    let bvh = Bvh::build(view.meshes.clone())?;
    let unshadowed = Unshadowed(&bvh);
    let tracer = Tracer {
        view,
        primary: &unshadowed,
        secondary: &Exact(&bvh),
        lighting,
        settings,
    };
    render_trace(&tracer, &())
}

/// The BVH with shadow rays that never meet anything.
struct Unshadowed<'a>(&'a Bvh);

impl RayQuery for Unshadowed<'_> {
    fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.0.closest_hit(ray, t_max)
    }
    fn any_hit(&self, _: &Ray, _: f32) -> bool {
        false
    }
}
