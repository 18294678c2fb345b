//! Layered projective rendering ("Layered view-dependent projective textures" §5): every
//! object textured by the image layers that hold it, each through its layer's asymmetric
//! sub-frustum ([`super::frustum`]), views blended with the view-dependent weights of
//! [`crate::views::blend`] — and, beside it, plain projective texturing (whole photographs,
//! no visibility), the baseline whose artefacts the layers remove.
//!
//! Invariants: no geometry is subdivided; a view contributes to a surface point only through
//! the layer that holds the point's triangle, and only where that layer knows the texel (alpha
//! ≥ ½) and the texel is that surface (the layer's own depth, so an object's far side is not
//! painted with its near side); from an input viewpoint that view alone colours every point it
//! shows.

use super::LayerSet;
use crate::camera::{Pinhole, Projection};
use crate::frame::{FrameError, Image, Rgba};
use crate::geom::Mesh;
use crate::raster::{StoreFragment, rasterize};
use crate::views::blend::{Blend, weights};
use crate::views::{CalibratedView, Weighting};
use glam::{DVec2, DVec3, Vec4};
use rayon::prelude::*;

/// Settings of a layered render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// The view weights.
    pub weighting: Weighting,
    /// Most views blended at a point.
    pub k: usize,
    /// Relative depth tolerance of "this texel is this surface".
    pub tolerance: f64,
}

impl Default for RenderSettings {
    /// Unstructured Lumigraph weights (β = 0.1), 4 views, 1 % depth tolerance.
    fn default() -> Self {
        RenderSettings {
            weighting: Weighting::Ulr { beta: 0.1 },
            k: 4,
            tolerance: crate::views::visibility::DEFAULT_TOLERANCE,
        }
    }
}

/// Renders the layer set's meshes through `camera`.
pub fn render(
    camera: &Pinhole,
    set: &LayerSet,
    settings: &RenderSettings,
) -> Result<Blend, FrameError> {
    let refs: Vec<&Mesh> = set.meshes.iter().collect();
    let centres: Vec<DVec3> = set.views.iter().map(|v| v.pose.centre()).collect();
    shade(camera, &refs, &centres, settings, |i, o, t, p| {
        let vl = &set.layers[i];
        let l = vl.assignment.get(o)?.layer(t)? as usize;
        let (tx, z) = set.projectors[i][l].texel(p)?;
        sample_layer(&vl.layers[l].image, &vl.depth[l], tx, z, settings.tolerance)
    })
}

/// Plain projective texturing: each view's whole photograph projected onto everything in its
/// frustum, hidden or not (`views` with their images loaded, undistorted pinholes).
pub fn render_projective(
    camera: &Pinhole,
    meshes: &[&Mesh],
    views: &[CalibratedView],
    settings: &RenderSettings,
) -> Result<Blend, FrameError> {
    let centres: Vec<DVec3> = views.iter().map(|v| v.pose.centre()).collect();
    shade(camera, meshes, &centres, settings, |i, _, _, p| {
        let v = &views[i];
        let (px, _) = v.project(p)?;
        if !v.contains(px) {
            return None;
        }
        let img = v.image.as_ref()?;
        Some(img.sample_bilinear(
            glam::Vec2::new(px.x as f32, px.y as f32),
            crate::frame::Wrap::Clamp,
            crate::frame::Wrap::Clamp,
        ))
    })
}

/// The shared pixel loop: rasterize, then at each covered pixel ask every view for a colour
/// (`lookup(view, object, triangle, point)`) and blend those that answer.
fn shade(
    camera: &Pinhole,
    meshes: &[&Mesh],
    centres: &[DVec3],
    settings: &RenderSettings,
    lookup: impl Fn(usize, usize, usize, DVec3) -> Option<Rgba> + Sync,
) -> Result<Blend, FrameError> {
    let (target, _) = rasterize(camera, meshes, &StoreFragment, None)?;
    let (w, h) = camera.resolution();
    let eye = camera.position();
    let fragments = target.attributes.pixels();
    let mut image = Image::new(w, h, Vec4::ZERO)?;
    let counts: Vec<(usize, usize)> = image
        .pixels_mut()
        .par_chunks_mut(w as usize)
        .enumerate()
        .map(|(y, row)| {
            let (mut covered, mut holes) = (0, 0);
            let mut samples = vec![None; centres.len()];
            for (x, out) in row.iter_mut().enumerate() {
                let Some(f) = fragments[y * w as usize + x] else {
                    continue;
                };
                covered += 1;
                let (o, t) = (f.item.object as usize, f.item.triangle as usize);
                let c = meshes[o].corners(t);
                let p = (c[0] * f.bary.x + c[1] * f.bary.y + c[2] * f.bary.z).as_dvec3();
                for (i, s) in samples.iter_mut().enumerate() {
                    *s = lookup(i, o, t, p);
                }
                let ws = weights(
                    p,
                    eye,
                    centres,
                    |i| samples[i].is_some(),
                    settings.weighting,
                    settings.k,
                );
                if ws.is_empty() {
                    holes += 1;
                    continue;
                }
                let mut colour = Vec4::ZERO;
                for (i, wgt) in ws {
                    colour += samples[i].unwrap_or(Vec4::ZERO) * wgt as f32;
                }
                *out = colour.truncate().extend(1.0);
            }
            (covered, holes)
        })
        .collect();
    let (covered, holes) = counts
        .into_iter()
        .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    Ok(Blend {
        image,
        covered,
        holes,
    })
}

/// A bilinear lookup of a layer at texel `tx` that takes only taps the layer knows (alpha ≥ ½)
/// and whose surface is at depth `z` (within `tolerance`); `None` when no tap qualifies.
fn sample_layer(
    img: &Image<Rgba>,
    depth: &Image<f32>,
    tx: DVec2,
    z: f64,
    tolerance: f64,
) -> Option<Rgba> {
    img.sample_bilinear_where(tx, |x, y, c| {
        let g = depth.get(x, y) as f64;
        c.w >= 0.5 && g > 0.0 && (1.0 / g - z).abs() <= tolerance * z
    })
}
