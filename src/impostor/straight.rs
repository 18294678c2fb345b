//! The exact straight walk for projective impostor cameras (pinhole, orthographic; paper 1 §3.2
//! notes the pinhole case is exact): a world segment projects to a straight image segment, so
//! the walk visits every texel the segment crosses, once, in order (a 2-D grid traversal,
//! Amanatides & Woo 1987), and tests the ray against the stored plane where it enters and leaves
//! each texel. Nothing between two samples is missed, unlike fixed sub-segments.
//!
//! Image position and the world parameter are related projectively: with homogeneous `w`
//! (`1/inv_w`: the eye depth for a pinhole, 1 for parallel projection) at the segment's ends,
//! the image point a fraction `μ` along the image segment is the world point a fraction
//! `λ = μ·w_c / ((1 − μ)·w_e + μ·w_c)` along the world segment.

use super::Impostor;
use super::walk::{Sample, WalkStats};
use crate::camera::Projection;
use crate::geom::Ray;
use crate::trace::Hit;
use glam::DVec3;

impl Impostor {
    /// Walks the world segment `[c, e]` of `ray` texel by texel through a projective camera.
    pub(super) fn walk_straight<P: Projection>(
        &self,
        camera: &P,
        ray: &Ray,
        c: DVec3,
        e: DVec3,
        stats: &mut WalkStats,
    ) -> Option<Hit> {
        let (pc, pe) = (camera.project(c)?, camera.project(e)?);
        let (wc, we) = (1.0 / pc.inv_w, 1.0 / pe.inv_w);
        let (a, d) = (pc.uv, pe.uv - pc.uv);
        stats.projection_length = d.length().ceil() as u64;
        let (w, h) = self.gd.size();
        // Clip the image segment to the image (Liang–Barsky); outside, every texel is empty.
        let (mut mu0, mut mu1) = (0.0f64, 1.0f64);
        for (p, q) in [
            (-d.x, a.x),
            (d.x, w as f64 - a.x),
            (-d.y, a.y),
            (d.y, h as f64 - a.y),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return None;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    mu0 = mu0.max(r);
                } else {
                    mu1 = mu1.min(r);
                }
            }
        }
        if mu0 > mu1 {
            return None;
        }
        let world = |mu: f64| {
            let lambda = mu * wc / ((1.0 - mu) * we + mu * wc);
            c + (e - c) * lambda
        };
        let at_uv = |mu: f64| a + d * mu;
        // Grid traversal from the texel holding the clipped start.
        let mid_start = at_uv(mu0 + (mu1 - mu0) * 1e-9);
        let mut cell = [
            (mid_start.x.floor() as i64).clamp(0, w as i64 - 1),
            (mid_start.y.floor() as i64).clamp(0, h as i64 - 1),
        ];
        let step = [d.x.signum() as i64, d.y.signum() as i64];
        let next_boundary = |cell: [i64; 2], k: usize| -> f64 {
            let dk = if k == 0 { d.x } else { d.y };
            let ak = if k == 0 { a.x } else { a.y };
            if dk == 0.0 {
                return f64::INFINITY;
            }
            let b = if dk > 0.0 {
                (cell[k] + 1) as f64
            } else {
                cell[k] as f64
            };
            (b - ak) / dk
        };
        let mut mu_in = mu0;
        let mut prev: Option<Sample> = None;
        loop {
            let (tx, ty) = (cell[0] as u32, cell[1] as u32);
            let (bx, by) = (next_boundary(cell, 0), next_boundary(cell, 1));
            let mu_out = bx.min(by).min(mu1);
            stats.texel_visits += 1;
            let entry = self.texel_sample(camera, world(mu_in), (tx, ty));
            let exit = self.texel_sample(camera, world(mu_out), (tx, ty));
            for cur in [entry, exit].into_iter().flatten() {
                if let Some(p) = prev
                    && p.delta > 0.0
                    && cur.delta <= 0.0
                    && let Some(hit) = self.accept(ray, &p, &cur)
                {
                    return Some(hit);
                }
                prev = Some(cur);
            }
            if mu_out >= mu1 {
                return None;
            }
            if bx <= by {
                cell[0] += step[0];
            }
            if by <= bx {
                cell[1] += step[1];
            }
            if cell[0] < 0 || cell[1] < 0 || cell[0] >= w as i64 || cell[1] >= h as i64 {
                return None;
            }
            mu_in = mu_out;
        }
    }

    /// The ray point `s` tested against texel `(x, y)` (rather than the texel `s` projects to,
    /// which at a boundary is ambiguous).
    fn texel_sample<P: Projection>(
        &self,
        camera: &P,
        s: DVec3,
        (x, y): (u32, u32),
    ) -> Option<Sample> {
        let p = camera.project(s)?;
        let (stored, delta) = self.texel_plane_side(s, x, y);
        Some(Sample {
            p,
            texel: Some((x, y)),
            stored,
            delta,
        })
    }
}
