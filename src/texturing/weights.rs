//! How the views that see a surface point are weighted: Debevec, Taylor and Malik's VDTM weights
//! (inverse angle, "Modeling and Rendering Architecture from Photographs", 1996), the weights of
//! "Unstructured Lumigraph Rendering" (Buehler et al. 2001, §6: angle, resolution and
//! field-of-view penalties, the k best cameras, a threshold that hands over continuously), and
//! the two per-face weightings ([`Weighting::ViewMap`], [`Weighting::BestFace`]) whose tables
//! [`super::faces`] builds.
//!
//! Invariants: [`weights`] returns at most `k` views, each of which sees the point, with weights
//! summing to one; ties are broken by view index, so the result does not depend on thread count.

use crate::frame::Rgba;
use glam::DVec3;

/// Default relative depth tolerance of "this texel is this surface" (1 %).
pub const DEFAULT_TOLERANCE: f64 = 0.01;

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
    /// Whether the weighting weighs the views at each surface point (ULR, VDTM); the view map
    /// and best face weigh per face, from a table of every view's visibility of every triangle's
    /// centroid ([`super::faces::FaceWeights`]).
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
    /// The colour of the nearest pixel of the mesh that a view sees, counted across the mesh's
    /// pixels ([`super::fill`]); transparent where the hole's patch of the mesh has none.
    Nearest,
}

/// Settings of a projective render, whatever textures it: views, layers or master textures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlendSettings {
    /// The weights.
    pub weighting: Weighting,
    /// Most views blended at a point (per-point weightings).
    pub k: usize,
    /// Relative depth tolerance of the visibility tests that use depth (views, layers).
    pub tolerance: f64,
    /// Hole policy.
    pub holes: Holes,
    /// Whether each view's image is prefiltered to the render pixel's footprint
    /// ([`super::prefiltered`]); without it, one bilinear lookup a view.
    pub prefilter: bool,
    /// With [`Weighting::BestFace`]: make its one-view-a-face bake seamless
    /// ([`super::seams`]: photometric outliers left out, one gain a view, seams levelled).
    /// Other weightings blend as they do without it.
    pub seamless: bool,
}

impl Default for BlendSettings {
    /// ULR with β = 0.1, k = 4, 1 % depth tolerance, transparent holes, one bilinear lookup a
    /// view, best-face bakes as they are.
    fn default() -> Self {
        BlendSettings {
            weighting: Weighting::Ulr { beta: 0.1 },
            k: 4,
            tolerance: DEFAULT_TOLERANCE,
            holes: Holes::Transparent,
            prefilter: false,
            seamless: false,
        }
    }
}

/// The per-point blending weights of the views that see surface point `x` from a camera at
/// `eye` (the per-face weightings are weighted here as [`Weighting::Vdtm`]; the renderer uses
/// their tables): `(view index, weight)`, at most `k`, weights summing to one; empty when no
/// view sees `x`. `sees(i)` says whether view `i` sees `x`; `centres[i]` is its centre.
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
