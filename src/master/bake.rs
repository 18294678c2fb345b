//! The view-independent bake (beyond paper 5: what mvs-texturing and OpenMVS users expect), made
//! seamless ([`crate::texturing::seams`]). Two passes over the views:
//!
//! 1. [`Baker::add`], as each view streams past: per face, the view's projected area, whether it
//!    sees every texel of the face clearly, and the face's mean colour in it (a look).
//! 2. [`Baker::bake`], when all have: per view one gain a channel that brings its looks to the
//!    faces' consensus (exposure, white balance), and per face the looks that agree
//!    photometrically (a view where something passed in front is left out of that face). Each
//!    face is then taken from its largest agreeing whole view, its texels scaled by the view's
//!    gain; a face no agreeing view sees whole takes, texel by texel, the gain-corrected mean of
//!    the agreeing views that see it. The master textures are asked for once more, one at a time.
//!
//! Then **levelled**: where faces from two views (or from the mean) meet, per-vertex colour
//! offsets solved on the mesh make the two sides agree, fading away from the seam; and
//! **filled**: a texel no view sees takes its face's corners' colours, carried across the mesh
//! from the nearest seen faces. [`BakeReport`] says how large the step across seams was with
//! the gains alone and after levelling.
//!
//! Invariants: the result depends only on the views and their order (ties keep the earlier
//! view), on any thread count; gains are clamped to `[1/2, 2]`; only texels no view sees are
//! filled.

use super::{Atlas, MasterError};
use crate::camera::{Pinhole, Projection};
use crate::frame::{Image, Rgba};
use crate::geom::Mesh;
use crate::texturing::seams::{self, Look, SeamReport, Seams};
use glam::{Vec3, Vec4};

/// One view's look at one face, with what picks the face's view.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    /// The view and the face's mean colour in it.
    look: Look,
    /// The face's projected area in the view, pixels².
    area: f32,
}

/// The label of faces the bake took texel by texel from the mean ([`Seams`] between them and a
/// view's faces are levelled like any other).
const MEAN: u32 = u32::MAX;

/// The weight of a texel a view sees only at its edge ([`super::EDGE_ALPHA`]) in the
/// texel-by-texel mean: small enough that it counts only where no view sees the texel clearly.
const EDGE_WEIGHT: f32 = 1e-3;

/// The bake's first pass: what every view showed of every face.
pub struct Baker {
    /// Per face, the views that see any of it, in view order.
    faces: Vec<Vec<Candidate>>,
    /// Views added.
    views: usize,
}

/// What the bake did, for the report.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BakeReport {
    /// Faces taken whole from one view.
    pub whole: usize,
    /// Outliers left out, and the step across seams before and after levelling.
    pub seams: SeamReport,
    /// Texels no view sees, filled from the nearest seen faces.
    pub filled: usize,
    /// Texels left empty (a part of the mesh no view sees any of).
    pub empty: usize,
}

/// The bake: its atlas image, per face the view it was taken from (`None`: the texel-by-texel
/// mean, or nothing), and what was done.
#[derive(Clone, Debug)]
pub struct Baked {
    /// The bake, in the atlas.
    pub image: Image<Rgba>,
    /// Per face, the view it was taken whole from.
    pub choice: Vec<Option<usize>>,
    /// What the bake did.
    pub report: BakeReport,
}

impl BakeReport {
    /// The report in words, for a mesh of `faces` faces.
    pub fn told(&self, faces: usize) -> String {
        let mut out = format!(
            "{} of {faces} faces from one view whole, the rest texel by texel; {}",
            self.whole, self.seams
        );
        if self.filled + self.empty > 0 {
            out += &format!(
                "; {} texels no view sees filled from the nearest seen faces",
                self.filled
            );
        }
        if self.empty > 0 {
            out += &format!(", {} on parts no view sees left empty", self.empty);
        }
        out
    }
}

impl Baker {
    /// An empty bake over `atlas`, for at most `views` views: refused when their looks at
    /// every face could pass the memory budget.
    pub fn new(atlas: &Atlas, views: usize) -> Result<Baker, MasterError> {
        let faces = atlas.layout.faces.len();
        crate::memory::check(
            || format!("the bake's looks of {views} views at {faces} faces"),
            crate::memory::times(
                (faces as u64).saturating_mul(views as u64),
                std::mem::size_of::<Candidate>() as u64,
            ),
        )?;
        Ok(Baker {
            faces: vec![Vec::new(); faces],
            views: 0,
        })
    }

    /// Takes view `view` (its camera and master texture) into account: the first pass.
    pub fn add(
        &mut self,
        atlas: &Atlas,
        mesh: &Mesh,
        view: usize,
        camera: &Pinhole,
        master: &Image<Rgba>,
    ) {
        let (w, _) = atlas.size();
        self.views = self.views.max(view + 1);
        for (t, place) in atlas.layout.faces.iter().enumerate() {
            let px = mesh
                .corners(t)
                .map(|p| camera.project(p.as_dvec3()).map(|q| q.uv));
            let [Some(a), Some(b), Some(c)] = px else {
                continue;
            };
            let px = [a, b, c];
            let area = (px[1] - px[0]).perp_dot(px[2] - px[0]).abs() as f32;
            // The face's texels: whole when every one inside the triangle is seen clearly;
            // its colour the mean of those seen clearly (failing them, of those seen at all).
            let [bx, by, bw, bh] = place.bbox;
            let (mut whole, mut clear, mut any) = (true, (Vec3::ZERO, 0u32), (Vec3::ZERO, 0u32));
            for y in by..by + bh {
                for x in bx..bx + bw {
                    let i = (y * w + x) as usize;
                    if atlas.face[i] != t as u32 {
                        continue;
                    }
                    let m = master.pixels()[i];
                    if m.w >= 1.0 {
                        clear = (clear.0 + m.truncate(), clear.1 + 1);
                    } else if whole {
                        let (b1, b2) = place
                            .barycentrics(crate::frame::pixel_centre(f64::from(x), f64::from(y)));
                        whole = !(b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0);
                    }
                    if m.w > 0.0 {
                        any = (any.0 + m.truncate(), any.1 + 1);
                    }
                }
            }
            let (sum, n) = if clear.1 > 0 { clear } else { any };
            if n == 0 {
                continue;
            }
            self.faces[t].push(Candidate {
                look: Look {
                    view: view as u32,
                    colour: sum / n as f32,
                    whole,
                },
                area,
            });
        }
    }

    /// The bake: gains and photometric outliers from the looks, the faces' views, then the
    /// master textures asked of `master_of` once more, one at a time, for their texels; then
    /// levelled and filled.
    pub fn bake(
        self,
        atlas: &Atlas,
        mesh: &Mesh,
        master_of: &mut dyn FnMut(usize) -> Result<Image<Rgba>, MasterError>,
    ) -> Result<Baked, MasterError> {
        let looks: Vec<Vec<Look>> = self
            .faces
            .iter()
            .map(|f| f.iter().map(|c| c.look).collect())
            .collect();
        let (gains, agree) = seams::gains_and_inliers(&looks, self.views);
        let mut report = BakeReport::default();
        report.seams.outliers = agree.iter().flatten().filter(|a| !**a).count();
        // Per face, its largest agreeing whole view (ties keep the earlier view).
        let choice: Vec<Option<usize>> = self
            .faces
            .iter()
            .zip(&agree)
            .map(|(cands, agree)| {
                let mut best: Option<&Candidate> = None;
                for (c, _) in cands.iter().zip(agree).filter(|(c, a)| **a && c.look.whole) {
                    if best.is_none_or(|b| c.area > b.area) {
                        best = Some(c);
                    }
                }
                best.map(|c| c.look.view as usize)
            })
            .collect();
        report.whole = choice.iter().flatten().count();
        let (w, h) = atlas.size();
        let mut chosen = Image::new(w, h, Vec4::ZERO)?;
        let mut sum = Image::new(w, h, Vec4::ZERO)?;
        // Per view, the faces where its look agrees, in face order.
        let mut agreeing: Vec<Vec<u32>> = vec![Vec::new(); self.views];
        for (f, (cands, agree)) in self.faces.iter().zip(&agree).enumerate() {
            for (c, _) in cands.iter().zip(agree).filter(|(_, a)| **a) {
                agreeing[c.look.view as usize].push(f as u32);
            }
        }
        let mut agrees = vec![false; self.faces.len()];
        for (view, &gain) in gains.iter().enumerate() {
            if agreeing[view].is_empty() {
                continue;
            }
            agrees.fill(false);
            for &f in &agreeing[view] {
                agrees[f as usize] = true;
            }
            let master = master_of(view)?;
            if master.size() != (w, h) {
                return Err(MasterError::Size {
                    index: view,
                    got: master.size(),
                    expected: (w, h),
                });
            }
            for (i, m) in master.pixels().iter().enumerate() {
                let f = atlas.face[i];
                if f == u32::MAX || m.w == 0.0 || !agrees[f as usize] {
                    continue;
                }
                let colour = m.truncate() * gain;
                if choice[f as usize] == Some(view) {
                    chosen.pixels_mut()[i] = colour.extend(m.w);
                }
                // A texel seen only at the view's edge counts where no view sees it clearly.
                let weight = if m.w >= 1.0 { 1.0 } else { EDGE_WEIGHT };
                sum.pixels_mut()[i] += (colour * weight).extend(weight);
            }
        }
        // The chosen texels; the mean where a face has no view, or its view missed a texel.
        let mut image = chosen;
        let mut labels: Vec<Option<u32>> = choice.iter().map(|c| c.map(|v| v as u32)).collect();
        for (i, texel) in image.pixels_mut().iter_mut().enumerate() {
            let f = atlas.face[i];
            if f == u32::MAX || (choice[f as usize].is_some() && texel.w > 0.0) {
                continue;
            }
            let s = sum.pixels()[i];
            if s.w > 0.0 {
                *texel = (s.truncate() / s.w).extend(1.0);
                labels[f as usize].get_or_insert(MEAN);
            }
        }
        drop(sum);
        let seams = Seams::find(mesh, &labels);
        report.seams.edges = seams.edges.len();
        report.seams.step_gains = seams.step(|f, b| texel_at(atlas, &image, f, b));
        let offsets = seams::level(mesh, &labels, &seams, |f, b| texel_at(atlas, &image, f, b));
        if !offsets.is_empty() {
            for (i, texel) in image.pixels_mut().iter_mut().enumerate() {
                let f = atlas.face[i];
                let Some(label) = labels.get(f as usize).copied().flatten() else {
                    continue;
                };
                if texel.w == 0.0 {
                    continue;
                }
                let b = bary_of_texel(atlas, f as usize, i);
                let shift = offsets.at(mesh, &seams.welded, f as usize, label, b);
                *texel = (texel.truncate() + shift).max(Vec3::ZERO).extend(texel.w);
            }
        }
        report.seams.step_levelled = seams.step(|f, b| texel_at(atlas, &image, f, b));
        (report.filled, report.empty) = fill(atlas, mesh, &seams.welded, &labels, &mut image);
        Ok(Baked {
            image,
            choice,
            report,
        })
    }
}

/// The barycentrics of face `face`'s surface point at atlas texel `i`, moved into the triangle.
fn bary_of_texel(atlas: &Atlas, face: usize, i: usize) -> Vec3 {
    let w = atlas.size().0 as usize;
    let centre = crate::frame::pixel_centre((i % w) as f64, (i / w) as f64);
    let (b1, b2) = super::clamp_to_triangle(atlas.layout.faces[face].barycentrics(centre));
    Vec3::new((1.0 - b1 - b2) as f32, b1 as f32, b2 as f32)
}

/// The colour of `image` (an atlas image) at face `face`'s point of barycentrics `bary`: the
/// face's texel under it, nudged a little into the triangle; `None` where that texel is empty.
fn texel_at(atlas: &Atlas, image: &Image<Rgba>, face: usize, bary: Vec3) -> Option<Vec3> {
    let b = bary * (1.0 - 1e-3) + Vec3::splat(1e-3 / 3.0);
    let place = &atlas.layout.faces[face];
    let p = place.at(f64::from(b.y), f64::from(b.z));
    let [bx, by, bw, bh] = place.bbox;
    let x = (p.x.floor() as i64).clamp(i64::from(bx), i64::from(bx + bw) - 1) as u32;
    let y = (p.y.floor() as i64).clamp(i64::from(by), i64::from(by + bh) - 1) as u32;
    let i = (y * atlas.size().0 + x) as usize;
    let texel = image.pixels()[i];
    (atlas.face[i] == face as u32 && texel.w > 0.0).then(|| texel.truncate())
}

/// Fills the texels of `image` no view saw (alpha 0 on a face): each takes its face's corners'
/// colours, interpolated, where a vertex's colour is the mean its seen faces (`labels`) give
/// it, carried ring by ring across the mesh to vertices no seen face touches. Returns the
/// texels filled and those left empty (on parts of the mesh no seen face reaches).
fn fill(
    atlas: &Atlas,
    mesh: &Mesh,
    welded: &[u32],
    labels: &[Option<u32>],
    image: &mut Image<Rgba>,
) -> (usize, usize) {
    let holes = atlas
        .face
        .iter()
        .zip(image.pixels())
        .filter(|(f, t)| **f != u32::MAX && t.w == 0.0)
        .count();
    if holes == 0 {
        return (0, 0);
    }
    let n = mesh.positions.len();
    let mut colour: Vec<Option<Vec3>> = vec![None; n];
    let mut sums = vec![(Vec3::ZERO, 0u32); n];
    for (f, tri) in mesh.triangles.iter().enumerate() {
        if labels[f].is_none() {
            continue;
        }
        for k in 0..3 {
            let mut b = Vec3::ZERO;
            b[k] = 1.0;
            if let Some(c) = texel_at(atlas, image, f, b) {
                let s = &mut sums[welded[tri[k] as usize] as usize];
                *s = (s.0 + c, s.1 + 1);
            }
        }
    }
    for (v, s) in sums.iter().enumerate() {
        if s.1 > 0 {
            colour[v] = Some(s.0 / s.1 as f32);
        }
    }
    // Ring by ring: a vertex without a colour takes the mean of its coloured neighbours.
    loop {
        let mut next = colour.clone();
        let mut grown = false;
        let mut ring = vec![(Vec3::ZERO, 0u32); n];
        for tri in &mesh.triangles {
            let w = tri.map(|v| welded[v as usize] as usize);
            for a in 0..3 {
                for b in [(a + 1) % 3, (a + 2) % 3] {
                    if let (None, Some(c)) = (colour[w[a]], colour[w[b]]) {
                        ring[w[a]] = (ring[w[a]].0 + c, ring[w[a]].1 + 1);
                    }
                }
            }
        }
        for (v, r) in ring.iter().enumerate() {
            if r.1 > 0 {
                next[v] = Some(r.0 / r.1 as f32);
                grown = true;
            }
        }
        colour = next;
        if !grown {
            break;
        }
    }
    let (mut filled, mut empty) = (0, 0);
    for (i, texel) in image.pixels_mut().iter_mut().enumerate() {
        let f = atlas.face[i];
        if f == u32::MAX || texel.w > 0.0 {
            continue;
        }
        let b = bary_of_texel(atlas, f as usize, i);
        let corners = mesh.triangles[f as usize].map(|v| colour[welded[v as usize] as usize]);
        match corners {
            [Some(c0), Some(c1), Some(c2)] => {
                *texel = (c0 * b.x + c1 * b.y + c2 * b.z).extend(1.0);
                filled += 1;
            }
            _ => empty += 1,
        }
    }
    (filled, empty)
}

#[cfg(test)]
mod tests {
    use super::super::tests::duck_capture;
    use super::super::{DEFAULT_SCALE, Encoding, encode_views};
    use super::*;

    /// The Duck's capture of `count` views, each view's image changed by `change(view, pixel,
    /// colour)`, encoded and baked.
    fn baked(count: usize, change: impl Fn(usize, (u32, u32), Vec3) -> Vec3) -> (Encoding, Baked) {
        let (mesh, mut set) = duck_capture(count);
        for (v, view) in set.views.iter_mut().enumerate() {
            if let Some(img) = &mut view.image {
                let w = img.width();
                for (i, p) in img.pixels_mut().iter_mut().enumerate() {
                    let xy = ((i as u32) % w, (i as u32) / w);
                    *p = change(v, xy, p.truncate()).extend(p.w);
                }
            }
        }
        let enc = encode_views(&mesh, &set.views, DEFAULT_SCALE, &()).unwrap();
        let mut b = Baker::new(&enc.atlas, enc.masters.len()).unwrap();
        for (v, ((_, cam), m)) in enc.cameras.iter().zip(&enc.masters).enumerate() {
            b.add(&enc.atlas, &mesh, v, cam, m);
        }
        let baked = b
            .bake(&enc.atlas, &mesh, &mut |v| Ok(enc.masters[v].clone()))
            .unwrap();
        (enc, baked)
    }

    /// Mean squared error of `img` against `reference` where both hold colour, after the one
    /// global scale that fits best (levelling cannot know the true exposure, only make the
    /// views agree).
    fn mse_up_to_scale(img: &Image<Rgba>, reference: &Image<Rgba>) -> f64 {
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
    }

    #[test]
    fn levelling_takes_out_a_views_exposure() {
        // Every other view 40 % too bright (an exposure the photographer got wrong).
        let (_, truth) = baked(8, |_, _, c| c);
        let (enc, bright) = baked(8, |v, _, c| if v % 2 == 0 { c * 1.4 } else { c });
        // Unlevelled: each face's texels as its view's master holds them.
        let mut raw = bright.image.clone();
        for (i, t) in raw.pixels_mut().iter_mut().enumerate() {
            let f = enc.atlas.face[i];
            if let Some(v) = bright.choice.get(f as usize).copied().flatten() {
                let m = enc.masters[v].pixels()[i];
                if m.w > 0.0 {
                    *t = m;
                }
            }
        }
        let (raw, levelled) = (
            mse_up_to_scale(&raw, &truth.image),
            mse_up_to_scale(&bright.image, &truth.image),
        );
        println!("unlevelled {raw:.5}, levelled {levelled:.5} (mean squared error up to scale)");
        assert!(levelled < raw * 0.5, "{levelled} vs {raw}");
        let r = &bright.report;
        assert!(r.seams.step_levelled < r.seams.step_gains, "{r:?}");
    }

    #[test]
    fn seam_levelling_halves_the_step_that_gains_leave() {
        // Each view's exposure falls off from its image's left to its right (a gradient no one
        // gain a view can take out), by a different amount a view.
        let (_, b) = baked(8, |v, (x, _), c| {
            c * (1.3 - (0.1 + 0.08 * v as f32) * x as f32 / 160.0)
        });
        let r = &b.report;
        println!("{}", r.told(b.choice.len()));
        assert!(r.seams.edges > 100, "{r:?}");
        assert!(r.seams.step_levelled < 0.5 * r.seams.step_gains, "{r:?}");
    }

    #[test]
    fn a_view_with_something_in_front_is_left_out_of_the_faces_it_hides() {
        // A red square passes in front of view 3 (a person walking through the capture).
        let red = Vec3::new(0.9, 0.02, 0.02);
        let inside = |(x, y): (u32, u32)| (50..110).contains(&x) && (30..90).contains(&y);
        let (enc, b) = baked(8, |v, xy, c| if v == 3 && inside(xy) { red } else { c });
        let is_red = |t: &Vec4| t.w > 0.0 && (t.truncate() - red).length() < 0.1;
        let in_view = enc.masters[3].pixels().iter().filter(|t| is_red(t)).count();
        let in_bake = b.image.pixels().iter().filter(|t| is_red(t)).count();
        println!(
            "{} looks left out; red texels: {in_view} in view 3's master, {in_bake} in the bake",
            b.report.seams.outliers
        );
        assert!(in_view > 1000, "{in_view}");
        assert!(b.report.seams.outliers > 0);
        assert!(in_bake * 50 < in_view, "{in_bake} of {in_view}");
    }

    #[test]
    fn texels_no_view_sees_are_filled_from_the_seen_faces() {
        // Two views see the Duck from one side only.
        let (enc, b) = baked(2, |_, _, c| c);
        let r = &b.report;
        println!("{}", r.told(b.choice.len()));
        assert!(r.filled > 1000 && r.empty == 0, "{r:?}");
        let faces = enc.atlas.face.iter().zip(b.image.pixels());
        assert!(
            faces
                .filter(|(f, _)| **f != u32::MAX)
                .all(|(_, t)| t.w > 0.0)
        );
    }
}
