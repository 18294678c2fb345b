//! Equirectangular environment maps: radiance at infinity, looked up by direction.
//!
//! Mapping (`docs/conventions.md` §1.3, Mitsuba's): direction `d` ↦ `u = atan2(d.x, −d.z) / 2π (mod 1)`,
//! `v = acos(d.y) / π`; the top row is `+y`, the image centre looks along `+z`. A map may be
//! rotated about `y` by `rotation` radians. Invariant: [`EnvMap::direction`] inverts the lookup
//! mapping, and [`EnvMap::irradiance`] of a constant map is that constant.

use super::{FrameError, Image, Wrap, io};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;
use std::path::Path;

/// Size of the precomputed diffuse-irradiance map (longitude × latitude texels).
const IRRADIANCE_SIZE: (u32, u32) = (32, 16);
/// Size the radiance map is box-filtered to before the irradiance convolution.
const CONVOLUTION_SOURCE_SIZE: (u32, u32) = (64, 32);

/// An equirectangular panorama of linear radiance, with its cosine-convolved irradiance.
#[derive(Clone, Debug)]
pub struct EnvMap {
    radiance: Image<Vec3>,
    irradiance: Image<Vec3>,
    rotation: f32,
    intensity: f32,
}

impl EnvMap {
    /// Loads a Radiance `.hdr` or OpenEXR panorama.
    pub fn load(path: &Path, rotation: f32, intensity: f32) -> Result<Self, FrameError> {
        let image = io::read_color(path)?;
        Ok(Self::from_image(
            image.map(|p| p.truncate()),
            rotation,
            intensity,
        ))
    }

    /// Wraps a panorama already in memory (negative samples, e.g. EXR ringing, are clamped to 0).
    pub fn from_image(radiance: Image<Vec3>, rotation: f32, intensity: f32) -> Self {
        let radiance = radiance.map(|c| {
            let c = c.max(Vec3::ZERO);
            if c.is_finite() { c } else { Vec3::ZERO }
        });
        let irradiance = convolve_cosine(&radiance);
        Self {
            radiance,
            irradiance,
            rotation,
            intensity,
        }
    }

    /// A uniform environment of one radiance.
    pub fn constant(radiance: Vec3) -> Self {
        let one = Image::derived(4, 2, radiance);
        Self::from_image(one, 0.0, 1.0)
    }

    /// Radiance arriving from direction `d` (need not be normalized).
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        let st = self.lookup_uv(d);
        self.radiance.sample_panorama(st) * self.intensity
    }

    /// Cosine-weighted mean radiance over the hemisphere around `n` (irradiance / π): the
    /// ambient term of a Lambertian surface with normal `n`.
    pub fn irradiance(&self, n: Vec3) -> Vec3 {
        let st = self.lookup_uv(n);
        self.irradiance.sample_uv_lonlat(st) * self.intensity
    }

    /// Texture coordinates `(u, v) ∈ [0, 1)²` of direction `d`, rotation included.
    pub fn lookup_uv(&self, d: Vec3) -> Vec2 {
        let d = rotate_y(d.normalize_or(Vec3::Y), -self.rotation);
        direction_to_uv(d)
    }

    /// The world direction that texture coordinates `(u, v)` look along, rotation included.
    pub fn direction(&self, uv: Vec2) -> Vec3 {
        rotate_y(uv_to_direction(uv), self.rotation)
    }

    /// The radiance panorama.
    pub fn image(&self) -> &Image<Vec3> {
        &self.radiance
    }

    /// The cosine-convolved irradiance grid [`EnvMap::irradiance`] looks up (longitude ×
    /// latitude, texel centres at `((x + ½)/W, (y + ½)/H)`).
    pub fn irradiance_image(&self) -> &Image<Vec3> {
        &self.irradiance
    }

    /// Rotation about `y`, in radians.
    pub fn rotation(&self) -> f32 {
        self.rotation
    }

    /// The factor every lookup is scaled by.
    pub fn intensity(&self) -> f32 {
        self.intensity
    }
}

/// `d` (unit) ↦ equirectangular `(u, v)`.
pub fn direction_to_uv(d: Vec3) -> Vec2 {
    let u = (d.x.atan2(-d.z) / (2.0 * PI)).rem_euclid(1.0);
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    Vec2::new(u, v)
}

/// Equirectangular `(u, v)` ↦ unit direction (the inverse of [`direction_to_uv`]).
pub fn uv_to_direction(uv: Vec2) -> Vec3 {
    let (theta, phi) = (uv.y * PI, uv.x * 2.0 * PI);
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    Vec3::new(st * sp, ct, -st * cp)
}

fn rotate_y(d: Vec3, angle: f32) -> Vec3 {
    if angle == 0.0 {
        return d;
    }
    let (s, c) = angle.sin_cos();
    Vec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
}

impl Image<Vec3> {
    /// Bilinear lookup of a panorama with Mitsuba's texel placement (docs/conventions.md §1.3):
    /// an `H`-row map's continuous row is `v·(H − 1)` (the first row's centre at the `+y` pole,
    /// the last's at `−y`), its column `u·W − ½`, wrapping around.
    fn sample_panorama(&self, st: Vec2) -> Vec3 {
        let rows = self.height().saturating_sub(1) as f32;
        // `sample_bilinear` takes pixel coordinates, texel centres at +½.
        let uv = Vec2::new(st.x * self.width() as f32, st.y * rows + 0.5);
        self.sample_bilinear(uv, Wrap::Repeat, Wrap::Clamp)
    }

    /// Bilinear lookup of a longitude-latitude grid whose texel centres are at
    /// `((x + ½)/W, (y + ½)/H)` (the irradiance grid trompe computes): repeats in `u`, clamps
    /// in `v`.
    fn sample_uv_lonlat(&self, st: Vec2) -> Vec3 {
        let uv = Vec2::new(st.x * self.width() as f32, st.y * self.height() as f32);
        self.sample_bilinear(uv, Wrap::Repeat, Wrap::Clamp)
    }
}

/// Box-filters `src` down to `size` (each target texel averages the source texels it covers).
/// A map smaller than `size` is resampled bilinearly instead.
fn downsample(src: &Image<Vec3>, size: (u32, u32)) -> Image<Vec3> {
    let (w, h) = size;
    if src.width() < w || src.height() < h {
        let mut out = Image::derived(w, h, Vec3::ZERO);
        for y in 0..h {
            for x in 0..w {
                let st = (super::pixel_centre(f64::from(x), f64::from(y)).as_vec2())
                    / Vec2::new(w as f32, h as f32);
                out.set(x, y, src.sample_uv_lonlat(st));
            }
        }
        return out;
    }
    let mut out = Image::derived(w, h, Vec3::ZERO);
    for y in 0..h {
        let (y0, y1) = (
            y * src.height() / h,
            ((y + 1) * src.height() / h).max(y * src.height() / h + 1),
        );
        for x in 0..w {
            let (x0, x1) = (
                x * src.width() / w,
                ((x + 1) * src.width() / w).max(x * src.width() / w + 1),
            );
            let mut sum = Vec3::ZERO;
            for sy in y0..y1 {
                for sx in x0..x1 {
                    sum += src.get(sx, sy);
                }
            }
            out.set(x, y, sum / ((y1 - y0) * (x1 - x0)) as f32);
        }
    }
    out
}

/// Cosine convolution `E(n)/π = (1/π) ∫ L(ω) max(0, n·ω) dω`, evaluated on a small grid.
fn convolve_cosine(radiance: &Image<Vec3>) -> Image<Vec3> {
    let src = downsample(radiance, CONVOLUTION_SOURCE_SIZE);
    let (sw, sh) = src.size();
    // Texel directions and solid angles dω = (2π/sw)(π/sh) sin θ.
    let mut texels = Vec::with_capacity((sw * sh) as usize);
    for y in 0..sh {
        for x in 0..sw {
            let uv = super::pixel_centre(f64::from(x), f64::from(y)).as_vec2()
                / Vec2::new(sw as f32, sh as f32);
            let d_omega = (2.0 * PI / sw as f32) * (PI / sh as f32) * (uv.y * PI).sin();
            texels.push((uv_to_direction(uv), src.get(x, y) * d_omega));
        }
    }
    let (w, h) = IRRADIANCE_SIZE;
    let mut out = Image::derived(w, h, Vec3::ZERO);
    for y in 0..h {
        for x in 0..w {
            let n = uv_to_direction(
                super::pixel_centre(f64::from(x), f64::from(y)).as_vec2()
                    / Vec2::new(w as f32, h as f32),
            );
            let mut sum = Vec3::ZERO;
            for (d, l) in &texels {
                let c = n.dot(*d);
                if c > 0.0 {
                    sum += *l * c;
                }
            }
            out.set(x, y, sum / PI);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lookup_follows_the_documented_convention() {
        // +z is the image centre, +y the top row, −z the left/right seam.
        assert!((direction_to_uv(Vec3::Z) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!(direction_to_uv(Vec3::Y).y.abs() < 1e-6);
        assert!((direction_to_uv(Vec3::X) - Vec2::new(0.25, 0.5)).length() < 1e-6);
    }

    #[test]
    fn direction_inverts_lookup() {
        for i in 0..200 {
            let uv = Vec2::new(
                (i as f32 * 0.618).fract(),
                0.02 + 0.96 * (i as f32 * 0.377).fract(),
            );
            let d = uv_to_direction(uv);
            assert!((direction_to_uv(d) - uv).length() < 1e-4, "{uv}");
        }
        let env = EnvMap::constant(Vec3::ONE);
        let env = EnvMap {
            rotation: 0.7,
            ..env
        };
        let d = Vec3::new(0.3, 0.4, -0.5).normalize();
        assert!((env.direction(env.lookup_uv(d)) - d).length() < 1e-4);
    }

    #[test]
    fn irradiance_of_a_constant_sky_is_that_constant() {
        let env = EnvMap::constant(Vec3::new(0.5, 1.0, 2.0));
        for n in [Vec3::Y, Vec3::X, -Vec3::Z, Vec3::new(1.0, -1.0, 0.3)] {
            let e = env.irradiance(n);
            assert!(
                (e - Vec3::new(0.5, 1.0, 2.0)).abs().max_element() < 0.03,
                "{n}: {e}"
            );
        }
    }
}
