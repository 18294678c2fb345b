//! The per-face weightings' tables ([`Weighting::BestFace`], [`Weighting::ViewMap`]), built for
//! every object of a render from its source's own visibility test at each triangle's centroid —
//! so views, layers and master textures honour them alike.
//!
//! Invariant: a table names a view for a triangle only if the source says that view sees the
//! triangle's centroid.

use super::view_map::ViewMap;
use super::{Source, SurfacePoint, Weighting};
use crate::geom::Mesh;
use glam::{DVec2, DVec3, Vec3};
use rayon::prelude::*;

/// How a render weighs the views at a pixel: per point, or from one table an object.
pub(super) enum FaceWeights {
    /// [`Weighting::Ulr`] or [`Weighting::Vdtm`], weighed at each surface point.
    PerPoint,
    /// Per object, per triangle: the view that sees its centroid largest, if any.
    BestFace(Vec<Vec<Option<usize>>>),
    /// Per object: its triangles' view maps.
    ViewMap(Vec<ViewMap>),
}

impl FaceWeights {
    /// The tables `weighting` needs for `meshes` seen by `source`.
    pub(super) fn build(weighting: Weighting, meshes: &[&Mesh], source: &impl Source) -> Self {
        match weighting {
            Weighting::Ulr { .. } | Weighting::Vdtm => FaceWeights::PerPoint,
            Weighting::BestFace => FaceWeights::BestFace(
                meshes
                    .iter()
                    .enumerate()
                    .map(|(o, mesh)| best_views(o, mesh, source))
                    .collect(),
            ),
            Weighting::ViewMap => FaceWeights::ViewMap(
                meshes
                    .iter()
                    .enumerate()
                    .map(|(o, mesh)| {
                        ViewMap::build(mesh, source.centres(), &|view, t, centroid| {
                            source.sees(view, &centroid_point(o, t, centroid))
                        })
                    })
                    .collect(),
            ),
        }
    }
}

/// Triangle `t` of object `o` at its centroid.
fn centroid_point(object: usize, triangle: usize, position: DVec3) -> SurfacePoint {
    SurfacePoint {
        object,
        triangle,
        bary: Vec3::splat(1.0 / 3.0),
        position,
        footprint: [DVec3::ZERO; 2],
        footprint_bary: [Vec3::ZERO; 2],
    }
}

/// Per triangle of object `o`, the view that sees its centroid with the largest projected area.
fn best_views(o: usize, mesh: &Mesh, source: &impl Source) -> Vec<Option<usize>> {
    (0..mesh.triangle_count())
        .into_par_iter()
        .map(|t| {
            let c = mesh.corners(t).map(|p| p.as_dvec3());
            let at = centroid_point(o, t, (c[0] + c[1] + c[2]) / 3.0);
            let mut best: Option<(usize, f64)> = None;
            for i in 0..source.centres().len() {
                if !source.sees(i, &at) {
                    continue;
                }
                let px: Option<Vec<DVec2>> = c.iter().map(|&p| source.pixel(i, p)).collect();
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
