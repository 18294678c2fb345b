//! The optics of perfect mirrors and smooth dielectrics: reflection, Snell refraction, exact
//! Fresnel weights, the side of a surface a viewer is on, and the mirror ray a renderer or a
//! fidelity check sends out (paper 1 §1: reflected and refracted rays are what impostors answer).
//!
//! Invariants: every direction returned is unit length when the inputs are; nothing here knows
//! about meshes, cameras or ray queries.

use super::Ray;
use glam::Vec3;

/// Mirror direction of `d` about unit normal `n`: `d − 2(d·n)n`.
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Snell refraction of unit `d` through unit `n` (facing against `d`) with `eta = n₁/n₂`;
/// `None` on total internal reflection.
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    (k >= 0.0).then(|| (eta * d + (eta * cos_i - k.sqrt()) * n).normalize())
}

/// Unpolarized Fresnel reflectance of a smooth dielectric (exact form), `cos_i ≥ 0`,
/// `eta = n₁/n₂`. 1 on total internal reflection.
pub fn fresnel(cos_i: f32, eta: f32) -> f32 {
    let sin_t2 = eta * eta * (1.0 - cos_i * cos_i);
    if sin_t2 >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t2).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// The shading normal turned to the side the viewer (ray direction `d`) is on, decided by the
/// geometric normal `ng`. Returns `(n, ng)` both facing the viewer, and whether the ray hit the
/// front (counter-clockwise) side.
pub fn facing(d: Vec3, n: Vec3, ng: Vec3) -> (Vec3, Vec3, bool) {
    let front = d.dot(ng) < 0.0;
    let ng = if front { ng } else { -ng };
    let n = if n.dot(ng) < 0.0 { -n } else { n };
    (n, ng, front)
}

/// The mirror ray of `ray` at a surface point `position` with shading normal `normal` and
/// geometric normal `geometric_normal`: reflected about the shading normal turned toward the
/// viewer ([`facing`]), starting `epsilon` off the surface along the geometric normal.
pub fn mirror_ray(
    ray: &Ray,
    position: Vec3,
    normal: Vec3,
    geometric_normal: Vec3,
    epsilon: f32,
) -> Ray {
    let (n, ng, _) = facing(ray.dir, normal, geometric_normal);
    Ray::new(position + ng * epsilon, reflect(ray.dir, n).normalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_matches_known_values() {
        // Normal incidence on glass: ((1 − 1.5)/(1 + 1.5))² = 0.04.
        assert!((fresnel(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-6);
        // Grazing incidence reflects everything; past the critical angle too.
        assert!((fresnel(0.0, 1.0 / 1.5) - 1.0).abs() < 1e-6);
        assert_eq!(fresnel(0.1, 1.5), 1.0);
    }

    #[test]
    fn refraction_obeys_snell() {
        let n = Vec3::Y;
        let d = Vec3::new(0.6, -0.8, 0.0);
        let t = refract(d, n, 1.0 / 1.5).unwrap();
        let (sin_i, sin_t) = (d.x, t.x);
        assert!((sin_i - 1.5 * sin_t).abs() < 1e-6);
        assert!(refract(Vec3::new(0.9, -0.436, 0.0).normalize(), n, 1.5).is_none());
        assert!((reflect(d, n) - Vec3::new(0.6, 0.8, 0.0)).length() < 1e-6);
    }

    #[test]
    fn a_mirror_ray_leaves_on_the_viewers_side() {
        // Seen from above, a floor whose normals point down still reflects upward.
        let ray = Ray::new(
            Vec3::new(0.0, 1.0, -1.0),
            Vec3::new(0.0, -1.0, 1.0).normalize(),
        );
        let r = mirror_ray(&ray, Vec3::ZERO, -Vec3::Y, -Vec3::Y, 1e-3);
        assert!((r.origin - Vec3::new(0.0, 1e-3, 0.0)).length() < 1e-7);
        assert!((r.dir - Vec3::new(0.0, 1.0, 1.0).normalize()).length() < 1e-6);
    }
}
