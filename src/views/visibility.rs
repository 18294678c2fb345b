//! Per-view visibility: each view's depth map of a mesh, drawn by the rasterizer through the
//! view's undistorted pinhole, and the test that says whether a surface point is what the view
//! saw there. Occluded and out-of-frame points are refused, so a blend never copies an
//! occluder's pixels onto what it hides.
//!
//! Invariant: a point is seen ([`Sight::Seen`]) when it projects inside the image and the
//! depth map's texel under it does not hide it (the point at most a relative tolerance behind
//! the stored surface). Failing that, it is at the view's edge ([`Sight::Edge`]) when it is not
//! behind all four texels of its bilinear footprint (an empty texel being infinitely far) by
//! more than the tolerance plus half their depth range (beyond the image, as on an empty
//! texel, the view saw nothing): a surface the view saw is then not lost
//! where a render's pixel grid is not the view's, a fraction of a texel from a silhouette.

use super::CalibratedView;
use crate::camera::Projection;
use crate::frame::{FrameError, Image};
use crate::geom::Mesh;
use crate::raster::{NoAttributes, rasterize};
use crate::texturing::Sight;
use glam::{DVec2, DVec3};

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

    /// The pinhole the map was drawn through.
    pub fn camera(&self) -> &crate::camera::Pinhole {
        &self.camera
    }

    /// The map's generalized depth.
    pub fn gd(&self) -> &Image<f32> {
        &self.gd
    }

    /// Whether `world` is the surface this view saw at its pixel, within `tolerance` (relative
    /// depth; the module's rule). Points outside the frame, behind the camera or where the view
    /// saw nothing near them are not visible.
    pub fn sees(&self, world: DVec3, tolerance: f64) -> bool {
        self.sight(world, tolerance) == Sight::Seen
    }

    /// How the view sees `world` (the module's rule), within `tolerance` (relative depth).
    pub fn sight(&self, world: DVec3, tolerance: f64) -> Sight {
        match self.camera.project(world) {
            Some(p) => sight_at(&self.gd, p.uv, 1.0 / p.gd, tolerance),
            None => Sight::Hidden,
        }
    }
}

/// The module's visibility rule for a point of depth `z` projecting at `uv` in the depth map
/// `gd` (generalized depth `1/z`, zero where nothing was drawn).
pub(crate) fn sight_at(gd: &Image<f32>, uv: DVec2, z: f64, tolerance: f64) -> Sight {
    sight_in(gd.size(), |x, y| gd.get(x, y), uv, z, tolerance)
}

/// [`sight_at`] in a `w` × `h` depth map given texel by texel (`gd(x, y)`, zero where nothing
/// was seen).
pub(crate) fn sight_in(
    (w, h): (u32, u32),
    gd: impl Fn(u32, u32) -> f32,
    uv: DVec2,
    z: f64,
    tolerance: f64,
) -> Sight {
    // A point more than a texel outside the image has no texel of its footprint in it.
    let near_image = uv.x > -1.0 && uv.y > -1.0 && uv.x < w as f64 + 1.0 && uv.y < h as f64 + 1.0;
    if !(near_image && z.is_finite()) {
        return Sight::Hidden;
    }
    if uv.x >= 0.0 && uv.y >= 0.0 && uv.x < w as f64 && uv.y < h as f64 {
        let stored = gd(uv.x as u32, uv.y as u32) as f64;
        if stored > 0.0 && z <= (1.0 / stored) * (1.0 + tolerance) {
            return Sight::Seen;
        }
    }
    // The bilinear footprint: the texel centres on either side of `uv` in each axis. The
    // surface the view saw passes between them, so the point is hidden only when it is behind
    // all of them — by more than the tolerance and, as a shadow map's slope-scaled bias, half
    // the depth range they span (a crease between them is deeper than any of them). A texel
    // where the view saw nothing is infinitely far, but one at least must have seen something
    // (a point between four empty texels is a sliver the view missed).
    let (fx, fy) = (uv.x - 0.5, uv.y - 0.5);
    let (tx, ty) = (fx - fx.floor(), fy - fy.floor());
    let (x0, y0) = (fx.floor() as i64, fy.floor() as i64);
    let (mut nearest, mut farthest) = (f64::INFINITY, 0.0f64);
    for (x, y, weight) in [
        (x0, y0, (1.0 - tx) * (1.0 - ty)),
        (x0 + 1, y0, tx * (1.0 - ty)),
        (x0, y0 + 1, (1.0 - tx) * ty),
        (x0 + 1, y0 + 1, tx * ty),
    ] {
        // A texel the bilinear filter gives no weight is not in the footprint.
        if weight <= 0.0 {
            continue;
        }
        // Beyond the image, as on an empty texel, the view saw nothing.
        let inside = x >= 0 && y >= 0 && x < w as i64 && y < h as i64;
        let g = if inside {
            gd(x as u32, y as u32) as f64
        } else {
            0.0
        };
        let depth = if g > 0.0 { 1.0 / g } else { f64::INFINITY };
        nearest = nearest.min(depth);
        farthest = farthest.max(depth);
    }
    if nearest.is_finite() && z <= farthest * (1.0 + tolerance) + 0.5 * (farthest - nearest) {
        Sight::Edge
    } else {
        Sight::Hidden
    }
}

/// Whether the stored generalized depth `g` is the surface at depth `z`, within `tolerance`
/// (relative to `z`).
pub(crate) fn on_surface(g: f32, z: f64, tolerance: f64) -> bool {
    let g = g as f64;
    g > 0.0 && (1.0 / g - z).abs() <= tolerance * z
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 × 4 depth map: a surface at depth 2 over the left half, nothing on the right.
    fn half() -> Image<f32> {
        let mut gd = Image::new(4, 4, 0.0f32).unwrap();
        for y in 0..4 {
            for x in 0..2 {
                gd.set(x, y, 0.5);
            }
        }
        gd
    }

    #[test]
    fn a_point_is_seen_on_its_texel_at_the_edge_beside_it_and_hidden_behind() {
        let gd = half();
        let tol = DEFAULT_TOLERANCE;
        // On a texel that saw its surface, or in front of it.
        assert_eq!(sight_at(&gd, DVec2::new(1.5, 1.5), 2.0, tol), Sight::Seen);
        assert_eq!(sight_at(&gd, DVec2::new(1.5, 1.5), 1.0, tol), Sight::Seen);
        // Past the silhouette by a fraction of a texel: its texel is empty, its footprint
        // holds its surface.
        assert_eq!(sight_at(&gd, DVec2::new(2.3, 1.5), 2.0, tol), Sight::Edge);
        // Behind the surface, on it or beside it: hidden.
        assert_eq!(sight_at(&gd, DVec2::new(1.5, 1.5), 2.5, tol), Sight::Hidden);
        assert_eq!(sight_at(&gd, DVec2::new(1.2, 1.5), 2.5, tol), Sight::Hidden);
        // Two texels past the silhouette: nothing of its footprint saw anything.
        assert_eq!(sight_at(&gd, DVec2::new(3.5, 1.5), 2.0, tol), Sight::Hidden);
        // Just outside the image beside the surface: the edge; far outside, or not a number:
        // hidden, without overflow.
        assert_eq!(sight_at(&gd, DVec2::new(-0.2, 1.5), 2.0, tol), Sight::Edge);
        for uv in [
            DVec2::new(-5.0, 1.0),
            DVec2::new(1e300, 1.0),
            DVec2::new(f64::NAN, 1.0),
        ] {
            assert_eq!(sight_at(&gd, uv, 2.0, tol), Sight::Hidden, "{uv}");
        }
    }

    #[test]
    fn a_crease_between_texels_is_kept_by_the_slope_of_their_depths() {
        // Depths 2.0 and 2.4 on either side of a point at 2.3: behind the nearer texel by 15 %
        // but in front of the farther one, so the view's surface passes between them.
        let mut gd = Image::new(2, 2, 0.5f32).unwrap();
        gd.set(1, 0, 1.0 / 2.4);
        gd.set(1, 1, 1.0 / 2.4);
        assert_eq!(sight_at(&gd, DVec2::new(0.9, 1.0), 2.3, 0.01), Sight::Edge);
        // A point behind both by more than the tolerance and half their range is hidden.
        assert_eq!(
            sight_at(&gd, DVec2::new(0.9, 1.0), 2.7, 0.01),
            Sight::Hidden
        );
    }
}
