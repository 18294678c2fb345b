//! When a relief impostor stops being good enough (paper 3 §3): the brute-force measure — the
//! ratio of interpolated to direct texels in the pre-warped image
//! ([`Prewarped::interpolated_ratio`](super::Prewarped::interpolated_ratio)), 20 % by default —
//! and the critical-point heuristic that predicts it from a handful of texels: the image split
//! in regions, each with its critical pair (4-neighbours, both covered, with the largest
//! difference in displacement). For an eye, a pair's warped positions are `E` texels apart; the
//! heuristic is the mean over regions of the stretch `max(0, E − 1)`. (The paper's Eq. 5–6
//! write `|1 + Δu₁ − Δu₂|` for both axes, which fits a pair one texel apart in `u` for one and
//! in `v` for the other; the distance between warped positions is the form that holds for
//! either — docs/conventions.md §5.4.) Also Schaufler's test for skipping a warp: the largest
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
            at: crate::frame::pixel_centre(u as f64, v as f64),
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

/// The heuristic made to speak in the brute force's terms, for one impostor: `(heuristic,
/// ratio)` pairs measured at eyes turned left, right, up and down from the one it was made for,
/// one curve a direction, from which the ratio at any eye is predicted from the heuristic alone
/// (piecewise linear and non-decreasing along each curve, the curves blended by the direction
/// the eye has moved in).
///
/// Why: the stretch of the critical pairs grows in step with the interpolated share as the eye
/// moves, but at a rate that depends on the object and on the direction of motion (one deep
/// discontinuity against many shallow ones), so no one stretch threshold matches the paper's
/// 20 % on every object. A few pre-warps when an impostor is made — on the rendering thread —
/// fix the rates for that impostor; each frame then costs only the critical pairs.
#[derive(Clone, Debug, PartialEq)]
pub struct Calibration {
    /// Per direction: the unit direction, in texels, the eye's foot moved in, and the
    /// `(heuristic, ratio)` samples, sorted by heuristic.
    pub curves: Vec<(DVec2, Vec<(f64, f64)>)>,
    /// The foot of the impostor's own eye, texel coordinates.
    pub origin: DVec2,
}

/// Angles, degrees, at which [`calibrate`] samples both measures in each of four directions.
pub const CALIBRATION_ANGLES: [f64; 4] = [3.0, 6.0, 12.0, 24.0];

/// Samples both measures of `impostor` at its own eye and at eyes turned about `centre` by
/// [`CALIBRATION_ANGLES`] left, right, up and down.
pub fn calibrate(impostor: &ReliefImpostor, pairs: &CriticalPairs, centre: DVec3) -> Calibration {
    let fr = &impostor.frame;
    let foot = |eye: DVec3| {
        let c = fr.coordinates(eye);
        DVec2::new(c.x, c.y)
    };
    let origin = foot(impostor.eye);
    let at_source = {
        let v = verdicts(impostor, pairs, impostor.eye);
        (v.heuristic, v.ratio)
    };
    let r = impostor.eye - centre;
    let side = r.cross(DVec3::Y).try_normalize().unwrap_or(DVec3::X);
    let mut curves = Vec::new();
    for axis in [DVec3::Y, -DVec3::Y, side, -side] {
        let mut samples = vec![at_source];
        let mut direction = DVec2::ZERO;
        for deg in CALIBRATION_ANGLES {
            let eye = centre + glam::DQuat::from_axis_angle(axis, deg.to_radians()) * r;
            direction += (foot(eye) - origin).normalize_or_zero();
            let v = verdicts(impostor, pairs, eye);
            if v.heuristic.is_finite() && v.ratio.is_finite() {
                samples.push((v.heuristic, v.ratio));
            }
        }
        samples.retain(|s| s.0.is_finite() && s.1.is_finite());
        samples.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let mut top = f64::NEG_INFINITY;
        for s in &mut samples {
            top = top.max(s.1);
            s.1 = top;
        }
        curves.push((direction.normalize_or_zero(), samples));
    }
    Calibration { curves, origin }
}

impl Calibration {
    /// The ratio predicted for a heuristic value at an eye whose foot is `foot` (texel
    /// coordinates; [`Coefficients::epipole`]); infinite for an infinite error.
    pub fn predict(&self, heuristic: f64, foot: (f64, f64)) -> f64 {
        if !heuristic.is_finite() {
            return f64::INFINITY;
        }
        let g = (DVec2::new(foot.0, foot.1) - self.origin).normalize_or_zero();
        let weights: Vec<f64> = self
            .curves
            .iter()
            .map(|(d, _)| {
                if g == DVec2::ZERO {
                    1.0
                } else {
                    g.dot(*d).max(0.0).powi(2)
                }
            })
            .collect();
        let total: f64 = weights.iter().sum();
        if total <= 0.0 {
            return self
                .curves
                .iter()
                .map(|(_, s)| along(s, heuristic))
                .fold(0.0, f64::max);
        }
        self.curves
            .iter()
            .zip(&weights)
            .map(|((_, s), w)| w * along(s, heuristic))
            .sum::<f64>()
            / total
    }
}

/// A curve's ratio at `heuristic`: interpolated between samples, extended past the last by the
/// slope from the first to the last.
fn along(s: &[(f64, f64)], heuristic: f64) -> f64 {
    let (Some(&first), Some(&last)) = (s.first(), s.last()) else {
        return 0.0;
    };
    if heuristic <= first.0 {
        return first.1;
    }
    if let Some(w) = s.windows(2).find(|w| heuristic <= w[1].0) {
        let (a, b) = (w[0], w[1]);
        let t = if b.0 > a.0 {
            (heuristic - a.0) / (b.0 - a.0)
        } else {
            1.0
        };
        return a.1 + (b.1 - a.1) * t;
    }
    let slope = if last.0 > first.0 {
        (last.1 - first.1) / (last.0 - first.0)
    } else {
        0.0
    };
    last.1 + slope * (heuristic - last.0)
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
/// cell green where the impostor stays valid by the brute-force ratio (at most `threshold`,
/// and no texel pushed off the warp's margin), red where it does not, grey where the eye is inside `keep_out` or behind the base plane.
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
                Some(p) if p.dropped == 0 && p.interpolated_ratio() <= threshold => {
                    Rgba::new(0.1, 0.6, 0.15, 1.0)
                }
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
