//! Where a renderer hands an object over from its mesh to its octahedral impostor: the switch
//! distance and the dithered cross-fade the `.glb` layout carries (docs/conventions.md §8.5),
//! which both runtimes honour (`shaders/octahedral_impostor.wgsl`, `web/trompe-octahedral.js`).
//!
//! Between the fade's `start` and `end` (distances from the eye to the bounding sphere's centre,
//! in the bake's units: a world distance over the instance's scale) the impostor draws a share
//! `s = (distance − start) / (end − start)` of the pixels and the mesh the others, chosen by a
//! 4 × 4 Bayer matrix on the render target's pixel grid: pixel `(x, y)` is the impostor's when
//! its threshold `(B[y mod 4][x mod 4] + ½) / 16` is below `s`. Before `start` only the mesh
//! draws, past `end` only the impostor; a fade with `end ≤ start` is a hard switch at `start`.
//!
//! Invariants: every pixel is drawn by exactly one of the two at any distance, and the share
//! the impostor draws grows with distance.

use serde::{Deserialize, Serialize};

/// The cross-fade band's width, as a share of the switch distance it begins at.
pub const BAND: f32 = 0.2;

/// The 4 × 4 Bayer (ordered dither) matrix, row by row.
pub const BAYER4: [u32; 16] = [0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5];

/// The dither a cross-fade uses (only one is defined).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Dither {
    /// [`BAYER4`] on the render target's pixels.
    #[default]
    #[serde(rename = "bayer-4x4")]
    Bayer4,
}

/// A dithered cross-fade from the mesh to the impostor.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CrossFade {
    /// Where the impostor starts to appear (the bake's units).
    pub start: f32,
    /// Where it has replaced the mesh.
    pub end: f32,
    /// How pixels are shared.
    #[serde(default)]
    pub dither: Dither,
}

impl CrossFade {
    /// The fade of an atlas of frames `frame_size` texels across a sphere of `radius`: from the
    /// switch distance ([`super::file::switch_distance`]) to [`BAND`] beyond it.
    pub fn of(radius: f32, frame_size: u32) -> Self {
        let start = super::file::switch_distance(radius, frame_size);
        Self {
            start,
            end: start * (1.0 + BAND),
            dither: Dither::Bayer4,
        }
    }

    /// The share of pixels the impostor draws at `distance`.
    pub fn impostor_share(&self, distance: f32) -> f32 {
        if self.end <= self.start {
            return if distance >= self.start { 1.0 } else { 0.0 };
        }
        ((distance - self.start) / (self.end - self.start)).clamp(0.0, 1.0)
    }

    /// Whether pixel `(x, y)` of the render target is the impostor's at `distance` (the mesh's
    /// otherwise).
    pub fn impostor_draws(&self, (x, y): (u32, u32), distance: f32) -> bool {
        threshold(x, y) < self.impostor_share(distance)
    }
}

/// Pixel `(x, y)`'s dither threshold, in `(0, 1)`.
pub fn threshold(x: u32, y: u32) -> f32 {
    (BAYER4[(y % 4 * 4 + x % 4) as usize] as f32 + 0.5) / 16.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_impostors_share_of_a_tile_grows_from_none_to_all_across_the_band() {
        let fade = CrossFade::of(1.0, 64);
        let drawn = |d: f32| {
            (0..4)
                .flat_map(|y| (0..4).map(move |x| (x, y)))
                .filter(|&p| fade.impostor_draws(p, d))
                .count()
        };
        assert_eq!(drawn(fade.start - 1.0), 0);
        assert_eq!(drawn(fade.end + 1.0), 16);
        assert_eq!(drawn((fade.start + fade.end) / 2.0), 8);
        let mut last = 0;
        for k in 0..=64 {
            let d = fade.start + (fade.end - fade.start) * k as f32 / 64.0;
            assert!(drawn(d) >= last);
            last = drawn(d);
        }
        let mut sorted = BAYER4;
        sorted.sort_unstable();
        assert_eq!(sorted, std::array::from_fn(|k| k as u32));
    }
}
