//! Compact texel encodings for images that are built often and read a texel at a time (an
//! impostor's maps): colour as four half floats, unit vectors in the octahedral encoding.
//!
//! A fresh impostor takes as much new memory as its maps hold, and the system's cost of that
//! memory (page faults, or clearing recycled pages) grows with it: packing the colour and the two
//! normals of a texel into 8 + 4 + 4 bytes rather than 16 + 12 + 12 is what brings building a
//! SPOC impostor near the cost of a plain rasterization.
//!
//! Invariants:
//! - [`unpack_rgba`]`(`[`pack_rgba`]`(c))` is `c` rounded to half precision (11 significant
//!   bits); finite values beyond ±65504 clamp to it. Packing what was unpacked gives it back.
//! - [`unpack_unit`]`(`[`pack_unit`]`(n))` is within 10⁻⁴ rad of a unit `n` (the octahedral
//!   map of Cigolle et al. 2014, each coordinate in a 16-bit signed integer); the zero vector
//!   packs to [`ZERO_UNIT`] and unpacks to zero. Packing what was unpacked gives it back.
//! - The all-zero bit pattern of either type is a valid value (black, transparent; the `+z`
//!   axis), so zeroed memory is a valid image.

use glam::{Vec2, Vec3, Vec4};
use half::f16;
use half::slice::HalfFloatSliceExt;

/// Linear RGBA colour in four IEEE half floats: 8 bytes.
pub type HalfRgba = [f16; 4];

/// A unit vector (or zero) in the octahedral encoding: 4 bytes.
pub type OctUnit = [i16; 2];

/// The code of the zero vector (no unit vector packs to it: packed coordinates stay within
/// ±32767).
pub const ZERO_UNIT: OctUnit = [i16::MIN, i16::MIN];

/// Largest finite half float.
const HALF_MAX: f32 = 65504.0;

/// `c` in half precision, clamping finite values beyond the half range (infinities stay).
#[inline]
pub fn pack_rgba(c: Vec4) -> HalfRgba {
    let clamped = c.to_array().map(|v| {
        if v.is_finite() {
            v.clamp(-HALF_MAX, HALF_MAX)
        } else {
            v
        }
    });
    // Four at once: one conversion instruction where the CPU has F16C.
    let mut out = [f16::ZERO; 4];
    out.convert_from_f32_slice(&clamped);
    out
}

/// [`pack_rgba`] of opaque colours that remembers the last colour it packed: a run of texels
/// of one colour (an untextured material's) is converted once, where each conversion is a call
/// to the CPU's half-precision routine. The same bits give the same code, so every code equals
/// `pack_rgba(c.extend(1.0))`.
#[derive(Clone, Copy, Debug, Default)]
pub struct OpaquePacker {
    last: Option<([u32; 3], HalfRgba)>,
}

impl OpaquePacker {
    /// The code of opaque colour `c`.
    #[inline]
    pub fn pack(&mut self, c: Vec3) -> HalfRgba {
        let bits = c.to_array().map(f32::to_bits);
        match self.last {
            Some((last, code)) if last == bits => code,
            _ => {
                let code = pack_rgba(c.extend(1.0));
                self.last = Some((bits, code));
                code
            }
        }
    }
}

/// The colour a [`HalfRgba`] holds.
pub fn unpack_rgba(c: HalfRgba) -> Vec4 {
    Vec4::from_array(c.map(f16::to_f32))
}

/// Scale of a packed coordinate: the octahedron's `[-1, 1]` maps to `[-32767, 32767]`.
const OCT_SCALE: f32 = 32767.0;

/// The octahedral code of `n` (normalized first); [`ZERO_UNIT`] for a zero or non-finite `n`.
pub fn pack_unit(n: Vec3) -> OctUnit {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    if !(l1 > 0.0 && l1.is_finite()) {
        return ZERO_UNIT;
    }
    // Project onto the octahedron |x| + |y| + |z| = 1, then fold its lower half over the
    // upper one's outside triangles.
    let p = Vec2::new(n.x, n.y) * (1.0 / l1);
    let p = if n.z < 0.0 { fold(p) } else { p };
    let q = p.clamp(Vec2::splat(-1.0), Vec2::ONE) * OCT_SCALE;
    [round_to_i16(q.x), round_to_i16(q.y)]
}

/// `v` (within ±32767) rounded half away from zero. The cast truncates; `f32::round` would be a
/// library call on x86-64 without SSE 4.1.
fn round_to_i16(v: f32) -> i16 {
    (v + 0.5f32.copysign(v)) as i16
}

/// The unit vector an [`OctUnit`] holds (zero for [`ZERO_UNIT`]).
pub fn unpack_unit(code: OctUnit) -> Vec3 {
    if code == ZERO_UNIT {
        return Vec3::ZERO;
    }
    let p = Vec2::new(code[0] as f32, code[1] as f32) / OCT_SCALE;
    let z = 1.0 - p.x.abs() - p.y.abs();
    let p = if z < 0.0 { fold(p) } else { p };
    Vec3::new(p.x, p.y, z).normalize()
}

/// The octahedral fold, its own inverse: `(1 − |p.yx|)·sign(p)`.
fn fold(p: Vec2) -> Vec2 {
    let sign = Vec2::new(
        if p.x >= 0.0 { 1.0 } else { -1.0 },
        if p.y >= 0.0 { 1.0 } else { -1.0 },
    );
    (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs())) * sign
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::SplitMix64;

    #[test]
    fn opaque_packer_gives_the_codes_of_pack_rgba() {
        // Runs, signed zeros (equal as floats, not as codes), NaN (unequal to itself) and
        // values that round to the same half but are not the same bits.
        let colors = [
            Vec3::new(0.2, 0.4, 0.6),
            Vec3::new(0.2, 0.4, 0.6),
            Vec3::ZERO,
            Vec3::new(-0.0, 0.0, 0.0),
            Vec3::new(f32::NAN, 0.5, 0.5),
            Vec3::new(f32::NAN, 0.5, 0.5),
            Vec3::new(0.2 + 1e-7, 0.4, 0.6),
            Vec3::new(1e6, 0.4, 0.6),
            Vec3::new(0.2, 0.4, 0.6),
        ];
        let mut packer = OpaquePacker::default();
        for c in colors {
            let code = packer.pack(c).map(f16::to_bits);
            assert_eq!(code, pack_rgba(c.extend(1.0)).map(f16::to_bits), "{c}");
        }
    }

    fn random_unit(rng: &mut SplitMix64) -> Vec3 {
        loop {
            let v = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            let l = v.length();
            if l > 0.05 && l <= 1.0 {
                return v / l;
            }
        }
    }

    #[test]
    fn unit_vectors_survive_packing_within_the_bound() {
        let mut rng = SplitMix64::new(7);
        let mut worst: f32 = 0.0;
        let axes = [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z];
        for i in 0..200_000 {
            let n = match axes.get(i) {
                Some(a) => *a,
                None => random_unit(&mut rng),
            };
            let code = pack_unit(n);
            assert_ne!(code, ZERO_UNIT);
            let back = unpack_unit(code);
            assert!((back.length() - 1.0).abs() < 1e-6);
            // The angle, from the chord between the two unit vectors (acos is ill-conditioned
            // near 1 in f32).
            let chord = (back.as_dvec3() - n.as_dvec3().normalize()).length();
            worst = worst.max((2.0 * (chord / 2.0).asin()) as f32);
            // Packing what was unpacked gives the code back (a reload is bit-exact).
            assert_eq!(pack_unit(back), code, "{n}");
        }
        assert!(worst < 1e-4, "worst angle {worst} rad");
        // Not vacuous: quantization does move vectors.
        assert!(worst > 1e-6, "{worst}");
    }

    #[test]
    fn zero_and_non_finite_vectors_pack_to_zero() {
        assert_eq!(pack_unit(Vec3::ZERO), ZERO_UNIT);
        assert_eq!(pack_unit(Vec3::NAN), ZERO_UNIT);
        assert_eq!(unpack_unit(ZERO_UNIT), Vec3::ZERO);
        // Zeroed memory is the +z axis, a valid code.
        assert_eq!(unpack_unit([0, 0]), Vec3::Z);
        // Scale does not matter.
        assert_eq!(
            pack_unit(Vec3::new(0.0, 3.0, 4.0)),
            pack_unit(Vec3::new(0.0, 0.6, 0.8))
        );
    }

    #[test]
    fn colours_round_to_half_precision_and_clamp() {
        let c = Vec4::new(0.123_456, 1.0, 1234.5678, 0.0);
        let back = unpack_rgba(pack_rgba(c));
        for k in 0..4 {
            assert!(
                (back[k] - c[k]).abs() <= c[k].abs() * (1.0 / 2048.0),
                "{back} {c}"
            );
        }
        assert_eq!(pack_rgba(back), pack_rgba(c));
        let big = unpack_rgba(pack_rgba(Vec4::new(1e6, -1e6, f32::INFINITY, 1.0)));
        assert_eq!(big, Vec4::new(65504.0, -65504.0, f32::INFINITY, 1.0));
        assert_eq!(unpack_rgba([f16::ZERO; 4]), Vec4::ZERO);
    }
}
