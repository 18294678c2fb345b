//! Choosing a SPOC's strength per object (paper 1 §4; docs/conventions.md §3.2).
//!
//! The rule `k = 2Δ/z_O` sizes the push for the parallax of the rays' region, but the push has a
//! price: texels stretched across the pushed-out silhouette, where the walk's thickness rule
//! invents hits in the gaps between thin parts and steps through a thin part to what lies behind
//! it (`docs/fidelity.md` measures both on the Cesium milk truck). An object with little to
//! disocclude — a slab, an assembly of thin parts — can lose more there than it gains from the
//! surface the push uncovers. [`choose_strength`] builds the impostor at the rule's strength, at
//! half and a quarter of it, and at zero — where the SPOC is its pinhole, framed alike — fires
//! held-out rays at each and at the exact BVH, and keeps the rule's push unless a weaker one
//! agrees more often by [`STRENGTH_MARGIN`] of the rays, and the push kept only if it beats zero
//! by as much; otherwise the SPOC falls back to its pinhole ([`StrengthChoice::camera`]), and
//! says so.
//!
//! Invariants: the rays are like those the impostor will answer but never a check's own (a bake's
//! from the region with their own seed, [`region_rays`]; a reflector check's from a second
//! viewer); the choice depends only on the mesh, the camera's placement, the layers, the
//! resolution and those rays.

use super::{ImpostorCamera, LayerError, Layers, albedo_of, build};
use crate::camera::CameraError;
use crate::frame::FrameError;
use crate::geom::{Mesh, Ray, sphere_rays};
use crate::memory::OverBudget;
use crate::trace::{Bvh, RayQuery};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::Arc;
use thiserror::Error;

/// The share of the held-out rays a push must win by over the pinhole (`k = 0`) to be kept.
pub const STRENGTH_MARGIN: f64 = 0.001;

/// The fewest held-out rays a choice is made on; with fewer, the rule's strength stands.
pub const MIN_STRENGTH_RAYS: usize = 1000;

/// Rays from the region the choice fires at each candidate.
pub const STRENGTH_RAYS: usize = 8000;

/// The seed of those rays (the checks draw theirs with others).
const STRENGTH_SEED: u64 = 0x005e_ed0f_5b0c;

/// What [`choose_strength`] tried and kept.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StrengthChoice {
    /// The rule's strength, `2Δ/z_O` clamped.
    pub rule: f64,
    /// The strength kept: one of those tried; 0 where the SPOC falls back to its pinhole.
    pub chosen: f64,
    /// Each strength tried and the share of the held-out rays its impostor agreed on.
    pub tried: Vec<(f64, f64)>,
    /// Rays fired at each.
    pub rays: usize,
}

impl StrengthChoice {
    /// Whether the SPOC fell back to its pinhole.
    pub fn fell_back(&self) -> bool {
        self.chosen == 0.0
    }

    /// The camera to build: the SPOC at the chosen strength, or the pinhole it falls back to.
    pub fn camera(&self) -> super::ViewCamera {
        match self.fell_back() {
            true => super::ViewCamera::Pinhole,
            false => super::ViewCamera::Spoc(Some(self.chosen)),
        }
    }
}

/// "SPOC strength k = K, chosen from …: the rule's k = R (a %), R/2 (b %), …".
impl std::fmt::Display for StrengthChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let tried: Vec<String> = self
            .tried
            .iter()
            .map(|(k, a)| format!("{k:.3} {:.2} %", a * 100.0))
            .collect();
        if self.tried.is_empty() {
            return write!(
                f,
                "SPOC strength k = {:.3} (the rule's: {} held-out rays are too few to choose on)",
                self.rule, self.rays
            );
        }
        let what = if self.fell_back() {
            "falls back to the pinhole: no push beat it by 0.1 % of the rays".to_string()
        } else {
            format!("SPOC strength k = {:.3}", self.chosen)
        };
        write!(
            f,
            "{what} (rule k = {:.3}; on {} held-out rays, k and agreement: {})",
            self.rule,
            self.rays,
            tried.join(", ")
        )
    }
}

/// Why a strength could not be chosen.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum StrengthError {
    /// A candidate's camera could not be placed.
    #[error("placing the SPOC: {0}")]
    Camera(#[from] CameraError),
    /// A candidate's maps could not be allocated.
    #[error("building an impostor: {0}")]
    Build(#[from] FrameError),
    /// A candidate's layers could not be peeled.
    #[error("peeling an impostor's layers: {0}")]
    Layers(#[from] LayerError),
    /// The mesh's BVH would pass the memory budget.
    #[error(transparent)]
    Budget(#[from] OverBudget),
}

/// [`STRENGTH_RAYS`] rays from the sphere of radius `region` around `eye`, aimed at `mesh`'s
/// box: the rays a baked impostor serves, drawn with the choice's own seed.
pub fn region_rays(mesh: &Mesh, (eye, region): (Vec3, f32)) -> Vec<Ray> {
    sphere_rays(eye, region, mesh.bounds(), STRENGTH_RAYS, STRENGTH_SEED)
}

/// Chooses the strength of a SPOC of `mesh` whose camera `camera_for(k)` places (the rule's
/// strength with `None`), peeled into `layers`, on `rays` like those it will answer but not
/// the same (the module's rule; with fewer than [`MIN_STRENGTH_RAYS`], the rule's strength).
pub fn choose_strength(
    mesh: &Mesh,
    camera_for: impl Fn(Option<f64>) -> Result<ImpostorCamera, CameraError>,
    layers: Layers,
    rays: &[Ray],
) -> Result<StrengthChoice, StrengthError> {
    let rule = match camera_for(None)? {
        ImpostorCamera::Spoc(s) => s.strength(),
        _ => return Err(CameraError::Degenerate("a strength is a SPOC's").into()),
    };
    if rays.len() < MIN_STRENGTH_RAYS {
        // Too little to choose on: the rule stands.
        return Ok(StrengthChoice {
            rule,
            chosen: rule,
            tried: Vec::new(),
            rays: rays.len(),
        });
    }
    let target = Arc::new(mesh.clone());
    let exact = Bvh::build(vec![target.clone()])?;
    let answers: Vec<_> = rays
        .par_iter()
        .map(|r| exact.closest_hit(r, f32::INFINITY))
        .collect();
    let albedo = albedo_of(mesh);
    let mut tried = Vec::new();
    for k in [rule, rule / 2.0, rule / 4.0, 0.0] {
        let mut impostor = build(camera_for(Some(k))?, mesh, 0, &albedo)?;
        if layers != Layers::ONE {
            impostor.peel(mesh, 0, &albedo, layers)?;
        }
        impostor.prepare_walks();
        let agreeing = rays
            .par_iter()
            .zip(&answers)
            .filter(|(r, e)| {
                let own = impostor.walk(r, f32::INFINITY).0;
                impostor.agrees(e.as_ref(), own.as_ref())
            })
            .count();
        tried.push((k, agreeing as f64 / rays.len().max(1) as f64));
    }
    // The rule's push stands unless a weaker one beats it by the margin; the best push stands
    // unless it fails to beat the pinhole by the margin.
    let pinhole = tried[3].1;
    let best = tried[1..3].iter().fold(
        tried[0],
        |b, t| {
            if t.1 >= b.1 + STRENGTH_MARGIN { *t } else { b }
        },
    );
    let chosen = if best.1 >= pinhole + STRENGTH_MARGIN {
        best.0
    } else {
        0.0
    };
    Ok(StrengthChoice {
        rule,
        chosen,
        tried,
        rays: rays.len(),
    })
}
