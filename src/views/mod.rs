//! Calibrated views: photographs (or renders) of a mesh with the cameras that took them — the
//! input of view-dependent texturing, layered projective textures (paper 4: "Layered
//! view-dependent projective textures") and the Master Texture (paper 5: "Master Texture Space").
//!
//! A [`ViewSet`] reads and writes COLMAP models ([`colmap`], with COLMAP 4's rigs and frames:
//! [`rig`]); each [`CalibratedView`] has its
//! intrinsics with lens distortion ([`intrinsics`]), its pose and its image. [`visibility`]
//! gives each view's depth map of a mesh; [`blend`] makes the views a source of
//! [`crate::texturing`], which renders the mesh at a new viewpoint from them; [`capture`] renders synthetic captures whose
//! every novel view has a known ground truth.
//!
//! Invariants: a pose maps world to camera, `x_cam = R·x_world + t`, `R` from a unit
//! quaternion; a view's image, once loaded, has its camera's size.

pub mod blend;
pub mod capture;
pub mod colmap;
pub use crate::camera::intrinsics;
pub mod rig;
pub mod score;
pub mod visibility;

pub use crate::texturing::{Blend, BlendSettings, Holes, Weighting};
pub use intrinsics::{CameraModel, Intrinsics};

use crate::camera::Pinhole;
use crate::frame::{FrameError, Image, Rgba};
use glam::{DMat3, DQuat, DVec2, DVec3};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Errors from reading, writing or using calibrated views.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ViewsError {
    /// The output folder cannot take the result, or publishing it failed.
    #[error(transparent)]
    Folder(#[from] crate::files::FolderError),
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A model file is malformed.
    #[error("{path}: {element}: {reason}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// Where: `line 4`, `camera 2`, `image 7` …
        element: String,
        /// What is wrong.
        reason: String,
    },
    /// A model has no image of that name or id.
    #[error("{model}: no image named {key:?} or with that id")]
    NoImage {
        /// The model's folder.
        model: PathBuf,
        /// The name or id asked for.
        key: String,
    },
    /// A folder holds neither a text nor a binary COLMAP model.
    #[error("{0}: no COLMAP model here (cameras.txt + images.txt, or cameras.bin + images.bin)")]
    NoModel(PathBuf),
    /// A view's image could not be loaded, or disagrees with its camera.
    #[error("image {name}: {source}")]
    Image {
        /// The image's name in the model.
        name: String,
        /// Why.
        source: FrameError,
    },
    /// A view's image is not the size its camera says.
    #[error("image {name}: {width} × {height} pixels, but camera {camera} is {cw} × {ch}")]
    ImageSize {
        /// The image's name.
        name: String,
        /// Its size.
        width: u32,
        /// Its size.
        height: u32,
        /// Its camera's id.
        camera: u32,
        /// The camera's size.
        cw: u32,
        /// The camera's size.
        ch: u32,
    },
    /// The views' depth maps could not be drawn (their size refused).
    #[error("depth maps of the views: {0}")]
    DepthMaps(FrameError),
    /// The model holds no view.
    #[error("{0}: no registered image")]
    Empty(PathBuf),
}

/// A rigid world-to-camera transform: `x_cam = R·x_world + t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Unit rotation, world to camera.
    pub rotation: DQuat,
    /// Translation, world to camera.
    pub translation: DVec3,
}

impl Pose {
    /// The pose of a camera at `centre` looking at `target`, `up` roughly up (camera `y` down).
    pub fn looking_at(centre: DVec3, target: DVec3, up: DVec3) -> Option<Pose> {
        // Camera y is down: the basis's up, reversed.
        let [z, x, up] = crate::camera::look_at_basis(centre, target, up).ok()?;
        let y = -up;
        // Rows of R are the camera axes in world coordinates.
        let r = DMat3::from_cols(x, y, z).transpose();
        let rotation = DQuat::from_mat3(&r).normalize();
        Some(Pose {
            rotation,
            translation: -(rotation * centre),
        })
    }

    /// Camera coordinates of a world point.
    pub fn to_camera(&self, world: DVec3) -> DVec3 {
        self.rotation * world + self.translation
    }

    /// The camera's centre in world coordinates, `−Rᵀt`.
    pub fn centre(&self) -> DVec3 {
        -(self.rotation.inverse() * self.translation)
    }
}

/// One calibrated view.
#[derive(Clone, Debug)]
pub struct CalibratedView {
    /// The image's name in the model (a path relative to the image folder).
    pub name: String,
    /// COLMAP's image id.
    pub image_id: u32,
    /// COLMAP's camera id.
    pub camera_id: u32,
    /// Intrinsics with distortion.
    pub intrinsics: Intrinsics,
    /// World to camera.
    pub pose: Pose,
    /// The image, once loaded ([`ViewSet::load_images`]).
    pub image: Option<Image<Rgba>>,
}

impl CalibratedView {
    /// The pixel a world point projects to (distortion applied) and its depth along the
    /// camera's `z`; `None` behind the camera.
    pub fn project(&self, world: DVec3) -> Option<(DVec2, f64)> {
        let p = self.pose.to_camera(world);
        if p.z <= 1e-9 {
            return None;
        }
        let px = self.intrinsics.pixel_of(DVec2::new(p.x / p.z, p.y / p.z));
        Some((px, p.z))
    }

    /// The loaded image's colour at pixel `px`, bilinear, clamped at the edges; `None` when the
    /// image is not loaded.
    pub fn colour_at(&self, px: DVec2) -> Option<Rgba> {
        let img = self.image.as_ref()?;
        Some(img.sample_bilinear(
            glam::Vec2::new(px.x as f32, px.y as f32),
            crate::frame::Wrap::Clamp,
            crate::frame::Wrap::Clamp,
        ))
    }

    /// Whether a pixel lies in the image.
    pub fn contains(&self, px: DVec2) -> bool {
        let (w, h) = self.intrinsics.size();
        px.x >= 0.0 && px.y >= 0.0 && px.x < w as f64 && px.y < h as f64
    }

    /// This view as a scene's camera: its centre, orientation, image size and undistorted
    /// intrinsics (the same pinhole as [`CalibratedView::pinhole`], up to the scene camera's
    /// single precision), still, with near plane `near`.
    pub fn camera_spec(&self, near: f64) -> crate::scene::CameraSpec {
        self.camera_spec_through(near, false)
    }

    /// [`CalibratedView::camera_spec`], and with `distort`, its lens too: the scene camera
    /// renders the photograph's distorted frame ([`crate::scene::View::lens`]).
    pub fn camera_spec_through(&self, near: f64, distort: bool) -> crate::scene::CameraSpec {
        let u = self.intrinsics.undistorted();
        let ((fx, fy), (cx, cy)) = (u.focal(), u.principal_point());
        let (width, height) = u.size();
        let r_inv = self.pose.rotation.inverse();
        let centre = self.pose.centre();
        crate::scene::CameraSpec {
            position: centre.as_vec3(),
            look_at: (centre + r_inv * DVec3::Z).as_vec3(),
            up: (r_inv * -DVec3::Y).as_vec3(),
            fov_y: 2.0 * (height as f64 * 0.5 / fy).atan().to_degrees(),
            intrinsics: Some([fx, fy, cx, cy]),
            lens: (distort && !self.intrinsics.is_undistorted()).then(|| self.intrinsics.clone()),
            width,
            height,
            near,
            path: Vec::new(),
        }
    }

    /// The undistorted pinhole of this view as a trompe camera (for rasterizing through it).
    pub fn pinhole(&self) -> Pinhole {
        let u = self.intrinsics.undistorted();
        let ((fx, fy), (cx, cy)) = (u.focal(), u.principal_point());
        let (w, h) = u.size();
        let r_inv = self.pose.rotation.inverse();
        let (x, y, z) = (r_inv * DVec3::X, r_inv * DVec3::Y, r_inv * DVec3::Z);
        let a = x / fx;
        let b = y / fy;
        let c = z - x * (cx / fx) - y * (cy / fy);
        Pinhole::from_mcmillan(self.pose.centre(), a, b, c, w, h)
    }
}

/// The camera of image `key` (its name, or its id) of the COLMAP model in `model`, as a scene's
/// camera ([`CalibratedView::camera_spec_through`], near plane `near`): to render from where a
/// photograph was taken, at its size, with its intrinsics — its undistorted frame, or with
/// `distort` its distorted one, through its lens.
pub fn camera_of(
    model: &Path,
    key: &str,
    near: f64,
    distort: bool,
) -> Result<crate::scene::CameraSpec, ViewsError> {
    let set = ViewSet::load(model, None)?;
    let view = set.find(key).ok_or_else(|| ViewsError::NoImage {
        model: model.to_path_buf(),
        key: key.to_string(),
    })?;
    Ok(view.camera_spec_through(near, distort))
}

/// A set of calibrated views and the folder their images are in.
#[derive(Clone, Debug)]
pub struct ViewSet {
    /// The views, in image-id order.
    pub views: Vec<CalibratedView>,
    /// The folder image names are relative to.
    pub image_folder: PathBuf,
    /// What the model held that was skipped (a camera no image uses, …).
    pub warnings: Vec<String>,
    /// What the model held: cameras, images, rigs and frames.
    pub summary: colmap::ModelSummary,
}

impl ViewSet {
    /// Reads the COLMAP model in `model` (text or binary); images are looked for in
    /// `image_folder` (default: `model` itself, then its `images/` subfolder).
    pub fn load(model: &Path, image_folder: Option<&Path>) -> Result<ViewSet, ViewsError> {
        let (views, warnings, summary) = colmap::read_model_summarized(model)?;
        let image_folder = image_folder.map_or_else(
            || {
                let beside = model.join("images");
                match views.first() {
                    Some(v) if !model.join(&v.name).is_file() && beside.is_dir() => beside,
                    _ => model.to_path_buf(),
                }
            },
            Path::to_path_buf,
        );
        Ok(ViewSet {
            views,
            image_folder,
            warnings,
            summary,
        })
    }

    /// The view whose image is named `key`, or whose image id it is.
    pub fn find(&self, key: &str) -> Option<&CalibratedView> {
        let id: Option<u32> = key.parse().ok();
        self.views
            .iter()
            .find(|v| v.name == key)
            .or_else(|| self.views.iter().find(|v| Some(v.image_id) == id))
    }

    /// Loads every view's image, checking its size against its camera.
    pub fn load_images(&mut self) -> Result<(), ViewsError> {
        for i in 0..self.views.len() {
            let img = self.read_image(&self.views[i])?;
            self.views[i].image = Some(img);
        }
        Ok(())
    }

    /// Reads `view`'s image from the image folder, checking its size against its camera.
    pub fn read_image(&self, view: &CalibratedView) -> Result<Image<Rgba>, ViewsError> {
        let path = self.image_folder.join(&view.name);
        let img = crate::frame::io::read_color(&path).map_err(|source| ViewsError::Image {
            name: view.name.clone(),
            source,
        })?;
        let (w, h) = view.intrinsics.size();
        if img.size() != (w, h) {
            return Err(ViewsError::ImageSize {
                name: view.name.clone(),
                width: img.size().0,
                height: img.size().1,
                camera: view.camera_id,
                cw: w,
                ch: h,
            });
        }
        Ok(img)
    }
}
