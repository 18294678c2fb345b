//! McMillan's 3-D image warp (paper 3 Eq. 1; McMillan 1997; docs/conventions.md §5.1): a
//! perspective colour + generalized-disparity image re-projected to another pinhole camera,
//! `w = M_t⁻¹ M_s x̄_s + δ_s · M_t⁻¹ (C_s − C_t)`, `x̄_t = w / w.z`, `δ_t = δ_s / w.z`. The relief
//! pre-warp factors this equation for an orthographic source; this full form is the reference
//! it is checked against.
//!
//! Invariants: `δ = gd = 1/t` in the camera's own units (docs/conventions.md §1.2); each source
//! pixel lands on the target pixel containing its warped centre, the larger `δ_t` winning (a
//! z-buffer, equivalent to McMillan's occlusion-compatible order for one-pixel splats).

use crate::camera::{Pinhole, Projection};
use crate::frame::{FrameError, Image, Rgba, pixel_centre};

/// A perspective depth image: colour and generalized disparity per pixel (0 = empty).
#[derive(Clone, Debug)]
pub struct DepthImage {
    /// Its camera.
    pub camera: Pinhole,
    /// Linear colour.
    pub color: Image<Rgba>,
    /// `gd = 1/t`, 0 where empty.
    pub gd: Image<f32>,
}

/// Warps `source` to `target`'s camera.
pub fn warp(source: &DepthImage, target: &Pinhole) -> Result<DepthImage, FrameError> {
    let (w, h) = target.resolution();
    let mut color = Image::new(w, h, Rgba::ZERO)?;
    let mut gd = Image::new(w, h, 0.0f32)?;
    let (a, b, c) = source.camera.mcmillan();
    let m_t_inv = target.mcmillan_inverse();
    let homography = m_t_inv * glam::DMat3::from_cols(a, b, c);
    let shift = m_t_inv * (source.camera.position() - target.position());
    let (sw, sh) = source.gd.size();
    for y in 0..sh {
        for x in 0..sw {
            let delta = source.gd.get(x, y) as f64;
            if delta <= 0.0 {
                continue;
            }
            let p = homography * pixel_centre(x as f64, y as f64).extend(1.0) + shift * delta;
            if p.z <= 0.0 {
                continue;
            }
            let (u, v) = (p.x / p.z, p.y / p.z);
            if !(u >= 0.0 && v >= 0.0 && u < w as f64 && v < h as f64) {
                continue;
            }
            let (i, j) = (u as u32, v as u32);
            let d = (delta / p.z) as f32;
            if d > gd.get(i, j) {
                gd.set(i, j, d);
                color.set(i, j, source.color.get(x, y));
            }
        }
    }
    Ok(DepthImage {
        camera: target.clone(),
        color,
        gd,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec2, Vec3};

    /// A depth image of a tilted plane: every pixel covered, colour from its 3-D point.
    fn plane_image(camera: &Pinhole) -> DepthImage {
        let (w, h) = camera.resolution();
        let mut color = Image::new(w, h, Rgba::ZERO).unwrap();
        let mut gd = Image::new(w, h, 0.0).unwrap();
        let (n, off) = (glam::DVec3::new(0.2, 0.1, 1.0).normalize(), -0.3);
        let (a, b, c) = camera.mcmillan();
        for y in 0..h {
            for x in 0..w {
                let centre = pixel_centre(x as f64, y as f64);
                let dir = a * centre.x + b * centre.y + c;
                // Plane n·X = off: t = (off − n·C) / n·dir.
                let t = (off - n.dot(camera.position())) / n.dot(dir);
                let p = camera.position() + dir * t;
                color.set(x, y, (p.as_vec3() * 0.5 + Vec3::splat(0.5)).extend(1.0));
                gd.set(x, y, (1.0 / t) as f32);
            }
        }
        DepthImage {
            camera: camera.clone(),
            color,
            gd,
        }
    }

    #[test]
    fn warping_to_the_source_camera_is_the_identity() {
        let cam =
            Pinhole::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 40.0, 48, 32).unwrap();
        let src = plane_image(&cam);
        let out = warp(&src, &cam).unwrap();
        assert_eq!(out.color.pixels(), src.color.pixels());
        for (a, b) in out.gd.pixels().iter().zip(src.gd.pixels()) {
            assert!((a - b).abs() <= 1e-6 * b.abs(), "{a} {b}");
        }
    }

    #[test]
    fn warped_pixels_land_where_their_points_project() {
        let src_cam =
            Pinhole::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 40.0, 48, 32).unwrap();
        let dst =
            Pinhole::look_at(Vec3::new(0.6, 0.3, 2.8), Vec3::ZERO, Vec3::Y, 45.0, 48, 32).unwrap();
        let src = plane_image(&src_cam);
        let (a, b, c) = src_cam.mcmillan();
        let m_t_inv = dst.mcmillan_inverse();
        let homography = m_t_inv * glam::DMat3::from_cols(a, b, c);
        let shift = m_t_inv * (src_cam.position() - dst.position());
        for (x, y) in [(3u32, 4u32), (20, 10), (40, 30), (47, 0)] {
            let delta = src.gd.get(x, y) as f64;
            let centre = crate::frame::pixel_centre(x as f64, y as f64);
            let point = src_cam.position() + (a * centre.x + b * centre.y + c) / delta;
            let p = homography * centre.extend(1.0) + shift * delta;
            let expect = dst.project(point).unwrap();
            assert!((DVec2::new(p.x / p.z, p.y / p.z) - expect.uv).length() < 1e-6);
            assert!((delta / p.z - expect.gd).abs() < 1e-6 * expect.gd);
        }
        // And the warp covers most of the target with the plane.
        let out = warp(&src, &dst).unwrap();
        let covered = out.gd.pixels().iter().filter(|&&g| g > 0.0).count();
        assert!(covered > 48 * 32 / 2, "{covered}");
    }
}
