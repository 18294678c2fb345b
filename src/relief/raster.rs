//! The objects of a relief walk drawn directly (paper 3 §4's fallback, and the objects without
//! relief): rasterized with the same lighting minus what only the software shader does, their
//! scene ids kept.

use super::ReliefError;
use crate::camera::Pinhole;
use crate::frame::Frame;
use crate::progress::Timings;
use crate::scene::View;
use std::sync::Arc;

/// How the objects drawn directly are shaded: at depth 1 (mirrors and glass take the
/// panorama's radiance), shadow rays offset as a scene's are, by 10⁻⁴ of `meshes`' radius.
pub fn raster_settings(meshes: &[Arc<crate::geom::Mesh>]) -> crate::scene::RenderSettings {
    let radius = meshes
        .iter()
        .map(|m| m.bounds())
        .reduce(|a, b| a.union(b))
        .map_or(1.0, |b| b.radius());
    crate::scene::RenderSettings {
        max_depth: 1,
        time: 0.0,
        ray_epsilon: 1e-4 * radius,
    }
}

/// Rasterizes the objects `objects` of `view` through `camera` (ids kept), the environment
/// behind them.
pub fn raster_subset(
    view: &View,
    lighting: &crate::scene::Lighting,
    camera: &Pinhole,
    objects: &[usize],
    timings: &mut Timings,
) -> Result<Frame, ReliefError> {
    let subset = View {
        lens: None,
        camera: camera.clone(),
        meshes: objects.iter().map(|&o| view.meshes[o].clone()).collect(),
        surfaces: objects.iter().map(|&o| view.surfaces[o].clone()).collect(),
    };
    let settings = raster_settings(&subset.meshes);
    let mut frame = crate::render::render_raster(&subset, lighting, &settings, &(), timings)?;
    for id in frame.object_id.pixels_mut() {
        if let Some(&o) = objects.get(*id as usize) {
            *id = o as u32;
        }
    }
    Ok(frame)
}
