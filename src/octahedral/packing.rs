//! The normal and depth of an octahedral atlas packed in one RGBA texture, as engines' impostor
//! bakers pack them (one texture fetch for both, one 8-bit map to compress): red, green and blue
//! hold the object-space unit normal as `n · ½ + ½`, alpha the depth behind the frame's front
//! plane over the bounding sphere's diameter (`[0, 1]`, as [`super::bake`] defines it). Stored
//! linearly (not sRGB) at 8 bits a channel, a normal comes back within [`NORMAL_BOUND`] radians
//! and a depth within [`DEPTH_BOUND`] of what was baked.
//!
//! Invariants: `unpack(pack(n, d))` is within the bounds above for unit `n` and `d ∈ [0, 1]`;
//! the layout is docs/conventions.md §8's and the runtimes' (`shaders/`, `web/`).

use crate::frame::{FrameError, Image, Rgba};
use glam::{Vec3, Vec4};

/// The largest angle (radians) between a unit normal and its 8-bit packing read back:
/// half a step of 2/255 on each of three components.
pub const NORMAL_BOUND: f32 = 0.0068;

/// The largest error of a depth read back from 8 bits: half a step.
pub const DEPTH_BOUND: f32 = 0.5 / 255.0;

/// The packed texel of unit normal `n` and depth `d`.
pub fn pack_texel(n: Vec3, d: f32) -> Rgba {
    (n * 0.5 + Vec3::splat(0.5)).extend(d.clamp(0.0, 1.0))
}

/// The normal and depth of packed texel `t` (a zero normal, from a texel no surface covered and
/// no dilation reached, reads back as `+z`).
pub fn unpack_texel(t: Vec4) -> (Vec3, f32) {
    let n = (t.truncate() * 2.0 - Vec3::ONE).normalize_or(Vec3::Z);
    (n, t.w)
}

/// The packed texture of an atlas's `normal` and `depth` maps (the same size).
pub fn pack(normal: &Image<Vec3>, depth: &Image<f32>) -> Result<Image<Rgba>, FrameError> {
    let (w, h) = normal.size();
    if depth.size() != (w, h) {
        return Err(FrameError::SizeMismatch {
            a: (w, h),
            b: depth.size(),
        });
    }
    let texels = (normal.pixels().iter().zip(depth.pixels()))
        .map(|(&n, &d)| pack_texel(n, d))
        .collect();
    Image::from_vec(w, h, texels)
}

/// The normal and depth maps of a packed texture.
pub fn unpack(packed: &Image<Rgba>) -> Result<(Image<Vec3>, Image<f32>), FrameError> {
    let (w, h) = packed.size();
    let (normal, depth): (Vec<Vec3>, Vec<f32>) =
        packed.pixels().iter().map(|&t| unpack_texel(t)).unzip();
    Ok((
        Image::from_vec(w, h, normal)?,
        Image::from_vec(w, h, depth)?,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 8-bit quantization as the PNG writer does it.
    fn quantize(t: Vec4) -> Vec4 {
        Vec4::from_array(
            t.to_array()
                .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() / 255.0),
        )
    }

    #[test]
    fn normals_and_depths_come_back_within_the_bounds() {
        let mut worst = (0.0f32, 0.0f32);
        for k in 0..20_000u32 {
            // Spread directions by a golden-angle spiral, depths along [0, 1].
            let z = 1.0 - 2.0 * (k as f32 + 0.5) / 20_000.0;
            let phi = k as f32 * 2.399_963;
            let r = (1.0 - z * z).sqrt();
            let n = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            let d = (k as f32 * 0.618_034).fract();
            let (n2, d2) = unpack_texel(quantize(pack_texel(n, d)));
            worst.0 = worst.0.max(n.angle_between(n2));
            worst.1 = worst.1.max((d - d2).abs());
        }
        assert!(worst.0 <= NORMAL_BOUND, "normal off by {} rad", worst.0);
        assert!(worst.1 <= DEPTH_BOUND + 1e-7, "depth off by {}", worst.1);
        // The bounds are not loose: 8 bits cost at least half of each.
        assert!(worst.0 > NORMAL_BOUND * 0.5 && worst.1 > DEPTH_BOUND * 0.9);
    }
}
