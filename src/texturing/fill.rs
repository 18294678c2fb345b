//! Hole filling from the nearest seen surface ([`super::Holes::Nearest`]): a pixel of the mesh
//! that no view sees takes the colour of the nearest pixel some view does see, the distance
//! counted in steps across the mesh's own pixels (four-neighbour), so a hole is filled from the
//! surface around it and never across the background.
//!
//! Invariants: only hole pixels change; a hole with no seen pixel in its connected patch of the
//! mesh stays a hole; ties go to the neighbour reached first in a breadth-first walk seeded in
//! row order, so the result does not depend on thread count.

use crate::frame::{Image, Rgba};
use std::collections::VecDeque;

/// What a render's pixel showed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pixel {
    /// No mesh.
    Background,
    /// A mesh some view sees.
    Seen,
    /// A mesh no view sees.
    Hole,
}

/// Fills the holes of `image` (`pixels` in row order says what each showed) from the nearest
/// seen pixel, opaque; returns how many it filled.
pub fn from_nearest(image: &mut Image<Rgba>, pixels: &[Pixel]) -> usize {
    let (w, h) = (image.width() as usize, image.height() as usize);
    debug_assert_eq!(pixels.len(), w * h);
    let mut reached: Vec<bool> = pixels.iter().map(|&p| p != Pixel::Hole).collect();
    let mut queue: VecDeque<usize> = (0..w * h).filter(|&i| pixels[i] == Pixel::Seen).collect();
    let mut filled = 0;
    while let Some(i) = queue.pop_front() {
        let (x, y) = (i % w, i / w);
        let colour = image.pixels()[i];
        let neighbours = [
            (x > 0).then(|| i - 1),
            (x + 1 < w).then(|| i + 1),
            (y > 0).then(|| i - w),
            (y + 1 < h).then(|| i + w),
        ];
        for n in neighbours.into_iter().flatten() {
            if !reached[n] {
                reached[n] = true;
                image.pixels_mut()[n] = colour.truncate().extend(1.0);
                filled += 1;
                queue.push_back(n);
            }
        }
    }
    filled
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4;

    #[test]
    fn a_hole_takes_the_nearest_seen_colour_and_never_crosses_the_background() {
        // One row: seen red, two holes, seen blue | background | a hole alone.
        let (r, b) = (Vec4::new(1.0, 0.0, 0.0, 1.0), Vec4::new(0.0, 0.0, 1.0, 1.0));
        let mut image = Image::from_vec(
            7,
            1,
            vec![
                r,
                Vec4::ZERO,
                Vec4::ZERO,
                b,
                Vec4::ZERO,
                Vec4::ZERO,
                Vec4::ZERO,
            ],
        )
        .unwrap();
        use Pixel::*;
        let pixels = [Seen, Hole, Hole, Seen, Background, Hole, Background];
        assert_eq!(from_nearest(&mut image, &pixels), 2);
        let got = image.pixels();
        assert_eq!((got[1], got[2]), (r, b));
        assert_eq!((got[4], got[5]), (Vec4::ZERO, Vec4::ZERO));
    }
}
