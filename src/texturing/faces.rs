//! The per-face weightings' tables ([`Weighting::BestFace`], [`Weighting::ViewMap`]), built for
//! every object of a render from its source's own visibility test at each triangle's centroid —
//! so views, layers and master textures honour them alike.
//!
//! The best-face table is a bake and, when asked ([`super::BlendSettings::seamless`]), made
//! seamless as the master bake is ([`super::seams`]): each face's looks (its mean colour in each view that sees it) are tested
//! for photometric outliers and give each view a gain; a face takes its largest agreeing view;
//! and the seams between faces from different views are levelled by per-vertex offsets.
//!
//! Invariant: a table names a view for a triangle only if the source says that view sees the
//! triangle's centroid.

use super::seams::{self, Look, Offsets, SeamReport, Seams};
use super::view_map::ViewMap;
use super::{Sight, Source, SurfacePoint, Weighting};
use crate::frame::{FrameError, Rgba};
use crate::geom::Mesh;
use glam::{DVec2, DVec3, Vec3};
use rayon::prelude::*;

/// How a render weighs the views at a pixel: per point, or from one table an object.
pub(super) enum FaceWeights {
    /// [`Weighting::Ulr`] or [`Weighting::Vdtm`], weighed at each surface point.
    PerPoint,
    /// Per object, per triangle: the view that sees its centroid largest (when seamless, among
    /// those whose colour of it agrees), if any; and how its colours are levelled.
    BestFace(BestFaces),
    /// Per object: its triangles' view maps.
    ViewMap(Vec<ViewMap>),
}

impl FaceWeights {
    /// The tables `weighting` needs for `meshes` seen by `source` (`seamless`: the best-face
    /// bake made seamless); refused when a seamless bake's looks could pass the memory budget.
    pub(super) fn build(
        weighting: Weighting,
        seamless: bool,
        meshes: &[&Mesh],
        source: &impl Source,
    ) -> Result<Self, FrameError> {
        Ok(match weighting {
            Weighting::Ulr { .. } | Weighting::Vdtm => FaceWeights::PerPoint,
            Weighting::BestFace => {
                FaceWeights::BestFace(BestFaces::build(meshes, source, seamless)?)
            }
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
        })
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

/// The best-face bake of a render: per object and triangle its view, per view its gain, per
/// object its seams' offsets.
pub(super) struct BestFaces {
    /// Per object, per triangle: its view.
    pub(super) table: Vec<Vec<Option<usize>>>,
    /// Per view: its gain.
    gains: Vec<Vec3>,
    /// Per object: its welded vertices and its seams' offsets.
    levelled: Vec<(Vec<u32>, Offsets)>,
    /// What making it seamless did (`None`: it was not).
    pub(super) report: Option<SeamReport>,
}

/// Where on a triangle its look is taken: the centroid and the points halfway from it to each
/// corner.
const LOOK_POINTS: [[f32; 3]; 4] = [
    [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
    [2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0],
    [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
    [1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0],
];

impl BestFaces {
    /// The best-face bake of `meshes` from `source`'s views; `seamless` or as it is (the
    /// largest view that sees a face's centroid, no gains, no offsets).
    fn build(
        meshes: &[&Mesh],
        source: &impl Source,
        seamless: bool,
    ) -> Result<BestFaces, FrameError> {
        let views = source.centres().len();
        if seamless {
            let faces: usize = meshes.iter().map(|m| m.triangle_count()).sum();
            crate::memory::check(
                || format!("a seamless best-face bake's looks of {views} views at {faces} faces"),
                crate::memory::times(
                    (faces as u64).saturating_mul(views as u64),
                    std::mem::size_of::<(f64, Look)>() as u64,
                ),
            )?;
        }
        // Per object, per triangle: the views that see its centroid, with its projected area and
        // (when seamless) its look.
        let candidates: Vec<Vec<Vec<(f64, Look)>>> = meshes
            .iter()
            .enumerate()
            .map(|(o, mesh)| candidates(o, mesh, source, seamless))
            .collect();
        let looks: Vec<Vec<Look>> = candidates
            .iter()
            .flatten()
            .map(|c| c.iter().map(|(_, l)| *l).collect())
            .collect();
        let (gains, agree) = match seamless {
            true => seams::gains_and_inliers(&looks, views),
            false => (
                vec![Vec3::ONE; views],
                looks.iter().map(|l| vec![true; l.len()]).collect(),
            ),
        };
        let mut report = SeamReport {
            outliers: agree.iter().flatten().filter(|a| !**a).count(),
            ..SeamReport::default()
        };
        let mut agree = agree.into_iter();
        let table: Vec<Vec<Option<usize>>> = candidates
            .iter()
            .map(|object| {
                object
                    .iter()
                    .zip(agree.by_ref())
                    .map(|(cands, agree)| {
                        let mut best: Option<(usize, f64)> = None;
                        for ((area, look), _) in cands.iter().zip(agree).filter(|(_, a)| *a) {
                            if best.is_none_or(|(_, a)| *area > a) {
                                best = Some((look.view as usize, *area));
                            }
                        }
                        best.map(|b| b.0)
                    })
                    .collect()
            })
            .collect();
        let mut levelled = Vec::with_capacity(meshes.len());
        for (o, mesh) in meshes.iter().enumerate().filter(|_| seamless) {
            let labels: Vec<Option<u32>> = table[o].iter().map(|v| v.map(|v| v as u32)).collect();
            let found = Seams::find(mesh, &labels);
            // The colour face `t`'s view gives its point at `bary`, with the view's gain.
            let sample = |t: usize, bary: Vec3| {
                let view = table[o][t]?;
                let at = point(o, mesh, t, bary);
                if source.sight(view, &at) == Sight::Hidden {
                    return None;
                }
                Some(source.colour(view, &at)?.truncate() * gains[view])
            };
            let offsets = seams::level(mesh, &labels, &found, sample);
            let step = found.step(sample);
            let after = found.step(|t, bary| {
                let label = labels[t]?;
                Some(sample(t, bary)? + offsets.at(mesh, &found.welded, t, label, bary))
            });
            // Summed over objects, weighted by their seams.
            let n = found.edges.len() as f64;
            report.step_gains += step * n;
            report.step_levelled += after * n;
            report.edges += found.edges.len();
            levelled.push((found.welded, offsets));
        }
        if report.edges > 0 {
            report.step_gains /= report.edges as f64;
            report.step_levelled /= report.edges as f64;
        }
        Ok(BestFaces {
            table,
            gains,
            levelled,
            report: seamless.then_some(report),
        })
    }

    /// `colour`, which `view` gave `at` (on object `at.object` of `meshes`), with the view's
    /// gain and the seam offsets of its face.
    pub(super) fn level(
        &self,
        meshes: &[&Mesh],
        at: &SurfacePoint,
        view: usize,
        colour: Rgba,
    ) -> Rgba {
        let Some((welded, offsets)) = self.levelled.get(at.object) else {
            return colour;
        };
        let shift = offsets.at(meshes[at.object], welded, at.triangle, view as u32, at.bary);
        (colour.truncate() * self.gains[view] + shift)
            .max(Vec3::ZERO)
            .extend(colour.w)
    }
}

/// Triangle `t` of object `o` of `mesh` at barycentrics `bary`.
fn point(object: usize, mesh: &Mesh, triangle: usize, bary: Vec3) -> SurfacePoint {
    let c = mesh.corners(triangle).map(|p| p.as_dvec3());
    SurfacePoint {
        object,
        triangle,
        bary,
        position: c[0] * f64::from(bary.x) + c[1] * f64::from(bary.y) + c[2] * f64::from(bary.z),
        footprint: [DVec3::ZERO; 2],
        footprint_bary: [Vec3::ZERO; 2],
    }
}

/// Per triangle of object `o`, the views that see its centroid, each with the triangle's
/// projected area in it and, with `looks`, its look: the mean colour of the view at
/// [`LOOK_POINTS`] it sees (whole when it sees them all; a view that sees none of them is left
/// out). Without `looks`, only the largest of them (the earlier on a tie).
fn candidates(o: usize, mesh: &Mesh, source: &impl Source, looks: bool) -> Vec<Vec<(f64, Look)>> {
    (0..mesh.triangle_count())
        .into_par_iter()
        .map(|t| {
            let c = mesh.corners(t).map(|p| p.as_dvec3());
            let at = centroid_point(o, t, (c[0] + c[1] + c[2]) / 3.0);
            let mut out = Vec::new();
            for i in 0..source.centres().len() {
                if !source.sees(i, &at) {
                    continue;
                }
                let px: Option<Vec<DVec2>> = c.iter().map(|&p| source.pixel(i, p)).collect();
                let Some(px) = px else { continue };
                let area = (px[1] - px[0]).perp_dot(px[2] - px[0]).abs() * 0.5;
                if !looks {
                    if out.first().is_none_or(|(a, _)| area > *a) {
                        let look = Look {
                            view: i as u32,
                            colour: Vec3::ZERO,
                            whole: true,
                        };
                        out = vec![(area, look)];
                    }
                    continue;
                }
                let (mut sum, mut n) = (Vec3::ZERO, 0);
                for b in LOOK_POINTS {
                    let p = point(o, mesh, t, Vec3::from(b));
                    if source.sees(i, &p)
                        && let Some(colour) = source.colour(i, &p)
                    {
                        sum += colour.truncate();
                        n += 1;
                    }
                }
                if n > 0 {
                    let colour = sum / n as f32;
                    out.push((
                        area,
                        Look {
                            view: i as u32,
                            colour,
                            whole: n == LOOK_POINTS.len(),
                        },
                    ));
                }
            }
            out
        })
        .collect()
}
