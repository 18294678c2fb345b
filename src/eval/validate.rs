//! Cross-checks between methods that must agree: rasterized depth and item ids against BVH
//! primary hits . Used by the tests and shown in the demo report.

use super::fixtures::framing_camera;
use crate::camera::Projection;
use crate::frame::FrameError;
use crate::geom::Mesh;
use crate::raster::{NoAttributes, rasterize};
use crate::trace::{Bvh, RayQuery};
use rayon::prelude::*;
use std::sync::Arc;

/// How a rasterized view of a mesh compares with the BVH's primary hits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterAgreement {
    /// Pixels covered by the raster or hit by the BVH.
    pub covered: usize,
    /// Largest `|d_raster − d_bvh| / d_bvh` over pixels both cover with the same triangle.
    pub max_relative_depth_error: f64,
    /// Fraction of covered pixels where both name the same triangle.
    pub id_agreement: f64,
    /// Fraction of covered pixels that both cover.
    pub coverage_agreement: f64,
}

/// Rasterizes `mesh` at `size²` through a framing camera and traces the same pixel centres.
pub fn raster_vs_bvh(mesh: &Mesh, size: u32) -> Result<RasterAgreement, FrameError> {
    let cam = framing_camera(mesh, size).ok_or(FrameError::InvalidSize {
        width: u64::from(size),
        height: u64::from(size),
        reason: "no camera frames this mesh at this size",
    })?;
    let (target, _) = rasterize(&cam, &[mesh], &NoAttributes, ())?;
    let bvh = Bvh::build(vec![Arc::new(mesh.clone())])?;
    let (w, _) = cam.resolution();
    let per_pixel: Vec<(bool, bool, bool, f64)> = target
        .gd
        .pixels()
        .par_iter()
        .zip(target.item.pixels())
        .enumerate()
        .map(|(i, (&gd, id))| {
            let uv = crate::frame::pixel_centre((i as u32 % w) as f64, (i as u32 / w) as f64);
            let hit = bvh.closest_hit(&cam.ray(uv), f32::INFINITY);
            let raster_covers = gd > 0.0;
            match hit {
                Some(h) if raster_covers => {
                    let same = h.triangle == id.triangle;
                    let d_raster = cam.distance(uv, gd as f64);
                    let err = if same {
                        (d_raster - h.t as f64).abs() / h.t as f64
                    } else {
                        0.0
                    };
                    (true, true, same, err)
                }
                Some(_) => (true, false, false, 0.0),
                None => (raster_covers, false, false, 0.0),
            }
        })
        .collect();
    let covered = per_pixel.iter().filter(|p| p.0).count();
    let both = per_pixel.iter().filter(|p| p.1).count();
    let same = per_pixel.iter().filter(|p| p.2).count();
    let max_err = per_pixel.iter().map(|p| p.3).fold(0.0, f64::max);
    Ok(RasterAgreement {
        covered,
        max_relative_depth_error: max_err,
        id_agreement: same as f64 / covered.max(1) as f64,
        coverage_agreement: both as f64 / covered.max(1) as f64,
    })
}
