//! The texture-mapping phase of relief rendering (paper 3 §2, after Oliveira et al.): the
//! pre-warped image, mapped onto the impostor's base quad (enlarged by the warp's margin), drawn
//! by the view camera into a frame. Each pixel also gets the depth of the relief point it shows
//! — on the eye's line through the base point, at the carried displacement — so that other
//! geometry in the frame interpenetrates the impostor correctly (paper §2: the nailboard's
//! depth in the z-buffer).
//!
//! Invariants: a pixel is drawn only where at least half of its bilinear footprint falls on
//! non-empty texels, and only where it is nearer than what the frame holds.

use super::ReliefFrame;
use super::prewarp::{Prewarped, flag};
use crate::camera::{Pinhole, Projection};
use crate::frame::{Frame, Rgba};
use glam::{DVec2, DVec3, Vec3};
use rayon::prelude::*;

/// Draws `image` (pre-warped for the eye of `camera`) over `frame`'s base quad into `target`,
/// z-tested against its depth; drawn pixels take object id `object`. Returns the pixels drawn.
pub fn draw(
    image: &Prewarped,
    frame: &ReliefFrame,
    camera: &Pinhole,
    target: &mut Frame,
    object: u32,
) -> usize {
    let eye = camera.position();
    let h = (eye - frame.origin).dot(frame.f);
    if h <= 0.0 {
        return 0;
    }
    let (w_img, h_img) = (image.width as usize, image.height as usize);
    let (mx, my) = (image.margin.0 as f64, image.margin.1 as f64);
    // Rows the enlarged quad can cover: its corners' projections, or every row when a corner is
    // behind the camera.
    let (width, height) = camera.resolution();
    let mut rows = (0usize, height as usize);
    let corners = [
        (-mx, -my),
        (frame.width as f64 + mx, -my),
        (-mx, frame.height as f64 + my),
    ]
    .into_iter()
    .chain([(frame.width as f64 + mx, frame.height as f64 + my)])
    .map(|(u, v)| camera.project(frame.point(u, v, 0.0)));
    let projected: Option<Vec<_>> = corners.collect();
    let mut cols = (0usize, width as usize);
    if let Some(p) = projected {
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for q in p {
            lo = lo.min(q.uv);
            hi = hi.max(q.uv);
        }
        rows = (
            lo.y.floor().clamp(0.0, height as f64) as usize,
            (hi.y.ceil() + 1.0).clamp(0.0, height as f64) as usize,
        );
        cols = (
            lo.x.floor().clamp(0.0, width as f64) as usize,
            (hi.x.ceil() + 1.0).clamp(0.0, width as f64) as usize,
        );
    }
    let normal = frame.f.as_vec3();
    target
        .par_rows_mut()
        .skip(rows.0)
        .take(rows.1 - rows.0)
        .map(|(y, (color, depth, normals, id))| {
            let mut drawn = 0;
            for x in cols.0..cols.1 {
                let ray = camera.ray(crate::frame::pixel_centre(x as f64, y as f64));
                let dir = ray.dir.as_dvec3();
                let along = dir.dot(frame.f);
                if along >= 0.0 {
                    continue;
                }
                let t = (frame.origin - eye).dot(frame.f) / along;
                let base = frame.coordinates(eye + dir * t);
                let Some((c, d)) = lookup(image, base.x + mx, base.y + my, w_img, h_img) else {
                    continue;
                };
                // The relief point on the eye's line, `d` above the plane.
                let s = 1.0 - d / h;
                let distance = (s * t) as f32;
                if s > 0.0 && distance < depth[x] {
                    color[x] = c;
                    depth[x] = distance;
                    normals[x] = normal;
                    id[x] = object;
                    drawn += 1;
                }
            }
            drawn
        })
        .sum()
}

/// Bilinear lookup over non-empty texels at continuous coordinates `(x, y)`: colour (alpha 1)
/// and displacement, or `None` where less than half the footprint is covered.
fn lookup(image: &Prewarped, x: f64, y: f64, w: usize, h: usize) -> Option<(Rgba, f64)> {
    let (fx, fy) = (x - 0.5, y - 0.5);
    let (x0, y0) = (fx.floor(), fy.floor());
    let (tx, ty) = (fx - x0, fy - y0);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let mut sum = 0.0;
    let mut c = Vec3::ZERO;
    let mut d = 0.0;
    for (dx, dy, wgt) in [
        (0, 0, (1.0 - tx) * (1.0 - ty)),
        (1, 0, tx * (1.0 - ty)),
        (0, 1, (1.0 - tx) * ty),
        (1, 1, tx * ty),
    ] {
        let (i, j) = (x0 + dx, y0 + dy);
        if i < 0 || j < 0 || i >= w as i64 || j >= h as i64 || wgt == 0.0 {
            continue;
        }
        let k = j as usize * w + i as usize;
        if image.flags[k] == flag::EMPTY {
            continue;
        }
        sum += wgt;
        c += super::decode(image.color[k]).truncate() * wgt as f32;
        d += image.displacement[k] as f64 * wgt;
    }
    (sum >= 0.5).then(|| ((c / sum as f32).extend(1.0), d / sum))
}

/// The point a drawn pixel shows (for tests and tools): on the ray through pixel centre `uv`,
/// at the base plane's crossing moved toward the eye by `d` of height.
pub fn relief_point(frame: &ReliefFrame, camera: &Pinhole, uv: DVec2, d: f64) -> Option<DVec3> {
    let eye = camera.position();
    let dir = camera.ray(uv).dir.as_dvec3();
    let along = dir.dot(frame.f);
    let h = (eye - frame.origin).dot(frame.f);
    (along < 0.0 && h > 0.0).then(|| {
        let t = (frame.origin - eye).dot(frame.f) / along;
        eye + dir * t * (1.0 - d / h)
    })
}

#[cfg(test)]
mod tests {
    use super::super::prewarp::{Eye, prewarp};
    use super::super::shader::SoftwareShader;
    use super::super::{DepthEncoding, ReliefImpostor};
    use super::*;
    use crate::frame::metrics::psnr;
    use crate::scene::{Lighting, RenderSettings, View};

    fn shaded_box() -> (std::sync::Arc<SoftwareShader>, View) {
        // A box with a bumped top: a relief a height field describes well.
        let mut mesh = crate::geom::plane(48);
        for p in &mut mesh.positions {
            let r = (p.x * p.x + p.z * p.z).sqrt();
            p.y = 0.15 * (1.0 - (r / 0.5).min(1.0)).powi(2);
        }
        mesh.compute_normals();
        shaded(mesh.transformed(&glam::Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2)))
    }

    fn shaded(mesh: crate::geom::Mesh) -> (std::sync::Arc<SoftwareShader>, View) {
        let view = View {
            lens: None,
            camera: Pinhole::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 30.0, 96, 96)
                .unwrap(),
            meshes: vec![std::sync::Arc::new(mesh)],
            surfaces: vec![crate::scene::Surface::Diffuse(None)],
        };
        let lighting = Lighting {
            environment: crate::frame::envmap::EnvMap::constant(Vec3::splat(0.3)),
            light: Some(crate::scene::Light {
                direction: Vec3::new(0.3, 0.5, 1.0).normalize(),
                irradiance: Vec3::splat(0.8 * std::f32::consts::PI),
            }),
        };
        let settings = RenderSettings {
            max_depth: 2,
            time: 0.0,
            ray_epsilon: 1e-4,
        };
        (
            SoftwareShader::new(&view, &lighting, &settings).unwrap(),
            view,
        )
    }

    fn relief(shader: &SoftwareShader, eye: DVec3, n: u32) -> ReliefImpostor {
        shader
            .impostor(0, eye, n, DepthEncoding::F32, &|| false)
            .unwrap()
            .unwrap()
    }

    /// Frame and true render of the relief's object from `eye`, PSNR over the object's pixels.
    fn score(shader: &SoftwareShader, imp: &ReliefImpostor, eye: DVec3) -> f64 {
        let camera = Pinhole::look_at(eye.as_vec3(), Vec3::ZERO, Vec3::Y, 30.0, 96, 96).unwrap();
        let truth = shader.render(&camera, &[0]).unwrap();
        // The environment behind: a texel the impostor misses counts as an error.
        let mut frame = Frame::new(96, 96).unwrap();
        frame.color = crate::frame::Image::new(96, 96, Rgba::new(0.3, 0.3, 0.3, 1.0)).unwrap();
        let warped = prewarp(imp, Eye::Point(eye), false).unwrap();
        draw(&warped, &imp.frame, &camera, &mut frame, 0);
        psnr(&truth.color, &frame.color, None).unwrap()
    }

    #[test]
    fn a_bumped_plane_warped_for_small_moves_matches_its_true_render() {
        let (shader, _) = shaded_box();
        let source = DVec3::new(0.0, 0.0, 3.0);
        let imp = relief(&shader, source, 128);
        for eye in [
            DVec3::new(0.25, 0.0, 2.99),
            DVec3::new(0.0, -0.3, 2.95),
            DVec3::new(-0.35, 0.2, 2.9),
        ] {
            let p = score(&shader, &imp, eye);
            assert!(p >= 30.0, "{eye}: {p:.2} dB");
        }
    }

    #[test]
    fn a_sphere_warped_for_small_moves_keeps_its_silhouette() {
        // Every edge of a sphere's picture is a silhouette, where the warp stretches the surface
        // seen at a grazing angle and each run's last texel covers its own warped footprint.
        let sphere =
            crate::geom::icosphere(4).transformed(&glam::Mat4::from_scale(Vec3::splat(0.6)));
        let (shader, _) = shaded(sphere);
        let imp = relief(&shader, DVec3::new(0.0, 0.0, 3.0), 128);
        for eye in [
            DVec3::new(0.25, 0.0, 2.99),
            DVec3::new(0.0, -0.3, 2.95),
            DVec3::new(-0.35, 0.2, 2.9),
        ] {
            let p = score(&shader, &imp, eye);
            println!("sphere from {eye}: {p:.2} dB");
            assert!(p >= 30.0, "{eye}: {p:.2} dB");
        }
    }

    #[test]
    fn drawn_depth_is_the_relief_point_distance() {
        let (shader, _) = shaded_box();
        let eye = DVec3::new(0.2, 0.1, 3.0);
        let imp = relief(&shader, eye, 96);
        let camera = Pinhole::look_at(eye.as_vec3(), Vec3::ZERO, Vec3::Y, 30.0, 96, 96).unwrap();
        let truth = shader.render(&camera, &[0]).unwrap();
        let mut frame = Frame::new(96, 96).unwrap();
        let warped = prewarp(&imp, Eye::Point(eye), false).unwrap();
        let drawn = draw(&warped, &imp.frame, &camera, &mut frame, 0);
        assert!(drawn > 3000, "{drawn}");
        // Where both see the object, the depths agree to a fraction of the relief's height.
        let mut worst: f32 = 0.0;
        for (a, b) in frame.depth.pixels().iter().zip(truth.depth.pixels()) {
            if a.is_finite() && b.is_finite() {
                worst = worst.max((a - b).abs());
            }
        }
        assert!(worst < 0.02, "{worst}");
    }
}
