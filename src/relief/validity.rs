//! When a relief impostor stops being good enough (paper 3 §3): the brute-force measure — the
//! ratio of interpolated to direct texels in the pre-warped image
//! ([`Prewarped::interpolated_ratio`](super::Prewarped::interpolated_ratio)), 20 % by default —
//! and the critical-point heuristic that predicts it from a handful of texels: the image split
//! in regions, each with its critical pair (4-neighbours, both covered, with the largest
//! difference in displacement). For an eye, a pair's warped positions are `E` texels apart; the
//! heuristic is the mean over regions of the stretch `max(0, E − 1)`. (The paper's Eq. 5–6
//! write `|1 + Δu₁ − Δu₂|` for both axes, which fits a pair one texel apart in `u` for one and
//! in `v` for the other; the distance between warped positions is the form that holds for
//! either — docs/conventions.md §7.4.) Also Schaufler's test for skipping a warp: the largest
//! move of any critical texel since the last warp.
//!
//! Invariants: pairs are chosen in a fixed scan order (the first maximum wins), so the
//! heuristic is deterministic; an eye the warp cannot serve has infinite error.

use super::ReliefImpostor;
use super::prewarp::{Coefficients, Eye, prewarp};
use crate::frame::{Image, Rgba};
use glam::{DVec2, DVec3};

/// Default brute-force threshold: interpolated over direct texels (paper §3, Fig. 3: 20 %).
pub const RATIO_THRESHOLD: f64 = 0.2;

/// A texel of a critical pair: centre `(u, v)` and displacement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CriticalTexel {
    /// Texel centre, texel coordinates.
    pub at: DVec2,
    /// Displacement, world units.
    pub d: f64,
}

/// The critical pairs of an impostor, one per region that has a covered pair.
#[derive(Clone, Debug, PartialEq)]
pub struct CriticalPairs {
    /// Regions a side.
    pub grid: u32,
    /// The pairs.
    pub pairs: Vec<(CriticalTexel, CriticalTexel)>,
}

impl CriticalPairs {
    /// The critical pairs of `impostor` over a `grid × grid` split of its image.
    pub fn of(impostor: &ReliefImpostor, grid: u32) -> Self {
        let grid = grid.max(1);
        let (w, h) = (
            impostor.frame.width as usize,
            impostor.frame.height as usize,
        );
        let g = grid as usize;
        let mut best: Vec<Option<(f64, CriticalTexel, CriticalTexel)>> = vec![None; g * g];
        let texel = |u: usize, v: usize| CriticalTexel {
            at: DVec2::new(u as f64 + 0.5, v as f64 + 0.5),
            d: impostor.displacement(v * w + u),
        };
        for v in 0..h {
            for u in 0..w {
                let i = v * w + u;
                if !impostor.covered(i) {
                    continue;
                }
                let region = (v * g / h) * g + u * g / w;
                for (nu, nv) in [(u + 1, v), (u, v + 1)] {
                    if nu >= w || nv >= h || !impostor.covered(nv * w + nu) {
                        continue;
                    }
                    let (a, b) = (texel(u, v), texel(nu, nv));
                    let jump = (a.d - b.d).abs();
                    if best[region].is_none_or(|(j, _, _)| jump > j) {
                        best[region] = Some((jump, a, b));
                    }
                }
            }
        }
        Self {
            grid,
            pairs: best.into_iter().flatten().map(|(_, a, b)| (a, b)).collect(),
        }
    }

    /// The heuristic for `eye`: mean stretch `max(0, E − 1)` over the pairs, texels;
    /// `f64::INFINITY` where no warp serves the eye, 0 when there are no pairs.
    pub fn error(&self, k: Option<&Coefficients>) -> f64 {
        let Some(k) = k else {
            return f64::INFINITY;
        };
        if self.pairs.is_empty() {
            return 0.0;
        }
        let mut sum = 0.0;
        for (a, b) in &self.pairs {
            match (warp(k, a), warp(k, b)) {
                (Some(p), Some(q)) => sum += ((p - q).length() - 1.0).max(0.0),
                _ => return f64::INFINITY,
            }
        }
        sum / self.pairs.len() as f64
    }

    /// Schaufler's test: the largest distance, in texels, any critical texel moves between the
    /// warps for `k_then` and `k_now` (`INFINITY` if either warp fails).
    pub fn largest_move(&self, k_then: &Coefficients, k_now: &Coefficients) -> f64 {
        let mut worst: f64 = 0.0;
        for t in self.pairs.iter().flat_map(|(a, b)| [a, b]) {
            match (warp(k_then, t), warp(k_now, t)) {
                (Some(p), Some(q)) => worst = worst.max((p - q).length()),
                _ => return f64::INFINITY,
            }
        }
        worst
    }
}

fn warp(k: &Coefficients, t: &CriticalTexel) -> Option<DVec2> {
    Some(DVec2::new(k.warp_u(t.at.x, t.d)?, k.warp_v(t.at.y, t.d)?))
}

/// Both verdicts for one eye: the heuristic's error and the brute-force ratio.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Verdicts {
    /// Critical-point heuristic (mean stretch, texels).
    pub heuristic: f64,
    /// Interpolated over direct texels of the actual pre-warp.
    pub ratio: f64,
}

/// Both measures of `impostor` seen from `eye`.
pub fn verdicts(impostor: &ReliefImpostor, pairs: &CriticalPairs, eye: DVec3) -> Verdicts {
    let k = Coefficients::new(&impostor.frame, Eye::Point(eye));
    Verdicts {
        heuristic: pairs.error(k.as_ref()),
        ratio: prewarp(impostor, Eye::Point(eye), true)
            .map_or(f64::INFINITY, |p| p.interpolated_ratio()),
    }
}

/// The map of paper Fig. 3: eyes on an `n × n` grid over the square of half side `extent`
/// around `centre` in the plane through it spanned by `x` and `y` (unit, orthogonal), each
/// cell green where the impostor stays valid by the brute-force ratio (at most `threshold`),
/// red where it does not, grey where the eye is inside `keep_out` or behind the base plane.
/// The impostor's own eye is marked white. Returns the image and the valid share of cells.
#[allow(clippy::too_many_arguments)]
pub fn validity_map(
    impostor: &ReliefImpostor,
    centre: DVec3,
    x: DVec3,
    y: DVec3,
    extent: f64,
    keep_out: f64,
    n: u32,
    threshold: f64,
) -> Result<(Image<Rgba>, f64), crate::frame::FrameError> {
    use rayon::prelude::*;
    let cells: Vec<Rgba> = (0..n * n)
        .into_par_iter()
        .map(|i| {
            let (cx, cy) = ((i % n) as f64, (i / n) as f64);
            let s = |c: f64| (c + 0.5) / n as f64 * 2.0 - 1.0;
            let eye = centre + x * (s(cx) * extent) - y * (s(cy) * extent);
            if (eye - centre).length() < keep_out {
                return Rgba::new(0.3, 0.3, 0.3, 1.0);
            }
            match prewarp(impostor, Eye::Point(eye), true) {
                None => Rgba::new(0.3, 0.3, 0.3, 1.0),
                Some(p) if p.interpolated_ratio() <= threshold => Rgba::new(0.1, 0.6, 0.15, 1.0),
                Some(_) => Rgba::new(0.7, 0.12, 0.1, 1.0),
            }
        })
        .collect();
    let valid = cells.iter().filter(|c| c.y > 0.5).count() as f64;
    let tested = cells.iter().filter(|c| c.x != 0.3).count().max(1) as f64;
    let mut image = Image::from_vec(n, n, cells)?;
    // The impostor's own eye.
    let r = impostor.eye - centre;
    let to_cell = |a: f64| ((a / extent + 1.0) * 0.5 * n as f64).floor();
    let (ex, ey) = (to_cell(r.dot(x)), to_cell(-r.dot(y)));
    if (0.0..n as f64).contains(&ex) && (0.0..n as f64).contains(&ey) {
        image.set(ex as u32, ey as u32, Rgba::ONE);
    }
    Ok((image, valid / tested))
}

#[cfg(test)]
mod tests {
    use super::super::prewarp::tests_support::bumped;
    use super::*;

    #[test]
    fn the_critical_pair_is_the_largest_jump_of_its_region() {
        // One step of height 2 between texels 9 and 10 of every row, small ripples elsewhere.
        let imp = bumped(16, |u, v| {
            Some(if u >= 10 {
                2.0
            } else {
                ((u + v) % 3) as f32 * 0.1
            })
        });
        let pairs = CriticalPairs::of(&imp, 2);
        assert_eq!(pairs.pairs.len(), 4);
        // The right-hand regions hold no step (all 2.0 but the ripple-free side): their jump is
        // 0; the left-hand regions (u < 8) hold ripples only. The step is in the right column
        // of regions (u = 9 belongs to region column 1 since 9·2/16 = 1).
        let (a, b) = pairs.pairs[1];
        assert_eq!((a.at.x, b.at.x), (9.5, 10.5));
        assert!(((a.d - b.d).abs() - 2.0).abs() < 1e-6);
    }

    #[test]
    fn the_heuristic_grows_as_the_eye_moves_off_the_source_view() {
        let imp = bumped(32, |u, v| {
            let (x, y) = (u as f32 - 16.0, v as f32 - 16.0);
            Some(if x * x + y * y < 60.0 { 3.0 } else { 0.0 })
        });
        let pairs = CriticalPairs::of(&imp, 4);
        let at = |x: f64| {
            let eye = imp.frame.point(16.0 + x, 16.0, 40.0);
            pairs.error(Coefficients::new(&imp.frame, Eye::Point(eye)).as_ref())
        };
        let (e0, e1, e2) = (at(0.0), at(20.0), at(60.0));
        assert!(e0 < e1 && e1 < e2, "{e0} {e1} {e2}");
        // And the brute force agrees in direction.
        let ratio = |x: f64| {
            let eye = imp.frame.point(16.0 + x, 16.0, 40.0);
            verdicts(&imp, &pairs, eye).ratio
        };
        assert!(ratio(0.0) < ratio(60.0));
        // Behind the plane: infinite.
        assert!(pairs.error(None).is_infinite());
    }

    #[test]
    fn schaufler_moves_are_zero_for_the_same_eye() {
        let imp = bumped(16, |u, _| Some(u as f32 * 0.1));
        let pairs = CriticalPairs::of(&imp, 2);
        let k = |x: f64| Coefficients::new(&imp.frame, Eye::Point(imp.frame.point(x, 8.0, 20.0)));
        let (a, b) = (k(8.0).unwrap(), k(8.5).unwrap());
        assert_eq!(pairs.largest_move(&a, &a), 0.0);
        assert!(pairs.largest_move(&a, &b) > 0.0);
    }
}
