//! The single-pole occlusion camera (SPOC; Mei, Popescu and Sacks 2005; paper 1 §4;
//! docs/conventions.md §3.2 — the distortion there is a proposal honouring everything the papers state,
//! implemented as written).
//!
//! A planar pinhole projection followed by a radial push away from the pole `p0` (the image of
//! the object's centre) that grows with depth: `(u′, v′) = p0 + (1 + κ(z))(q − p0)`, with
//! `κ(z) = k · max(0, (z − z_n)/(z_f − z_n))`. Deeper samples move farther out, so surfaces just
//! behind the silhouette escape it and the impostor captures more of the object than a pinhole.
//!
//! Invariants: one projection per point; continuous (the displacement vanishes at the pole); for
//! a fixed depth the map is a uniform scaling about `p0`, so points at one depth never collide;
//! `S⁻¹(S(X)) = X`; points with `z ≤ z_n` are not moved.

use super::{CameraError, ImagePoint, Pinhole, Projection};
use glam::{DVec2, DVec3, Vec3};

/// Smallest and largest strength the selection rule returns (docs/conventions.md §3.2).
pub const SPOC_STRENGTH_RANGE: (f64, f64) = (0.2, 1.5);

/// A SPOC around a bounding sphere.
#[derive(Clone, Debug, PartialEq)]
pub struct Spoc {
    ppc: Pinhole,
    pole: DVec2,
    z_near: f64,
    z_far: f64,
    k: f64,
    /// Derived, kept for the per-vertex cost of `project`: the focal distance `f` and the ramp's
    /// slope `k/(z_f − z_n)`; for the per-triangle cost of `midpoint_deviation_bound`, `1/f`;
    /// and for the per-texel cost of `gd_on_plane`, `M·(p0, 1)`.
    focal: f64,
    inv_focal: f64,
    slope: f64,
    to_pole: DVec3,
}

impl Spoc {
    /// The distortion strength for secondary rays coming from a region of radius `delta` around
    /// the eye, the object's centre at depth `z_o`: `k ≈ 2Δ/z_O`, clamped to
    /// [`SPOC_STRENGTH_RANGE`] (the parallax argument of docs/conventions.md §3.2).
    pub fn strength_for_region(delta: f64, z_o: f64) -> f64 {
        (2.0 * delta / z_o).clamp(SPOC_STRENGTH_RANGE.0, SPOC_STRENGTH_RANGE.1)
    }

    /// A SPOC at `eye` looking at a sphere (`center`, `radius`) with strength `k`, `size × size`
    /// pixels. The field of view is widened so the pushed-out silhouette, `(1 + k)` times the
    /// sphere's image radius, still fits with a 5 % margin.
    pub fn around(
        eye: Vec3,
        center: Vec3,
        radius: f32,
        k: f64,
        size: u32,
    ) -> Result<Self, CameraError> {
        Self::around_framed(eye, center, radius, k, size, 1.0)
    }

    /// [`Spoc::around`] with the half-width of the view multiplied by `scale` (every image
    /// offset from the pole divides by it; `κ` is unchanged): `scale < 1` frames an object
    /// that fills less than its pushed-out bounding sphere more tightly.
    pub fn around_framed(
        eye: Vec3,
        center: Vec3,
        radius: f32,
        k: f64,
        size: u32,
        scale: f64,
    ) -> Result<Self, CameraError> {
        if !(scale > 0.0 && scale.is_finite()) {
            return Err(CameraError::Degenerate("a framing scale must be positive"));
        }
        let d = (center - eye).length() as f64;
        let r = radius as f64;
        if !(r > 0.0 && d > r * 1.0001) {
            return Err(CameraError::Degenerate(
                "the SPOC eye must be outside the bounding sphere",
            ));
        }
        if !(k >= 0.0 && k.is_finite()) {
            return Err(CameraError::Degenerate(
                "SPOC strength must be non-negative",
            ));
        }
        // Image radius of the sphere at unit focal distance: tan(asin(R/d)).
        let r_s = r / (d * d - r * r).sqrt();
        let half = r_s * (1.0 + k) * 1.05 * scale;
        let fov = 2.0 * half.atan().to_degrees();
        let up = if ((center - eye).normalize().dot(Vec3::Y)).abs() > 0.99 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        let ppc = Pinhole::look_at(eye, center, up, fov, size, size)?.with_near((d - r) * 0.5);
        let pole = ppc
            .project(center.as_dvec3())
            .map(|p| p.uv)
            .unwrap_or(DVec2::splat(size as f64 / 2.0));
        // Eye-space depth of the centre, z_O = (O − C)·n̂ (docs/conventions.md §3.2).
        let z_o = (center.as_dvec3() - ppc.position()).dot(ppc.forward());
        Self::from_parts(ppc, pole, z_o - r, z_o + r, k)
    }

    /// Rebuilds a SPOC from its reference camera and parameters (for loading impostors).
    pub fn from_parts(
        ppc: Pinhole,
        pole: DVec2,
        z_near: f64,
        z_far: f64,
        k: f64,
    ) -> Result<Self, CameraError> {
        if !(pole.is_finite() && z_near.is_finite() && z_far > z_near && k >= 0.0 && k.is_finite())
        {
            return Err(CameraError::Degenerate("SPOC parameters are degenerate"));
        }
        Ok(Self {
            focal: ppc.focal(),
            inv_focal: 1.0 / ppc.focal(),
            slope: k / (z_far - z_near),
            to_pole: ppc.unproject(pole, 1.0) - ppc.position(),
            ppc,
            pole,
            z_near,
            z_far,
            k,
        })
    }

    /// The reference pinhole camera.
    pub fn pinhole(&self) -> &Pinhole {
        &self.ppc
    }
    /// The pole `p0`.
    pub fn pole(&self) -> DVec2 {
        self.pole
    }
    /// `(z_n, z_f)`: where the depth ramp starts and where it reaches `k`.
    pub fn depth_range(&self) -> (f64, f64) {
        (self.z_near, self.z_far)
    }
    /// The strength `k`.
    pub fn strength(&self) -> f64 {
        self.k
    }

    /// A box holding the SPOC image of every point of the world segment `[a, b]`: the pinhole
    /// images `q` of its points run along the segment `[q_a, q_b]` and their eye depths between
    /// `z_a` and `z_b`, so each image point `p0 + (1 + κ(z))(q − p0)` lies in the trapezoid whose
    /// corners scale `q_a`, `q_b` about the pole by the smallest and largest `1 + κ`.
    pub fn segment_image_bounds(&self, a: DVec3, b: DVec3) -> Option<(DVec2, DVec2)> {
        Some(self.pinhole_segment_bounds(self.ppc.project(a)?, self.ppc.project(b)?))
    }

    /// [`Spoc::segment_image_bounds`] from the images `qa`, `qb` of the segment's ends through
    /// the reference pinhole ([`Spoc::pinhole`]), for a caller that projects each point once.
    pub fn pinhole_segment_bounds(&self, qa: ImagePoint, qb: ImagePoint) -> (DVec2, DVec2) {
        let f = self.focal;
        let (sa, sb) = (1.0 + self.kappa(f / qa.gd), 1.0 + self.kappa(f / qb.gd));
        let (s0, s1) = (sa.min(sb), sa.max(sb));
        let corners = [qa.uv, qb.uv].map(|q| [s0, s1].map(|s| self.pole + (q - self.pole) * s));
        let all = corners.iter().flatten();
        let min = all.clone().fold(DVec2::INFINITY, |m, p| m.min(*p));
        let max = all.fold(DVec2::NEG_INFINITY, |m, p| m.max(*p));
        (min, max)
    }

    /// The depth ramp `κ(z)`.
    pub fn kappa(&self, z: f64) -> f64 {
        self.slope * (z - self.z_near).max(0.0)
    }

    /// The `gd` at which the SPOC's ray through image point `uv` meets the plane through
    /// `point` with normal `normal` (any length), found from `gd_guess` (a rasterized `gd`,
    /// within a fraction of a texel); `None` when there is no crossing within 10 % of the guess
    /// (a plane seen edge-on).
    ///
    /// Along the ray `X(t) = C + t·M·(q(t), 1)`, with `q(t) = p0 + (uv − p0)/s(t)` and
    /// `s(t) = 1 + κ(f·t)`, the plane's equation `n·(X − C) = h` reads `t·(A + B/s(t)) = h`
    /// with `A = n·M(p0, 1)` and `B = n·M(uv − p0, 0)`. Nearer than `z_n`, `s = 1` and
    /// `gd = 1/t = (A + B)/h`. On the ramp `s = α + β·t` (`α = 1 − κ′·z_n`, `β = κ′·f`, `κ′`
    /// the ramp's slope), which in `gd` is the quadratic
    /// `R(gd) = −h·α·gd² + (A·α + B − h·β)·gd + A·β = 0`, solved by Newton's method from the
    /// guess (the error squares at each step: from a rasterized guess one step leaves an error
    /// below 10⁻⁹ of `gd`, from a guess 1 % off two or three do; `None` if four do not).
    #[inline]
    pub fn gd_on_plane(
        &self,
        uv: DVec2,
        normal: DVec3,
        point: DVec3,
        gd_guess: f64,
    ) -> Option<f64> {
        let c = self.ppc.position();
        let a = normal.dot(self.to_pole);
        let b = normal.dot(self.ppc.unproject(uv, 1.0) - c - self.to_pole);
        let h = normal.dot(point - c);
        // Nearer than z_n: f/gd < z_n.
        let straight = |gd: f64| self.focal < self.z_near * gd;
        let ramp = || {
            let (alpha, beta) = (1.0 - self.slope * self.z_near, self.slope * self.focal);
            let (r2, r1, r0) = (-h * alpha, a * alpha + b - h * beta, a * beta);
            let mut g = gd_guess;
            for _ in 0..4 {
                let slope = 2.0 * r2 * g + r1;
                let step = (r2 * g * g + r1 * g + r0) / slope;
                g -= step;
                // The error left after a Newton step on a quadratic is about
                // |R″/(2R′)|·step² = |r2/R′|·step². Stopping once that is below 10⁻⁹ of `gd`,
                // rather than once the step itself is, saves the step that would only confirm
                // it: from the rasterized guess the first step is already 10⁻⁵ – 10⁻⁷ of `gd`.
                if (r2 * step * step).abs() <= 1e-9 * (g * slope).abs() {
                    return Some(g);
                }
            }
            None
        };
        // The piece of the ray the guess is on first; the other if the crossing is not there.
        let on_straight = Some((a + b) / h).filter(|&g| straight(g));
        let on_ramp = || ramp().filter(|&g| !straight(g));
        let gd = if straight(gd_guess) {
            on_straight.or_else(on_ramp)
        } else {
            on_ramp().or(on_straight)
        }?;
        (gd > 0.0 && (gd - gd_guess).abs() <= 0.1 * gd_guess).then_some(gd)
    }
}

impl Projection for Spoc {
    fn resolution(&self) -> (u32, u32) {
        self.ppc.resolution()
    }

    /// `(u′, v′) = p0 + (1 + κ(z))(q − p0)`, `gd = 1/t` of the undistorted pinhole point.
    fn project(&self, p: DVec3) -> Option<ImagePoint> {
        // The pinhole's homogeneous point t·(q, 1), with eye depth z = f·t.
        let w = self.ppc.homogeneous(p);
        if w.z <= 0.0 {
            return None;
        }
        let gd = 1.0 / w.z;
        let q = DVec2::new(w.x * gd, w.y * gd);
        Some(ImagePoint {
            uv: self.pole + (q - self.pole) * (1.0 + self.kappa(self.focal * w.z)),
            gd,
            inv_w: gd,
        })
    }

    /// `t = 1/gd`, `q = p0 + ((u′, v′) − p0)/(1 + κ(z))`, `X = C + t·M·(q, 1)`.
    fn unproject(&self, uv: DVec2, gd: f64) -> DVec3 {
        let z = self.focal / gd;
        let q = self.pole + (uv - self.pole) / (1.0 + self.kappa(z));
        self.ppc.unproject(q, gd)
    }

    fn clip_distance(&self, p: DVec3) -> f64 {
        self.ppc.clip_distance(p)
    }

    /// With `r = q − p0` the pinhole image relative to the pole, `s = 1 + κ(z)`, and `Δ`, bars
    /// the differences and means of a segment's two ends: the pinhole image of its midpoint is
    /// `r̄ + Δz·Δr/(4z̄)`, and `s` there is `s̄ − ε` with `0 ≤ ε ≤ K|Δz|/4` (`κ` is a convex
    /// hinge of slope `K = k/(z_f − z_n)`, and `z` is affine along the segment). The deviation
    /// is then exactly `s̄·Δz·Δr/(4z̄) − Δs·Δr/4 − ε·r_m`, so
    /// `|dev| ≤ |Δz|/4 · (|Δr|·(s̄/z̄ + K) + K·|r_m|)`, with `|Δr| ≤ |Δuv| + K|Δz|·|uv_b − p0|`
    /// (since `s ≥ 1`) and `|r_m| ≤ max |uv − p0|`. Over-estimates that hold for any two of
    /// `ends` keep it to one division: `s̄ ≤ 1 + k`, `1/z̄ ≤ max gd / f`,
    /// `|Δz| ≤ f·(max gd − min gd)/(max gd · min gd)`, and `|x| ≤ |x₁| + |x₂|` (so `|Δuv|` is
    /// at most the width plus the height of the images' bounding box).
    fn midpoint_deviation_bound(&self, ends: &[ImagePoint]) -> f64 {
        let Some(first) = ends.first() else {
            return 0.0;
        };
        // Set-up asks this of every triangle. Plain comparisons, not `f64::min`/`max` (which
        // step around NaN at several instructions each): a NaN or non-positive `gd`, or a
        // non-finite image coordinate, fails `valid` instead, and the bound is infinite.
        let (mut gd_min, mut gd_max) = (first.gd, first.gd);
        let (mut lo, mut hi) = (first.uv, first.uv);
        let (mut r_max, mut valid) = (0.0f64, true);
        for p in ends {
            valid &= p.gd > 0.0 && p.uv.is_finite();
            gd_min = if p.gd < gd_min { p.gd } else { gd_min };
            gd_max = if p.gd > gd_max { p.gd } else { gd_max };
            lo.x = if p.uv.x < lo.x { p.uv.x } else { lo.x };
            lo.y = if p.uv.y < lo.y { p.uv.y } else { lo.y };
            hi.x = if p.uv.x > hi.x { p.uv.x } else { hi.x };
            hi.y = if p.uv.y > hi.y { p.uv.y } else { hi.y };
            let r = (p.uv.x - self.pole.x).abs() + (p.uv.y - self.pole.y).abs();
            r_max = if r > r_max { r } else { r_max };
        }
        if !valid {
            return f64::INFINITY;
        }
        let dz = self.focal * (gd_max - gd_min) / (gd_max * gd_min);
        let dr = (hi.x - lo.x) + (hi.y - lo.y) + self.slope * dz * r_max;
        let inv_z_mean = gd_max * self.inv_focal;
        0.25 * dz * (dr * ((1.0 + self.k) * inv_z_mean + self.slope) + self.slope * r_max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spoc() -> Spoc {
        Spoc::around(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, 1.0, 0.8, 128).unwrap()
    }

    fn random_point(i: u32) -> DVec3 {
        let h = |k: u32| {
            ((i.wrapping_mul(2_654_435_761) ^ k.wrapping_mul(40_503)) % 10_007) as f64 / 10_007.0
        };
        DVec3::new(h(1) - 0.5, h(2) - 0.5, h(3) - 0.5) * 2.0
    }

    #[test]
    fn unproject_inverts_project() {
        let s = spoc();
        for i in 0..2000 {
            let p = random_point(i);
            let q = s.project(p).unwrap();
            assert!((s.unproject(q.uv, q.gd) - p).length() < 1e-9, "{p}");
        }
    }

    #[test]
    fn near_points_are_unmoved_and_deep_points_pushed_out() {
        let s = spoc();
        let ppc = s.pinhole();
        // In front of z_n: identical to the pinhole.
        let front = DVec3::new(0.3, 0.2, 1.5);
        assert_eq!(s.project(front).unwrap().uv, ppc.project(front).unwrap().uv);
        // Behind: farther from the pole than the pinhole image, by (1 + κ).
        let back = DVec3::new(0.3, 0.2, -0.5);
        let (a, b) = (
            s.project(back).unwrap().uv - s.pole(),
            ppc.project(back).unwrap().uv - s.pole(),
        );
        assert!(a.length() > b.length() * 1.3);
        assert!((a.normalize() - b.normalize()).length() < 1e-9, "radial");
    }

    #[test]
    fn continuous_with_a_single_projection_per_point() {
        let s = spoc();
        // Nearby points project nearby (no tear), including across z_n and at the pole.
        for i in 0..2000 {
            let p = random_point(i);
            let e = DVec3::new(1e-7, -2e-7, 1.5e-7);
            let (a, b) = (s.project(p).unwrap(), s.project(p + e).unwrap());
            assert!((a.uv - b.uv).length() < 1e-3, "{p}");
        }
        // Points at one depth never collide: the map is a scaling about the pole.
        let p0 = s.project(DVec3::new(0.2, 0.0, -0.3)).unwrap();
        let p1 = s.project(DVec3::new(0.2001, 0.0, -0.3)).unwrap();
        assert!((p0.uv - p1.uv).length() > 0.0);
    }

    #[test]
    fn gd_on_plane_puts_the_unprojected_point_on_the_plane() {
        // Planes through random points, in front of and on the ramp: from a guess 0.5 % off,
        // the ray through a pixel near the point's image meets the plane at the returned gd.
        let s = spoc();
        let mut solved = 0;
        for i in 0..4000 {
            let p = random_point(i);
            let n = random_point(i + 7919).normalize_or_zero();
            let Some(q) = s.project(p) else { continue };
            let uv = q.uv + DVec2::new((i % 7) as f64 * 0.1 - 0.3, (i % 5) as f64 * 0.1 - 0.2);
            let guess = q.gd * (1.0 + 0.005 * ((i % 3) as f64 - 1.0));
            let Some(gd) = s.gd_on_plane(uv, n * 3.0, p, guess) else {
                continue;
            };
            // Within f32 precision of the distance: what an impostor stores of gd.
            let x = s.unproject(uv, gd);
            let off = (x - p).dot(n).abs() / (x - s.pinhole().position()).length();
            assert!(off < 1e-7, "{i}: off the plane by {off} of the distance");
            solved += 1;
        }
        // Planes seen nearly edge-on may have no crossing near the guess; most do.
        assert!(solved > 3600, "{solved}");
    }

    #[test]
    fn midpoint_deviation_bound_is_infinite_for_corners_it_cannot_bound() {
        // A corner with no depth, or off every image, whichever corner it is: the bound must
        // then send the triangle to tessellation, not report it straight.
        let s = spoc();
        let good = [0.3, 0.0, -0.2].map(|x| s.project(DVec3::new(x, 0.2, 0.1)).unwrap());
        assert!(s.midpoint_deviation_bound(&good).is_finite());
        let spoilers = [
            |p: &mut ImagePoint| p.gd = f64::NAN,
            |p: &mut ImagePoint| p.gd = 0.0,
            |p: &mut ImagePoint| p.uv.x = f64::NAN,
            |p: &mut ImagePoint| p.uv.y = f64::INFINITY,
        ];
        for spoil in spoilers {
            for k in 0..3 {
                let mut ends = good;
                spoil(&mut ends[k]);
                assert_eq!(
                    s.midpoint_deviation_bound(&ends),
                    f64::INFINITY,
                    "corner {k}"
                );
            }
        }
    }

    #[test]
    fn midpoint_deviation_bound_holds() {
        // Segments of every length and direction, across z_n and the pole: the exact deviation
        // never exceeds the bound, and the bound is not vacuous for short segments.
        let s = spoc();
        let mut tight = 0;
        for i in 0..4000 {
            let a = random_point(i);
            let len = [0.001, 0.01, 0.1, 1.0][i as usize % 4];
            let b = a + (random_point(i + 7919) - DVec3::splat(0.0)).normalize_or_zero() * len;
            let (pa, pb) = (s.project(a).unwrap(), s.project(b).unwrap());
            let pm = s.project((a + b) * 0.5).unwrap();
            let exact = (pm.uv - (pa.uv + pb.uv) * 0.5).length();
            let bound = s.midpoint_deviation_bound(&[pa, pb]);
            // A third point only loosens the bound.
            let c = s.project(random_point(i + 104_729)).unwrap();
            assert!(s.midpoint_deviation_bound(&[pa, pb, c]) >= bound);
            assert!(
                exact <= bound * (1.0 + 1e-9) + 1e-12,
                "{a} {b}: {exact} > {bound}"
            );
            if len <= 0.01 && bound < 0.5 {
                tight += 1;
            }
        }
        assert!(tight > 1900, "{tight}");
    }

    #[test]
    fn strength_rule_follows_the_parallax_argument() {
        assert!((Spoc::strength_for_region(1.0, 5.0) - 0.4).abs() < 1e-12);
        assert_eq!(Spoc::strength_for_region(100.0, 5.0), SPOC_STRENGTH_RANGE.1);
        assert_eq!(Spoc::strength_for_region(0.01, 5.0), SPOC_STRENGTH_RANGE.0);
    }
}
