//! View-dependent projective texturing: a mesh seen from a new camera, each surface point
//! coloured by blending the calibrated views that see it — Debevec, Taylor and Malik's VDTM
//! weights (inverse angle, "Modeling and Rendering Architecture from Photographs", 1996) or the
//! weights of "Unstructured Lumigraph Rendering" (Buehler et al. 2001, §6: angle, resolution and
//! field-of-view penalties, the k best cameras, a threshold that hands over continuously).
//!
//! Invariants: at most `k` views contribute to a point, each of them sees it (the visibility
//! test of [`super::visibility`]), and the weights sum to one; a point no view sees is a hole,
//! filled by the named [`Holes`] policy.

use super::CalibratedView;
use super::visibility::{DEFAULT_TOLERANCE, DepthMap};
use crate::camera::{Pinhole, Projection};
use crate::frame::{FrameError, Image, Rgba, Wrap};
use crate::geom::Mesh;
use crate::raster::{StoreFragment, rasterize};
use glam::{DVec2, DVec3, Vec2, Vec4};
use rayon::prelude::*;

/// How the views that see a point are weighted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Weighting {
    /// VDTM: weight ∝ 1 / angle between the view's and the new camera's rays, over the `k`
    /// smallest angles.
    Vdtm,
    /// Unstructured Lumigraph: angle + `beta` × resolution penalty, the `k` best cameras
    /// weighted `1 − penalty / threshold`, the threshold the (k+1)-th best penalty.
    Ulr {
        /// Weight of the resolution penalty (SIBR uses 0.1).
        beta: f64,
    },
    /// Debevec's view map (1998): per triangle, a sphere of directions sampled with the nearest
    /// view that sees it; a new direction blends the (at most three) views of the spherical
    /// triangle it falls in by its barycentric coordinates ([`super::view_map`]).
    ViewMap,
    /// The baseline a single-texture bake gives: every triangle takes the one view that sees its
    /// centroid with the largest projected area, alone.
    BestFace,
}

impl Weighting {
    /// Whether the weighting weighs the views at each surface point (ULR, VDTM), which every
    /// projective renderer can honour; the view map and best face weigh per face, from a table
    /// of every view's visibility of every triangle that only [`render`] builds from depth maps.
    pub fn per_point(self) -> bool {
        matches!(self, Weighting::Ulr { .. } | Weighting::Vdtm)
    }

    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Weighting::Ulr { .. } => "ulr",
            Weighting::Vdtm => "vdtm",
            Weighting::ViewMap => "view-map",
            Weighting::BestFace => "best-face",
        }
    }
}

/// What a pixel whose surface no view sees shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Holes {
    /// Transparent black (alpha 0): the coverage of the blend is its alpha.
    Transparent,
    /// This colour, alpha 1.
    Fill(Rgba),
}

/// Settings of a blend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlendSettings {
    /// The weights.
    pub weighting: Weighting,
    /// Most views blended at a point.
    pub k: usize,
    /// Relative depth tolerance of the visibility test.
    pub tolerance: f64,
    /// Hole policy.
    pub holes: Holes,
}

impl Default for BlendSettings {
    /// ULR with β = 0.1, k = 4, 1 % depth tolerance, transparent holes.
    fn default() -> Self {
        BlendSettings {
            weighting: Weighting::Ulr { beta: 0.1 },
            k: 4,
            tolerance: DEFAULT_TOLERANCE,
            holes: Holes::Transparent,
        }
    }
}

/// The blending weights of the views that see surface point `x` from a camera at `eye` (the
/// per-triangle weightings, [`Weighting::ViewMap`] and [`Weighting::BestFace`], are weighted
/// here as [`Weighting::Vdtm`]; [`render`] uses their tables):
/// `(view index, weight)`, at most `k`, weights summing to one; empty when no view sees `x`.
/// `sees[i]` says whether view `i` sees `x`; `centres[i]` is its centre.
pub fn weights(
    x: DVec3,
    eye: DVec3,
    centres: &[DVec3],
    sees: impl Fn(usize) -> bool,
    weighting: Weighting,
    k: usize,
) -> Vec<(usize, f64)> {
    let v2 = x - eye;
    let mut penalties: Vec<(usize, f64)> = centres
        .iter()
        .enumerate()
        .filter(|&(i, _)| sees(i))
        .map(|(i, &c)| {
            let v1 = x - c;
            let angle = v1.angle_between(v2);
            let pen = match weighting {
                Weighting::Vdtm | Weighting::ViewMap | Weighting::BestFace => angle,
                Weighting::Ulr { beta } => {
                    let res = ((v1.length() - v2.length()) / v1.length()).max(0.0);
                    angle + beta * res
                }
            };
            (i, pen)
        })
        .collect();
    if penalties.is_empty() || k == 0 {
        return Vec::new();
    }
    penalties.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    // A view that looks along the new camera's ray exactly takes the point alone.
    const EXACT: f64 = 1e-9;
    if penalties[0].1 <= EXACT {
        return vec![(penalties[0].0, 1.0)];
    }
    let raw: Vec<(usize, f64)> = match weighting {
        Weighting::Vdtm | Weighting::ViewMap | Weighting::BestFace => penalties
            .iter()
            .take(k)
            .map(|&(i, p)| (i, 1.0 / p))
            .collect(),
        Weighting::Ulr { .. } => {
            let threshold = match penalties.get(k) {
                Some(&(_, p)) => p,
                // Fewer than k + 1 candidates: the worst of them still contributes a little.
                None => penalties[penalties.len() - 1].1 * (1.0 + 1e-3),
            };
            penalties
                .iter()
                .take(k)
                .map(|&(i, p)| (i, (1.0 - p / threshold).max(0.0)))
                .filter(|&(_, w)| w > 0.0)
                .collect()
        }
    };
    let total: f64 = raw.iter().map(|w| w.1).sum();
    if total.is_nan() || total <= 0.0 {
        return vec![(penalties[0].0, 1.0)];
    }
    raw.into_iter().map(|(i, w)| (i, w / total)).collect()
}

/// What a blend makes: the image and how many of its pixels were holes.
#[derive(Clone, Debug)]
pub struct Blend {
    /// Linear RGBA; alpha 0 on background and (with [`Holes::Transparent`]) holes.
    pub image: Image<Rgba>,
    /// Pixels that show the mesh.
    pub covered: usize,
    /// Of those, pixels no view sees.
    pub holes: usize,
}

/// Renders `mesh` through `camera` textured from `views` (their images loaded), each view's
/// visibility from `depth` (one map a view, [`DepthMap::of_all`]). `exclude` leaves one view
/// out (leave-one-out scoring).
pub fn render(
    camera: &Pinhole,
    mesh: &Mesh,
    views: &[CalibratedView],
    depth: &[DepthMap],
    settings: &BlendSettings,
    exclude: Option<usize>,
) -> Result<Blend, FrameError> {
    let (target, _) = rasterize(camera, &[mesh], &StoreFragment, None)?;
    let (w, h) = camera.resolution();
    let eye = camera.position();
    let centres: Vec<DVec3> = views.iter().map(|v| v.pose.centre()).collect();
    let fragments = target.attributes.pixels();
    let usable = |i: usize| Some(i) != exclude && views[i].image.is_some();
    let best_face = (settings.weighting == Weighting::BestFace)
        .then(|| best_views(mesh, views, depth, settings.tolerance, &usable));
    let view_map = (settings.weighting == Weighting::ViewMap)
        .then(|| super::view_map::ViewMap::build(mesh, views, depth, settings.tolerance, &usable));
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
                let c = mesh.corners(f.item.triangle as usize);
                let p = (c[0] * f.bary.x + c[1] * f.bary.y + c[2] * f.bary.z).as_dvec3();
                let sees = |i: usize| usable(i) && depth[i].sees(p, settings.tolerance);
                let t = f.item.triangle as usize;
                let ws = match (&best_face, &view_map) {
                    (Some(table), _) => table[t]
                        .filter(|&i| sees(i))
                        .map_or_else(Vec::new, |i| vec![(i, 1.0)]),
                    (_, Some(map)) => {
                        let mut ws = map.weights(t, (eye - p).normalize());
                        ws.retain(|&(i, _)| sees(i));
                        let sum: f64 = ws.iter().map(|w| w.1).sum();
                        ws.iter_mut().for_each(|w| w.1 /= sum);
                        ws
                    }
                    _ => weights(p, eye, &centres, sees, settings.weighting, settings.k),
                };
                if ws.is_empty() {
                    holes += 1;
                    *out = match settings.holes {
                        Holes::Transparent => Vec4::ZERO,
                        Holes::Fill(c) => c,
                    };
                    continue;
                }
                let mut colour = Vec4::ZERO;
                for (i, wgt) in ws {
                    let v = &views[i];
                    let (px, z) = v.project(p).unwrap_or((DVec2::ZERO, 0.0));
                    if let Some(img) = &v.image {
                        let s = if v.intrinsics.is_undistorted() {
                            sample_on_surface(img, depth[i].gd(), px, z)
                        } else {
                            img.sample_bilinear(
                                Vec2::new(px.x as f32, px.y as f32),
                                Wrap::Clamp,
                                Wrap::Clamp,
                            )
                        };
                        colour += s * wgt as f32;
                    }
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

/// How far (relative depth) a texel's surface may be from the sampled point and still be the
/// same surface, for [`sample_on_surface`].
const SAME_SURFACE: f64 = 0.05;

/// A bilinear lookup of a view's image at `px` that takes only the texels whose depth says
/// they show the surface at depth `z`: at a silhouette, plain bilinear filtering would mix the
/// background (or an occluder) into the surface's colour. The depth map `gd` is on the image's
/// own pixel grid (a view without distortion). Falls back to the nearest texel when no tap is on
/// the surface.
pub(crate) fn sample_on_surface(img: &Image<Rgba>, gd: &Image<f32>, px: DVec2, z: f64) -> Rgba {
    img.sample_bilinear_where(px, |x, y, _| {
        let g = gd.get(x, y) as f64;
        g > 0.0 && (1.0 / g - z).abs() <= SAME_SURFACE * z
    })
    .unwrap_or_else(|| img.sample_nearest(Vec2::new(px.x as f32, px.y as f32)))
}

/// Per triangle, the usable view that sees its centroid with the largest projected area.
fn best_views(
    mesh: &Mesh,
    views: &[CalibratedView],
    depth: &[DepthMap],
    tolerance: f64,
    usable: &(dyn Fn(usize) -> bool + Sync),
) -> Vec<Option<usize>> {
    (0..mesh.triangle_count())
        .into_par_iter()
        .map(|t| {
            let c = mesh.corners(t).map(|p| p.as_dvec3());
            let centroid = (c[0] + c[1] + c[2]) / 3.0;
            let mut best: Option<(usize, f64)> = None;
            for (i, v) in views.iter().enumerate() {
                if !usable(i) || !depth[i].sees(centroid, tolerance) {
                    continue;
                }
                let px: Option<Vec<DVec2>> = c.iter().map(|&p| v.project(p).map(|q| q.0)).collect();
                let Some(px) = px else { continue };
                let area = (px[1] - px[0]).perp_dot(px[2] - px[0]).abs() * 0.5;
                if best.is_none_or(|(_, a)| area > a) {
                    best = Some((i, area));
                }
            }
            best.map(|b| b.0)
        })
        .collect()
}

/// `view`'s image resampled to its undistorted pinhole ([`CalibratedView::pinhole`]); the image
/// itself when the lens has no distortion.
pub fn undistorted_image(view: &CalibratedView) -> Option<Image<Rgba>> {
    let img = view.image.as_ref()?;
    if view.intrinsics.is_undistorted() {
        return Some(img.clone());
    }
    let u = view.intrinsics.undistorted();
    let ((fx, fy), (cx, cy)) = (u.focal(), u.principal_point());
    let (w, h) = u.size();
    let mut out = Image::new(w, h, Vec4::ZERO).ok()?;
    out.pixels_mut()
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let n = DVec2::new((x as f64 + 0.5 - cx) / fx, (y as f64 + 0.5 - cy) / fy);
                let px = view.intrinsics.pixel_of(n);
                if view.contains(px) {
                    *o = img.sample_bilinear(
                        Vec2::new(px.x as f32, px.y as f32),
                        Wrap::Clamp,
                        Wrap::Clamp,
                    );
                }
            }
        });
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three views at known angles from the new camera's ray, worked by hand.
    #[test]
    fn ulr_weights_match_a_hand_worked_example() {
        let x = DVec3::ZERO;
        let eye = DVec3::new(0.0, 0.0, 2.0);
        // Views on a circle of radius 2 around x, at 10°, 20° and 40° from the eye's ray.
        let at = |deg: f64| {
            let r = deg.to_radians();
            DVec3::new(2.0 * r.sin(), 0.0, 2.0 * r.cos())
        };
        let centres = [at(10.0), at(20.0), at(40.0)];
        let w = weights(x, eye, &centres, |_| true, Weighting::Ulr { beta: 0.1 }, 2);
        // Equal distances: no resolution penalty. Threshold = the third penalty (40°):
        // w̃ = 1 − 10/40 = 0.75 and 1 − 20/40 = 0.5; normalised 0.6 and 0.4.
        assert_eq!(w.len(), 2);
        assert_eq!((w[0].0, w[1].0), (0, 1));
        assert!(
            (w[0].1 - 0.6).abs() < 1e-9 && (w[1].1 - 0.4).abs() < 1e-9,
            "{w:?}"
        );
    }

    #[test]
    fn weights_sum_to_one_and_pick_only_views_that_see() {
        let x = DVec3::ZERO;
        let eye = DVec3::new(0.3, 0.1, 2.0);
        let centres: Vec<DVec3> = (0..12)
            .map(|i| {
                let a = i as f64 * 0.5;
                DVec3::new(2.0 * a.sin(), 0.2, 2.0 * a.cos())
            })
            .collect();
        let sees = |i: usize| !i.is_multiple_of(3);
        for weighting in [Weighting::Vdtm, Weighting::Ulr { beta: 0.1 }] {
            for k in 1..6 {
                let w = weights(x, eye, &centres, sees, weighting, k);
                assert!(!w.is_empty() && w.len() <= k);
                assert!(w.iter().all(|&(i, _)| sees(i)));
                let total: f64 = w.iter().map(|p| p.1).sum();
                assert!((total - 1.0).abs() < 1e-12);
            }
        }
        assert!(weights(x, eye, &centres, |_| false, Weighting::Vdtm, 3).is_empty());
    }
}
