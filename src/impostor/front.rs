//! Front bounds (beyond paper 1): for every texel, the largest `gd` a point can have
//! while projecting into the texel and lying behind (or on) the texel's stored plane. A walk
//! sample with a larger `gd` is in front of its texel's surface (`delta > 0` in
//! [`super::walk`]), so no crossing can end there. The max pyramid of these bounds lets the
//! texel walk step over nodes of covered texels too, not only empty ones.
//!
//! Math. With the texel's plane through `P` with normal `N` turned toward the camera:
//! - pinhole (McMillan `X = C + t·(a·u + b·v + c)`, `gd = 1/t`): the pre-image of `(u, v)`
//!   meets the plane at `gd*(u, v) = (d(u, v)·N) / ((P − C)·N)` with `d = a·u + b·v + c`;
//!   affine in `(u, v)`, so its maximum over the texel square is at a corner — exact;
//! - orthographic (`X = O + a·u + b·v + dir·(1 − gd)·depth`): `gd* = 1 + (O + a·u + b·v −
//!   P)·N / (depth·(dir·N))`, affine too — exact;
//! - SPOC: a pixel's pre-image at depth `z` is the pinhole point `q = p0 + (u′ − p0)/(1 +
//!   κ(z))`; over the depths of the walk's reach (the box grown by the exit margin, where
//!   every walk sample lies) `κ` spans `[κ_lo, κ_hi]`, so the texel's pre-image lies in the
//!   convex hull of the texel square
//!   undistorted by `κ_lo` and by `κ_hi`, and the pinhole bound at those eight corners bounds
//!   it — exact, if loose far from the pole;
//! - graph camera: unbounded (its walks do not use the pyramid).
//!
//! Invariant: empty texels have bound 0; every bound is rounded up by a relative 1e-5.

use super::{Impostor, ImpostorCamera};
use crate::camera::Pinhole;
use crate::frame::Image;
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// Relative margin added to every bound (rounding of `f32` maps and of the walk's arithmetic).
const MARGIN: f64 = 1e-5;

/// Writes the front bound of every texel of `impostor` into `out` (row-major, the impostor's
/// size), in parallel over rows.
pub fn front_bounds_into(impostor: &Impostor, out: &mut [f32]) {
    let w = impostor.gd.size().0 as usize;
    // The SPOC's κ range over the walk's reach (the bounding box grown by the exit margin,
    // where every walk sample lies) is the same for every texel.
    let kappa = match &impostor.camera {
        ImpostorCamera::Spoc(s) => {
            let margin = glam::Vec3::splat(super::walk::exit_margin(impostor));
            let reach = crate::geom::Aabb {
                min: impostor.bounds.min - margin,
                max: impostor.bounds.max + margin,
            };
            spoc_kappa_range(s, &reach)
        }
        _ => None,
    };
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, b) in row.iter_mut().enumerate() {
            *b = texel_bound(impostor, kappa, x as u32, y as u32);
        }
    });
}

/// The front bound of every texel of `impostor`, as an image.
pub fn front_bounds(impostor: &Impostor) -> Image<f32> {
    let (w, h) = impostor.gd.size();
    let mut out = vec![0.0; w as usize * h as usize];
    front_bounds_into(impostor, &mut out);
    Image::from_vec(w, h, out).expect("the size of the impostor")
}

fn texel_bound(imp: &Impostor, kappa: Option<(f64, f64)>, x: u32, y: u32) -> f32 {
    let gd = imp.gd.get(x, y);
    if gd <= 0.0 {
        return 0.0;
    }
    let p = imp.position_at(x, y).as_dvec3();
    let n = imp.face_normal_at(x, y).as_dvec3();
    let square = |grow: f64| {
        let (x0, y0) = (x as f64 - grow, y as f64 - grow);
        let (x1, y1) = (x as f64 + 1.0 + grow, y as f64 + 1.0 + grow);
        [(x0, y0), (x1, y0), (x0, y1), (x1, y1)].map(|(u, v)| DVec2::new(u, v))
    };
    let bound = match &imp.camera {
        ImpostorCamera::Pinhole(c) => pinhole_bound(c, p, n, square(0.0)),
        ImpostorCamera::Spoc(s) => {
            // Every depth a walk sample can have lies in the walk's reach's depth range, so
            // the texel's pre-image lies in the hull of the texel square undistorted with the
            // smallest and the largest κ there; gd* is affine over it: its corners bound it.
            let Some((k_lo, k_hi)) = kappa else {
                return f32::INFINITY;
            };
            let pole = s.pole();
            let sq = square(0.0);
            let lo = sq.map(|c| pole + (c - pole) / (1.0 + k_lo));
            let hi = sq.map(|c| pole + (c - pole) / (1.0 + k_hi));
            pinhole_bound(s.pinhole(), p, n, lo).max(pinhole_bound(s.pinhole(), p, n, hi))
        }
        ImpostorCamera::Orthographic(o) => {
            let (origin, a, b, dir, depth) = o.parameters();
            let dn = dir.dot(n) * depth;
            if dn < 0.0 {
                square(0.0)
                    .iter()
                    .map(|c| 1.0 + (origin + a * c.x + b * c.y - p).dot(n) / dn)
                    .fold(0.0, f64::max)
            } else {
                f64::INFINITY
            }
        }
        ImpostorCamera::Graph(_) => f64::INFINITY,
    };
    let up = bound.max(0.0) * (1.0 + MARGIN);
    if up.is_finite() {
        // Round up to an f32 no smaller than the bound.
        let f = up as f32;
        if (f as f64) < up {
            f32::from_bits(f.to_bits() + 1)
        } else {
            f
        }
    } else {
        f32::INFINITY
    }
}

/// The range of the SPOC's `κ` over the depths of `bounds` (`None` if a corner is not in
/// front of the camera). `κ` is monotone in depth, so the box corners give it.
fn spoc_kappa_range(s: &crate::camera::Spoc, bounds: &crate::geom::Aabb) -> Option<(f64, f64)> {
    use crate::camera::Projection;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..8 {
        let c = glam::Vec3::new(
            if i & 1 == 0 {
                bounds.min.x
            } else {
                bounds.max.x
            },
            if i & 2 == 0 {
                bounds.min.y
            } else {
                bounds.max.y
            },
            if i & 4 == 0 {
                bounds.min.z
            } else {
                bounds.max.z
            },
        );
        let q = s.pinhole().project(c.as_dvec3())?;
        let kappa = s.kappa(s.pinhole().focal() / q.gd);
        (lo, hi) = (lo.min(kappa), hi.max(kappa));
    }
    Some((lo, hi))
}

/// `max over corners of (d(c)·N)/((P − C)·N)`, or ∞ when the camera is not in front of the
/// plane.
fn pinhole_bound(c: &Pinhole, p: DVec3, n: DVec3, corners: [DVec2; 4]) -> f64 {
    let cp = (p - c.position()).dot(n);
    if cp.is_nan() || cp >= 0.0 {
        return f64::INFINITY;
    }
    let (a, b, cc) = c.mcmillan();
    corners
        .iter()
        .map(|q| (a * q.x + b * q.y + cc).dot(n) / cp)
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Spoc;
    use crate::geom::SplitMix64;
    use glam::Vec3;

    /// Points in a texel's pre-image (within the bounding box) that lie behind its plane never
    /// have a `gd` above its bound.
    #[test]
    fn no_point_behind_a_texel_plane_exceeds_its_bound() {
        let sphere = crate::geom::icosphere(3);
        let eye = Vec3::new(0.3, 0.4, 3.0);
        let cameras = [
            ImpostorCamera::Spoc(Spoc::around(eye, Vec3::ZERO, 1.0, 1.0, 64).unwrap()),
            ImpostorCamera::Pinhole(
                Pinhole::look_at(eye, Vec3::ZERO, Vec3::Y, 45.0, 64, 64).unwrap(),
            ),
        ];
        for camera in cameras {
            let imp = super::super::build(camera, &sphere, 0, &|_| Vec3::ONE).unwrap();
            let bounds = front_bounds(&imp);
            let mut rng = SplitMix64::new(3);
            let (mut behind, mut tight) = (0, 0);
            for _ in 0..200_000 {
                let (x, y) = (
                    (rng.next_f32() * 64.0) as u32,
                    (rng.next_f32() * 64.0) as u32,
                );
                let (x, y) = (x.min(63), y.min(63));
                if imp.gd.get(x, y) <= 0.0 {
                    continue;
                }
                let uv = DVec2::new(
                    x as f64 + rng.next_f32() as f64,
                    y as f64 + rng.next_f32() as f64,
                );
                let gd = imp.gd.get(x, y) as f64 * (0.7 + 0.6 * rng.next_f32() as f64);
                let p = imp.camera.unproject(uv, gd);
                let q = p.as_vec3();
                if q.cmplt(imp.bounds.min).any() || q.cmpgt(imp.bounds.max).any() {
                    continue;
                }
                let (sp, n) = (
                    imp.position_at(x, y).as_dvec3(),
                    imp.face_normal_at(x, y).as_dvec3(),
                );
                if (p - sp).dot(n) <= 0.0 {
                    behind += 1;
                    let b = bounds.get(x, y) as f64;
                    assert!(
                        gd <= b,
                        "{}: texel ({x}, {y}) gd {gd} above bound {b}",
                        imp.camera.kind()
                    );
                    tight += (gd > 0.97 * b) as u32;
                }
            }
            assert!(behind > 1000, "{behind}");
            // The bound is useful: some points behind come close to it.
            assert!(tight > 0, "{}: bound never approached", imp.camera.kind());
        }
    }
}
