//! The automatic fill for users without an artist: push-pull (Gortler et al., "The Lumigraph",
//! 1996, §3.4) over a layer's hidden texels — the parts of its objects that nearer layers hide in
//! the photograph, which the paper leaves to an artist's clone brush ("Layered view-dependent
//! projective textures" §3, Fig. 1).
//!
//! Invariants: known texels (alpha ≥ ½) are never changed; only texels of `region` are filled,
//! each with alpha 1; the result is deterministic.

use crate::frame::{Image, Rgba};
use glam::Vec4;

/// Fills the unknown texels of `image` where `region > 0` from the known ones; returns how
/// many were filled (0 when the layer knows no texel at all).
pub fn push_pull(image: &mut Image<Rgba>, region: &Image<f32>) -> usize {
    let (w, h) = image.size();
    // Level 0: premultiplied colour with weight 1 where known.
    let mut levels: Vec<(u32, u32, Vec<Vec4>)> = vec![(
        w,
        h,
        image
            .pixels()
            .iter()
            .map(|p| {
                if p.w >= 0.5 {
                    p.truncate().extend(1.0)
                } else {
                    Vec4::ZERO
                }
            })
            .collect(),
    )];
    // Push: halve until one texel, each coarse texel the weighted mean of its children.
    while levels.last().is_some_and(|l| l.0 > 1 || l.1 > 1) {
        let (fw, fh, fine) = levels.last().expect("a level");
        let (cw, ch) = (fw.div_ceil(2), fh.div_ceil(2));
        let mut coarse = vec![Vec4::ZERO; (cw * ch) as usize];
        for y in 0..*fh {
            for x in 0..*fw {
                coarse[((y / 2) * cw + x / 2) as usize] += fine[(y * fw + x) as usize];
            }
        }
        for c in &mut coarse {
            if c.w > 0.0 {
                *c = (c.truncate() / c.w).extend(c.w.min(1.0));
            }
        }
        levels.push((cw, ch, coarse));
    }
    if levels.last().is_none_or(|l| l.2[0].w == 0.0) {
        return 0;
    }
    // Pull: each unknown texel takes its parent's colour, from coarse to fine.
    for k in (0..levels.len() - 1).rev() {
        let (cw, _, coarse) = levels[k + 1].clone();
        let (fw, _, fine) = &mut levels[k];
        for (i, f) in fine.iter_mut().enumerate() {
            let (x, y) = (i as u32 % *fw, i as u32 / *fw);
            let parent = coarse[((y / 2) * cw + x / 2) as usize];
            if f.w < 1.0 {
                let a = f.w;
                let own = if a > 0.0 {
                    f.truncate()
                } else {
                    parent.truncate()
                };
                *f = (own * a + parent.truncate() * (1.0 - a)).extend(1.0);
            }
        }
    }
    let filled = &levels[0].2;
    let mut count = 0;
    for (i, p) in image.pixels_mut().iter_mut().enumerate() {
        if p.w < 0.5 && region.pixels()[i] > 0.0 {
            *p = filled[i].truncate().extend(1.0);
            count += 1;
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_texels_stay_and_the_hole_takes_its_surroundings() {
        let mut img = Image::new(8, 8, Vec4::new(0.2, 0.4, 0.6, 1.0)).expect("8 × 8");
        for y in 2..5 {
            for x in 3..6 {
                img.set(x, y, Vec4::ZERO);
            }
        }
        let before = img.clone();
        let region = Image::new(8, 8, 1.0f32).expect("8 × 8");
        assert_eq!(push_pull(&mut img, &region), 9);
        for (a, b) in img.pixels().iter().zip(before.pixels()) {
            if b.w >= 0.5 {
                assert_eq!(a, b);
            } else {
                assert!((*a - Vec4::new(0.2, 0.4, 0.6, 1.0)).abs().max_element() < 1e-6);
            }
        }
    }
}
