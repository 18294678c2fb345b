//! A scene drawn the way an engine draws objects far enough away (beyond the papers): every
//! object replaced by its octahedral atlas, baked on first use, each pixel's ray looked up in
//! every atlas it passes through ([`OctahedralAtlas::blend`]: the three frames around the
//! direction toward the eye, parallax-corrected) and the surfaces found composited front to back
//! by their coverage. Each surface is shaded by the one shading path of every method
//! ([`crate::render::shading::surface_radiance`]) with the blended normal: diffuse surfaces
//! relit unshadowed, as an engine's impostor shader does; mirrors and glass reflecting and
//! refracting the environment (environment mapping — an atlas holds no other object).
//!
//! Invariants: the atlases are baked in world space from the scene at the frame's time; a
//! pixel's result depends only on its ray (the same pixels for any thread count).

use super::bake::{BakeError, BakeSettings, OctahedralAtlas, bake};
use super::render::PARALLAX_STEPS;
use crate::frame::{Frame, FrameError};
use crate::geom::optics::facing;
use crate::progress::{Progress, Timings};
use crate::render::shading::surface_radiance;
use crate::scene::{Scene, Surface};
use glam::{Vec3, Vec4};
use rayon::prelude::*;

/// Errors drawing a scene from octahedral atlases.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneAtlasError {
    /// The camera could not be placed at the time asked.
    #[error(transparent)]
    Camera(#[from] crate::camera::CameraError),
    /// The scene could not be placed at the time asked.
    #[error(transparent)]
    View(#[from] crate::scene::ViewError),
    /// An object's atlas could not be baked.
    #[error("object {object}: {source}")]
    Bake {
        /// The object (scene file order, from 0).
        object: usize,
        /// Why.
        source: BakeError,
    },
    /// The frame could not be made.
    #[error(transparent)]
    Frame(#[from] FrameError),
}

/// The scene's objects as octahedral atlases, in world space.
pub struct SceneAtlases {
    atlases: Vec<(OctahedralAtlas, Surface)>,
}

impl SceneAtlases {
    /// Bakes every object of `scene` as it stands at time `t` (`progress` advances an object at
    /// a time).
    pub fn bake(
        scene: &Scene,
        t: f32,
        settings: BakeSettings,
        progress: &dyn Progress,
    ) -> Result<Self, SceneAtlasError> {
        let view = scene.view(t)?;
        let atlases = view
            .meshes
            .iter()
            .zip(&view.surfaces)
            .enumerate()
            .map(|(object, (mesh, surface))| {
                let atlas = bake(mesh, surface, settings)
                    .map_err(|source| SceneAtlasError::Bake { object, source })?;
                progress.advance(1);
                Ok((atlas, surface.clone()))
            })
            .collect::<Result<_, SceneAtlasError>>()?;
        Ok(Self { atlases })
    }

    /// The atlases, in the scene's object order.
    pub fn atlases(&self) -> impl Iterator<Item = &OctahedralAtlas> {
        self.atlases.iter().map(|(a, _)| a)
    }

    /// Bytes the atlases hold in memory (colour, normal, depth, ORM).
    pub fn bytes(&self) -> u64 {
        self.atlases()
            .map(|a| u64::from(a.side()).pow(2) * (16 + 12 + 4 + 12))
            .sum()
    }

    /// The frame of `scene` at time `t` through its camera, every object drawn from its atlas
    /// (`progress` advances a row at a time).
    pub fn render(
        &self,
        scene: &Scene,
        t: f32,
        progress: &dyn Progress,
    ) -> Result<Frame, SceneAtlasError> {
        let camera = scene.camera.at(t)?;
        self.render_through(&camera, &scene.lighting, progress)
    }

    /// The frame through `camera` under `lighting`, every object drawn from its atlas
    /// (`progress` advances a row at a time).
    pub fn render_through(
        &self,
        camera: &crate::camera::Pinhole,
        lighting: &crate::scene::Lighting,
        progress: &dyn Progress,
    ) -> Result<Frame, SceneAtlasError> {
        let (w, h) = crate::camera::Projection::resolution(camera);
        let mut frame = Frame::new(w, h)?;
        let eye = camera.position();
        // Each atlas's three frames, chosen by its direction toward the eye.
        let frames: Vec<_> = self
            .atlases
            .iter()
            .map(|(a, _)| {
                let toward = (eye - a.centre.as_dvec3()).normalize_or(glam::DVec3::Y);
                a.settings.grid.frames_around(toward)
            })
            .collect();
        let rows: Vec<Vec<(Vec4, u32)>> = (0..h)
            .into_par_iter()
            .map(|y| {
                let row = (0..w)
                    .map(|x| {
                        let ray =
                            camera.ray(crate::frame::pixel_centre(f64::from(x), f64::from(y)));
                        let mut found: Vec<(f64, usize, super::render::Blended)> = self
                            .atlases
                            .iter()
                            .zip(&frames)
                            .enumerate()
                            .filter_map(|(i, ((a, _), f))| {
                                a.blend(f, ray, PARALLAX_STEPS)
                                    .filter(|b| b.t > 0.0)
                                    .map(|b| (b.t, i, b))
                            })
                            .collect();
                        found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                        // Front to back: each surface over what is behind it, by coverage.
                        let (mut color, mut left) = (Vec3::ZERO, 1.0f32);
                        let mut id = crate::geom::NO_OBJECT;
                        for (_, i, b) in &found {
                            let surface = &self.atlases[*i].1;
                            // The one shading path, the blended normal both shading and
                            // geometric, unshadowed, every bounce the environment's.
                            let (n, _, front) = facing(ray.dir, b.normal, b.normal);
                            let c = surface_radiance(
                                surface,
                                ray.dir,
                                (n, front),
                                || b.albedo,
                                lighting,
                                |_| true,
                                |bounce| lighting.environment.radiance(bounce.dir),
                            );
                            if id == crate::geom::NO_OBJECT && b.alpha >= 0.5 {
                                id = *i as u32;
                            }
                            color += c * b.alpha * left;
                            left *= 1.0 - b.alpha;
                            if left <= 1e-4 {
                                break;
                            }
                        }
                        color += lighting.environment.radiance(ray.dir) * left;
                        (color.extend(1.0), id)
                    })
                    .collect();
                progress.advance(1);
                row
            })
            .collect();
        for (y, row) in rows.into_iter().enumerate() {
            for (x, (c, id)) in row.into_iter().enumerate() {
                frame.color.set(x as u32, y as u32, c);
                frame.object_id.set(x as u32, y as u32, id);
            }
        }
        Ok(frame)
    }
}

/// Bakes `scene`'s objects at time `t` with `settings` and draws the frame from them;
/// `timings` receives the bake and the frame.
pub fn render(
    scene: &Scene,
    t: f32,
    settings: BakeSettings,
    progress: &dyn Progress,
    timings: &mut Timings,
) -> Result<Frame, SceneAtlasError> {
    let atlases = timings.time("bake atlases", || {
        SceneAtlases::bake(scene, t, settings, &())
    })?;
    timings.time("draw from atlases", || atlases.render(scene, t, progress))
}
