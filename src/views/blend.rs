//! View-dependent projective texturing from calibrated views: the [`Source`] whose views are
//! photographs with depth maps — a view sees a surface point where its depth map says the point
//! is what it photographed ([`super::visibility`]), and colours it by a bilinear lookup that
//! keeps to that surface ([`sample_on_surface`]). The renderer and the weights (VDTM, ULR, view
//! map, best face) are [`crate::texturing`]'s.
//!
//! Invariant: a view without a loaded image or a depth map, or the one left out, sees nothing.

use super::CalibratedView;
use super::visibility::{DepthMap, on_surface};
use crate::frame::{FrameError, Image, Rgba, pixel_centre};
use crate::geom::Mesh;
use crate::texturing::{Blend, BlendSettings, Sight, Source, SurfacePoint, prefiltered};
use glam::{DVec2, DVec3, Vec2, Vec4};
use rayon::prelude::*;

/// Calibrated views with their depth maps, as a projective-texturing [`Source`].
pub struct ViewSource<'a> {
    views: &'a [CalibratedView],
    depth: &'a [DepthMap],
    centres: Vec<DVec3>,
    tolerance: f64,
    exclude: Option<usize>,
}

impl<'a> ViewSource<'a> {
    /// `views` (their images loaded) with one depth map a view ([`DepthMap::of_all`]), the
    /// visibility test's relative depth `tolerance`; `exclude` leaves one view out
    /// (leave-one-out scoring).
    pub fn new(
        views: &'a [CalibratedView],
        depth: &'a [DepthMap],
        tolerance: f64,
        exclude: Option<usize>,
    ) -> ViewSource<'a> {
        ViewSource {
            views,
            depth,
            centres: views.iter().map(|v| v.pose.centre()).collect(),
            tolerance,
            exclude,
        }
    }
}

impl Source for ViewSource<'_> {
    fn centres(&self) -> &[DVec3] {
        &self.centres
    }

    fn sight(&self, view: usize, at: &SurfacePoint) -> Sight {
        match self.depth.get(view) {
            Some(d) if Some(view) != self.exclude && self.views[view].image.is_some() => {
                d.sight(at.position, self.tolerance)
            }
            _ => Sight::Hidden,
        }
    }

    fn colour(&self, view: usize, at: &SurfacePoint) -> Option<Rgba> {
        let v = &self.views[view];
        let img = v.image.as_ref()?;
        let gd = match v.intrinsics.is_undistorted() {
            true => Some(self.depth.get(view)?.gd()),
            false => None,
        };
        // Each lookup kept to the point's surface where the depth map is on the image's grid,
        // plain bilinear through the lens otherwise.
        let lookup = |q: &SurfacePoint| {
            let (px, z) = v.project(q.position)?;
            Some(match gd {
                Some(gd) => sample_on_surface(img, gd, px, z),
                None => v.colour_at(px)?,
            })
        };
        let texel = |q: &SurfacePoint| v.project(q.position).map(|p| p.0);
        prefiltered(at, texel, lookup)
    }

    fn pixel(&self, view: usize, p: DVec3) -> Option<DVec2> {
        self.views[view].project(p).map(|q| q.0)
    }
}

/// Renders `mesh` through `camera` textured from `views` (their images loaded), each view's
/// visibility from `depth` (one map a view, [`DepthMap::of_all`]). `exclude` leaves one view
/// out (leave-one-out scoring).
pub fn render(
    camera: &crate::camera::Pinhole,
    mesh: &Mesh,
    views: &[CalibratedView],
    depth: &[DepthMap],
    settings: &BlendSettings,
    exclude: Option<usize>,
) -> Result<Blend, FrameError> {
    render_through(camera, None, mesh, views, depth, settings, exclude)
}

/// [`render`] through the `lens` the camera's pixels look through, when it has one
/// ([`crate::texturing::render_through`]).
pub fn render_through(
    camera: &crate::camera::Pinhole,
    lens: Option<&crate::camera::Intrinsics>,
    mesh: &Mesh,
    views: &[CalibratedView],
    depth: &[DepthMap],
    settings: &BlendSettings,
    exclude: Option<usize>,
) -> Result<Blend, FrameError> {
    let source = ViewSource::new(views, depth, settings.tolerance, exclude);
    crate::texturing::render_through(camera, lens, &[mesh], &source, settings)
}

/// How far (relative depth) a texel's surface may be from the sampled point and still be the
/// same surface, for [`sample_on_surface`].
pub(crate) const SAME_SURFACE: f64 = 0.05;

/// A bilinear lookup of a view's image at `px` that takes only the texels whose depth says
/// they show the surface at depth `z`: at a silhouette, plain bilinear filtering would mix the
/// background (or an occluder) into the surface's colour. The depth map `gd` is on the image's
/// own pixel grid (a view without distortion). When no tap is on the surface (a point the
/// visibility test keeps at the view's edge), the nearest texel around the point that is on the
/// surface answers; failing that, the nearest texel.
pub(crate) fn sample_on_surface(img: &Image<Rgba>, gd: &Image<f32>, px: DVec2, z: f64) -> Rgba {
    let surface = |x: u32, y: u32, _: Rgba| on_surface(gd.get(x, y), z, SAME_SURFACE);
    img.sample_bilinear_where(px, surface)
        .or_else(|| nearest_where(img, px, surface))
        .unwrap_or_else(|| img.sample_nearest(Vec2::new(px.x as f32, px.y as f32)))
}

/// The colour of the texel nearest `px`, among the 3 × 3 around the texel under it, that
/// `keep` accepts; ties go to the first in row order.
pub(crate) fn nearest_where(
    img: &Image<Rgba>,
    px: DVec2,
    keep: impl Fn(u32, u32, Rgba) -> bool,
) -> Option<Rgba> {
    let (w, h) = img.size();
    // Beyond two texels outside the image, no texel of the 3 × 3 is in it.
    if !(px.x > -2.0 && px.y > -2.0 && px.x < w as f64 + 2.0 && px.y < h as f64 + 2.0) {
        return None;
    }
    let (cx, cy) = (px.x.floor() as i64, px.y.floor() as i64);
    let mut best: Option<(f64, Rgba)> = None;
    for y in cy - 1..=cy + 1 {
        for x in cx - 1..=cx + 1 {
            if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                continue;
            }
            let (x, y) = (x as u32, y as u32);
            let c = img.get(x, y);
            if !keep(x, y, c) {
                continue;
            }
            let d = (pixel_centre(x as f64, y as f64) - px).length_squared();
            if best.is_none_or(|(b, _)| d < b) {
                best = Some((d, c));
            }
        }
    }
    best.map(|(_, c)| c)
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
                let n =
                    (pixel_centre(x as f64, y as f64) - DVec2::new(cx, cy)) / DVec2::new(fx, fy);
                let px = view.intrinsics.pixel_of(n);
                if view.contains(px) {
                    *o = view.colour_at(px).unwrap_or(Vec4::ZERO);
                }
            }
        });
    Some(out)
}
