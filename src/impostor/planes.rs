//! What a walk reads of each texel, packed into one record (beyond paper 1): the
//! texel's `gd`, the plane of the triangle it stores (its point, [`Impostor::position_at`], and
//! its unpacked face normal) and its front bound (`front.rs`). A walk sample first reads
//! its texel's `gd` from the compact map — most samples lie over empty texels, sixteen to a
//! cache line there — and only for a covered texel its plane and bound: from the maps an
//! unprojection, an octahedral decoding and lines far apart, from a [`TexelPlane`] one line
//! (two records fill a line, and records are aligned so none straddles two).
//!
//! Invariant: derived from the maps, never edited — [`Impostor::maps_changed`] drops it with
//! the pyramid, and the next walk rebuilds both.

use super::Impostor;
use crate::frame::Image;
use glam::Vec3;

/// One texel as the walk sees it (empty texels hold `gd` 0 and zeros).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub struct TexelPlane {
    /// World position of the stored point: a point of the texel's plane.
    pub point: Vec3,
    /// Stored generalized depth (0 = empty).
    pub gd: f32,
    /// Unit face normal, turned toward the camera.
    pub normal: Vec3,
    /// Front bound: the largest `gd` of a point behind the texel's plane (0 where empty).
    pub front: f32,
}

/// The records of every texel of `impostor`, whose front bounds are `front` (row-major).
pub(super) fn texel_planes(impostor: &Impostor, front: &[f32]) -> Image<TexelPlane> {
    let w = impostor.gd.size().0 as usize;
    impostor.map_image(|x, y| {
        let gd = impostor.gd.get(x, y);
        if gd <= 0.0 {
            return TexelPlane::default();
        }
        TexelPlane {
            point: impostor.position_at(x, y),
            gd,
            normal: impostor.face_normal_at(x, y),
            front: front[y as usize * w + x as usize],
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Spoc;
    use glam::Vec3;

    /// Every record repeats its texel's maps and front bound, and records never straddle two
    /// cache lines; editing the maps and saying so rebuilds them.
    #[test]
    fn each_record_is_its_texel() {
        assert_eq!(std::mem::size_of::<TexelPlane>(), 32);
        assert_eq!(std::mem::align_of::<TexelPlane>(), 32);
        let sphere = crate::geom::icosphere(3);
        let eye = Vec3::new(0.3, 0.4, 3.0);
        let camera = super::super::ImpostorCamera::Spoc(
            Spoc::around(eye, Vec3::ZERO, 1.0, 1.0, 48).unwrap(),
        );
        let mut imp = super::super::build(camera, &sphere, 0, &|_| Vec3::ONE).unwrap();
        let front = super::super::front_bounds(&imp);
        let planes = imp.texel_planes();
        let (w, h) = imp.gd.size();
        let mut covered = 0;
        for (x, y) in (0..h).flat_map(|y| (0..w).map(move |x| (x, y))) {
            let t = planes.get(x, y);
            assert_eq!(t.gd, imp.gd.get(x, y));
            assert_eq!(t.point, imp.position_at(x, y));
            assert_eq!(t.normal, imp.face_normal_at(x, y));
            assert_eq!(t.front, front.get(x, y));
            covered += usize::from(t.gd > 0.0);
        }
        assert!(covered > 200, "{covered}");
        imp.gd.set(w / 2, h / 2, 0.0);
        imp.maps_changed();
        assert_eq!(imp.texel_planes().get(w / 2, h / 2).gd, 0.0);
    }
}
