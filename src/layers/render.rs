//! Layered projective rendering ("Layered view-dependent projective textures" §5): every
//! object textured by the image layers that hold it, each through its layer's asymmetric
//! sub-frustum ([`super::frustum`]) — a [`Source`] of [`crate::texturing`], whose renderer
//! weighs and blends the views — and, beside it, plain projective texturing (whole photographs,
//! no visibility), the baseline whose artefacts the layers remove.
//!
//! Invariants: no geometry is subdivided; a view sees a surface point only through the layer
//! that holds the point's triangle, and only where that layer knows the texel (alpha ≥ ½) and
//! the texel is that surface (the layer's own depth, so an object's far side is not painted with
//! its near side) — or, where no view sees it so, at the layer's edge (the rule of
//! [`crate::views::visibility`] on the layer's depth); from an input viewpoint that view alone
//! colours every point it shows.

use super::LayerSet;
use crate::camera::Pinhole;
use crate::frame::{FrameError, Image, Rgba};
use crate::geom::Mesh;
use crate::texturing::{Blend, BlendSettings, Sight, Source, SurfacePoint};
use crate::views::CalibratedView;
use crate::views::blend::{SAME_SURFACE, nearest_where};
use crate::views::visibility::{on_surface, sight_in};
use glam::{DVec2, DVec3};

/// A layer set as a texturing source: each view answers through the layer that holds the
/// point's triangle.
struct Layered<'a> {
    set: &'a LayerSet,
    centres: Vec<DVec3>,
    tolerance: f64,
}

impl<'a> Layered<'a> {
    /// The layer of `view` that holds `at`'s triangle (its image and depth), and where `at`
    /// lands in it: texel and depth.
    fn texel(
        &self,
        view: usize,
        at: &SurfacePoint,
    ) -> Option<(&'a Image<Rgba>, &'a Image<f32>, DVec2, f64)> {
        let vl = &self.set.layers[view];
        let l = vl.assignment.get(at.object)?.layer(at.triangle)? as usize;
        let (tx, z) = self.set.projectors[view][l].texel(at.position)?;
        Some((&vl.layers[l].image, &vl.depth[l], tx, z))
    }
}

impl Source for Layered<'_> {
    fn centres(&self) -> &[DVec3] {
        &self.centres
    }

    fn sight(&self, view: usize, at: &SurfacePoint) -> Sight {
        let Some((image, depth, tx, z)) = self.texel(view, at) else {
            return Sight::Hidden;
        };
        if sample_layer(image, depth, tx, z, self.tolerance).is_some() {
            return Sight::Seen;
        }
        // The layer saw nothing where it holds no texel (alpha below ½).
        let known = |x, y| {
            if image.get(x, y).w >= 0.5 {
                depth.get(x, y)
            } else {
                0.0
            }
        };
        match sight_in(depth.size(), known, tx, z, self.tolerance) {
            Sight::Hidden => Sight::Hidden,
            _ if edge_colour(image, depth, tx, z).is_some() => Sight::Edge,
            _ => Sight::Hidden,
        }
    }

    fn colour(&self, view: usize, at: &SurfacePoint) -> Option<Rgba> {
        let lookup = |q: &SurfacePoint| {
            let (image, depth, tx, z) = self.texel(view, q)?;
            sample_layer(image, depth, tx, z, self.tolerance)
                .or_else(|| edge_colour(image, depth, tx, z))
        };
        crate::texturing::prefiltered(at, |q| self.texel(view, q).map(|t| t.2), lookup)
    }

    fn pixel(&self, view: usize, p: DVec3) -> Option<DVec2> {
        self.set.views[view].project(p).map(|q| q.0)
    }
}

/// Whole photographs projected on everything in their frusta, hidden or not.
struct Photographs<'a> {
    views: &'a [CalibratedView],
    centres: Vec<DVec3>,
}

impl Source for Photographs<'_> {
    fn centres(&self) -> &[DVec3] {
        &self.centres
    }

    fn sight(&self, view: usize, at: &SurfacePoint) -> Sight {
        match self.colour(view, at) {
            Some(_) => Sight::Seen,
            None => Sight::Hidden,
        }
    }

    fn colour(&self, view: usize, at: &SurfacePoint) -> Option<Rgba> {
        let v = &self.views[view];
        let (px, _) = v.project(at.position)?;
        if !v.contains(px) {
            return None;
        }
        v.colour_at(px)
    }

    fn pixel(&self, view: usize, p: DVec3) -> Option<DVec2> {
        self.views[view].project(p).map(|q| q.0)
    }
}

/// Renders the layer set's meshes through `camera` (`settings.tolerance`: how far a layer's
/// texel may be from the surface point and still be that surface).
pub fn render(
    camera: &Pinhole,
    set: &LayerSet,
    settings: &BlendSettings,
) -> Result<Blend, FrameError> {
    render_through((camera, None), set, settings)
}

/// [`render`] through the `lens` the camera's pixels look through, when it has one
/// ([`crate::texturing::render_through`]).
pub fn render_through(
    (camera, lens): (&Pinhole, Option<&crate::camera::Intrinsics>),
    set: &LayerSet,
    settings: &BlendSettings,
) -> Result<Blend, FrameError> {
    let source = Layered {
        set,
        centres: set.views.iter().map(|v| v.pose.centre()).collect(),
        tolerance: settings.tolerance,
    };
    crate::texturing::render_through(camera, lens, &set.mesh_refs(), &source, settings)
}

/// The table `settings.weighting` weighs the layer set's meshes by (per object, per face: the
/// best face's view, or the view maps; none for the per-point weightings), as [`render`] builds
/// it: for a renderer that blends elsewhere (the GPU's).
pub fn face_table(
    set: &LayerSet,
    settings: &BlendSettings,
) -> Result<crate::texturing::FaceTable, FrameError> {
    let source = Layered {
        set,
        centres: set.views.iter().map(|v| v.pose.centre()).collect(),
        tolerance: settings.tolerance,
    };
    crate::texturing::face_table(settings.weighting, &set.mesh_refs(), &source)
}

/// The table `weighting` weighs `meshes` by under plain projective texturing (whole
/// photographs), as [`render_projective`] builds it: for a renderer that blends elsewhere (the
/// GPU's).
pub fn projective_face_table(
    meshes: &[&Mesh],
    views: &[CalibratedView],
    weighting: crate::texturing::Weighting,
) -> Result<crate::texturing::FaceTable, FrameError> {
    let source = Photographs {
        views,
        centres: views.iter().map(|v| v.pose.centre()).collect(),
    };
    crate::texturing::face_table(weighting, meshes, &source)
}

/// Plain projective texturing: each view's whole photograph projected onto everything in its
/// frustum, hidden or not (`views` with their images loaded, undistorted pinholes).
pub fn render_projective(
    camera: &Pinhole,
    meshes: &[&Mesh],
    views: &[CalibratedView],
    settings: &BlendSettings,
) -> Result<Blend, FrameError> {
    render_projective_through((camera, None), meshes, views, settings)
}

/// [`render_projective`] through the `lens` the camera's pixels look through, when it has one
/// ([`crate::texturing::render_through`]).
pub fn render_projective_through(
    (camera, lens): (&Pinhole, Option<&crate::camera::Intrinsics>),
    meshes: &[&Mesh],
    views: &[CalibratedView],
    settings: &BlendSettings,
) -> Result<Blend, FrameError> {
    let source = Photographs {
        views,
        centres: views.iter().map(|v| v.pose.centre()).collect(),
    };
    crate::texturing::render_through(camera, lens, meshes, &source, settings)
}

/// The colour of a layer at texel `tx` for a point at depth `z` that the layer sees only at its
/// edge ([`Sight::Edge`]): its texels that the layer holds (alpha ≥ ½) and whose depth is the
/// point's surface, bilinear, else the nearest of them around `tx`.
fn edge_colour(img: &Image<Rgba>, depth: &Image<f32>, tx: DVec2, z: f64) -> Option<Rgba> {
    let surface =
        |x: u32, y: u32, c: Rgba| c.w >= 0.5 && on_surface(depth.get(x, y), z, SAME_SURFACE);
    img.sample_bilinear_where(tx, surface)
        .or_else(|| nearest_where(img, tx, surface))
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
