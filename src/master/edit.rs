//! Edits propagated through master space (paper 5 §4.1; docs/conventions.md §6.5): an edit made
//! in one view's image — or an effect seen from any new camera, rendered with and without it —
//! is encoded with the same packing map, and the difference is applied to every view's master
//! texture. No correspondence search: the packing map is the correspondence.
//!
//! Invariant: a texel changes only where both encodings of the edit see the surface and the
//! master texture being edited sees it too (alpha stays the view's visibility).

use super::MasterError;
use crate::frame::{Image, Rgba};
use glam::Vec4;

/// How a delta is applied.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Apply {
    /// `M ← max(0, M + Δ)` (the paper's default; its 8-bit images also clip at 1, trompe's
    /// linear ones do so only when written as PNG).
    #[default]
    Add,
    /// `M ← M′` where the edit changed the texel (the paper's Fig. 6 caption: "written
    /// directly").
    Replace,
}

/// The difference between two encodings of the same camera (`after − before`), where both see
/// the surface and the change is larger than `threshold` in some channel (resampling noise
/// below it is left out); alpha 1 marks texels that carry a change.
pub fn delta(
    before: &Image<Rgba>,
    after: &Image<Rgba>,
    threshold: f32,
) -> Result<Image<Rgba>, MasterError> {
    if before.size() != after.size() {
        return Err(MasterError::Size {
            index: 0,
            got: after.size(),
            expected: before.size(),
        });
    }
    let data = before
        .pixels()
        .iter()
        .zip(after.pixels())
        .map(|(b, a)| {
            let d = (*a - *b).truncate();
            if b.w > 0.0 && a.w > 0.0 && d.abs().max_element() > threshold {
                d.extend(1.0)
            } else {
                Vec4::ZERO
            }
        })
        .collect();
    Ok(Image::from_vec(before.width(), before.height(), data)?)
}

/// Applies `delta` (from [`delta`]; `after` is the edited encoding, for [`Apply::Replace`]) to
/// every master texture where it sees the surface. Returns the texels changed, over all masters.
pub fn propagate(
    masters: &mut [Image<Rgba>],
    delta: &Image<Rgba>,
    after: &Image<Rgba>,
    apply: Apply,
) -> Result<usize, MasterError> {
    let mut changed = 0;
    for (index, m) in masters.iter_mut().enumerate() {
        if m.size() != delta.size() {
            return Err(MasterError::Size {
                index,
                got: m.size(),
                expected: delta.size(),
            });
        }
        for ((t, d), a) in m
            .pixels_mut()
            .iter_mut()
            .zip(delta.pixels())
            .zip(after.pixels())
        {
            if t.w > 0.0 && d.w > 0.0 {
                let c = match apply {
                    Apply::Add => (t.truncate() + d.truncate()).max(glam::Vec3::ZERO),
                    Apply::Replace => a.truncate(),
                };
                *t = c.extend(t.w);
                changed += 1;
            }
        }
    }
    Ok(changed)
}

/// An effect seen from any camera (paper 5 §4.1, e.g. a shadow): `without` and `with` are two
/// renders of the mesh through `camera` (undistorted), one without the effect and one with it;
/// both are encoded with the packing map of `atlas` and their difference returned (as
/// [`delta`]), with the encoding of `with` (for [`Apply::Replace`]). Texels `camera` does not
/// see carry no change.
pub fn delta_from_camera(
    atlas: &super::Atlas,
    mesh: &crate::geom::Mesh,
    camera: &crate::camera::Pinhole,
    without: &Image<Rgba>,
    with: &Image<Rgba>,
    threshold: f32,
) -> Result<(Image<Rgba>, Image<Rgba>), MasterError> {
    let depth = crate::views::visibility::DepthMap::through(camera, mesh)?;
    let before = super::encode(atlas, camera, without, &depth)?;
    let after = super::encode(atlas, camera, with, &depth)?;
    Ok((delta(&before, &after, threshold)?, after))
}
