//! Cameras: the [`Projection`] trait every camera model implements; the pinhole, orthographic and
//! single-pole occlusion cameras (paper 1 §3–4; docs/conventions.md §1, §3); and the continuous
//! 3-ray camera of paper 2 ([`C3rc`]), which is not a [`Projection`]: a point may have up to
//! three images.
//!
//! A projection maps a world point to continuous image coordinates `(u, v)` (pixels, origin
//! top-left, pixel centres at `+0.5`) and a **generalized depth** `gd` (docs/conventions.md §1.2):
//! `gd = 1/t` where the point is `C + t·M·(u, v, 1)`. Larger `gd` is nearer; an empty pixel has
//! `gd = 0`. The rasterizer interpolates `gd` linearly in image space and keeps the largest.
//!
//! Invariants: `unproject(project(X)) = X` wherever `project` succeeds; `clip_distance` is affine
//! in the world point and non-negative exactly where `project` is valid. Projection arithmetic is
//! `f64` (docs/conventions.md: "use f64 for all geometry").

mod c3rc;
mod graph;
pub mod intrinsics;
mod orthographic;
mod pinhole;
mod spoc;

pub use c3rc::{C3rc, C3rcProjection, real_roots};
pub use graph::{Frustum, FrustumProjection, GraphCamera, Plane, face_map};
pub use intrinsics::{CameraModel, Intrinsics};
pub use orthographic::Orthographic;
pub use pinhole::Pinhole;
pub use spoc::{SPOC_STRENGTH_RANGE, Spoc};

use glam::{DVec2, DVec3, Vec3};
use thiserror::Error;

/// The orthonormal frame of a camera at `eye` looking at `target`, `up` roughly up (the one
/// look-at basis every camera and calibrated pose is made with): `[forward, right, up]`, where
/// `right = forward × up` and the true up is `right × forward`.
pub fn look_at_basis(eye: DVec3, target: DVec3, up: DVec3) -> Result<[DVec3; 3], CameraError> {
    let forward = (target - eye)
        .try_normalize()
        .ok_or(CameraError::Degenerate("look_at equals position"))?;
    let right = forward
        .cross(up)
        .try_normalize()
        .ok_or(CameraError::Degenerate(
            "up is parallel to the view direction",
        ))?;
    Ok([forward, right, right.cross(forward)])
}

/// Where a world point lands in an image: continuous pixel coordinates and generalized depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImagePoint {
    /// Pixel coordinates; `(i + 0.5, j + 0.5)` is the centre of pixel `(i, j)`.
    pub uv: DVec2,
    /// Generalized depth `gd = 1/t` (docs/conventions.md §1.2): larger is nearer, never ≤ 0 for a
    /// point the camera sees.
    pub gd: f64,
    /// Reciprocal of the homogeneous `w`: on a plane, attributes × `inv_w` are affine in image
    /// space (perspective-correct interpolation). Equals `gd` for perspective cameras, 1 for the
    /// orthographic camera.
    pub inv_w: f64,
}

/// A camera model: world point → `(u, v, gd)` and back. The rasterizer and the ray walks are
/// generic over it, so any camera can build an image.
pub trait Projection: Sync {
    /// Image size in pixels `(width, height)`.
    fn resolution(&self) -> (u32, u32);

    /// Projects a world point; `None` outside the camera's domain (behind its near boundary).
    fn project(&self, p: DVec3) -> Option<ImagePoint>;

    /// The world point at image coordinates `uv` and generalized depth `gd > 0`.
    fn unproject(&self, uv: DVec2, gd: f64) -> DVec3;

    /// Signed distance to the near boundary, affine in `p`, `≥ 0` where [`Projection::project`]
    /// is valid. The rasterizer clips triangles where it is negative.
    fn clip_distance(&self, p: DVec3) -> f64;

    /// An upper bound, in pixels, on how far the image of the midpoint of a world segment strays
    /// from the midpoint of the images of its ends — the tessellation criterion of
    /// docs/conventions.md §2.2 — valid for every segment whose two ends have images among `ends`
    /// (two for an edge, three for all edges of a triangle at once) and computed from those
    /// images alone; `INFINITY` when the camera has no such bound.
    ///
    /// Cameras projective on planes (pinhole, orthographic, one frustum of a graph camera)
    /// answer 0: they image a segment straight, and the rasterizer's perspective-correct
    /// interpolation puts its midpoint exactly where the camera does, so a triangle never needs
    /// splitting. Every camera must say which it is: there is no default, so a new curved camera
    /// cannot silently skip tessellation.
    fn midpoint_deviation_bound(&self, ends: &[ImagePoint]) -> f64;

    /// [`Projection::clip_distance`] of `p`, and its projection where that is `≥ 0`: what the
    /// rasterizer asks of every mesh vertex. One call, so that a camera chosen at run time
    /// (an enum of cameras) dispatches once per vertex, and each camera's two answers are
    /// computed together.
    fn clip_and_project(&self, p: DVec3) -> (f64, Option<ImagePoint>) {
        let clip = self.clip_distance(p);
        (clip, if clip >= 0.0 { self.project(p) } else { None })
    }

    /// Projects an `f32` world point (convenience for mesh vertices).
    fn project_f32(&self, p: Vec3) -> Option<ImagePoint> {
        self.project(p.as_dvec3())
    }
}

/// Errors from building a camera from user parameters.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum CameraError {
    /// Position, look-at or up vector make no camera.
    #[error("camera: {0}")]
    Degenerate(&'static str),
    /// Field of view outside (0°, 180°).
    #[error("camera: field of view {0}° must be in (0, 180)")]
    FieldOfView(f64),
    /// Resolution refused by the allocation limits.
    #[error("camera: {0}")]
    Resolution(#[from] crate::frame::FrameError),
}
