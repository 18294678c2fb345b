//! The view volume of a continuous 3-ray camera against a box: the conservative test that culls
//! kd-tree nodes (paper 2 §5.2; docs/conventions.md §7.4).
//!
//! A box can hold a point the camera sees only if one of these holds: a corner of the box is
//! seen (the box is inside the volume, or straddles it); a side wall — the ruled surface swept by
//! a base edge, `S(α, λ) = P(α) + λD(α)` — meets a face of the box; the base triangle or the far
//! cap `T(λmax)` overlaps the box (the volume starts or ends inside it, the two cases the paper's
//! two conditions miss); or the box overlaps the hull of the sweep over a range where the sweep
//! folds back on itself (multiple projections, where the volume's boundary may include the fold).
//!
//! Invariants: conservative — a box that holds a seen point is never dropped (tested against
//! brute-force projection); leaves are treated as full.

use super::C3rc;
use glam::DVec3;

impl C3rc {
    /// Whether the box `[lo, hi]` may hold a point with a projection with `0 ≤ λ ≤ lambda_max`.
    /// Conservative: it may say yes for a box that holds none, never no for one that holds one.
    pub fn may_see_box(&self, lo: DVec3, hi: DVec3, lambda_max: f64) -> bool {
        self.may_see_box_between(lo, hi, 0.0, lambda_max)
    }

    /// [`C3rc::may_see_box`] for the volume cut to `lambda_min ≤ λ ≤ lambda_max`: the near cap
    /// `T(lambda_min)` takes the base's place.
    pub fn may_see_box_between(
        &self,
        lo: DVec3,
        hi: DVec3,
        lambda_min: f64,
        lambda_max: f64,
    ) -> bool {
        let tol = 1e-9 * (1.0 + (hi - lo).max_element() + lo.abs().max(hi.abs()).max_element());
        let (lo, hi) = (lo - DVec3::splat(tol), hi + DVec3::splat(tol));
        // Cheap rejection: the volume lies inside the hull of its base and its far cap (a point
        // of the sweep is bilinear in the barycentrics and λ).
        if lambda_max.is_finite() {
            let (hlo, hhi) = self.hull_box(lambda_min, lambda_max);
            if (hlo.cmpgt(hi) | hhi.cmplt(lo)).any() {
                return false;
            }
        }
        // A corner seen.
        for k in 0..8 {
            let corner = DVec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            if self.sees_between(corner, lambda_min, lambda_max) {
                return true;
            }
        }
        // A side wall meets a face.
        for (i, j) in [(0, 1), (1, 2), (2, 0)] {
            for axis in 0..3 {
                for c in [lo[axis], hi[axis]] {
                    let range = (lambda_min, lambda_max);
                    if self.wall_meets_face(i, j, axis, c, lo, hi, range, tol) {
                        return true;
                    }
                }
            }
        }
        // The base (the near cap) or the far cap overlaps the box.
        let near = [0, 1, 2].map(|k| self.v[k] + self.d[k] * lambda_min);
        if triangle_overlaps_box(near, lo, hi) {
            return true;
        }
        if lambda_max.is_finite() {
            let cap = [0, 1, 2].map(|k| self.v[k] + self.d[k] * lambda_max);
            if triangle_overlaps_box(cap, lo, hi) {
                return true;
            }
        }
        // Where the sweep folds, its fold may bound the volume: keep what overlaps the sweep there.
        for (a, b) in self.multiple_projection_ranges(lambda_max) {
            if b < lambda_min {
                continue;
            }
            if !b.is_finite() {
                return true;
            }
            let (hlo, hhi) = self.hull_box(a.max(lambda_min), b);
            if !(hlo.cmpgt(hi) | hhi.cmplt(lo)).any() {
                return true;
            }
        }
        false
    }

    /// The bounding box of the sweep for `λ ∈ [a, b]`: the box of `T(a)` and `T(b)`.
    pub fn hull_box(&self, a: f64, b: f64) -> (DVec3, DVec3) {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for k in 0..3 {
            for l in [a, b] {
                let p = self.v[k] + self.d[k] * l;
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        (lo, hi)
    }

    /// Whether the wall over base edge `(i, j)` meets the face `x[axis] = c` of the box, with
    /// `λ` in `range`. The set of wall parameters `α ∈ [0, 1]` that land on the face is a union
    /// of intervals bounded by `α = 0, 1`, by `λ(α) = λmin` or `λmax` (linear), and by the
    /// face's edges (quadratic): it is non-empty exactly when one of those candidates is on it.
    #[allow(clippy::too_many_arguments)]
    fn wall_meets_face(
        &self,
        i: usize,
        j: usize,
        axis: usize,
        c: f64,
        lo: DVec3,
        hi: DVec3,
        (lambda_min, lambda_max): (f64, f64),
        tol: f64,
    ) -> bool {
        let (p0, p1) = (self.v[i], self.v[j] - self.v[i]);
        let (d0, d1) = (self.d[i], self.d[j] - self.d[i]);
        let k = axis;
        let (m1, m2) = ((k + 1) % 3, (k + 2) % 3);
        // A wall lying in the face's plane: the face and the wall share a plane; keep the box.
        if d0[k].abs() <= tol
            && (d0[k] + d1[k]).abs() <= tol
            && (p0[k] - c).abs() <= tol
            && (p0[k] + p1[k] - c).abs() <= tol
        {
            return true;
        }
        let mut candidates = [0.0f64; 16];
        let mut n = 0;
        let mut add = |a: f64| {
            if n < candidates.len() && (-1e-12..=1.0 + 1e-12).contains(&a) {
                candidates[n] = a.clamp(0.0, 1.0);
                n += 1;
            }
        };
        add(0.0);
        add(1.0);
        // λ(α) = λmin or λmax: c − P_k(α) = λ·D_k(α).
        for l in [lambda_min, lambda_max] {
            if l.is_finite() {
                let slope = -p1[k] - l * d1[k];
                if slope != 0.0 {
                    add((l * d0[k] - (c - p0[k])) / slope);
                }
            }
        }
        // p_m(α) = bound: N_m(α) − bound·D_k(α) = 0, with
        // N_m = P_m·D_k + (c − P_k)·D_m (quadratic in α).
        for m in [m1, m2] {
            let (a0, a1, b0, b1) = (p0[m], p1[m], d0[k], d1[k]);
            let (e0, e1, q0, q1) = (d0[m], d1[m], c - p0[k], -p1[k]);
            let n0 = a0 * b0 + q0 * e0;
            let n1 = a0 * b1 + a1 * b0 + q0 * e1 + q1 * e0;
            let n2 = a1 * b1 + q1 * e1;
            for bound in [lo[m], hi[m]] {
                let roots = super::roots_of([n0 - bound * b0, n1 - bound * b1, n2, 0.0]);
                for &r in roots.as_slice() {
                    add(r);
                }
            }
        }
        candidates[..n].iter().any(|&a| {
            let dk = d0[k] + d1[k] * a;
            if dk == 0.0 {
                return false;
            }
            let p = p0 + p1 * a;
            let lambda = (c - p[k]) / dk;
            if !(lambda >= lambda_min - tol && lambda <= lambda_max + tol) {
                return false;
            }
            let q = p + (d0 + d1 * a) * lambda;
            [m1, m2]
                .iter()
                .all(|&m| q[m] >= lo[m] - tol && q[m] <= hi[m] + tol)
        })
    }
}

/// Whether a triangle overlaps a box: the separating-axis test on the box's three axes, the
/// triangle's normal and the nine edge–axis cross products (Akenine-Möller 2001).
fn triangle_overlaps_box(t: [DVec3; 3], lo: DVec3, hi: DVec3) -> bool {
    let centre = (lo + hi) * 0.5;
    let half = (hi - lo) * 0.5;
    let v = t.map(|p| p - centre);
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    let separated = |axis: DVec3| {
        if axis.length_squared() < 1e-300 {
            return false;
        }
        let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in v {
            let d = p.dot(axis);
            a = a.min(d);
            b = b.max(d);
        }
        let r = half.dot(axis.abs());
        a > r || b < -r
    };
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    if axes.iter().any(|&a| separated(a)) || separated(edges[0].cross(edges[1])) {
        return false;
    }
    !edges
        .iter()
        .any(|e| axes.iter().any(|&a| separated(e.cross(a))))
}
