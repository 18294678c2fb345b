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
//! A render may prefilter each view's image to its pixel ([`prefiltered`]): every surface point
//! carries the render pixel's footprint on its triangle's plane, and a source that is asked
//! averages its lookups across it where it spans two or more of its texels.
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
pub mod fill;
pub mod seams;
pub mod view_map;
pub mod weights;

pub use weights::{BlendSettings, DEFAULT_TOLERANCE, Holes, Weighting, weights};

use crate::camera::Intrinsics;
use crate::camera::{Pinhole, Projection};
use crate::frame::{FrameError, Image, Rgba};
use crate::geom::Mesh;
use crate::raster::{Fragment, ItemId, StoreFragment, rasterize};
use faces::FaceWeights;
use glam::{DVec2, DVec3, Vec3, Vec4};
use rayon::prelude::*;
use std::sync::Arc;

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
    /// The world steps to the surface points of the next pixel right and the next pixel down,
    /// on the triangle's plane: the render pixel's footprint on the surface, which a source
    /// prefilters its image over. Zero when the point is not a render's pixel (a triangle's
    /// centroid), where the plane is seen edge-on, or where the render does not prefilter
    /// ([`BlendSettings::prefilter`]).
    pub footprint: [DVec3; 2],
    /// The same two steps in barycentric coordinates.
    pub footprint_bary: [Vec3; 2],
}

impl SurfacePoint {
    /// The point `(s, t)` pixel steps from this one along its footprint, on its triangle's
    /// plane (its barycentric coordinates may leave the triangle).
    pub fn offset(&self, s: f64, t: f64) -> SurfacePoint {
        SurfacePoint {
            position: self.position + self.footprint[0] * s + self.footprint[1] * t,
            bary: self.bary + self.footprint_bary[0] * s as f32 + self.footprint_bary[1] * t as f32,
            footprint: [DVec3::ZERO; 2],
            footprint_bary: [Vec3::ZERO; 2],
            ..*self
        }
    }
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
    /// Of those, pixels filled from the nearest seen surface ([`Holes::Nearest`]).
    pub filled: usize,
    /// With [`Weighting::BestFace`] and [`BlendSettings::seamless`], what making its per-face
    /// bake seamless did.
    pub seams: Option<seams::SeamReport>,
}

impl Blend {
    /// The share of the mesh's pixels no view sees (0 when none shows the mesh).
    pub fn unseen_share(&self) -> f64 {
        self.holes as f64 / self.covered.max(1) as f64
    }
}

/// "N pixels show the mesh, M of them seen by no view (x %)", and how many were filled.
impl std::fmt::Display for Blend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} pixels show the mesh, {} of them seen by no view ({:.2} %)",
            self.covered,
            self.holes,
            100.0 * self.unseen_share()
        )?;
        if self.filled > 0 {
            write!(f, ", {} filled from the nearest seen surface", self.filled)?;
        }
        if let Some(seams) = &self.seams {
            write!(f, "\nbest-face bake: {seams}")?;
        }
        Ok(())
    }
}

/// Renders `meshes` through `camera`, textured by `source`'s views.
pub fn render(
    camera: &Pinhole,
    meshes: &[&Mesh],
    source: &impl Source,
    settings: &BlendSettings,
) -> Result<Blend, FrameError> {
    render_through(camera, None, meshes, source, settings)
}

/// Renders `meshes` through `camera` and, when given, the `lens` its pixels look through (a
/// real camera's distortion, [`crate::scene::View::lens`]: each pixel's surface is then found
/// by tracing its ray, as no rasterizer draws through a lens), textured by `source`'s views.
pub fn render_through(
    camera: &Pinhole,
    lens: Option<&Intrinsics>,
    meshes: &[&Mesh],
    source: &impl Source,
    settings: &BlendSettings,
) -> Result<Blend, FrameError> {
    let (a, b, c) = camera.mcmillan();
    // The direction of the ray through continuous pixel `uv` of the frame.
    let direction = |uv: DVec2| match lens {
        None => Some(a * uv.x + b * uv.y + c),
        Some(lens) => lens.undistorted_pixel_of(uv).map(|u| a * u.x + b * u.y + c),
    };
    let traced;
    let rasterized;
    let fragments: &[Option<Fragment>] = match lens {
        None => {
            rasterized = rasterize(camera, meshes, &StoreFragment, None)?.0;
            rasterized.attributes.pixels()
        }
        Some(_) => {
            traced = trace_fragments(camera, meshes, &direction)?;
            &traced
        }
    };
    let faces = FaceWeights::build(settings.weighting, settings.seamless, meshes, source)?;
    let (w, h) = camera.resolution();
    let eye = camera.position();
    let centres = source.centres();
    let mut image = Image::new(w, h, Vec4::ZERO)?;
    let mut pixels = vec![fill::Pixel::Background; w as usize * h as usize];
    let counts: Vec<(usize, usize)> = image
        .pixels_mut()
        .par_chunks_mut(w as usize)
        .zip(pixels.par_chunks_mut(w as usize))
        .enumerate()
        .map(|(y, (row, shown))| {
            let (mut covered, mut holes) = (0, 0);
            for (x, (out, shown)) in row.iter_mut().zip(shown).enumerate() {
                let Some(f) = fragments[y * w as usize + x] else {
                    continue;
                };
                covered += 1;
                let (o, t) = (f.item.object as usize, f.item.triangle as usize);
                let c = meshes[o].corners(t).map(|p| p.as_dvec3());
                let position =
                    c[0] * f.bary.x as f64 + c[1] * f.bary.y as f64 + c[2] * f.bary.z as f64;
                let steps = match settings.prefilter {
                    true => footprint(eye, direction, &c, position, (x, y)),
                    false => [DVec3::ZERO; 2],
                };
                let at = SurfacePoint {
                    object: o,
                    triangle: t,
                    bary: f.bary,
                    position,
                    footprint: steps,
                    footprint_bary: steps.map(|d| bary_step(&c, d)),
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
                        FaceWeights::BestFace(best) => {
                            let view = best.table[o][t].filter(|&i| sees(i));
                            return view.and_then(|i| {
                                let colour = blend(source, &at, &[(i, 1.0)])?;
                                Some(best.level(meshes, &at, i, colour))
                            });
                        }
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
                    Some(colour) => {
                        *out = colour.truncate().extend(1.0);
                        *shown = fill::Pixel::Seen;
                    }
                    None => {
                        holes += 1;
                        *shown = fill::Pixel::Hole;
                        *out = match settings.holes {
                            Holes::Transparent | Holes::Nearest => Vec4::ZERO,
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
    let filled = match settings.holes {
        Holes::Nearest if holes > 0 => fill::from_nearest(&mut image, &pixels),
        _ => 0,
    };
    Ok(Blend {
        image,
        covered,
        holes,
        filled,
        seams: match faces {
            FaceWeights::BestFace(best) => best.report,
            _ => None,
        },
    })
}

/// A weighting's per-face table, for a renderer that blends elsewhere (the GPU's) from the
/// same tables as [`render`] builds.
#[derive(Clone, Debug)]
pub enum FaceTable {
    /// [`Weighting::Ulr`] and [`Weighting::Vdtm`] weigh each point: no table.
    PerPoint,
    /// Per object, per triangle: the view that sees its centroid with the largest projected
    /// area, if any (the plain bake, not [`BlendSettings::seamless`]).
    BestFace(Vec<Vec<Option<usize>>>),
    /// Per object: its triangles' view maps.
    ViewMap(Vec<view_map::ViewMap>),
}

/// The table `weighting` weighs `meshes` seen by `source` by, as [`render`] builds it (a
/// best-face table without [`BlendSettings::seamless`]).
pub fn face_table(
    weighting: Weighting,
    meshes: &[&Mesh],
    source: &impl Source,
) -> Result<FaceTable, FrameError> {
    Ok(
        match FaceWeights::build(weighting, false, meshes, source)? {
            FaceWeights::PerPoint => FaceTable::PerPoint,
            FaceWeights::BestFace(best) => FaceTable::BestFace(best.table),
            FaceWeights::ViewMap(maps) => FaceTable::ViewMap(maps),
        },
    )
}

/// The footprint of render pixel `(x, y)` on the plane of triangle `corners` through `p`: the
/// steps from `p` to where the rays from `eye` along `direction` of the next pixel's centre
/// right and down meet that plane; zero where the plane is seen edge-on or the step is not
/// finite.
fn footprint(
    eye: DVec3,
    direction: impl Fn(DVec2) -> Option<DVec3>,
    corners: &[DVec3; 3],
    p: DVec3,
    (x, y): (usize, usize),
) -> [DVec3; 2] {
    let n = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
    let along = n.dot(p - eye);
    let centre = crate::frame::pixel_centre(x as f64, y as f64);
    let step = |d: DVec2| {
        let Some(ray) = direction(centre + d) else {
            return DVec3::ZERO;
        };
        let t = along / n.dot(ray);
        let q = eye + ray * t;
        if t > 0.0 && q.is_finite() {
            q - p
        } else {
            DVec3::ZERO
        }
    };
    let (right, down) = (step(DVec2::X), step(DVec2::Y));
    if right == DVec3::ZERO || down == DVec3::ZERO {
        return [DVec3::ZERO; 2];
    }
    [right, down]
}

/// The surfaces `camera`'s pixels see along `direction` (the ray through a continuous pixel),
/// found by tracing one ray a pixel centre through a BVH of `meshes`, as fragments (their
/// depth unset).
fn trace_fragments(
    camera: &Pinhole,
    meshes: &[&Mesh],
    direction: &(impl Fn(DVec2) -> Option<DVec3> + Sync),
) -> Result<Vec<Option<Fragment>>, FrameError> {
    let bvh = crate::trace::Bvh::build(meshes.iter().map(|&m| Arc::new(m.clone())).collect())?;
    let (w, h) = camera.resolution();
    let eye = camera.position().as_vec3();
    let pixels: Vec<(u32, u32)> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).collect();
    Ok(pixels
        .par_iter()
        .map(|&(x, y)| {
            let d = direction(crate::frame::pixel_centre(f64::from(x), f64::from(y)))?;
            let ray = crate::geom::Ray::new(eye, d.normalize().as_vec3());
            let hit = crate::trace::RayQuery::closest_hit(&bvh, &ray, f32::INFINITY)?;
            Some(Fragment {
                x,
                y,
                gd: 0.0,
                bary: Vec3::new(1.0 - hit.bary.x - hit.bary.y, hit.bary.x, hit.bary.y),
                item: ItemId {
                    object: hit.object,
                    triangle: hit.triangle,
                },
            })
        })
        .collect())
}

/// The change of barycentric coordinates on triangle `c` along the in-plane step `d`.
fn bary_step(c: &[DVec3; 3], d: DVec3) -> Vec3 {
    let (e1, e2) = (c[1] - c[0], c[2] - c[0]);
    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d20, d21) = (d.dot(e1), d.dot(e2));
    let det = d00 * d11 - d01 * d01;
    if det.abs() <= f64::MIN_POSITIVE || !det.is_finite() {
        return Vec3::ZERO;
    }
    let b = (d11 * d20 - d01 * d21) / det;
    let g = (d00 * d21 - d01 * d20) / det;
    DVec3::new(-(b + g), b, g).as_vec3()
}

/// Most lookups along each side of a render pixel's footprint ([`prefiltered`]): a pixel that
/// covers more than this many texels of an image is sampled at this rate, no finer.
pub const MAX_FOOTPRINT_TAPS: usize = 8;

/// A source's colour for `at` prefiltered to the render pixel's footprint. `texel` says where
/// a surface point lands in the image the view samples; where the footprint's longer side
/// spans `n ≥ 2` of its texels, `lookup` is asked at `n × n` points across the footprint (`n`
/// at most [`MAX_FOOTPRINT_TAPS`]) and the colours it gives are averaged — a box prefilter of
/// the image to the pixel — and otherwise once, at `at`. When no point across the footprint
/// gives a colour, `at`'s own lookup answers.
pub fn prefiltered(
    at: &SurfacePoint,
    texel: impl Fn(&SurfacePoint) -> Option<DVec2>,
    lookup: impl Fn(&SurfacePoint) -> Option<Rgba>,
) -> Option<Rgba> {
    let n = footprint_taps(at, &texel);
    if n == 1 {
        return lookup(at);
    }
    let (mut sum, mut count) = (Vec4::ZERO, 0usize);
    for j in 0..n {
        for i in 0..n {
            let s = (i as f64 + 0.5) / n as f64 - 0.5;
            let t = (j as f64 + 0.5) / n as f64 - 0.5;
            if let Some(c) = lookup(&at.offset(s, t)) {
                sum += c;
                count += 1;
            }
        }
    }
    match count {
        0 => lookup(at),
        _ => Some(sum / count as f32),
    }
}

/// How many lookups along each side of `at`'s footprint an image whose texel `texel` gives
/// needs: the footprint's longer side in texels, rounded down, from 1 to
/// [`MAX_FOOTPRINT_TAPS`].
pub fn footprint_taps(at: &SurfacePoint, texel: impl Fn(&SurfacePoint) -> Option<DVec2>) -> usize {
    let Some(p) = texel(at) else { return 1 };
    let side = |s: f64, t: f64| texel(&at.offset(s, t)).map_or(0.0, |q| (q - p).length());
    let texels = side(1.0, 0.0).max(side(0.0, 1.0));
    if texels.is_finite() && texels >= 2.0 {
        (texels.floor() as usize).min(MAX_FOOTPRINT_TAPS)
    } else {
        1
    }
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
