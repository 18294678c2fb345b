//! The view-independent bake (beyond paper 5: what mvs-texturing users expect): per face, the
//! view that sees it largest (projected area) with every texel of the face seen clearly, its texels
//! copied from that view's master texture; a face no view sees whole takes, texel by texel, the
//! mean of the views that see it. Built while the views stream past, so only one master
//! texture is in memory at a time. Then **levelled**: each view's texels are scaled by one gain
//! a channel, the ratio of the all-view mean to that view's own colours over the texels it gave
//! the bake, so that faces from views of different exposure or white balance meet without a
//! step at their seams (a global gain per view, not mvs-texturing's local seam levelling).
//!
//! Invariant: the result depends only on the views and their order (ties keep the earlier
//! view); gains are clamped to `[1/2, 2]`.

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
    /// Per texel: the view `chosen` took it from (`u32::MAX`: none).
    from: Vec<u32>,
    /// Per texel: the weighted sum of every view's colour that sees it (alpha: the weights'
    /// sum; [`EDGE_WEIGHT`] for a view that sees it only at its edge, 1 otherwise).
    sum: Image<Rgba>,
}

/// The weight of a texel a view sees only at its edge ([`super::EDGE_ALPHA`]) in the
/// texel-by-texel mean: small enough that it counts only where no view sees the texel clearly.
const EDGE_WEIGHT: f32 = 1e-3;

impl Baker {
    /// An empty bake over `atlas`.
    pub fn new(atlas: &Atlas) -> Result<Baker, MasterError> {
        let (w, h) = atlas.size();
        Ok(Baker {
            best: vec![None; atlas.layout.faces.len()],
            chosen: Image::new(w, h, Vec4::ZERO)?,
            from: vec![u32::MAX; w as usize * h as usize],
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
            // A texel seen only at the view's edge counts where no view sees it clearly.
            let weight = if m.w >= 1.0 { 1.0 } else { EDGE_WEIGHT };
            if m.w > 0.0 {
                *s += (m.truncate() * weight).extend(weight);
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
            // Whole: every texel inside the triangle seen clearly.
            let [bx, by, bw, bh] = place.bbox;
            let inside = |x: u32, y: u32| {
                let i = (y * w + x) as usize;
                if atlas.face[i] != t as u32 {
                    return false;
                }
                let (b1, b2) = place.barycentrics(crate::frame::pixel_centre(x as f64, y as f64));
                b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0
            };
            let mut whole = true;
            'scan: for y in by..by + bh {
                for x in bx..bx + bw {
                    if inside(x, y) && master.pixels()[(y * w + x) as usize].w < 1.0 {
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
                        self.from[i] = view as u32;
                    }
                }
            }
        }
    }

    /// Per view that gave the bake texels, its gain (RGB): the all-view mean over its own
    /// colours on those texels, clamped to `[1/2, 2]`.
    pub fn gains(&self) -> std::collections::BTreeMap<u32, glam::Vec3> {
        let mut acc: std::collections::BTreeMap<u32, (glam::DVec3, glam::DVec3)> =
            std::collections::BTreeMap::new();
        for (i, &v) in self.from.iter().enumerate() {
            let (c, s) = (self.chosen.pixels()[i], self.sum.pixels()[i]);
            if v == u32::MAX || c.w == 0.0 || s.w == 0.0 {
                continue;
            }
            let e = acc.entry(v).or_default();
            e.0 += (s.truncate() / s.w).as_dvec3();
            e.1 += c.truncate().as_dvec3();
        }
        acc.into_iter()
            .map(|(v, (mean, own))| {
                let g = (mean / own.max(glam::DVec3::splat(1e-9)))
                    .clamp(glam::DVec3::splat(0.5), glam::DVec3::splat(2.0));
                (v, g.as_vec3())
            })
            .collect()
    }

    /// The bake, levelled, and per face the view it was taken from (`None`: the
    /// texel-by-texel mean).
    pub fn finish(self, atlas: &Atlas) -> (Image<Rgba>, Vec<Option<usize>>) {
        let gains = self.gains();
        let mut out = self.chosen;
        for (texel, v) in out.pixels_mut().iter_mut().zip(&self.from) {
            if let Some(g) = gains.get(v) {
                *texel = (texel.truncate() * *g).extend(texel.w);
            }
        }
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

#[cfg(test)]
mod tests {
    use super::super::tests::duck_capture;
    use super::super::{DEFAULT_SCALE, encode_views};
    use super::*;

    #[test]
    fn levelling_takes_out_a_views_exposure() {
        // Every other view 40 % too bright (an exposure the photographer got wrong).
        let (mesh, mut set) = duck_capture(8);
        let truth = encode_views(&mesh, &set.views, DEFAULT_SCALE, &()).unwrap();
        for v in set.views.iter_mut().step_by(2) {
            if let Some(img) = &mut v.image {
                for p in img.pixels_mut() {
                    *p = (p.truncate() * 1.4).extend(p.w);
                }
            }
        }
        let bright = encode_views(&mesh, &set.views, DEFAULT_SCALE, &()).unwrap();
        let bake = |enc: &super::super::Encoding, level: bool| {
            let mut b = Baker::new(&enc.atlas).unwrap();
            for (v, ((_, cam), m)) in enc.cameras.iter().zip(&enc.masters).enumerate() {
                b.add(&enc.atlas, &mesh, v, cam, m);
            }
            if level {
                b.finish(&enc.atlas).0
            } else {
                let gains = b.gains();
                assert!(gains.values().any(|g| g.x < 0.9), "{gains:?}");
                // Unlevelled: the chosen texels as they are, the mean elsewhere.
                let mut one = Baker::new(&enc.atlas).unwrap();
                std::mem::swap(&mut one, &mut b);
                let mut out = one.chosen.clone();
                for (t, s) in out.pixels_mut().iter_mut().zip(one.sum.pixels()) {
                    if t.w == 0.0 && s.w > 0.0 {
                        *t = (s.truncate() / s.w).extend(1.0);
                    }
                }
                out
            }
        };
        let reference = bake(&truth, true);
        // Levelling cannot know the true exposure, only make the views agree: compare up to
        // the one global scale that fits best.
        let mse = |img: &Image<Rgba>| {
            let both = || {
                img.pixels()
                    .iter()
                    .zip(reference.pixels())
                    .filter(|(a, b)| a.w > 0.0 && b.w > 0.0)
            };
            let (ab, aa) = both().fold((0.0f64, 0.0f64), |(ab, aa), (a, b)| {
                (
                    ab + a.truncate().dot(b.truncate()) as f64,
                    aa + a.truncate().length_squared() as f64,
                )
            });
            let k = (ab / aa) as f32;
            let n = both().count() as f64;
            both()
                .map(|(a, b)| (a.truncate() * k - b.truncate()).length_squared() as f64)
                .sum::<f64>()
                / n
        };
        let (raw, levelled) = (mse(&bake(&bright, false)), mse(&bake(&bright, true)));
        println!("unlevelled {raw:.5}, levelled {levelled:.5} (mean squared error up to scale)");
        assert!(levelled < raw * 0.5, "{levelled} vs {raw}");
    }
}
