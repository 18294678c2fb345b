//! A scene drawn the way an engine draws objects far enough away (beyond the papers): every
//! object replaced by its octahedral atlas, baked on first use — one atlas for every copy of a
//! field of instances, placed once a copy — each pixel's ray looked up in every atlas it passes
//! through ([`OctahedralAtlas::blend`]: the three frames around the direction toward the eye,
//! parallax-corrected), and the nearest surface found with coverage ≥ ½ drawn: the alpha test
//! of an engine's impostor material (and of `shaders/octahedral_impostor.wgsl`). It is shaded by
//! the one shading path of every method ([`crate::render::shading::surface_radiance`]) with
//! the blended normal: diffuse surfaces relit unshadowed, as an engine's impostor shader does;
//! mirrors and glass reflecting and refracting the environment (environment mapping — an atlas
//! holds no other object).
//!
//! Invariants: the atlases are baked in world space from the scene at the frame's time, a
//! field's from its first copy; a pixel's result depends only on its ray (the same pixels for
//! any thread count).

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

/// The coverage from which a blended lookup is a surface: an engine's alpha test.
pub use super::render::ALPHA_TEST;

/// The scene's objects as octahedral atlases, in world space.
pub struct SceneAtlases {
    /// One atlas an object, or a field of copies, with its surface.
    atlases: Vec<(OctahedralAtlas, Surface)>,
    /// Every object (object id = index): its atlas and where that atlas is moved to.
    placed: Vec<Placed>,
}

/// An object drawn from an atlas.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placed {
    /// The atlas (see [`SceneAtlases::atlases`]).
    pub atlas: usize,
    /// Its translation from where it was baked (world units; zero but for a field's copies).
    pub offset: Vec3,
}

impl SceneAtlases {
    /// Bakes every object of `scene` as it stands at time `t`, a field of instances once from
    /// its first copy (`progress` advances an atlas at a time).
    pub fn bake(
        scene: &Scene,
        t: f32,
        settings: BakeSettings,
        progress: &dyn Progress,
    ) -> Result<Self, SceneAtlasError> {
        let view = scene.view(t)?;
        let mut atlases: Vec<(OctahedralAtlas, Surface)> = Vec::new();
        let mut placed: Vec<Placed> = Vec::with_capacity(view.meshes.len());
        for (object, (mesh, surface)) in view.meshes.iter().zip(&view.surfaces).enumerate() {
            let copy = scene.objects.get(object).and_then(|o| o.field);
            if let Some(field) = copy.filter(|f| f.first < object) {
                placed.push(Placed {
                    atlas: placed[field.first].atlas,
                    offset: field.offset,
                });
                continue;
            }
            let atlas = bake(mesh, surface, settings)
                .map_err(|source| SceneAtlasError::Bake { object, source })?;
            progress.advance(1);
            placed.push(Placed {
                atlas: atlases.len(),
                offset: Vec3::ZERO,
            });
            atlases.push((atlas, surface.clone()));
        }
        Ok(Self { atlases, placed })
    }

    /// The atlases baked (one an object, or a field of copies).
    pub fn atlases(&self) -> impl Iterator<Item = &OctahedralAtlas> {
        self.atlases.iter().map(|(a, _)| a)
    }

    /// Each atlas's surface, in the order of [`SceneAtlases::atlases`].
    pub fn surfaces(&self) -> impl Iterator<Item = &Surface> {
        self.atlases.iter().map(|(_, s)| s)
    }

    /// Every object, by object id: which atlas draws it, moved how far.
    pub fn placed(&self) -> &[Placed] {
        &self.placed
    }

    /// What a frame says of its atlases: baked (`n × n` frames each) or kept, and the objects
    /// they draw where fields of instances share them.
    pub fn report(&self, n: u32, baked: bool) -> String {
        let atlases = self.atlases.len();
        let done = match baked {
            true => format!("baked {atlases} atlases of {n} × {n} frames"),
            false => format!("kept {atlases} atlases"),
        };
        match self.placed.len() {
            objects if objects > atlases => format!("{done}, drawing {objects} objects"),
            _ => done,
        }
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
        // Each placed atlas's three frames, chosen by its direction toward the eye.
        let frames: Vec<_> = self
            .placed
            .iter()
            .map(|p| {
                let a = &self.atlases[p.atlas].0;
                let centre = (a.centre + p.offset).as_dvec3();
                let toward = (eye - centre).normalize_or(glam::DVec3::Y);
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
                        // The nearest surface the alpha test keeps, ties to the lower id.
                        let nearest = self
                            .placed
                            .iter()
                            .zip(&frames)
                            .enumerate()
                            .filter_map(|(i, (p, f))| {
                                // The atlas where it was baked sees the ray moved back.
                                let moved = crate::geom::Ray::new(ray.origin - p.offset, ray.dir);
                                self.atlases[p.atlas]
                                    .0
                                    .blend(f, moved, PARALLAX_STEPS)
                                    .filter(|b| b.t > 0.0 && b.alpha >= ALPHA_TEST)
                                    .map(|b| (b.t, i, b))
                            })
                            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                        let Some((_, i, b)) = nearest else {
                            let background = lighting.environment.radiance(ray.dir);
                            return (background.extend(1.0), crate::geom::NO_OBJECT);
                        };
                        let surface = &self.atlases[self.placed[i].atlas].1;
                        // The one shading path, the blended normal both shading and geometric,
                        // unshadowed, every bounce the environment's.
                        let (n, _, front) = facing(ray.dir, b.normal, b.normal);
                        let color = surface_radiance(
                            surface,
                            ray.dir,
                            (n, front),
                            || b.albedo,
                            lighting,
                            |_| true,
                            |bounce| lighting.environment.radiance(bounce.dir),
                        );
                        (color.extend(1.0), i as u32)
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
