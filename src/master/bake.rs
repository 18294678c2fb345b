//! The view-independent bake (beyond paper 5: what mvs-texturing users expect): per face, the
//! view that sees it largest (projected area) with every texel of the face seen, its texels
//! copied from that view's master texture; a face no view sees whole takes, texel by texel, the
//! mean of the views that see it. Built while the views stream past, so only one master
//! texture is in memory at a time. No colour levelling across seams.
//!
//! Invariant: the result depends only on the views and their order (ties keep the earlier
//! view).

use super::{Atlas, MasterError};
use crate::camera::{Pinhole, Projection};
use crate::frame::{Image, Rgba};
use crate::geom::Mesh;
use glam::{DVec2, Vec4};

/// The bake being built.
pub struct Baker {
    /// Per face: the best whole view so far and its projected area.
    best: Vec<Option<(usize, f64)>>,
    /// The texels of the best views.
    chosen: Image<Rgba>,
    /// Per texel: the sum of every view's colour that sees it (alpha: how many).
    sum: Image<Rgba>,
}

impl Baker {
    /// An empty bake over `atlas`.
    pub fn new(atlas: &Atlas) -> Result<Baker, MasterError> {
        let (w, h) = atlas.size();
        Ok(Baker {
            best: vec![None; atlas.layout.faces.len()],
            chosen: Image::new(w, h, Vec4::ZERO)?,
            sum: Image::new(w, h, Vec4::ZERO)?,
        })
    }

    /// Takes view `view` (its camera and master texture) into account.
    pub fn add(
        &mut self,
        atlas: &Atlas,
        mesh: &Mesh,
        view: usize,
        camera: &Pinhole,
        master: &Image<Rgba>,
    ) {
        let (w, _) = atlas.size();
        for (s, m) in self.sum.pixels_mut().iter_mut().zip(master.pixels()) {
            if m.w > 0.0 {
                *s += m.truncate().extend(1.0);
            }
        }
        for (t, place) in atlas.layout.faces.iter().enumerate() {
            let c = mesh.corners(t).map(|p| p.as_dvec3());
            let px: Option<Vec<DVec2>> =
                c.iter().map(|&p| camera.project(p).map(|q| q.uv)).collect();
            let Some(px) = px else { continue };
            let area = (px[1] - px[0]).perp_dot(px[2] - px[0]).abs();
            if self.best[t].is_some_and(|(_, a)| area <= a) {
                continue;
            }
            // Whole: every texel inside the triangle seen.
            let [bx, by, bw, bh] = place.bbox;
            let inside = |x: u32, y: u32| {
                let i = (y * w + x) as usize;
                if atlas.face[i] != t as u32 {
                    return false;
                }
                let (b1, b2) = place.barycentrics(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
                b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0
            };
            let mut whole = true;
            'scan: for y in by..by + bh {
                for x in bx..bx + bw {
                    if inside(x, y) && master.pixels()[(y * w + x) as usize].w == 0.0 {
                        whole = false;
                        break 'scan;
                    }
                }
            }
            if !whole {
                continue;
            }
            self.best[t] = Some((view, area));
            for y in by..by + bh {
                for x in bx..bx + bw {
                    let i = (y * w + x) as usize;
                    if atlas.face[i] == t as u32 {
                        self.chosen.pixels_mut()[i] = master.pixels()[i];
                    }
                }
            }
        }
    }

    /// The bake, and per face the view it was taken from (`None`: the texel-by-texel mean).
    pub fn finish(self, atlas: &Atlas) -> (Image<Rgba>, Vec<Option<usize>>) {
        let mut out = self.chosen;
        for (i, texel) in out.pixels_mut().iter_mut().enumerate() {
            let f = atlas.face[i];
            if f == u32::MAX {
                continue;
            }
            let picked = self.best[f as usize].is_some() && texel.w > 0.0;
            if !picked {
                let s = self.sum.pixels()[i];
                *texel = if s.w > 0.0 {
                    (s.truncate() / s.w).extend(1.0)
                } else {
                    Vec4::ZERO
                };
            }
        }
        (out, self.best.iter().map(|b| b.map(|(v, _)| v)).collect())
    }
}
