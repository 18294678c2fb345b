//! Projective texturing: the one renderer behind calibrated views ([`crate::views`]), image
//! layers ([`crate::layers`]) and master textures ([`crate::master`]). Meshes are rasterized
//! through a new camera; at each covered pixel the surface point is asked of every view of a
//! [`Source`]; the views that see it are weighted ([`weights`], or a per-face table of
//! [`faces`]) and their colours blended; a pixel no view sees is a hole, shown by one
//! [`Holes`] policy and counted.
//!
//! Papers: the view-dependent texture mapping of Debevec et al. and "Unstructured Lumigraph
//! Rendering" §6 ([`weights`]), "Layered view-dependent projective textures" §5 (a source that
//! answers through each object's layer), "Master Texture" §4 (a source that answers from one
//! texture coordinate a point).
//!
//! Invariants: a view contributes to a pixel only if its source says it sees the pixel's surface
//! point; the weights of a pixel sum to one; the same inputs give the same pixels on any thread
//! count.

pub mod faces;
pub mod view_map;
pub mod weights;

pub use weights::{BlendSettings, DEFAULT_TOLERANCE, Holes, Weighting, weights};

use crate::camera::{Pinhole, Projection};
use crate::frame::{FrameError, Image, Rgba};
use crate::geom::Mesh;
use crate::raster::{StoreFragment, rasterize};
use faces::FaceWeights;
use glam::{DVec2, DVec3, Vec3, Vec4};
use rayon::prelude::*;

/// A point of a rendered surface: which object and triangle, where on it, and where in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The object (index into the render's meshes).
    pub object: usize,
    /// The triangle of that object.
    pub triangle: usize,
    /// Barycentric coordinates on the triangle (of its corners 0, 1, 2).
    pub bary: Vec3,
    /// World position.
    pub position: DVec3,
}

/// What textures a projective render: a set of views, each of which may see a surface point
/// and, when it does, gives it a colour.
pub trait Source: Sync {
    /// Each view's centre of projection (the views are `0..centres().len()`).
    fn centres(&self) -> &[DVec3];
    /// Whether view `view` sees `at`.
    fn sees(&self, view: usize, at: &SurfacePoint) -> bool;
    /// The colour view `view` gives `at`, where it sees it; `None` drops the view from the
    /// pixel's blend (the others are renormalized).
    fn colour(&self, view: usize, at: &SurfacePoint) -> Option<Rgba>;
    /// Where world point `p` lands in view `view`'s image, in pixels (the best-face weighting
    /// compares projected areas); `None` behind the view.
    fn pixel(&self, view: usize, p: DVec3) -> Option<DVec2>;
}

/// What a render makes: the image and how many of its pixels were holes.
#[derive(Clone, Debug)]
pub struct Blend {
    /// Linear RGBA; alpha 0 on background and (with [`Holes::Transparent`]) holes.
    pub image: Image<Rgba>,
    /// Pixels that show a mesh.
    pub covered: usize,
    /// Of those, pixels no view sees.
    pub holes: usize,
}

/// Renders `meshes` through `camera`, textured by `source`'s views.
pub fn render(
    camera: &Pinhole,
    meshes: &[&Mesh],
    source: &impl Source,
    settings: &BlendSettings,
) -> Result<Blend, FrameError> {
    let (target, _) = rasterize(camera, meshes, &StoreFragment, None)?;
    let faces = FaceWeights::build(settings.weighting, meshes, source);
    let (w, h) = camera.resolution();
    let eye = camera.position();
    let centres = source.centres();
    let fragments = target.attributes.pixels();
    let mut image = Image::new(w, h, Vec4::ZERO)?;
    let counts: Vec<(usize, usize)> = image
        .pixels_mut()
        .par_chunks_mut(w as usize)
        .enumerate()
        .map(|(y, row)| {
            let (mut covered, mut holes) = (0, 0);
            for (x, out) in row.iter_mut().enumerate() {
                let Some(f) = fragments[y * w as usize + x] else {
                    continue;
                };
                covered += 1;
                let (o, t) = (f.item.object as usize, f.item.triangle as usize);
                let c = meshes[o].corners(t);
                let at = SurfacePoint {
                    object: o,
                    triangle: t,
                    bary: f.bary,
                    position: (c[0] * f.bary.x + c[1] * f.bary.y + c[2] * f.bary.z).as_dvec3(),
                };
                let sees = |i: usize| source.sees(i, &at);
                let ws = match &faces {
                    FaceWeights::PerPoint => weights(
                        at.position,
                        eye,
                        centres,
                        sees,
                        settings.weighting,
                        settings.k,
                    ),
                    FaceWeights::BestFace(table) => table[o][t]
                        .filter(|&i| sees(i))
                        .map_or_else(Vec::new, |i| vec![(i, 1.0)]),
                    FaceWeights::ViewMap(maps) => {
                        let mut ws = maps[o].weights(t, (eye - at.position).normalize());
                        ws.retain(|&(i, _)| sees(i));
                        let sum: f64 = ws.iter().map(|w| w.1).sum();
                        ws.iter_mut().for_each(|w| w.1 /= sum);
                        ws
                    }
                };
                match blend(source, &at, &ws) {
                    Some(colour) => *out = colour.truncate().extend(1.0),
                    None => {
                        holes += 1;
                        *out = match settings.holes {
                            Holes::Transparent => Vec4::ZERO,
                            Holes::Fill(c) => c,
                        };
                    }
                }
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

/// The weighted colours of the views `ws` give `at`; those that give none are dropped and the
/// others renormalized; `None` when none is left.
fn blend(source: &impl Source, at: &SurfacePoint, ws: &[(usize, f64)]) -> Option<Rgba> {
    let (mut colour, mut total, mut dropped) = (Vec4::ZERO, 0.0, false);
    for &(i, w) in ws {
        match source.colour(i, at) {
            Some(c) => {
                colour += c * w as f32;
                total += w;
            }
            None => dropped = true,
        }
    }
    if total <= 0.0 {
        return None;
    }
    Some(if dropped {
        colour / total as f32
    } else {
        colour
    })
}
