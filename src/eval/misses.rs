//! Pictures of where an impostor and the exact BVH disagree (`trompe impostor check --misses`):
//! the impostor's own colour image, shaded and dimmed, with a mark at each disagreeing ray's point in the
//! impostor's image coordinates — red where the BVH hits and the impostor misses, orange where
//! both hit too far apart (both at the exact hit), blue where only the impostor hits (at its
//! hit). Where a SPOC and a pinhole are compared, the two pictures side by side show which parts
//! of the object each camera loses (paper 1 §6, Fig. 6–7).
//!
//! Invariants: a ray is marked exactly when the fidelity check counts it as disagreeing (the
//! marks come from that check's own answers); the picture has the impostor's size; a point that
//! projects outside the image is counted, not drawn.

use super::fidelity::Disagreement;
use crate::frame::{FrameError, Image, Rgba};
use crate::impostor::Impostor;

/// The mark of a ray the BVH hits and the impostor misses.
pub const MISSED: Rgba = Rgba::new(1.0, 0.1, 0.1, 1.0);
/// The mark of a ray both hit, too far apart.
pub const PLACED: Rgba = Rgba::new(1.0, 0.6, 0.0, 1.0);
/// The mark of a ray only the impostor hits.
pub const SPURIOUS: Rgba = Rgba::new(0.2, 0.5, 1.0, 1.0);

/// One impostor's picture of its disagreements, and their counts.
#[derive(Clone, Debug)]
pub struct MissPicture {
    /// What it shows: `"impostor"`, or `"pinhole beside"`.
    pub name: &'static str,
    /// The impostor's colour image, shaded by facing and dimmed, the marks over it.
    pub image: Image<Rgba>,
    /// Rays the BVH hits and the impostor misses.
    pub missed: usize,
    /// Rays both hit, too far apart.
    pub placed: usize,
    /// Rays only the impostor hits.
    pub spurious: usize,
    /// Of those, the rays whose point projects outside the impostor's image (not drawn).
    pub outside: usize,
}

/// Draws `disagreements` ([`super::fidelity::check_disagreements`], on the same impostor) on `impostor`'s image.
pub fn miss_picture(
    name: &'static str,
    impostor: &Impostor,
    disagreements: &[Disagreement],
) -> MissPicture {
    // The colour image shaded by the normals' facing toward the viewpoint, at half brightness.
    let mut image = impostor.color_image();
    let (normals, positions) = (impostor.normal_image(), impostor.position_image());
    let eye = impostor.camera().viewpoint().as_vec3();
    for ((c, n), p) in image
        .pixels_mut()
        .iter_mut()
        .zip(normals.pixels())
        .zip(positions.pixels())
    {
        let facing = n.dot((eye - *p).normalize_or_zero()).abs();
        *c = (c.truncate() * (0.2 + 0.3 * facing)).extend(1.0);
    }
    let (w, h) = image.size();
    let mut picture = MissPicture {
        name,
        image,
        missed: 0,
        placed: 0,
        spurious: 0,
        outside: 0,
    };
    for d in disagreements {
        let (p, mark) = match *d {
            Disagreement::Missed(p) => {
                picture.missed += 1;
                (p, MISSED)
            }
            Disagreement::Placed(p) => {
                picture.placed += 1;
                (p, PLACED)
            }
            Disagreement::Spurious(p) => {
                picture.spurious += 1;
                (p, SPURIOUS)
            }
        };
        let Some(q) = impostor.camera().project(p.as_dvec3()) else {
            picture.outside += 1;
            continue;
        };
        let (x, y) = (q.uv.x.floor(), q.uv.y.floor());
        if !(x >= 0.0 && y >= 0.0 && x < f64::from(w) && y < f64::from(h)) {
            picture.outside += 1;
            continue;
        }
        // A 3 × 3 mark, clipped to the image.
        let (x, y) = (x as i64, y as i64);
        for (dx, dy) in (-1..=1).flat_map(|dx| (-1..=1).map(move |dy| (dx, dy))) {
            let (mx, my) = (x + dx, y + dy);
            if mx >= 0 && my >= 0 && mx < i64::from(w) && my < i64::from(h) {
                picture.image.set(mx as u32, my as u32, mark);
            }
        }
    }
    picture
}

/// `pictures` side by side, left to right, on a black ground as tall as the tallest.
pub fn side_by_side(pictures: &[MissPicture]) -> Result<Image<Rgba>, FrameError> {
    let width = pictures.iter().map(|p| p.image.width()).sum::<u32>().max(1);
    let height = pictures.iter().map(|p| p.image.height()).max().unwrap_or(1);
    let mut out = Image::new(width, height, Rgba::new(0.0, 0.0, 0.0, 1.0))?;
    let mut left = 0;
    for p in pictures {
        for y in 0..p.image.height() {
            for x in 0..p.image.width() {
                out.set(left + x, y, p.image.get(x, y));
            }
        }
        left += p.image.width();
    }
    Ok(out)
}
