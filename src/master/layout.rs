//! The packing map of Master Texture Space (paper 5 §3; docs/conventions.md §6.2–6.4): one
//! common shape per face (its corner nearest a right angle and the largest its two edges from
//! there have in any view), every face warped to a `w × h` right triangle, faces paired two to
//! a box — the second turned 180° into the opposite corner, a gutter between their
//! hypotenuses — and the boxes packed largest first at the topmost, then leftmost place that
//! fits. The same map serves every view, which is what makes the master textures
//! pixel-aligned.
//!
//! Invariants: a face's corners keep the mesh's cyclic order (its chosen corner `c` at the right
//! angle, `c + 1` along `+x`, `c + 2` along `+y` in its slot's frame, indices mod 3), whatever
//! the view; boxes never overlap; every texel the encoder writes for a face lies in its own box,
//! at most [`DILATION`] texels outside its triangle, and the two faces of a box are at least
//! [`GUTTER`] texels apart, so bilinear filtering never mixes two faces.

use glam::DVec2;
use serde::{Deserialize, Serialize};

/// Texels a face's region extends beyond its triangle (its gutter ring, filled by the encoder
/// with the surface just beyond the edge, so bilinear lookups at the edge read the face itself).
pub const DILATION: f64 = 1.0;
/// Least distance, texels, between the hypotenuses of two paired faces: their dilated regions
/// stay a texel apart.
pub const GUTTER: f64 = 2.0 * DILATION + 1.0;
/// Largest side of a face's triangle, texels (a face seen larger is sampled at this size).
pub const MAX_FACE_SIDE: u32 = 512;

/// How one face is warped to its right triangle: which of its corners takes the right angle,
/// and the legs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FaceShape {
    /// The mesh corner (0, 1 or 2) at the right angle; the next one (cyclically) lies along the
    /// first leg, the one after along the second.
    pub corner: u8,
    /// The legs `[w, h]`, texels.
    pub legs: [u32; 2],
}

/// Where one face lives in the atlas.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FacePlace {
    /// Its box: left, top, width, height, texels (the border of [`DILATION`] included).
    pub bbox: [u32; 4],
    /// Slot `A` (right angle at the box's top-left, unrotated) or `B` (right angle at the
    /// bottom-right, turned 180°).
    pub slot_b: bool,
    /// The mesh corner (0, 1 or 2) at the right angle ([`FaceShape::corner`]); 0 when absent
    /// from a stored map, the paper's warp.
    #[serde(default)]
    pub corner: u8,
    /// The right triangle's legs, texels.
    pub size: [u32; 2],
}

impl FacePlace {
    /// The face's shape.
    pub fn shape(&self) -> FaceShape {
        FaceShape {
            corner: self.corner,
            legs: self.size,
        }
    }

    /// The leg fractions `(l1, l2)` of the surface point with mesh barycentrics `(b1, b2)` of
    /// corners 1 and 2: the weights of the corners along the first and second leg.
    fn legs_of(&self, b1: f64, b2: f64) -> (f64, f64) {
        let b = [1.0 - b1 - b2, b1, b2];
        let c = usize::from(self.corner % 3);
        (b[(c + 1) % 3], b[(c + 2) % 3])
    }

    /// Mesh barycentrics `(b1, b2)` of corners 1 and 2 of the point with leg fractions
    /// `(l1, l2)`.
    fn barycentrics_of(&self, l1: f64, l2: f64) -> (f64, f64) {
        let c = usize::from(self.corner % 3);
        let mut b = [0.0; 3];
        b[c] = 1.0 - l1 - l2;
        b[(c + 1) % 3] = l1;
        b[(c + 2) % 3] = l2;
        (b[1], b[2])
    }

    /// The right angle's corner and the two leg directions, in atlas texel coordinates.
    fn frame(&self) -> (DVec2, DVec2, DVec2) {
        let [x, y, w, h] = self.bbox.map(|v| v as f64);
        if self.slot_b {
            (
                DVec2::new(x + w - DILATION, y + h - DILATION),
                DVec2::new(-1.0, 0.0),
                DVec2::new(0.0, -1.0),
            )
        } else {
            (DVec2::new(x + DILATION, y + DILATION), DVec2::X, DVec2::Y)
        }
    }

    /// Atlas texel coordinates of the face's surface point with barycentrics `(b1, b2)` of
    /// corners 1 and 2.
    pub fn at(&self, b1: f64, b2: f64) -> DVec2 {
        let (o, ex, ey) = self.frame();
        let (l1, l2) = self.legs_of(b1, b2);
        o + ex * (l1 * self.size[0] as f64) + ey * (l2 * self.size[1] as f64)
    }

    /// Barycentrics `(b1, b2)` of corners 1 and 2 at atlas coordinates `p` (extrapolated
    /// outside the triangle).
    pub fn barycentrics(&self, p: DVec2) -> (f64, f64) {
        let (l1, l2) = self.leg_fractions(p);
        self.barycentrics_of(l1, l2)
    }

    /// The leg fractions of atlas point `p`: its offset from the right angle along each leg,
    /// over the leg's length.
    fn leg_fractions(&self, p: DVec2) -> (f64, f64) {
        let (o, ex, ey) = self.frame();
        let d = p - o;
        (
            d.dot(ex) / self.size[0] as f64,
            d.dot(ey) / self.size[1] as f64,
        )
    }

    /// Whether atlas point `p` is within [`DILATION`] texels of the face's triangle.
    pub fn holds(&self, p: DVec2) -> bool {
        let (l1, l2) = self.leg_fractions(p);
        let (w, h) = (self.size[0] as f64, self.size[1] as f64);
        let (x, y) = (l1 * w, l2 * h);
        let hyp = (l1 + l2 - 1.0) / (1.0 / (w * w) + 1.0 / (h * h)).sqrt();
        x >= -DILATION && y >= -DILATION && hyp <= DILATION
    }
}

/// The packing map: every face's place, and the atlas size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Layout {
    /// Atlas width, texels.
    pub width: u32,
    /// Atlas height, texels.
    pub height: u32,
    /// Per face, in mesh order.
    pub faces: Vec<FacePlace>,
}

/// The box holding faces `a` and `b` (legs `(w, h)` each), `b` turned into the far corner with
/// its hypotenuse at least [`GUTTER`] texels from `a`'s; sizes without the border.
pub fn pair_box(a: [u32; 2], b: [u32; 2]) -> [u32; 2] {
    let (wa, ha) = (a[0].max(1) as f64, a[1].max(1) as f64);
    let (wb, hb) = (b[0].max(1) as f64, b[1].max(1) as f64);
    let norm = (1.0 / (wa * wa) + 1.0 / (ha * ha)).sqrt();
    let clear = |w: f64, h: f64| {
        // B's corners in the box: (W, H), (W − w_b, H), (W, H − h_b); each GUTTER beyond A's
        // hypotenuse x/w_a + y/h_a = 1.
        [(w, h), (w - wb, h), (w, h - hb)]
            .iter()
            .all(|&(x, y)| (x / wa + y / ha - 1.0) / norm >= GUTTER)
    };
    let (mut w, mut h) = (wa.max(wb), ha.max(hb));
    while !clear(w, h) {
        // Grow the side that is shorter for A's triangle.
        if w / wa <= h / ha {
            w += 1.0;
        } else {
            h += 1.0;
        }
    }
    [w as u32, h as u32]
}

impl Layout {
    /// The layout of faces of shapes `shapes` (mesh order): paired by their legs, packed
    /// largest first.
    pub fn new(shapes: &[FaceShape]) -> Layout {
        let sizes: Vec<[u32; 2]> = shapes.iter().map(|s| s.legs).collect();
        let border = 2 * DILATION as u32;
        // Pairs of consecutive faces by their legs, first then second, descending (ties by
        // index: deterministic): faces of like shape share a box. (The paper pairs by area,
        // which puts thin triangles beside wide ones: 39 % more box texels on the teapot seen
        // from 6 radii, docs/master.md.)
        let mut order: Vec<usize> = (0..sizes.len()).collect();
        order.sort_by(|&i, &j| sizes[j].cmp(&sizes[i]).then(i.cmp(&j)));
        struct Group {
            a: usize,
            b: Option<usize>,
            size: [u32; 2],
        }
        let mut groups: Vec<Group> = order
            .chunks(2)
            .map(|c| match *c {
                [a, b] => {
                    let inner = pair_box(sizes[a], sizes[b]);
                    Group {
                        a,
                        b: Some(b),
                        size: [inner[0] + border, inner[1] + border],
                    }
                }
                [a] => Group {
                    a,
                    b: None,
                    size: [sizes[a][0] + border, sizes[a][1] + border],
                },
                _ => unreachable!("chunks of two"),
            })
            .collect();
        groups.sort_by(|g, k| {
            let area = |x: &Group| x.size[0] as u64 * x.size[1] as u64;
            area(k).cmp(&area(g)).then(g.a.cmp(&k.a))
        });
        let total: f64 = groups
            .iter()
            .map(|g| g.size[0] as f64 * g.size[1] as f64)
            .sum();
        let widest = groups.iter().map(|g| g.size[0]).max().unwrap_or(1);
        // Sides in multiples of 4, so that the atlas block-compresses as it is.
        let width = widest
            .max((1.1 * total).sqrt().ceil() as u32)
            .max(1)
            .next_multiple_of(4);
        let mut sky = Skyline::new(width);
        let mut faces = vec![
            FacePlace {
                bbox: [0; 4],
                slot_b: false,
                corner: 0,
                size: [1, 1],
            };
            sizes.len()
        ];
        for g in &groups {
            let (x, y) = sky.place(g.size[0], g.size[1]);
            let bbox = [x, y, g.size[0], g.size[1]];
            faces[g.a] = FacePlace {
                bbox,
                slot_b: false,
                corner: shapes[g.a].corner,
                size: sizes[g.a],
            };
            if let Some(b) = g.b {
                faces[b] = FacePlace {
                    bbox,
                    slot_b: true,
                    corner: shapes[b].corner,
                    size: sizes[b],
                };
            }
        }
        Layout {
            width,
            height: sky.height().max(1).next_multiple_of(4),
            faces,
        }
    }

    /// Texture coordinates of every face's corners, `[0, 1]²` with `(0, 0)` the atlas's
    /// top-left (trompe's convention; glTF's too): 3 a face, in corner order.
    pub fn uvs(&self) -> Vec<[f32; 2]> {
        let (w, h) = (self.width as f64, self.height as f64);
        self.faces
            .iter()
            .flat_map(|f| {
                [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)].map(|(b1, b2)| {
                    let p = f.at(b1, b2);
                    [(p.x / w) as f32, (p.y / h) as f32]
                })
            })
            .collect()
    }
}

/// The skyline of a first-fit packer: for each column run, the lowest free row.
struct Skyline {
    width: u32,
    /// Segments `(x, width, top)`, left to right, covering `[0, width)`.
    segments: Vec<(u32, u32, u32)>,
}

impl Skyline {
    fn new(width: u32) -> Self {
        Skyline {
            width,
            segments: vec![(0, width, 0)],
        }
    }

    /// Places a `w × h` box at the topmost, then leftmost position over the skyline.
    fn place(&mut self, w: u32, h: u32) -> (u32, u32) {
        let w = w.min(self.width);
        let mut best: Option<(u32, u32, usize)> = None;
        for i in 0..self.segments.len() {
            let x = self.segments[i].0;
            if x + w > self.width {
                break;
            }
            // The top of the box: the highest segment it spans.
            let mut top = 0;
            let mut j = i;
            while j < self.segments.len() && self.segments[j].0 < x + w {
                top = top.max(self.segments[j].2);
                j += 1;
            }
            if best.is_none_or(|(by, bx, _)| (top, x) < (by, bx)) {
                best = Some((top, x, i));
            }
        }
        let (y, x, _) = best.unwrap_or((0, 0, 0));
        // Raise the skyline over [x, x + w) to y + h.
        let mut next = Vec::with_capacity(self.segments.len() + 2);
        for &(sx, sw, st) in &self.segments {
            let end = sx + sw;
            if end <= x || sx >= x + w {
                next.push((sx, sw, st));
                continue;
            }
            if sx < x {
                next.push((sx, x - sx, st));
            }
            if end > x + w {
                next.push((x + w, end - (x + w), st));
            }
        }
        next.push((x, w, y + h));
        next.sort_by_key(|s| s.0);
        // Merge neighbours at the same height.
        let mut merged: Vec<(u32, u32, u32)> = Vec::with_capacity(next.len());
        for s in next {
            match merged.last_mut() {
                Some(m) if m.2 == s.2 && m.0 + m.1 == s.0 => m.1 += s.1,
                _ => merged.push(s),
            }
        }
        self.segments = merged;
        (x, y)
    }

    fn height(&self) -> u32 {
        self.segments.iter().map(|s| s.2).max().unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` faces of pseudo-random legs, their right angles at corners 0, 1, 2 in turn.
    fn sizes(n: usize) -> Vec<FaceShape> {
        let mut seed = 11u64;
        (0..n)
            .map(|i| {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                FaceShape {
                    corner: (i % 3) as u8,
                    legs: [2 + (seed >> 59) as u32 * 3, 2 + ((seed >> 40) & 31) as u32],
                }
            })
            .collect()
    }

    #[test]
    fn the_chosen_corner_takes_the_right_angle_and_the_order_stays_cyclic() {
        for slot_b in [false, true] {
            for corner in 0..3u8 {
                let place = FacePlace {
                    bbox: [10, 20, 14, 9],
                    slot_b,
                    corner,
                    size: [8, 5],
                };
                // Mesh corners 0, 1, 2 as barycentrics (b1, b2).
                let at = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)].map(|(b1, b2)| place.at(b1, b2));
                let c = usize::from(corner);
                let (o, e1, e2) = (at[c], at[(c + 1) % 3] - at[c], at[(c + 2) % 3] - at[c]);
                let (right_angle, _, _) = place.frame();
                assert_eq!(o, right_angle, "corner {corner}");
                assert_eq!((e1.length(), e2.length()), (8.0, 5.0), "corner {corner}");
                assert_eq!(e1.dot(e2), 0.0, "corner {corner}");
                // There and back, inside and outside the triangle.
                for (b1, b2) in [(0.2, 0.3), (0.7, 0.1), (-0.1, 0.5), (0.6, 0.6)] {
                    let back = place.barycentrics(place.at(b1, b2));
                    assert!((back.0 - b1).abs() < 1e-12 && (back.1 - b2).abs() < 1e-12);
                }
                // The centroid is held, a point beyond the hypotenuse is not.
                assert!(place.holds(place.at(1.0 / 3.0, 1.0 / 3.0)));
                let outward = (e1 / e1.length_squared() + e2 / e2.length_squared()).normalize();
                let beyond = o + (e1 + e2) * 0.5 + outward * (DILATION + 0.5);
                assert!(!place.holds(beyond), "corner {corner}");
            }
        }
    }

    #[test]
    fn boxes_never_overlap_and_stay_inside_the_atlas() {
        let l = Layout::new(&sizes(301));
        let mut owner = vec![u32::MAX; (l.width * l.height) as usize];
        let mut seen = std::collections::HashSet::new();
        for (i, f) in l.faces.iter().enumerate() {
            let [x, y, w, h] = f.bbox;
            assert!(x + w <= l.width && y + h <= l.height, "face {i}");
            if !seen.insert(f.bbox) {
                continue; // the pair's second face
            }
            for yy in y..y + h {
                for xx in x..x + w {
                    let o = &mut owner[(yy * l.width + xx) as usize];
                    assert_eq!(*o, u32::MAX, "boxes of faces overlap at {xx},{yy}");
                    *o = i as u32;
                }
            }
        }
        // Reasonably tight: the boxes fill most of the atlas.
        let used = owner.iter().filter(|&&o| o != u32::MAX).count() as f64;
        assert!(
            used / owner.len() as f64 > 0.6,
            "{}",
            used / owner.len() as f64
        );
    }

    #[test]
    fn paired_faces_keep_their_gutter_and_their_texels_stay_apart() {
        let s = sizes(120);
        let l = Layout::new(&s);
        for (i, f) in l.faces.iter().enumerate() {
            // Corners land where the UVs say, inside the box.
            let [x, y, w, h] = f.bbox.map(|v| v as f64);
            for (b1, b2) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)] {
                let p = f.at(b1, b2);
                assert!(
                    p.x >= x && p.y >= y && p.x <= x + w && p.y <= y + h,
                    "face {i}"
                );
                let back = f.barycentrics(p);
                assert!((back.0 - b1).abs() < 1e-12 && (back.1 - b2).abs() < 1e-12);
            }
        }
        // No texel centre is held by two faces.
        for (i, f) in l.faces.iter().enumerate() {
            let Some((j, g)) = l
                .faces
                .iter()
                .enumerate()
                .find(|(j, g)| *j != i && g.bbox == f.bbox)
            else {
                continue;
            };
            let [x, y, w, h] = f.bbox;
            for yy in y..y + h {
                for xx in x..x + w {
                    let p = crate::frame::pixel_centre(xx as f64, yy as f64);
                    assert!(!(f.holds(p) && g.holds(p)), "faces {i} and {j} share {p}");
                }
            }
        }
        // The gutter: equal sizes need more than the bare rectangle.
        let b = pair_box([10, 10], [10, 10]);
        assert!(
            b[0] + b[1] >= 20 + (GUTTER * 2f64.sqrt()).floor() as u32,
            "{b:?}"
        );
    }
}

/// Where an atlas's texels go (paper 5 §3's sizing, warp, pairing and packing, each as the
/// share it adds): the faces' surface as their largest views show it, the right triangles they
/// are warped to, the boxes that pair them with gutters and borders, and the packed atlas.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct TexelBudget {
    /// Texels of the faces' surface: each face's largest projected area in any view, times the
    /// scale squared — what no layout can do without.
    pub surface: f64,
    /// Texels of the right triangles the faces are warped to (half their legs' product).
    pub triangles: f64,
    /// Texels of the boxes that pair them, gutters and borders included.
    pub boxes: f64,
    /// Texels of the atlas.
    pub atlas: f64,
}

impl TexelBudget {
    /// The budget of `layout`, whose faces' surface is `surface` texels.
    pub fn of(layout: &Layout, surface: f64) -> TexelBudget {
        let triangles = layout
            .faces
            .iter()
            .map(|f| f.size[0] as f64 * f.size[1] as f64 * 0.5)
            .sum();
        let mut boxes: Vec<[u32; 4]> = layout.faces.iter().map(|f| f.bbox).collect();
        boxes.sort_unstable();
        boxes.dedup();
        TexelBudget {
            surface,
            triangles,
            boxes: boxes.iter().map(|b| b[2] as f64 * b[3] as f64).sum(),
            atlas: layout.width as f64 * layout.height as f64,
        }
    }
}

/// "surface S texels; warped to right triangles × a, paired in boxes × b, packed × c: the atlas
/// is × d the surface".
impl std::fmt::Display for TexelBudget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let r = |a: f64, b: f64| a / b.max(1.0);
        write!(
            f,
            "the faces' surface at their largest views {:.0} texels; warped to right triangles \
             × {:.2}, paired in boxes with gutters × {:.2}, packed × {:.2}: the atlas is × {:.2} \
             the surface",
            self.surface,
            r(self.triangles, self.surface),
            r(self.boxes, self.triangles),
            r(self.atlas, self.boxes),
            r(self.atlas, self.surface)
        )
    }
}
