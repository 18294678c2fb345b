//! The planar pinhole camera in McMillan's form (McMillan 1997; docs/conventions.md §1.1).

use super::{CameraError, ImagePoint, Projection};
use crate::geom::Ray;
use glam::{DMat3, DVec2, DVec3, Vec3};

/// A planar pinhole camera: centre of projection `C` and `M = [a | b | c]`, where `a` and `b` are
/// the world vectors of one pixel step in `+u` and `+v` and `c` goes from `C` to the corner of
/// pixel `(0, 0)`. The image plane is at unit focal distance, so `t` equals eye-space depth `z`
/// and `gd = 1/z`.
#[derive(Clone, Debug, PartialEq)]
pub struct Pinhole {
    c: DVec3,
    m: DMat3,
    m_inv: DMat3,
    forward: DVec3,
    near: f64,
    width: u32,
    height: u32,
}

/// Default near-plane distance, in world units.
pub const DEFAULT_NEAR: f64 = 1e-3;

impl Pinhole {
    /// A camera at `position` looking at `look_at`, `up` roughly up, full vertical field of view
    /// `fov_y_deg` degrees, `width × height` pixels (`docs/conventions.md` §1.1).
    pub fn look_at(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        fov_y_deg: f64,
        width: u32,
        height: u32,
    ) -> Result<Self, CameraError> {
        crate::frame::check_size(width as u64, height as u64)?;
        if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) {
            return Err(CameraError::FieldOfView(fov_y_deg));
        }
        let (eye, target, up) = (position.as_dvec3(), look_at.as_dvec3(), up.as_dvec3());
        if !(eye.is_finite() && target.is_finite() && up.is_finite()) {
            return Err(CameraError::Degenerate(
                "position, look_at and up must be finite",
            ));
        }
        let [forward, right, true_up] = super::look_at_basis(eye, target, up)?;
        // Pixel size at unit distance; v grows downward (image origin top-left).
        let s = 2.0 * (fov_y_deg.to_radians() * 0.5).tan() / height as f64;
        let a = right * s;
        let b = -true_up * s;
        let c = forward - a * (width as f64 * 0.5) - b * (height as f64 * 0.5);
        Ok(Self::from_mcmillan(eye, a, b, c, width, height))
    }

    /// A camera at `position` looking at `look_at`, `up` roughly up, with pixel intrinsics: focal
    /// lengths `fx`, `fy` and principal point `(cx, cy)` in pixels, `(0, 0)` the top-left
    /// corner of the top-left pixel (COLMAP's PINHOLE model; `docs/conventions.md` §1.1).
    #[allow(clippy::too_many_arguments)]
    pub fn with_intrinsics(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        [fx, fy, cx, cy]: [f64; 4],
        width: u32,
        height: u32,
    ) -> Result<Self, CameraError> {
        crate::frame::check_size(width as u64, height as u64)?;
        if !(fx > 0.0 && fy > 0.0 && fx.is_finite() && fy.is_finite()) {
            return Err(CameraError::Degenerate(
                "focal lengths must be positive and finite",
            ));
        }
        if !(cx.is_finite() && cy.is_finite()) {
            return Err(CameraError::Degenerate(
                "the principal point must be finite",
            ));
        }
        let (eye, target, up) = (position.as_dvec3(), look_at.as_dvec3(), up.as_dvec3());
        if !(eye.is_finite() && target.is_finite() && up.is_finite()) {
            return Err(CameraError::Degenerate(
                "position, look_at and up must be finite",
            ));
        }
        let [forward, right, true_up] = super::look_at_basis(eye, target, up)?;
        let a = right / fx;
        let b = -true_up / fy;
        let c = forward - a * cx - b * cy;
        Ok(Self::from_mcmillan(eye, a, b, c, width, height))
    }

    /// A camera from McMillan's parameters directly (`a`, `b`, `c` as in docs/conventions.md §1.1).
    pub fn from_mcmillan(
        c_pos: DVec3,
        a: DVec3,
        b: DVec3,
        c: DVec3,
        width: u32,
        height: u32,
    ) -> Self {
        let m = DMat3::from_cols(a, b, c);
        let mut forward = a.cross(b).normalize_or_zero();
        if forward.dot(c) < 0.0 {
            forward = -forward;
        }
        Self {
            c: c_pos,
            m,
            m_inv: m.inverse(),
            forward,
            near: DEFAULT_NEAR,
            width,
            height,
        }
    }

    /// This camera with its near plane at eye-space depth `near > 0`.
    pub fn with_near(mut self, near: f64) -> Self {
        self.near = near.max(f64::MIN_POSITIVE);
        self
    }

    /// McMillan's `(a, b, c)`: the world steps of one pixel in `u` and `v`, and the vector from
    /// the centre of projection to the corner of pixel `(0, 0)`.
    pub fn mcmillan(&self) -> (DVec3, DVec3, DVec3) {
        (self.m.x_axis, self.m.y_axis, self.m.z_axis)
    }

    /// `M⁻¹` (rows: the world covectors of `u·t`, `v·t` and `t`).
    pub fn mcmillan_inverse(&self) -> DMat3 {
        self.m_inv
    }

    /// Near-plane distance.
    pub fn near(&self) -> f64 {
        self.near
    }

    /// Centre of projection.
    pub fn position(&self) -> DVec3 {
        self.c
    }

    /// Unit viewing direction (the image plane normal, toward the scene).
    pub fn forward(&self) -> DVec3 {
        self.forward
    }

    /// `M⁻¹(X − C) = t·(u, v, 1)`: the homogeneous image point of `X` (`t` is its last
    /// coordinate; eye-space depth is `f·t`).
    pub(crate) fn homogeneous(&self, p: DVec3) -> DVec3 {
        self.m_inv * (p - self.c)
    }

    /// Focal distance `f = c·n̂` (1 for cameras from [`Pinhole::look_at`]).
    pub fn focal(&self) -> f64 {
        self.m.z_axis.dot(self.forward)
    }

    /// The ray through image point `uv`, unit direction: `t` along it is Euclidean distance.
    pub fn ray(&self, uv: DVec2) -> Ray {
        let d = self.m * uv.extend(1.0);
        Ray::new(self.c.as_vec3(), d.normalize().as_vec3())
    }

    /// Euclidean distance from the eye of the point seen at `uv` with generalized depth `gd`.
    pub fn distance(&self, uv: DVec2, gd: f64) -> f64 {
        (self.m * uv.extend(1.0)).length() / gd
    }
}

impl Projection for Pinhole {
    fn resolution(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// `w = M⁻¹(X − C)`, `u = w.x/w.z`, `v = w.y/w.z`, `gd = 1/w.z`.
    fn project(&self, p: DVec3) -> Option<ImagePoint> {
        let w = self.homogeneous(p);
        if w.z <= 0.0 {
            return None;
        }
        let gd = 1.0 / w.z;
        Some(ImagePoint {
            uv: DVec2::new(w.x * gd, w.y * gd),
            gd,
            inv_w: gd,
        })
    }

    /// `X = C + (1/gd)·M·(u, v, 1)`.
    fn unproject(&self, uv: DVec2, gd: f64) -> DVec3 {
        self.c + self.m * uv.extend(1.0) / gd
    }

    fn clip_distance(&self, p: DVec3) -> f64 {
        (p - self.c).dot(self.forward) - self.near
    }

    /// Projective: a segment images straight.
    fn midpoint_deviation_bound(&self, _: &[ImagePoint]) -> f64 {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Pinhole {
        Pinhole::look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y, 50.0, 64, 48).unwrap()
    }

    #[test]
    fn unproject_inverts_project() {
        let cam = camera();
        for i in 0..1000u32 {
            // Replayable pseudo-random points in front of the camera.
            let h = |k: u32| {
                ((i.wrapping_mul(2_654_435_761) ^ k.wrapping_mul(40_503)) % 10_007) as f64
                    / 10_007.0
            };
            let p = DVec3::new(h(1) - 0.5, h(2) - 0.5, h(3) - 0.5) * 4.0;
            let Some(q) = cam.project(p) else { continue };
            assert!((cam.unproject(q.uv, q.gd) - p).length() < 1e-9, "{p}");
        }
    }

    #[test]
    fn look_at_target_projects_to_the_image_centre_at_its_depth() {
        let cam = camera();
        let q = cam.project(DVec3::ZERO).unwrap();
        assert!((q.uv - DVec2::new(32.0, 24.0)).length() < 1e-9);
        let z = DVec3::new(1.0, 2.0, 3.0).length();
        assert!((q.gd - 1.0 / z).abs() < 1e-12);
        assert!((cam.distance(q.uv, q.gd) - z).abs() < 1e-9);
        // Up in the world is up in the image (smaller v).
        assert!(cam.project(DVec3::new(0.0, 0.1, 0.0)).unwrap().uv.y < 24.0);
    }

    #[test]
    fn points_behind_are_outside_the_domain() {
        let cam = camera();
        assert!(cam.project(DVec3::new(2.0, 4.0, 6.0)).is_none());
        assert!(cam.clip_distance(DVec3::new(2.0, 4.0, 6.0)) < 0.0);
    }

    #[test]
    fn bad_parameters_are_errors() {
        assert!(Pinhole::look_at(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 50.0, 8, 8).is_err());
        assert!(Pinhole::look_at(Vec3::ZERO, Vec3::Y, Vec3::Y, 50.0, 8, 8).is_err());
        assert!(Pinhole::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 180.0, 8, 8).is_err());
        assert!(
            Pinhole::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 50.0, 1_000_000, 1_000_000).is_err()
        );
    }
}
