//! The mip chain of an atlas, frame by frame: each level halves every frame by a 2 × 2 box
//! filter within it, so a level's texel never mixes two frames (what a GPU's own mip generation
//! over the whole atlas does once frames are a few texels wide, and what a wide filter does at
//! every level). With frames filled whole by dilation ([`super::bake`]), no level pulls in the
//! background either. Colour is averaged in linear light; coverage is averaged as it is.
//!
//! Invariants: level `k` has frames of `frame_size / 2^k` texels; the chain stops before a
//! frame side would be odd or below 1; level 0 is the atlas itself.

use crate::frame::{FrameError, Image, Lerp};

/// The levels of `atlas` (frames `frame_size` texels square), level 0 first.
pub fn frame_mips<T: Lerp>(atlas: &Image<T>, frame_size: u32) -> Result<Vec<Image<T>>, FrameError> {
    let mut levels = vec![atlas.clone()];
    let mut fs = frame_size;
    while fs >= 2 && fs.is_multiple_of(2) {
        let Some(last) = levels.last() else { break };
        let (w, h) = (last.width() / 2, last.height() / 2);
        let texels = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                let (x0, y0) = (2 * x, 2 * y);
                (last.get(x0, y0)
                    + last.get(x0 + 1, y0)
                    + last.get(x0, y0 + 1)
                    + last.get(x0 + 1, y0 + 1))
                    * 0.25
            })
            .collect();
        levels.push(Image::from_vec(w, h, texels)?);
        fs /= 2;
    }
    Ok(levels)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4;

    #[test]
    fn levels_halve_each_frame_and_never_mix_two() {
        // Four frames of 8 × 8, each one flat colour: every level keeps each frame's own.
        let colours = [Vec4::X, Vec4::Y, Vec4::Z, Vec4::W];
        let atlas = Image::from_vec(
            16,
            16,
            (0..256u32)
                .map(|k| colours[((k % 16) / 8 + 2 * ((k / 16) / 8)) as usize])
                .collect(),
        )
        .unwrap();
        let levels = frame_mips(&atlas, 8).unwrap();
        assert_eq!(
            levels.iter().map(|l| l.width()).collect::<Vec<_>>(),
            [16, 8, 4, 2]
        );
        for (k, level) in levels.iter().enumerate() {
            let fs = 8 >> k;
            for y in 0..level.height() {
                for x in 0..level.width() {
                    let frame = (x / fs + 2 * (y / fs)) as usize;
                    assert_eq!(level.get(x, y), colours[frame], "level {k} ({x}, {y})");
                }
            }
        }
        // An odd frame side stops the chain: frames of 6, then 3.
        let six = Image::new(12, 12, Vec4::ONE).unwrap();
        assert_eq!(frame_mips(&six, 6).unwrap().len(), 2);
    }
}
