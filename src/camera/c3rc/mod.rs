//! The continuous 3-ray camera (paper 2, "Hybrid backward-forward reflection rendering with
//! continuous 3-ray cameras" §2–5; docs/conventions.md §7): one camera per reflector triangle,
//! whose rays are the reflected rays at its three vertices blended by barycentrics, so that two
//! triangles sharing an edge image the points on their shared wall identically. A point
//! projects where the sweeping triangle `T(λ) = (vᵢ + λ dᵢ)` passes through it: the real roots of
//! a cubic in the sweep parameter whose barycentrics lie inside the triangle — up to three
//! projections, all of them returned.
//!
//! Invariants: geometry in `f64`; construction rays unit length; a projection's barycentrics are
//! all `≥ −`[`BARY_EPS`] and its `λ ≥ 0`; the image point is `Σ bᵢ vᵢ` on the reflector.

mod volume;

use glam::DVec3;

/// Tolerance on barycentrics for a projection to count as inside the base triangle.
pub const BARY_EPS: f64 = 1e-9;

/// A continuous 3-ray camera over one reflector triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct C3rc {
    /// The base triangle's vertices (the reflector's).
    pub v: [DVec3; 3],
    /// The unit construction rays at the vertices.
    pub d: [DVec3; 3],
}

/// One projection of a point through a [`C3rc`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct C3rcProjection {
    /// Sweep parameter: the point is `Σ bᵢ (vᵢ + λ dᵢ)`.
    pub lambda: f64,
    /// Barycentrics on the base triangle.
    pub bary: DVec3,
    /// The image point on the reflector, `Σ bᵢ vᵢ`.
    pub point: DVec3,
    /// Distance from the image point to the projected point, `λ·|Σ bᵢ dᵢ|` (the visibility key
    /// pushes the image point back by it).
    pub distance: f64,
}

impl C3rc {
    /// The camera of reflector triangle `v` with vertex normals `n`, seen from `eye`: the
    /// construction rays are the mirror reflections of the eye's rays at the vertices.
    pub fn reflector(v: [DVec3; 3], n: [DVec3; 3], eye: DVec3) -> Option<C3rc> {
        let mut d = [DVec3::ZERO; 3];
        for k in 0..3 {
            let i = (v[k] - eye).try_normalize()?;
            let nk = n[k].try_normalize()?;
            d[k] = (i - 2.0 * i.dot(nk) * nk).try_normalize()?;
        }
        Some(C3rc { v, d })
    }

    /// The ray point at barycentrics `b` and sweep parameter `lambda`.
    pub fn at(&self, b: DVec3, lambda: f64) -> DVec3 {
        (0..3)
            .map(|k| (self.v[k] + self.d[k] * lambda) * b[k])
            .sum()
    }

    /// The cubic `f(λ) = c₃λ³ + c₂λ² + c₁λ + c₀` whose roots are the sweep parameters at which
    /// `T(λ)`'s plane holds `q` (docs/conventions.md §7.2), as `[c₀, c₁, c₂, c₃]`.
    pub fn cubic(&self, q: DVec3) -> [f64; 4] {
        let (e2, e3) = (self.v[1] - self.v[0], self.v[2] - self.v[0]);
        let (g2, g3) = (self.d[1] - self.d[0], self.d[2] - self.d[0]);
        let (n0, n1, n2) = (e2.cross(e3), e2.cross(g3) + g2.cross(e3), g2.cross(g3));
        let (r, d1) = (q - self.v[0], self.d[0]);
        [
            n0.dot(r),
            n1.dot(r) - n0.dot(d1),
            n2.dot(r) - n1.dot(d1),
            -n2.dot(d1),
        ]
    }

    /// Every projection of `q` with `0 ≤ λ ≤ lambda_max`, nearest sweep first.
    pub fn project(&self, q: DVec3, lambda_max: f64) -> Vec<C3rcProjection> {
        let mut out = Vec::new();
        self.project_each(q, lambda_max, |p| out.push(p));
        out
    }

    /// Calls `f` with every projection of `q` with `0 ≤ λ ≤ lambda_max`, nearest sweep first,
    /// without allocating (the splatting loop's form of [`C3rc::project`]).
    pub fn project_each(&self, q: DVec3, lambda_max: f64, f: impl FnMut(C3rcProjection)) {
        self.project_between(q, 0.0, lambda_max, f)
    }

    /// Calls `f` with every projection of `q` with `lambda_min ≤ λ ≤ lambda_max` (`lambda_min ≥
    /// 0`), nearest sweep first.
    pub fn project_between(
        &self,
        q: DVec3,
        lambda_min: f64,
        lambda_max: f64,
        mut f: impl FnMut(C3rcProjection),
    ) {
        let roots = roots_of(self.cubic(q));
        for &lambda in roots.as_slice() {
            // A root a rounding error below 0 is the base itself.
            let lambda = if (-1e-12..0.0).contains(&lambda) {
                0.0
            } else {
                lambda
            };
            if !(lambda_min..=lambda_max).contains(&lambda) {
                continue;
            }
            let t = [0, 1, 2].map(|k| self.v[k] + self.d[k] * lambda);
            let (a, b, w) = (t[1] - t[0], t[2] - t[0], q - t[0]);
            let n = a.cross(b);
            let nn = n.length_squared();
            if nn <= f64::MIN_POSITIVE {
                continue;
            }
            let b2 = w.cross(b).dot(n) / nn;
            let b3 = a.cross(w).dot(n) / nn;
            let bary = DVec3::new(1.0 - b2 - b3, b2, b3);
            if bary.min_element() < -BARY_EPS {
                continue;
            }
            let dir: DVec3 = (0..3).map(|k| self.d[k] * bary[k]).sum();
            f(C3rcProjection {
                lambda,
                bary,
                point: (0..3).map(|k| self.v[k] * bary[k]).sum(),
                distance: lambda * dir.length(),
            });
        }
    }

    /// The least area of the sweeping triangle `T(λ)` for `λ` in `[a, b]`: `|n(λ)|/2`, whose
    /// square is a quartic; its least value is at an end or where its derivative, the cubic
    /// `n(λ)·n′(λ)`, vanishes.
    pub fn least_sweep_area(&self, a: f64, b: f64) -> f64 {
        let (e2, e3) = (self.v[1] - self.v[0], self.v[2] - self.v[0]);
        let (g2, g3) = (self.d[1] - self.d[0], self.d[2] - self.d[0]);
        let (n0, n1, n2) = (e2.cross(e3), e2.cross(g3) + g2.cross(e3), g2.cross(g3));
        let area = |l: f64| 0.5 * (n0 + n1 * l + n2 * l * l).length();
        // n·n′ = (n0 + λn1 + λ²n2)·(n1 + 2λn2).
        let cubic = [
            n0.dot(n1),
            n1.dot(n1) + 2.0 * n0.dot(n2),
            3.0 * n1.dot(n2),
            2.0 * n2.dot(n2),
        ];
        let mut least = area(a);
        if b.is_finite() {
            least = least.min(area(b));
        }
        for &l in roots_of(cubic).as_slice() {
            if l > a && l < b {
                least = least.min(area(l));
            }
        }
        least
    }

    /// Whether `q` has at least one projection with `0 ≤ λ ≤ lambda_max`.
    pub fn sees(&self, q: DVec3, lambda_max: f64) -> bool {
        self.sees_between(q, 0.0, lambda_max)
    }

    /// Whether `q` has at least one projection with `lambda_min ≤ λ ≤ lambda_max`.
    pub fn sees_between(&self, q: DVec3, lambda_min: f64, lambda_max: f64) -> bool {
        let mut any = false;
        self.project_between(q, lambda_min, lambda_max, |_| any = true);
        any
    }

    /// The sweep ranges `[λa, λb]` (within `[0, lambda_max]`) where a point may have more than
    /// one projection: where the construction rays are not all on one side of `T(λ)`'s plane
    /// (paper 2 §5.1). Empty when every point projects at most once.
    pub fn multiple_projection_ranges(&self, lambda_max: f64) -> Vec<(f64, f64)> {
        let (e2, e3) = (self.v[1] - self.v[0], self.v[2] - self.v[0]);
        let (g2, g3) = (self.d[1] - self.d[0], self.d[2] - self.d[0]);
        let (n0, n1, n2) = (e2.cross(e3), e2.cross(g3) + g2.cross(e3), g2.cross(g3));
        let mut cuts = vec![0.0, lambda_max];
        for d in self.d {
            for r in real_roots([d.dot(n0), d.dot(n1), d.dot(n2), 0.0]) {
                if r > 0.0 && r < lambda_max {
                    cuts.push(r);
                }
            }
        }
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        let mut ranges: Vec<(f64, f64)> = Vec::new();
        for w in cuts.windows(2) {
            let mid = if w[1].is_finite() {
                0.5 * (w[0] + w[1])
            } else {
                w[0] + 1.0
            };
            let n = n0 + n1 * mid + n2 * mid * mid;
            let signs: Vec<bool> = self.d.iter().map(|d| d.dot(n) > 0.0).collect();
            if signs.iter().any(|&s| s != signs[0]) {
                match ranges.last_mut() {
                    Some(last) if last.1 == w[0] => last.1 = w[1],
                    _ => ranges.push((w[0], w[1])),
                }
            }
        }
        ranges
    }
}

/// The real roots of `c₀ + c₁x + c₂x² + c₃x³` (`c = [c₀, c₁, c₂, c₃]`), falling back to lower
/// degrees when leading coefficients vanish (relative to the largest), each polished by Newton
/// steps; sorted, duplicates within 1e-12 merged.
pub fn real_roots(c: [f64; 4]) -> Vec<f64> {
    roots_of(c).as_slice().to_vec()
}

/// At most three real roots, without allocating.
#[derive(Clone, Copy, Debug, Default)]
struct Roots {
    r: [f64; 3],
    len: usize,
}

impl Roots {
    fn push(&mut self, x: f64) {
        if self.len < 3 && x.is_finite() {
            self.r[self.len] = x;
            self.len += 1;
        }
    }
    fn as_slice(&self) -> &[f64] {
        &self.r[..self.len]
    }
}

/// [`real_roots`] into a fixed array.
fn roots_of(c: [f64; 4]) -> Roots {
    let mut roots = Roots::default();
    let scale = c.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return roots;
    }
    let c = c.map(|v| v / scale);
    let eval = |x: f64| ((c[3] * x + c[2]) * x + c[1]) * x + c[0];
    let deriv = |x: f64| (3.0 * c[3] * x + 2.0 * c[2]) * x + c[1];
    let tiny = 1e-12;
    if c[3].abs() > tiny {
        roots = cubic_roots(c[2] / c[3], c[1] / c[3], c[0] / c[3]);
    } else if c[2].abs() > tiny {
        let (a, b, k) = (c[2], c[1], c[0]);
        let disc = b * b - 4.0 * a * k;
        if disc >= 0.0 {
            // The stable form: no cancellation between −b and √disc.
            let s = -0.5 * (b + b.signum() * disc.sqrt());
            if s == 0.0 {
                roots.push(0.0);
            } else {
                roots.push(s / a);
                roots.push(k / s);
            }
        }
    } else if c[1].abs() > tiny {
        roots.push(-c[0] / c[1]);
    }
    let mut out = Roots::default();
    for &r0 in roots.as_slice() {
        let mut r = r0;
        for _ in 0..2 {
            let d = deriv(r);
            if d.abs() > 1e-300 {
                let next = r - eval(r) / d;
                if next.is_finite() {
                    r = next;
                }
            }
        }
        out.push(r);
    }
    let s = &mut out.r[..out.len];
    s.sort_by(f64::total_cmp);
    // Merge duplicates.
    let mut merged = Roots::default();
    for &r in out.as_slice() {
        match merged.as_slice().last() {
            Some(&last) if (r - last).abs() <= 1e-12 * (1.0 + last.abs()) => {}
            _ => merged.push(r),
        }
    }
    merged
}

/// Real roots of the monic cubic `x³ + a x² + b x + c` (trigonometric form for three roots,
/// Cardano's for one).
fn cubic_roots(a: f64, b: f64, c: f64) -> Roots {
    let q = (a * a - 3.0 * b) / 9.0;
    let r = (2.0 * a * a * a - 9.0 * a * b + 27.0 * c) / 54.0;
    let shift = a / 3.0;
    let mut roots = Roots::default();
    if r * r < q * q * q {
        let theta = (r / (q * q * q).sqrt()).clamp(-1.0, 1.0).acos();
        let m = -2.0 * q.sqrt();
        for k in 0..3 {
            roots.push(m * ((theta + 2.0 * std::f64::consts::PI * k as f64) / 3.0).cos() - shift);
        }
    } else {
        let s = -r.signum() * (r.abs() + (r * r - q * q * q).sqrt()).cbrt();
        let t = if s == 0.0 { 0.0 } else { q / s };
        roots.push(s + t - shift);
    }
    roots
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rng(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A curved reflector triangle seen from an eye: normals tilted apart.
    fn camera(seed: &mut u64) -> C3rc {
        let v = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.1 * rng(seed), 0.0),
            DVec3::new(0.2 * rng(seed), 1.0, 0.1 * rng(seed)),
        ];
        let n = [
            DVec3::new(-0.3, -0.3, 1.0),
            DVec3::new(0.35, -0.2, 1.0),
            DVec3::new(-0.1, 0.4, 1.0),
        ];
        let eye = DVec3::new(0.3 + rng(seed), 0.2 + rng(seed), 3.0);
        C3rc::reflector(v, n, eye).unwrap()
    }

    #[test]
    fn construction_rays_project_to_their_vertices_and_the_base_to_itself() {
        let mut seed = 5;
        for _ in 0..50 {
            let c = camera(&mut seed);
            for k in 0..3 {
                let lambda = 0.5 + 3.0 * rng(&mut seed);
                let q = c.v[k] + c.d[k] * lambda;
                let p = c.project(q, f64::INFINITY);
                let hit = p
                    .iter()
                    .find(|p| (p.lambda - lambda).abs() < 1e-7)
                    .expect("the construction parameter is a root");
                assert!((hit.point - c.v[k]).length() < 1e-7, "{hit:?}");
                let mut e = DVec3::ZERO;
                e[k] = 1.0;
                assert!((hit.bary - e).length() < 1e-7);
            }
            // A point of the base triangle: λ = 0, itself.
            let b = DVec3::new(0.2, 0.5, 0.3);
            let q = c.at(b, 0.0);
            let p = c.project(q, f64::INFINITY);
            let hit = p.iter().find(|p| p.lambda.abs() < 1e-9).expect("λ = 0");
            assert!((hit.point - q).length() < 1e-9 && (hit.bary - b).length() < 1e-7);
        }
    }

    #[test]
    fn random_points_of_the_view_volume_project_back_onto_rays_through_them() {
        let mut seed = 9;
        let mut multiple = 0;
        for i in 0..2000 {
            // Convex and concave reflectors alike.
            let c = if i % 2 == 0 {
                camera(&mut seed)
            } else {
                concave(&mut seed)
            };
            let (b1, b2) = (rng(&mut seed), rng(&mut seed));
            let (b1, b2) = if b1 + b2 > 1.0 {
                (1.0 - b1, 1.0 - b2)
            } else {
                (b1, b2)
            };
            let b = DVec3::new(1.0 - b1 - b2, b1, b2);
            let lambda = 4.0 * rng(&mut seed);
            let q = c.at(b, lambda);
            let p = c.project(q, f64::INFINITY);
            assert!(
                p.iter()
                    .any(|p| (p.lambda - lambda).abs() < 1e-6 && (p.bary - b).length() < 1e-6),
                "({b}, {lambda}) not among {p:?}"
            );
            // Every projection returned reconstructs a ray through the point.
            for pr in &p {
                let back = c.at(pr.bary, pr.lambda);
                assert!((back - q).length() < 1e-7, "{pr:?}");
                assert!(pr.bary.min_element() >= -BARY_EPS && pr.lambda >= 0.0);
            }
            multiple += (p.len() > 1) as usize;
        }
        println!("{multiple} of 2000 points had more than one projection");
        assert!(multiple > 0);
    }

    #[test]
    fn adjacent_cameras_agree_on_their_shared_wall() {
        let mut seed = 3;
        let eye = DVec3::new(0.4, 0.3, 3.0);
        let (a, b, c, d) = (
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 0.1),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.2),
        );
        let n = |p: DVec3| DVec3::new(p.x - 0.5, p.y - 0.5, 2.0);
        let left = C3rc::reflector([a, b, c], [n(a), n(b), n(c)], eye).unwrap();
        let right = C3rc::reflector([b, d, c], [n(b), n(d), n(c)], eye).unwrap();
        for _ in 0..200 {
            // A point on the wall over edge b–c.
            let (t, lambda) = (rng(&mut seed), 0.2 + 2.0 * rng(&mut seed));
            let q = left.at(DVec3::new(0.0, 1.0 - t, t), lambda);
            let pl = left.project(q, f64::INFINITY);
            let pr = right.project(q, f64::INFINITY);
            let on_wall = |p: &Vec<C3rcProjection>| {
                p.iter()
                    .find(|x| (x.lambda - lambda).abs() < 1e-6)
                    .map(|x| x.point)
            };
            let (x, y) = (on_wall(&pl).unwrap(), on_wall(&pr).unwrap());
            assert!((x - y).length() < 1e-7, "{x} vs {y}");
        }
    }

    #[test]
    fn root_counts_match_a_scan_of_the_cubic() {
        let mut seed = 17;
        for _ in 0..500 {
            let c = [0, 1, 2, 3].map(|_| rng(&mut seed) * 2.0 - 1.0);
            let f = |x: f64| ((c[3] * x + c[2]) * x + c[1]) * x + c[0];
            // Sign changes on a fine grid over a range holding every root (Cauchy's bound).
            let bound = 1.0 + c[..3].iter().map(|v| v.abs()).fold(0.0, f64::max) / c[3].abs();
            let steps = 200_000;
            let mut changes = 0;
            let mut prev = f(-bound);
            for i in 1..=steps {
                let x = -bound + 2.0 * bound * i as f64 / steps as f64;
                let y = f(x);
                if (y > 0.0) != (prev > 0.0) {
                    changes += 1;
                }
                prev = y;
            }
            let roots = real_roots(c);
            assert_eq!(roots.len(), changes, "{c:?}: {roots:?}");
            for r in roots {
                assert!(f(r).abs() < 1e-9, "{c:?}: f({r}) = {}", f(r));
            }
        }
        // Degenerate leading terms fall back to lower degrees.
        assert_eq!(real_roots([-2.0, 1.0, 0.0, 0.0]), vec![2.0]);
        assert_eq!(real_roots([-1.0, 0.0, 1.0, 0.0]), vec![-1.0, 1.0]);
        assert!(real_roots([1.0, 0.0, 0.0, 0.0]).is_empty());
    }

    /// A concave reflector: its construction rays converge and cross, so points beyond the
    /// crossing have several projections.
    fn concave(seed: &mut u64) -> C3rc {
        let v = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let tilt = 0.4 + 0.3 * rng(seed);
        let n = [
            DVec3::new(tilt, tilt, 1.0),
            DVec3::new(-tilt, 0.2 * rng(seed), 1.0),
            DVec3::new(0.1 * rng(seed), -tilt, 1.0),
        ];
        C3rc::reflector(v, n, DVec3::new(0.33, 0.33, 4.0)).unwrap()
    }

    #[test]
    fn the_multiple_projection_test_brackets_every_multiple_projection() {
        let mut seed = 23;
        let mut multiple = 0;
        for _ in 0..300 {
            let c = concave(&mut seed);
            let ranges = c.multiple_projection_ranges(6.0);
            let inside = |l: f64| ranges.iter().any(|&(a, b)| l >= a - 1e-9 && l <= b + 1e-9);
            for _ in 0..10 {
                let (b1, b2) = (rng(&mut seed), rng(&mut seed));
                let (b1, b2) = if b1 + b2 > 1.0 {
                    (1.0 - b1, 1.0 - b2)
                } else {
                    (b1, b2)
                };
                let q = c.at(DVec3::new(1.0 - b1 - b2, b1, b2), 6.0 * rng(&mut seed));
                let p = c.project(q, 6.0);
                if p.len() > 1 {
                    multiple += 1;
                    for pr in &p {
                        assert!(inside(pr.lambda), "λ {} outside {ranges:?}", pr.lambda);
                    }
                }
            }
        }
        // The test means something: the concave mirrors do project points several times.
        println!("{multiple} of 3000 points had more than one projection");
        assert!(multiple > 50, "{multiple}");
    }

    #[test]
    fn box_culling_never_drops_a_box_holding_a_seen_point() {
        let mut seed = 41;
        let (mut kept_seen, mut dropped, mut kept_empty) = (0, 0, 0);
        for case in 0..600 {
            let c = if case % 2 == 0 {
                camera(&mut seed)
            } else {
                concave(&mut seed)
            };
            let lambda_max = if case % 3 == 0 { f64::INFINITY } else { 4.0 };
            let lambda_min = if case % 4 == 1 { 0.3 } else { 0.0 };
            // Boxes of every size around the volume's first few units.
            let centre = DVec3::new(
                3.0 * rng(&mut seed) - 1.0,
                3.0 * rng(&mut seed) - 1.0,
                4.0 * rng(&mut seed) - 0.5,
            );
            let half = DVec3::new(rng(&mut seed), rng(&mut seed), rng(&mut seed))
                * (0.05 + 0.6 * rng(&mut seed));
            let (lo, hi) = (centre - half, centre + half);
            let keep = c.may_see_box_between(lo, hi, lambda_min, lambda_max);
            // Brute force: a fine grid of points in the box.
            let steps = 9;
            let mut seen = false;
            'grid: for x in 0..steps {
                for y in 0..steps {
                    for z in 0..steps {
                        let f = DVec3::new(x as f64, y as f64, z as f64) / (steps - 1) as f64;
                        if c.sees_between(lo + (hi - lo) * f, lambda_min, lambda_max) {
                            seen = true;
                            break 'grid;
                        }
                    }
                }
            }
            assert!(
                keep || !seen,
                "case {case}: dropped a box with a seen point"
            );
            match (keep, seen) {
                (true, true) => kept_seen += 1,
                (false, _) => dropped += 1,
                (true, false) => kept_empty += 1,
            }
        }
        println!("kept with points {kept_seen}, dropped {dropped}, kept empty {kept_empty}");
        // The test culls, and is not merely "keep everything".
        assert!(dropped > 100 && kept_seen > 100, "{dropped} {kept_seen}");
    }
}
