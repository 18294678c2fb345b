//! Per-view visibility: each view's depth map of a mesh, drawn by the rasterizer through the
//! view's undistorted pinhole, and the test that says whether a surface point is what the view
//! saw there. Occluded and out-of-frame points are refused, so a blend never copies an
//! occluder's pixels onto what it hides.
//!
//! Invariant: a point is visible in a view when it projects inside the image and its depth along
//! the pixel's ray is within a relative tolerance of the depth map's.

use super::CalibratedView;
use crate::camera::Projection;
use crate::frame::{FrameError, Image};
use crate::geom::Mesh;
use crate::raster::{NoAttributes, rasterize};
use glam::{DVec2, DVec3, Vec2};

pub use crate::texturing::DEFAULT_TOLERANCE;

/// One view's depth map: generalized depth `gd = 1/z` through its undistorted pinhole.
#[derive(Clone, Debug)]
pub struct DepthMap {
    camera: crate::camera::Pinhole,
    gd: Image<f32>,
}

impl DepthMap {
    /// Rasterizes `mesh` through `view`'s undistorted pinhole.
    pub fn of(view: &CalibratedView, mesh: &Mesh) -> Result<DepthMap, FrameError> {
        let camera = view.pinhole();
        let (target, _) = rasterize(&camera, &[mesh], &NoAttributes, ())?;
        Ok(DepthMap {
            camera,
            gd: target.gd,
        })
    }

    /// Rasterizes `mesh` through a pinhole (a view that is not a calibrated one: a new camera
    /// whose render is encoded, say).
    pub fn through(camera: &crate::camera::Pinhole, mesh: &Mesh) -> Result<DepthMap, FrameError> {
        let (target, _) = rasterize(camera, &[mesh], &NoAttributes, ())?;
        Ok(DepthMap {
            camera: camera.clone(),
            gd: target.gd,
        })
    }

    /// The depth maps of every view, in parallel (each is drawn on every core in turn).
    pub fn of_all(views: &[CalibratedView], mesh: &Mesh) -> Result<Vec<DepthMap>, FrameError> {
        views.iter().map(|v| DepthMap::of(v, mesh)).collect()
    }

    /// The map's generalized depth.
    pub fn gd(&self) -> &Image<f32> {
        &self.gd
    }

    /// Whether `world` is the surface this view saw at its pixel, within `tolerance` (relative
    /// depth). Points outside the frame, behind the camera or where the view saw nothing are
    /// not visible.
    pub fn sees(&self, world: DVec3, tolerance: f64) -> bool {
        let Some(p) = self.camera.project(world) else {
            return false;
        };
        let (w, h) = self.gd.size();
        let uv: DVec2 = p.uv;
        if !(uv.x >= 0.0 && uv.y >= 0.0 && uv.x < w as f64 && uv.y < h as f64) {
            return false;
        }
        let stored = self.gd.sample_nearest(Vec2::new(uv.x as f32, uv.y as f32)) as f64;
        if stored <= 0.0 {
            return false;
        }
        // Depth z = 1/gd; the point passes when it is not behind the stored surface by more
        // than the tolerance.
        let (z, z_map) = (1.0 / p.gd, 1.0 / stored);
        z <= z_map * (1.0 + tolerance)
    }
}
