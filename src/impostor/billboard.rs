//! Billboards: a textured quad with alpha, the simplest impostor (paper 1 §2, the baseline the
//! depth impostors improve on). A ray hits where the quad's texture is opaque enough.
//!
//! Invariant: the quad is the parallelogram `center ± right ± up`; texture `(0, 0)` is its
//! corner at `center − right + up` (top-left, the image convention).

use super::{Impostor, ImpostorCamera};
use crate::camera::Projection;
use crate::frame::{Image, Rgba, Wrap};
use crate::geom::Ray;
use crate::trace::{Hit, RayQuery};
use glam::{DVec2, Vec2, Vec3};
use std::sync::Arc;

/// A textured quad.
#[derive(Clone, Debug)]
pub struct Billboard {
    /// Centre of the quad.
    pub center: Vec3,
    /// Half of the quad's horizontal edge (texture `+u`).
    pub right: Vec3,
    /// Half of the quad's vertical edge (texture `−v`).
    pub up: Vec3,
    /// Linear colour with alpha.
    pub image: Arc<Image<Rgba>>,
    /// Texels with alpha below this are holes.
    pub alpha_cutoff: f32,
    /// Object id reported by hits.
    pub object: u32,
}

impl Billboard {
    /// The billboard of a pinhole impostor: its colour image placed on the plane through the
    /// centre of the impostor's bounds, parallel to the image plane, spanning the camera's view.
    pub fn from_impostor(impostor: &Impostor, object: u32) -> Option<Billboard> {
        let ImpostorCamera::Pinhole(cam) = &impostor.camera else {
            return None;
        };
        let (w, h) = cam.resolution();
        let center = impostor.bounds.center().as_dvec3();
        let depth = (center - cam.position()).dot(cam.forward());
        if depth <= 0.0 {
            return None;
        }
        // Unproject the image corners and centre at the depth of the bounds' centre.
        let gd = cam.focal() / depth;
        let at = |u: f64, v: f64| cam.unproject(DVec2::new(u, v), gd);
        let c = at(w as f64 / 2.0, h as f64 / 2.0);
        let right = (at(w as f64, h as f64 / 2.0) - c).as_vec3();
        let up = (at(w as f64 / 2.0, 0.0) - c).as_vec3();
        Some(Billboard {
            center: c.as_vec3(),
            right,
            up,
            image: Arc::new(impostor.color_image()),
            alpha_cutoff: 0.5,
            object,
        })
    }
}

impl RayQuery for Billboard {
    fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let n = self.right.cross(self.up);
        let denom = ray.dir.dot(n);
        if denom.abs() < 1e-12 {
            return None;
        }
        let t = (self.center - ray.origin).dot(n) / denom;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let p = ray.at(t);
        let d = p - self.center;
        // Coordinates along the (possibly non-orthogonal) edges: solve d = s·right + r·up.
        let (rr, uu, ru) = (
            self.right.dot(self.right),
            self.up.dot(self.up),
            self.right.dot(self.up),
        );
        let det = rr * uu - ru * ru;
        if det <= 0.0 {
            return None;
        }
        let (dr, du) = (d.dot(self.right), d.dot(self.up));
        let s = (dr * uu - du * ru) / det;
        let r = (du * rr - dr * ru) / det;
        if s.abs() > 1.0 || r.abs() > 1.0 {
            return None;
        }
        let st = Vec2::new((s + 1.0) * 0.5, (1.0 - r) * 0.5);
        let texel = self.image.sample_uv(st, Wrap::Clamp);
        if texel.w < self.alpha_cutoff {
            return None;
        }
        let normal = n.normalize();
        let normal = if normal.dot(ray.dir) > 0.0 {
            -normal
        } else {
            normal
        };
        Some(Hit {
            t,
            position: p,
            normal,
            geometric_normal: normal,
            uv: st,
            bary: Vec2::ZERO,
            object: self.object,
            triangle: 0,
            radiance: Some(texel.truncate() / texel.w.clamp(1e-6, 1.0)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4;

    fn board() -> Billboard {
        // 2 × 1 texels: left opaque red, right transparent.
        let img = Image::from_vec(2, 1, vec![Vec4::new(1.0, 0.0, 0.0, 1.0), Vec4::ZERO]).unwrap();
        Billboard {
            center: Vec3::new(0.0, 0.0, -2.0),
            right: Vec3::X,
            up: Vec3::Y,
            image: Arc::new(img),
            alpha_cutoff: 0.5,
            object: 7,
        }
    }

    #[test]
    fn rays_hit_opaque_texels_and_pass_through_holes() {
        let b = board();
        let hit = b
            .closest_hit(
                &Ray::new(Vec3::new(-0.6, 0.2, 0.0), -Vec3::Z),
                f32::INFINITY,
            )
            .unwrap();
        assert!((hit.t - 2.0).abs() < 1e-6 && hit.object == 7);
        assert_eq!(hit.radiance, Some(Vec3::new(1.0, 0.0, 0.0)));
        assert!(hit.normal.dot(Vec3::Z) > 0.99, "faces the ray");
        assert!(
            b.closest_hit(&Ray::new(Vec3::new(0.6, 0.2, 0.0), -Vec3::Z), f32::INFINITY)
                .is_none(),
            "hole"
        );
        assert!(
            b.closest_hit(
                &Ray::new(Vec3::new(-1.5, 0.0, 0.0), -Vec3::Z),
                f32::INFINITY
            )
            .is_none(),
            "off the quad"
        );
        assert!(
            b.closest_hit(&Ray::new(Vec3::new(-0.6, 0.2, 0.0), -Vec3::Z), 1.5)
                .is_none(),
            "beyond t_max"
        );
        // Oblique ray to the same point.
        let o = Vec3::new(1.0, 1.0, 0.0);
        let target = Vec3::new(-0.6, 0.2, -2.0);
        let h = b
            .closest_hit(&Ray::new(o, (target - o).normalize()), f32::INFINITY)
            .unwrap();
        assert!((h.position - target).length() < 1e-5);
    }
}
