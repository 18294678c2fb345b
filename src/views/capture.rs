//! Synthetic captures: calibrated views of a model rendered by the exact tracer, on a sphere, a
//! ring or a hemisphere of cameras around it — photographs whose every novel view has a known
//! ground truth. Lighting is a sun and a uniform sky, so a diffuse surface looks the same from
//! every view (what view-dependent texturing assumes of its inputs).
//!
//! Invariant: the views are `PINHOLE` cameras whose centres lie on the rig, each looking at the
//! model's centre; view `i` is rendered through exactly the camera its model records.

use super::{CalibratedView, Intrinsics, Pose, ViewSet};
use crate::progress::Progress;
use crate::render::{Method, RenderError};
use crate::scene::{Scene, SceneError};
use glam::DVec3;
use std::path::{Path, PathBuf};

/// Where the cameras stand.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rig {
    /// Evenly over the whole sphere (a Fibonacci lattice).
    Sphere,
    /// Over the upper hemisphere.
    Hemisphere,
    /// On a horizontal circle, 15° above the model's centre.
    Ring,
}

/// Settings of a capture.
#[derive(Clone, Debug)]
pub struct CaptureSettings {
    /// The rig.
    pub rig: Rig,
    /// Number of views.
    pub count: usize,
    /// Image size.
    pub size: (u32, u32),
    /// Camera distance from the model's centre, in bounding radii.
    pub distance: f64,
    /// Vertical field of view, degrees.
    pub fov_y: f64,
    /// Error put into the recorded camera centres (not the rendered ones): a random offset of
    /// this many bounding radii, as a calibration is never exact.
    pub pose_noise: f64,
    /// Noise added to every linear colour channel, uniform in `±colour_noise` (sensor noise).
    pub colour_noise: f32,
    /// Seed of both noises.
    pub seed: u64,
}

impl Default for CaptureSettings {
    /// 60 views on a ring, 320 × 240, 3 radii away, 40° field of view.
    fn default() -> Self {
        CaptureSettings {
            rig: Rig::Ring,
            count: 60,
            size: (320, 240),
            distance: 3.0,
            fov_y: 40.0,
            pose_noise: 0.0,
            colour_noise: 0.0,
            seed: 1,
        }
    }
}

/// Errors from a capture.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CaptureError {
    /// The model could not be loaded as a scene.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A view could not be rendered.
    #[error("view {view}: {source}")]
    Render {
        /// Which view.
        view: usize,
        /// Why.
        source: RenderError,
    },
    /// A setting is out of range.
    #[error("{0}")]
    Settings(String),
}

/// The scene a capture renders: the model as it is, a sun, a uniform sky.
pub fn capture_scene(mesh: &Path) -> Result<Scene, SceneError> {
    let mesh = std::path::absolute(mesh).unwrap_or_else(|_| mesh.to_path_buf());
    let text = format!(
        "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y = 40.0\nresolution = [64, 64]\n\
         [light]\ndirection = [0.4, 1.0, 0.6]\nintensity = 6.28\n\
         [render]\nbackground = [0.5, 0.5, 0.5]\n\
         [[object]]\nmesh = {:?}\n",
        mesh.display().to_string()
    );
    Scene::from_toml(&text, &mesh.with_extension("capture.toml"))
}

/// `n` directions spread evenly over the unit sphere (a Fibonacci lattice).
fn fibonacci_sphere(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - y * y).max(0.0).sqrt();
            let a = golden * i as f64;
            DVec3::new(r * a.cos(), y, r * a.sin())
        })
        .collect()
}

/// The rig's camera centres for a model of centre `centre` and bounding radius `radius`.
pub fn rig_centres(settings: &CaptureSettings, centre: DVec3, radius: f64) -> Vec<DVec3> {
    let r = radius * settings.distance;
    let n = settings.count;
    let dirs: Vec<DVec3> = match settings.rig {
        Rig::Sphere => fibonacci_sphere(n),
        Rig::Hemisphere => fibonacci_sphere(2 * n)
            .into_iter()
            .filter(|d| d.y >= 0.0)
            .take(n)
            .collect(),
        Rig::Ring => (0..n)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                let e = 15f64.to_radians();
                DVec3::new(a.sin() * e.cos(), e.sin(), a.cos() * e.cos())
            })
            .collect(),
    };
    dirs.into_iter().map(|d| centre + d * r).collect()
}

/// Renders a capture of `mesh`; the views' images are in memory (write them with
/// [`write_capture`]).
pub fn capture(
    mesh: &Path,
    settings: &CaptureSettings,
    progress: &dyn Progress,
) -> Result<ViewSet, CaptureError> {
    check(settings)?;
    capture_of(capture_scene(mesh)?, settings, progress)
}

/// Renders a capture of a whole scene (its objects, light and environment), the rig around
/// the bounds of all its objects at time 0.
pub fn capture_of(
    mut scene: Scene,
    settings: &CaptureSettings,
    progress: &dyn Progress,
) -> Result<ViewSet, CaptureError> {
    check(settings)?;
    let (centre, radius) = bounding_sphere(&scene)
        .ok_or_else(|| CaptureError::Settings("the scene has no objects".into()))?;
    let (w, h) = settings.size;
    let f = h as f64 * 0.5 / (settings.fov_y.to_radians() * 0.5).tan();
    let intrinsics = Intrinsics::pinhole(w, h, f, f, w as f64 * 0.5, h as f64 * 0.5);
    let mut views = Vec::new();
    let mut rng = crate::geom::SplitMix64::new(settings.seed);
    for (i, c) in rig_centres(settings, centre, radius)
        .into_iter()
        .enumerate()
    {
        // Straight up or down, "up" is +z.
        let up = if (c - centre).normalize().y.abs() > 0.999 {
            DVec3::Z
        } else {
            DVec3::Y
        };
        let pose = Pose::looking_at(c, centre, up)
            .ok_or_else(|| CaptureError::Settings(format!("view {i}: degenerate pose")))?;
        scene.camera.position = c.as_vec3();
        scene.camera.look_at = centre.as_vec3();
        scene.camera.up = up.as_vec3();
        scene.camera.fov_y = settings.fov_y;
        scene.camera.width = w;
        scene.camera.height = h;
        scene.camera.near = radius * 1e-3;
        let (frame, _) = crate::render::render(&scene, Method::Trace, &())
            .map_err(|source| CaptureError::Render { view: i, source })?;
        let mut image = frame.color;
        if settings.colour_noise > 0.0 {
            for p in image.pixels_mut() {
                for k in 0..3 {
                    p[k] = (p[k] + (2.0 * rng.next_f32() - 1.0) * settings.colour_noise).max(0.0);
                }
            }
        }
        // The recorded pose: the camera moved (keeping its rotation) by the pose noise.
        let recorded = if settings.pose_noise > 0.0 {
            let shift = rng.unit_vector().as_dvec3() * settings.pose_noise * radius;
            Pose {
                rotation: pose.rotation,
                translation: pose.translation - pose.rotation * shift,
            }
        } else {
            pose
        };
        views.push(CalibratedView {
            name: format!("view{i:04}.png"),
            image_id: i as u32 + 1,
            camera_id: 1,
            intrinsics: intrinsics.clone(),
            pose: recorded,
            image: Some(image),
        });
        progress.advance(1);
    }
    Ok(ViewSet {
        views,
        image_folder: PathBuf::new(),
        warnings: Vec::new(),
        summary: Default::default(),
    })
}

/// The centre and radius of the sphere around the box of a scene's objects at time 0 — what
/// a rig stands around; `None` without objects.
pub fn bounding_sphere(scene: &Scene) -> Option<(DVec3, f64)> {
    let bounds = scene
        .objects
        .iter()
        .map(|o| o.mesh.transformed(&o.world_from_object).bounds())
        .reduce(|a, b| a.union(b))?;
    let centre = ((bounds.min + bounds.max) * 0.5).as_dvec3();
    Some((centre, (bounds.extent().length() * 0.5) as f64))
}

/// Refuses settings out of range.
fn check(settings: &CaptureSettings) -> Result<(), CaptureError> {
    if settings.count == 0 || settings.count > 10_000 {
        return Err(CaptureError::Settings(format!(
            "--count {}: must be between 1 and 10000",
            settings.count
        )));
    }
    let fov_ok = settings.fov_y > 1.0 && settings.fov_y < 170.0;
    let distance_ok = settings.distance > 1.0 && settings.distance <= 1e6;
    if !fov_ok || !distance_ok {
        return Err(CaptureError::Settings(
            "the field of view must be in (1°, 170°) and the distance in (1, 10⁶] radii".into(),
        ));
    }
    // A calibration error larger than the cameras' distance from the model records no camera
    // of this capture at all.
    if !(settings.pose_noise >= 0.0 && settings.pose_noise <= settings.distance) {
        return Err(CaptureError::Settings(format!(
            "--pose-noise {:e}: must be between 0 and the distance ({} radii)",
            settings.pose_noise, settings.distance
        )));
    }
    if !(settings.colour_noise >= 0.0 && settings.colour_noise <= 1.0) {
        return Err(CaptureError::Settings(format!(
            "--colour-noise {}: must be between 0 and 1",
            settings.colour_noise
        )));
    }
    Ok(())
}

/// Writes a capture as a COLMAP text model and PNG images into `dir` (images under `images/`),
/// published whole: `dir` holds the earlier capture until the new one replaces it in one step.
pub fn write_capture(dir: &Path, set: &ViewSet) -> Result<(), super::ViewsError> {
    let staged = crate::files::StagedFolder::begin(dir, crate::files::FolderKind::Capture)?;
    write_capture_into(staged.path(), set)?;
    Ok(staged.publish()?)
}

fn write_capture_into(dir: &Path, set: &ViewSet) -> Result<(), super::ViewsError> {
    let images = dir.join("images");
    std::fs::create_dir_all(&images).map_err(|source| super::ViewsError::Io {
        path: images.clone(),
        source,
    })?;
    for v in &set.views {
        if let Some(img) = &v.image {
            let path = images.join(&v.name);
            crate::frame::io::write_png(&path, img).map_err(|source| super::ViewsError::Image {
                name: v.name.clone(),
                source,
            })?;
        }
    }
    super::colmap::write_text(dir, &set.views)
}
