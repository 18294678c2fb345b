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
//! A view sees a point clearly ([`Sight::Seen`]) or only at the edge of what it saw
//! ([`Sight::Edge`]: within a texel of a silhouette, where the render's pixel grid and the view's
//! disagree). A pixel is blended from the views that see it clearly; only where none does are the
//! edge views blended instead, so a boundary pixel is coloured rather than left a hole, and an
//! edge view never pulls a clearly seen pixel toward an occluder's colour.
//!
//! Invariants: a view contributes to a pixel only if its source says it sees the pixel's surface
//! point (clearly, or at the edge when no view sees it clearly); the weights of a pixel sum to
//! one; the same inputs give the same pixels on any thread count.

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

/// How a view sees a surface point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sight {
    /// Outside the view, behind it, or hidden by another surface.
    Hidden,
    /// Not at the view's sample under the point, but between samples of which one saw the
    /// point's surface or nothing: the point is within a texel of a silhouette the view saw.
    Edge,
    /// The view's sample under the point is the point's surface.
    Seen,
}

/// What textures a projective render: a set of views, each of which may see a surface point
/// and, when it does, gives it a colour.
pub trait Source: Sync {
    /// Each view's centre of projection (the views are `0..centres().len()`).
    fn centres(&self) -> &[DVec3];
    /// How view `view` sees `at`.
    fn sight(&self, view: usize, at: &SurfacePoint) -> Sight;
    /// Whether view `view` sees `at` clearly.
    fn sees(&self, view: usize, at: &SurfacePoint) -> bool {
        self.sight(view, at) == Sight::Seen
    }
    /// The colour view `view` gives `at`, where it sees it (clearly or at the edge); `None`
    /// drops the view from the pixel's blend (the others are renormalized).
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

impl Blend {
    /// The share of the mesh's pixels no view sees (0 when none shows the mesh).
    pub fn unseen_share(&self) -> f64 {
        self.holes as f64 / self.covered.max(1) as f64
    }
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
                // The views that see the point clearly; failing them, those at an edge.
                let colour = [true, false].into_iter().find_map(|clearly| {
                    let sees = |i: usize| match source.sight(i, &at) {
                        Sight::Seen => true,
                        Sight::Edge => !clearly,
                        Sight::Hidden => false,
                    };
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
                    blend(source, &at, &ws)
                });
                match colour {
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
