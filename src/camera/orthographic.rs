//! The orthographic camera: parallel rays along one direction.

use super::{CameraError, ImagePoint, Projection};
use crate::geom::Ray;
use glam::{DVec2, DVec3, Vec3};

/// Parallel projection onto an image plane. Pixel `(u, v)` looks from `corner + u·a + v·b` along
/// `dir`; `z` is the distance in front of the image plane.
///
/// Depth convention: `gd = 1 − z/depth`, which keeps docs/conventions.md §1.2's order (larger is nearer,
/// empty is 0 at `z = depth`) while staying affine in image space, as the rasterizer requires
/// (`1/t` is not affine for parallel rays). `inv_w = 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct Orthographic {
    corner: DVec3,
    a: DVec3,
    b: DVec3,
    dir: DVec3,
    depth: f64,
    width: u32,
    height: u32,
}

impl Orthographic {
    /// An image plane through `position`, perpendicular to `look_at − position`, `half_height`
    /// world units from centre to top edge, seeing `depth` units deep.
    pub fn look_at(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        half_height: f64,
        depth: f64,
        width: u32,
        height: u32,
    ) -> Result<Self, CameraError> {
        crate::frame::check_size(width as u64, height as u64)?;
        let (eye, target, up) = (position.as_dvec3(), look_at.as_dvec3(), up.as_dvec3());
        if !(half_height > 0.0 && half_height.is_finite() && depth > 0.0 && depth.is_finite()) {
            return Err(CameraError::Degenerate(
                "half_height and depth must be positive",
            ));
        }
        let [dir, right, true_up] = super::look_at_basis(eye, target, up)?;
        let s = 2.0 * half_height / height as f64;
        let (a, b) = (right * s, -true_up * s);
        let corner = eye - a * (width as f64 * 0.5) - b * (height as f64 * 0.5);
        Ok(Self {
            corner,
            a,
            b,
            dir,
            depth,
            width,
            height,
        })
    }

    /// The ray of image point `uv` (unit direction), starting on the image plane.
    pub fn ray(&self, uv: DVec2) -> Ray {
        Ray::new(
            (self.corner + self.a * uv.x + self.b * uv.y).as_vec3(),
            self.dir.as_vec3(),
        )
    }

    /// Parameters `(corner, a, b, dir, depth)`.
    pub fn parameters(&self) -> (DVec3, DVec3, DVec3, DVec3, f64) {
        (self.corner, self.a, self.b, self.dir, self.depth)
    }

    /// Rebuilds a camera from [`Orthographic::parameters`] (`a`, `b` orthogonal to `dir`).
    pub fn from_parameters(
        corner: DVec3,
        a: DVec3,
        b: DVec3,
        dir: DVec3,
        depth: f64,
        width: u32,
        height: u32,
    ) -> Result<Self, CameraError> {
        crate::frame::check_size(width as u64, height as u64)?;
        let finite = corner.is_finite() && a.is_finite() && b.is_finite() && dir.is_finite();
        if !finite
            || a.length_squared() == 0.0
            || b.length_squared() == 0.0
            || depth.is_nan()
            || depth <= 0.0
        {
            return Err(CameraError::Degenerate(
                "orthographic parameters are degenerate",
            ));
        }
        let dir = dir
            .try_normalize()
            .ok_or(CameraError::Degenerate("zero direction"))?;
        Ok(Self {
            corner,
            a,
            b,
            dir,
            depth,
            width,
            height,
        })
    }
}

impl Projection for Orthographic {
    fn resolution(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    fn project(&self, p: DVec3) -> Option<ImagePoint> {
        let r = p - self.corner;
        let z = r.dot(self.dir);
        if z < 0.0 {
            return None;
        }
        Some(ImagePoint {
            uv: DVec2::new(
                r.dot(self.a) / self.a.length_squared(),
                r.dot(self.b) / self.b.length_squared(),
            ),
            gd: 1.0 - z / self.depth,
            inv_w: 1.0,
        })
    }

    fn unproject(&self, uv: DVec2, gd: f64) -> DVec3 {
        self.corner + self.a * uv.x + self.b * uv.y + self.dir * ((1.0 - gd) * self.depth)
    }

    fn clip_distance(&self, p: DVec3) -> f64 {
        (p - self.corner).dot(self.dir)
    }

    /// Projective: a segment images straight.
    fn midpoint_deviation_bound(&self, _: &[ImagePoint]) -> f64 {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unproject_inverts_project_and_depth_is_ordered() {
        let cam = Orthographic::look_at(
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::ZERO,
            Vec3::Y,
            2.0,
            10.0,
            64,
            48,
        )
        .unwrap();
        for i in 0..500u32 {
            let h = |k: u32| {
                ((i.wrapping_mul(2_654_435_761) ^ k.wrapping_mul(40_503)) % 10_007) as f64
                    / 10_007.0
            };
            let p = DVec3::new(h(1) - 0.5, h(2) - 0.5, h(3) - 0.5) * 6.0;
            let q = cam.project(p).unwrap();
            assert!((cam.unproject(q.uv, q.gd) - p).length() < 1e-9);
        }
        let near = cam.project(DVec3::new(0.0, 0.0, 1.0)).unwrap();
        let far = cam.project(DVec3::new(0.0, 0.0, -1.0)).unwrap();
        assert!(near.gd > far.gd && far.gd > 0.0);
        assert!((near.uv - DVec2::new(32.0, 24.0)).length() < 1e-9);
        assert!((near.uv - far.uv).length() < 1e-9, "parallel rays");
    }
}
