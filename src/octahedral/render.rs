//! Rendering from an octahedral atlas: trompe's CPU reference of what an engine's impostor
//! shader does. For each pixel whose ray meets the bounding sphere, the three frames around the
//! view direction are looked up and blended by their barycentric weights; each lookup is
//! parallax-corrected with the frame's depth (the ray is intersected with the plane at the depth
//! read there, a few times over); frames that find a surface well behind the nearest one fade
//! out (depth-aware blending), and the blended base colour is relit with the blended normal.
//!
//! Invariants: a frame's texel `(x, y)` images the point `c + r·(2(x+½)/s − 1)·right +
//! r·(1 − 2(y+½)/s)·up` of its plane (orthographic frames; a pinhole frame the ray through that
//! point of the plane tangent to the sphere, scaled by its depth), as its baking camera did; lookups are bilinear and clamped
//! to the frame, never reading a neighbour frame.

use super::bake::{FrameProjection, OctahedralAtlas};
use super::mapping::frame_basis;
use crate::camera::Pinhole;
use crate::frame::{Image, Lerp, Rgba};
use crate::geom::Ray;
use crate::render::shading::lambert;
use crate::scene::Lighting;
use glam::{DVec2, DVec3, Vec3};
use rayon::prelude::*;

/// Parallax refinement steps (0: the frame's plane through the centre, no depth).
pub const PARALLAX_STEPS: u32 = 4;

/// Depth-aware blending's tolerance, in bounding radii: a frame whose surface lies `δ` behind the
/// nearest surface another covered frame finds along the ray keeps `exp(−(δ / (DEPTH_AGREEMENT·r))²)`
/// of its barycentric weight (the weights then renormalised). It keeps frames that see one
/// surface through small parallax errors and drops the ones that see past an occluder, the
/// ghosts between frames.
pub const DEPTH_AGREEMENT: f64 = 0.125;

/// The blended coverage a surface needs to be drawn by an alpha-tested impostor material (the
/// glTF card's `alphaCutoff`, the runtimes' alpha test).
pub const ALPHA_TEST: f32 = 0.5;

/// Where world point `p` lands in frame `(i, j)` of an atlas baked with `settings` on the
/// sphere `(centre, radius)`, in frame texel coordinates (texel centres at `+½`): along the
/// frame's direction (orthographic), or through its pinhole. The shader's `frame_texel` is the
/// same function (checked by the tests).
pub fn frame_texel(
    settings: &super::BakeSettings,
    (centre, r): (DVec3, f64),
    (i, j): (u32, u32),
    p: DVec3,
) -> DVec2 {
    let d = settings.grid.direction(i, j);
    let (right, up) = frame_basis(d);
    let s = f64::from(settings.frame_size);
    let (q, scale) = match settings.projection {
        FrameProjection::Orthographic => (p - centre, r),
        FrameProjection::Pinhole { distance } => {
            let distance = f64::from(distance);
            let q = p - (centre + d * (r * distance));
            let z = (-q.dot(d)).max(1e-12 * r);
            (q, z * FrameProjection::tan_half_fov(distance))
        }
    };
    DVec2::new(
        (q.dot(right) / scale + 1.0) * 0.5 * s,
        (1.0 - q.dot(up) / scale) * 0.5 * s,
    )
}

/// What a lookup returns, premultiplied by coverage.
#[derive(Clone, Copy, Debug, Default)]
struct Sample {
    color: Vec3,
    normal: Vec3,
    alpha: f32,
    /// Ray parameter of the point found, times coverage.
    t: f64,
}

/// The three frames' lookups along one ray, blended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blended {
    /// Base colour.
    pub albedo: Vec3,
    /// Unit normal (toward the ray's origin when the maps hold none).
    pub normal: Vec3,
    /// Coverage, `[0, 1]`.
    pub alpha: f32,
    /// Ray parameter of the surface found.
    pub t: f64,
}

impl OctahedralAtlas {
    /// Renders the atlas (placed in its own space) through `camera`, lit by `lighting`, over the
    /// environment; `parallax` steps of depth correction per lookup.
    pub fn render(&self, camera: &Pinhole, lighting: &Lighting, parallax: u32) -> Image<Rgba> {
        let (w, h) = crate::camera::Projection::resolution(camera);
        let view = (camera.position() - self.centre.as_dvec3()).normalize_or(DVec3::Y);
        self.render_rays((w, h), view, |uv| camera.ray(uv), lighting, parallax)
    }

    /// [`OctahedralAtlas::render`] for any camera: `ray(pixel centre)` gives each pixel's ray,
    /// `view` the direction toward the eye the frames are chosen by.
    pub fn render_rays(
        &self,
        (w, h): (u32, u32),
        view: DVec3,
        ray: impl Fn(DVec2) -> Ray + Sync,
        lighting: &Lighting,
        parallax: u32,
    ) -> Image<Rgba> {
        let frames = self.settings.grid.frames_around(view);
        let pixels: Vec<Rgba> = (0..h as usize * w as usize)
            .into_par_iter()
            .map(|k| {
                let (x, y) = (k % w as usize, k / w as usize);
                let ray = ray(crate::frame::pixel_centre(x as f64, y as f64));
                let env = lighting.environment.radiance(ray.dir);
                let Some(b) = self.blend(&frames, ray, parallax) else {
                    return env.extend(1.0);
                };
                let (a, albedo, n) = (b.alpha, b.albedo, b.normal);
                // An atlas holds no occluders: relit unshadowed, as an engine's shader does.
                (lambert(albedo, n, lighting, |_| true) * a + env * (1.0 - a)).extend(1.0)
            })
            .collect();
        match Image::from_vec(w, h, pixels) {
            Ok(img) => img,
            Err(_) => unreachable!("the camera's resolution is a valid image size"),
        }
    }

    /// Whether the ray from `eye` along `dir` crosses the card ([`super::card`]) where the
    /// runtimes draw it: tangent to the bounding sphere on the eye's side, facing the eye, its
    /// axes those of [`super::mapping::frame_basis`]. An eye inside the sphere sees the card
    /// across the whole view.
    pub fn crosses_card(&self, eye: DVec3, dir: DVec3) -> bool {
        let centre = self.centre.as_dvec3();
        let r = f64::from(self.radius);
        let to_eye = eye - centre;
        if to_eye.length() <= r {
            return true;
        }
        let v = to_eye.normalize();
        let (right, up) = super::mapping::frame_basis(v);
        let facing = dir.dot(v);
        if facing >= 0.0 {
            return false;
        }
        let q = eye + dir * ((centre + v * r - eye).dot(v) / facing) - (centre + v * r);
        self.card.contains(q.dot(right) / r, q.dot(up) / r)
    }

    /// [`OctahedralAtlas::render`] as engines' impostor materials draw: a pixel keeps the
    /// surface where its ray crosses the card ([`OctahedralAtlas::crosses_card`]) and the
    /// blended coverage passes the alpha test ([`ALPHA_TEST`]), whole, and shows the
    /// environment elsewhere — the reference of the runtimes in `shaders/` and `web/`.
    pub fn render_cutout(
        &self,
        camera: &Pinhole,
        lighting: &Lighting,
        parallax: u32,
    ) -> Image<Rgba> {
        let (w, h) = crate::camera::Projection::resolution(camera);
        let view = (camera.position() - self.centre.as_dvec3()).normalize_or(DVec3::Y);
        let frames = self.settings.grid.frames_around(view);
        let pixels: Vec<Rgba> = (0..h as usize * w as usize)
            .into_par_iter()
            .map(|k| {
                let (x, y) = (k % w as usize, k / w as usize);
                let ray = camera.ray(crate::frame::pixel_centre(x as f64, y as f64));
                let on_card = self.crosses_card(camera.position(), ray.dir.as_dvec3());
                match self.blend(&frames, ray, parallax) {
                    Some(b) if on_card && b.alpha >= ALPHA_TEST && b.t > 0.0 => {
                        lambert(b.albedo, b.normal, lighting, |_| true).extend(1.0)
                    }
                    _ => lighting.environment.radiance(ray.dir).extend(1.0),
                }
            })
            .collect();
        match Image::from_vec(w, h, pixels) {
            Ok(img) => img,
            Err(_) => unreachable!("the camera's resolution is a valid image size"),
        }
    }

    /// `frames` (from [`crate::octahedral::Grid::frames_around`]) looked up along `ray`,
    /// `parallax` steps each, and blended by their weights; `None` where the ray misses the
    /// bounding sphere or finds no coverage.
    pub fn blend(
        &self,
        frames: &[((u32, u32), f64); 3],
        ray: Ray,
        parallax: u32,
    ) -> Option<Blended> {
        let (o, dir) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
        let centre = self.centre.as_dvec3();
        let r = f64::from(self.radius);
        // Only rays through the bounding sphere can meet the object.
        let oc = o - centre;
        let b = oc.dot(dir);
        if b * b - (oc.length_squared() - r * r) < 0.0 {
            return None;
        }
        let looks = frames.map(|((i, j), weight)| {
            let sample = (weight > 0.0)
                .then(|| self.lookup(i, j, o, dir, parallax))
                .flatten()
                .unwrap_or_default();
            (weight.max(0.0), sample)
        });
        // Depth-aware blending: a frame that finds a surface well behind the nearest one a
        // covered frame finds is looking past an occluder the others see, and fades out.
        let front = looks
            .iter()
            .filter(|(w, s)| *w > 0.0 && s.alpha >= ALPHA_TEST)
            .map(|(_, s)| s.t / f64::from(s.alpha))
            .reduce(f64::min);
        let sigma = DEPTH_AGREEMENT * r;
        let mut acc = Sample::default();
        let mut total = 0.0;
        for (weight, s) in looks {
            let weight = match front {
                Some(front) if s.alpha >= ALPHA_TEST => {
                    let behind = (s.t / f64::from(s.alpha) - front) / sigma;
                    weight * (-behind * behind).exp()
                }
                _ => weight,
            };
            acc.color += s.color * weight as f32;
            acc.normal += s.normal * weight as f32;
            acc.alpha += s.alpha * weight as f32;
            acc.t += s.t * weight;
            total += weight;
        }
        if total <= 0.0 {
            return None;
        }
        let total_f32 = total as f32;
        acc.color /= total_f32;
        acc.normal /= total_f32;
        acc.alpha /= total_f32;
        acc.t /= total;
        if acc.alpha <= 1e-6 {
            return None;
        }
        Some(Blended {
            albedo: acc.color / acc.alpha,
            normal: acc.normal.normalize_or(-ray.dir),
            alpha: acc.alpha.min(1.0),
            t: acc.t / f64::from(acc.alpha),
        })
    }

    /// Frame `(i, j)` along the ray `o + t·dir`, parallax-corrected `steps` times.
    fn lookup(&self, i: u32, j: u32, o: DVec3, dir: DVec3, steps: u32) -> Option<Sample> {
        let d = self.settings.grid.direction(i, j);
        let facing = dir.dot(d);
        if facing >= -1e-9 {
            return None;
        }
        let centre = self.centre.as_dvec3();
        let r = f64::from(self.radius);
        // The ray against the plane at signed offset `off` from the centre along `d`.
        let along = |off: f64| (centre + d * off - o).dot(d) / facing;
        let at = |off: f64| o + dir * along(off);
        let s = f64::from(self.settings.frame_size);
        let texel = |p: DVec3| frame_texel(&self.settings, (centre, r), (i, j), p);
        let mut uv = texel(at(0.0));
        let mut t = along(0.0);
        for _ in 0..steps {
            let depth = f64::from(self.bilinear(&self.depth, i, j, uv));
            t = along(r - 2.0 * r * depth);
            uv = texel(o + dir * t);
        }
        if uv.x < -1.0 || uv.y < -1.0 || uv.x > s + 1.0 || uv.y > s + 1.0 {
            return None;
        }
        let c = self.bilinear(&self.color, i, j, uv);
        let n = self.bilinear(&self.normal, i, j, uv);
        Some(Sample {
            color: c.truncate() * c.w,
            normal: n * c.w,
            alpha: c.w,
            t: t * f64::from(c.w),
        })
    }

    /// Bilinear lookup of frame `(i, j)` of `img` at frame texel coordinates `uv` (texel
    /// centres at `+½`), clamped to the frame.
    fn bilinear<T: Lerp>(&self, img: &Image<T>, i: u32, j: u32, uv: DVec2) -> T {
        let s = self.settings.frame_size;
        img.sample_bilinear_tile((i * s, j * s), (s, s), uv)
    }
}
