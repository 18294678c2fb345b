//! The image of a ray segment through an impostor's camera, in closed form (paper 1 §3.2 and
//! §3.4; docs/conventions.md §2.3 and §3.2): what lets a walk visit every texel the ray crosses
//! without projecting a single point on the way.
//!
//! Along a world segment the homogeneous depth `s` of a projective camera (`1/gd` for a
//! pinhole) is affine in the ray parameter, and the image is `uv(s) = A + B/s`: a straight
//! segment. A SPOC scales that pinhole image about its pole `p0` by `σ(s) = 1 + κ(f·s)`, which
//! is 1 nearer than `z_n` and `α + β·s` on the ramp (`α = 1 − K·z_n`, `β = K·f`, `K` the ramp's
//! slope), so on the ramp the image is
//!
//! `uv(s) = P + R·s + Q/s`, with `P = p0 + α(A − p0) + β·B`, `R = β(A − p0)`, `Q = α·B`:
//!
//! a branch of a hyperbola. Each image coordinate of it turns at most once (where
//! `R·s² = Q`), so a SPOC path is at most four pieces on which both coordinates are monotone,
//! and the parameter where a coordinate reaches a grid line is a root of
//! `R·s² + (P − x)·s + Q = 0` — one division on a straight piece, one square root on a curved
//! one. A segment along which the depth does not change (an orthographic camera, or a ray
//! parallel to a pinhole's image plane) is parametrized affinely instead (`Q = 0`).
//!
//! Invariants: every piece's `s` is positive; both image coordinates are monotone on a piece;
//! consecutive pieces meet; the world point and `gd` at `s` are those the camera gives.

use crate::camera::{ImagePoint, Spoc};
use glam::{DVec2, DVec3};

/// Most pieces a path has: the straight part before the SPOC's ramp, and the ramp cut at the
/// turning points of its two coordinates.
const MAX_PIECES: usize = 4;

/// A stretch of an image path on which both image coordinates are monotone:
/// `uv(s) = p + r·s + q/s` for `s` from `from` to `to` (walk order; `s` may decrease).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Piece {
    p: DVec2,
    r: DVec2,
    q: DVec2,
    /// Where the walk enters the piece.
    pub from: f64,
    /// Where the walk leaves it.
    pub to: f64,
}

impl Piece {
    /// The image point at parameter `s`.
    #[inline]
    pub fn uv(&self, s: f64) -> DVec2 {
        self.p + self.r * s + self.q / s
    }

    /// The parameter on this piece where image coordinate `axis` (0: `u`, 1: `v`) equals `x`,
    /// if the piece reaches it (to rounding: a root a hair outside is clamped onto the piece).
    #[inline]
    pub fn crossing(&self, axis: usize, x: f64) -> Option<f64> {
        let (a, b, c) = (self.r[axis], self.p[axis] - x, self.q[axis]);
        let (lo, hi) = (self.from.min(self.to), self.from.max(self.to));
        let slack = (hi - lo) * 1e-9;
        let on = |s: f64| (s >= lo - slack && s <= hi + slack).then(|| s.clamp(lo, hi));
        if a == 0.0 {
            // Straight: p + q/s = x.
            return if b == 0.0 { None } else { on(-c / b) };
        }
        if c == 0.0 {
            // Affine: p + r·s = x.
            return on(-b / a);
        }
        // Both roots of a·s² + b·s + c, without cancellation; the piece holds at most one
        // (its coordinates are monotone), save at a turning point where both meet. No real
        // root: the coordinate turns before reaching `x`.
        let disc = b * b - 4.0 * a * c;
        if disc < 0.0 {
            return None;
        }
        let t = -0.5 * (b + disc.sqrt().copysign(b));
        if t == 0.0 {
            return None;
        }
        on(t / a).or_else(|| on(c / t))
    }
}

/// The closed-form image of a world segment: its monotone pieces, in walk order, with the world
/// point, `gd` and ray parameter as functions of the piece parameter `s`.
#[derive(Clone, Copy, Debug)]
pub(super) struct ImagePath {
    pieces: [Piece; MAX_PIECES],
    count: usize,
    /// World point `x0 + x1·s`.
    x0: DVec3,
    x1: DVec3,
    /// `gd = g0 + g1·s + g2/s`.
    g: [f64; 3],
}

impl ImagePath {
    /// The path of the world segment `[c, e]` through a projective camera (pinhole,
    /// orthographic, one frustum of a graph camera) that images its ends at `pc`, `pe`: a
    /// straight image segment.
    pub fn projective(c: DVec3, e: DVec3, pc: ImagePoint, pe: ImagePoint) -> ImagePath {
        let (wc, we) = (1.0 / pc.inv_w, 1.0 / pe.inv_w);
        if (we - wc).abs() > 1e-9 * wc.abs().max(we.abs()) {
            // s = w: the homogeneous image w·uv is affine in w.
            let dw = we - wc;
            let x1 = (e - c) / dw;
            let h1 = (pe.uv * we - pc.uv * wc) / dw;
            let piece = Piece {
                p: h1,
                r: DVec2::ZERO,
                q: pc.uv * wc - h1 * wc,
                from: wc,
                to: we,
            };
            // gd = inv_w = 1/w for perspective cameras.
            ImagePath::of_pieces(&[piece], c - x1 * wc, x1, [0.0, 0.0, 1.0])
        } else {
            ImagePath::affine(c, e, pc, pe)
        }
    }

    /// The depth does not change along the segment: `s = 1 + λ`, `λ` the fraction of the way
    /// from `c` to `e` (so `s` is positive and the image and `gd` are affine in it).
    fn affine(c: DVec3, e: DVec3, pc: ImagePoint, pe: ImagePoint) -> ImagePath {
        let d = pe.uv - pc.uv;
        let piece = Piece {
            p: pc.uv - d,
            r: d,
            q: DVec2::ZERO,
            from: 1.0,
            to: 2.0,
        };
        let dg = pe.gd - pc.gd;
        ImagePath::of_pieces(&[piece], c - (e - c), e - c, [pc.gd - dg, dg, 0.0])
    }

    /// The path of the world segment `[c, e]` through a SPOC; `None` if an end is behind its
    /// reference pinhole.
    pub fn spoc(camera: &Spoc, c: DVec3, e: DVec3) -> Option<ImagePath> {
        use crate::camera::Projection;
        let pinhole = camera.pinhole();
        let (qc, qe) = (pinhole.project(c)?, pinhole.project(e)?);
        let base = ImagePath::projective(c, e, qc, qe);
        let p0 = camera.pole();
        let f = pinhole.focal();
        let straight = base.pieces[0];
        if base.g[2] == 0.0 {
            // One depth along the whole segment: one scaling about the pole.
            let scale = 1.0 + camera.kappa(f * 0.5 * (1.0 / qc.gd + 1.0 / qe.gd));
            let piece = Piece {
                p: p0 + (straight.p - p0) * scale,
                r: straight.r * scale,
                ..straight
            };
            return Some(ImagePath::of_pieces(&[piece], base.x0, base.x1, base.g));
        }
        let (z_near, z_far) = camera.depth_range();
        let slope = camera.strength() / (z_far - z_near);
        let (alpha, beta) = (1.0 - slope * z_near, slope * f);
        let (a, b) = (straight.p, straight.q);
        let ramp = Piece {
            p: p0 + (a - p0) * alpha + b * beta,
            r: (a - p0) * beta,
            q: b * alpha,
            ..straight
        };
        // The ramp starts at eye depth z_n: s = z_n / f.
        let s_near = z_near / f;
        let (from, to) = (straight.from, straight.to);
        let (lo, hi) = (from.min(to), from.max(to));
        let mut pieces = [Piece::default(); 2];
        let mut n = 0;
        if lo < s_near {
            pieces[n] = Piece {
                from: lo,
                to: hi.min(s_near),
                ..straight
            };
            n += 1;
        }
        if hi > s_near {
            pieces[n] = Piece {
                from: lo.max(s_near),
                to: hi,
                ..ramp
            };
            n += 1;
        }
        if from > to {
            pieces[..n].reverse();
            for p in &mut pieces[..n] {
                std::mem::swap(&mut p.from, &mut p.to);
            }
        }
        Some(ImagePath::of_pieces(&pieces[..n], base.x0, base.x1, base.g))
    }

    /// A path of `pieces` (walk order, each possibly turning), cut where a coordinate turns.
    fn of_pieces(pieces: &[Piece], x0: DVec3, x1: DVec3, g: [f64; 3]) -> ImagePath {
        let mut path = ImagePath {
            pieces: [Piece::default(); MAX_PIECES],
            count: 0,
            x0,
            x1,
            g,
        };
        for piece in pieces {
            // Turning points: u′(s) = r − q/s² vanishes at s² = q/r.
            let mut cuts = [f64::NAN; 2];
            for (axis, cut) in cuts.iter_mut().enumerate() {
                let ratio = piece.q[axis] / piece.r[axis];
                if ratio > 0.0 && ratio.is_finite() {
                    let s = ratio.sqrt();
                    let (lo, hi) = (piece.from.min(piece.to), piece.from.max(piece.to));
                    if s > lo && s < hi {
                        *cut = s;
                    }
                }
            }
            // In walk order.
            let ahead = |s: f64| (s - piece.from) * (piece.to - piece.from).signum();
            cuts.sort_by(|a, b| ahead(*a).total_cmp(&ahead(*b)));
            let mut from = piece.from;
            for cut in cuts.into_iter().filter(|c| !c.is_nan()).chain([piece.to]) {
                if cut != from && path.count < MAX_PIECES {
                    path.pieces[path.count] = Piece {
                        from,
                        to: cut,
                        ..*piece
                    };
                    path.count += 1;
                    from = cut;
                }
            }
        }
        path
    }

    /// The pieces, in walk order.
    pub fn pieces(&self) -> &[Piece] {
        &self.pieces[..self.count]
    }

    /// The world point at parameter `s`.
    #[inline]
    #[cfg(test)]
    pub fn world(&self, s: f64) -> DVec3 {
        self.x0 + self.x1 * s
    }

    /// The world point as `x0 + x1·s`: `(x0, x1)`.
    #[inline]
    pub fn world_line(&self) -> (DVec3, DVec3) {
        (self.x0, self.x1)
    }

    /// The ray's `gd` at parameter `s`.
    #[inline]
    pub fn gd(&self, s: f64) -> f64 {
        self.g[0] + self.g[1] * s + self.g[2] / s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Orthographic, Pinhole, Projection};
    use glam::Vec3;

    fn point(i: u32, k: u32) -> f64 {
        ((i.wrapping_mul(2_654_435_761) ^ k.wrapping_mul(40_503)) % 10_007) as f64 / 10_007.0
    }

    fn random_segment(i: u32) -> (DVec3, DVec3) {
        let a = DVec3::new(point(i, 1), point(i, 2), point(i, 3)) * 2.0 - 1.0;
        let b = DVec3::new(point(i, 4), point(i, 5), point(i, 6)) * 2.0 - 1.0;
        (a, b)
    }

    /// Every point of the closed form is the camera's image of the world point it names, and
    /// the pieces are monotone and meet.
    fn agrees<P: Projection>(camera: &P, path: &ImagePath, c: DVec3, e: DVec3) {
        let pieces = path.pieces();
        assert!(!pieces.is_empty());
        assert!((path.world(pieces[0].from) - c).length() < 1e-9);
        assert!((path.world(pieces[pieces.len() - 1].to) - e).length() < 1e-9);
        for w in pieces.windows(2) {
            assert_eq!(w[0].to, w[1].from);
            assert!((w[0].uv(w[0].to) - w[1].uv(w[1].from)).length() < 1e-9);
        }
        for piece in pieces {
            let mut last: Option<DVec2> = None;
            let mut trend = [0.0f64; 2];
            for k in 0..=20 {
                let s = piece.from + (piece.to - piece.from) * k as f64 / 20.0;
                let want = camera.project(path.world(s)).unwrap();
                let got = piece.uv(s);
                assert!((got - want.uv).length() < 1e-7, "{got} against {}", want.uv);
                assert!((path.gd(s) - want.gd).abs() < 1e-9 * want.gd.abs().max(1.0));
                if let Some(l) = last {
                    for axis in 0..2 {
                        let step = got[axis] - l[axis];
                        assert!(step * trend[axis] >= -1e-9, "not monotone");
                        if step.abs() > 1e-9 {
                            trend[axis] = step;
                        }
                    }
                }
                last = Some(got);
            }
            // The crossings of a grid line inside the piece land on it.
            let (a, b) = (piece.uv(piece.from), piece.uv(piece.to));
            for axis in 0..2 {
                let x = 0.5 * (a[axis] + b[axis]);
                if (a[axis] - b[axis]).abs() > 1e-6 {
                    let s = piece
                        .crossing(axis, x)
                        .expect("a crossing inside the piece");
                    assert!((piece.uv(s)[axis] - x).abs() < 1e-6);
                }
            }
        }
    }

    #[test]
    fn spoc_paths_are_the_spoc_images_of_their_segments() {
        let spoc = Spoc::around(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, 1.0, 1.2, 256).unwrap();
        let (mut curved, mut cut) = (0, 0);
        for i in 0..2000 {
            let (c, e) = random_segment(i);
            let path = ImagePath::spoc(&spoc, c, e).unwrap();
            curved += usize::from(path.pieces().iter().any(|p| p.r != DVec2::ZERO));
            cut += usize::from(path.pieces().len() > 1);
            agrees(&spoc, &path, c, e);
        }
        // Most segments lie on the ramp; some turn, or cross z_n.
        assert!(curved > 1500 && cut > 40, "{curved} curved, {cut} cut");
    }

    #[test]
    fn projective_paths_are_straight_images_of_their_segments() {
        let pinhole = Pinhole::look_at(
            Vec3::new(0.3, 0.2, 5.0),
            Vec3::ZERO,
            Vec3::Y,
            40.0,
            200,
            100,
        )
        .unwrap();
        let ortho = Orthographic::look_at(
            Vec3::new(0.4, 0.3, 4.0),
            Vec3::ZERO,
            Vec3::Y,
            1.5,
            8.0,
            128,
            128,
        )
        .unwrap();
        for i in 0..2000 {
            let (c, e) = random_segment(i);
            let path = ImagePath::projective(
                c,
                e,
                pinhole.project(c).unwrap(),
                pinhole.project(e).unwrap(),
            );
            assert_eq!(path.pieces().len(), 1);
            agrees(&pinhole, &path, c, e);
            let path =
                ImagePath::projective(c, e, ortho.project(c).unwrap(), ortho.project(e).unwrap());
            agrees(&ortho, &path, c, e);
        }
        // A segment parallel to a pinhole's image plane.
        let facing =
            Pinhole::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 40.0, 64, 64).unwrap();
        let (c, e) = (DVec3::new(-0.5, 0.1, 0.0), DVec3::new(0.5, 0.3, 0.0));
        let path =
            ImagePath::projective(c, e, facing.project(c).unwrap(), facing.project(e).unwrap());
        assert_eq!(path.g[2], 0.0);
        agrees(&facing, &path, c, e);
    }
}
