//! Image layers ("Layered view-dependent projective textures" §4.2; docs/conventions.md §9.3):
//! each visibility layer projected into its view, its objects clustered by the power-of-two
//! rule, each cluster a rectangle of the photograph holding its objects' pixels.
//!
//! Invariants: a layer's texel is the photograph's pixel where one of its items is the nearest
//! surface there, transparent where its items are hidden (what an artist, or
//! [`super::fill`], fills) and outside their footprint; stacked front layer on top, with the
//! background layer at the bottom, the layers composite back to the photograph exactly;
//! clustering is deterministic (greedy, largest saving first, ties to the lowest indices).

use super::abuffer::ABuffer;
use super::order::{ItemIndex, Ordered};
use crate::frame::{FrameError, Image, Rgba};
use glam::Vec4;
use serde::{Deserialize, Serialize};

/// A rectangle of pixels, rows top-down.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Rect {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width.
    pub w: u32,
    /// Height.
    pub h: u32,
}

impl Rect {
    /// The smallest rectangle holding both.
    pub fn union(self, o: Rect) -> Rect {
        let (x0, y0) = (self.x.min(o.x), self.y.min(o.y));
        let (x1, y1) = (
            (self.x + self.w).max(o.x + o.w),
            (self.y + self.h).max(o.y + o.h),
        );
        Rect {
            x: x0,
            y: y0,
            w: x1 - x0,
            h: y1 - y0,
        }
    }

    /// Texels of the power-of-two texture that holds it: `P2(w)·P2(h)`.
    pub fn p2_area(self) -> u64 {
        p2(self.w) * p2(self.h)
    }

    /// Whether pixel `(x, y)` lies inside.
    pub fn contains(self, x: u32, y: u32) -> bool {
        x >= self.x && y >= self.y && x < self.x + self.w && y < self.y + self.h
    }
}

/// The smallest power of two ≥ `x` (the paper writes "> x"; with ≥, 64 stays 64).
pub fn p2(x: u32) -> u64 {
    (x.max(1) as u64).next_power_of_two()
}

/// Clusters rectangles by the power-of-two rule: `c₁` and `c₂` merge when
/// `A(c₁ ∪ c₂) < A(c₁) + A(c₂)`, the pair with the largest saving first. Returns the clusters
/// as lists of input indices, each sorted, in order of their first index.
pub fn cluster(rects: &[Rect]) -> Vec<Vec<usize>> {
    let mut clusters: Vec<(Rect, Vec<usize>)> = rects
        .iter()
        .enumerate()
        .map(|(i, &r)| (r, vec![i]))
        .collect();
    loop {
        let mut best: Option<(u64, usize, usize)> = None;
        for i in 0..clusters.len() {
            for j in i + 1..clusters.len() {
                let (a, b) = (clusters[i].0, clusters[j].0);
                let (sum, merged) = (a.p2_area() + b.p2_area(), a.union(b).p2_area());
                if merged < sum {
                    let saving = sum - merged;
                    if best.is_none_or(|(s, _, _)| saving > s) {
                        best = Some((saving, i, j));
                    }
                }
            }
        }
        let Some((_, i, j)) = best else { break };
        let (rj, mut members) = clusters.remove(j);
        clusters[i].0 = clusters[i].0.union(rj);
        clusters[i].1.append(&mut members);
        clusters[i].1.sort_unstable();
    }
    let mut out: Vec<Vec<usize>> = clusters.into_iter().map(|c| c.1).collect();
    out.sort_by_key(|c| c[0]);
    out
}

/// One image layer of a view.
#[derive(Clone, Debug)]
pub struct ImageLayer {
    /// Its name in the editable file (unique in the view).
    pub name: String,
    /// The visibility layer it comes from (0 = front).
    pub visibility: u32,
    /// Where it sits in the photograph.
    pub rect: Rect,
    /// The objects it holds (whole, or some of their triangles).
    pub objects: Vec<u32>,
    /// Its texels, `rect`-sized, linear RGBA; alpha 0 where unknown.
    pub image: Image<Rgba>,
}

/// A view's image layers and what is derived from its geometry (never stored: recomputed from
/// the meshes and the camera when a project is loaded).
#[derive(Clone, Debug)]
pub struct ViewLayers {
    /// Image layers, front visibility layer first.
    pub layers: Vec<ImageLayer>,
    /// The photograph where no item is (the bottom of the stack).
    pub background: Image<Rgba>,
    /// Per layer, `rect`-sized: the nearest `gd` of its items at each texel (0 outside their
    /// footprint) — where a layer's own surfaces are, so an object's far side is not textured
    /// by its near side.
    pub depth: Vec<Image<f32>>,
    /// Per object, which image layer textures it.
    pub assignment: Vec<Assignment>,
    /// Texture memory of this view, three ways.
    pub memory: Memory,
}

/// Which image layer textures an object in one view.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Assignment {
    /// The view does not see it.
    Unseen,
    /// All of it: this layer.
    Whole(u32),
    /// Triangle by triangle (an object the ordering opened).
    Triangles(Vec<Option<u32>>),
}

impl Assignment {
    /// The layer of triangle `t`.
    pub fn layer(&self, t: usize) -> Option<u32> {
        match self {
            Assignment::Unseen => None,
            Assignment::Whole(l) => Some(*l),
            Assignment::Triangles(v) => v.get(t).copied().flatten(),
        }
    }
}

/// Texture memory, bytes at 4 bytes a texel in power-of-two textures.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Memory {
    /// The clustered image layers.
    pub layers: u64,
    /// One texture an object a visibility layer (no clustering).
    pub unclustered: u64,
    /// One texture a seen triangle (per-polygon texture extraction).
    pub per_triangle: u64,
    /// The background layer.
    pub background: u64,
}

/// Image layers of a view from its ordering and photograph; `names` names the objects;
/// `clustering` off keeps one layer an object a visibility layer.
pub fn image_layers(
    ordered: &Ordered,
    index: &ItemIndex,
    triangle_counts: &[usize],
    photo: &Image<Rgba>,
    names: &[String],
    clustering: bool,
) -> Result<ViewLayers, FrameError> {
    let ab = &ordered.abuffer;
    let (w, h) = ab.size();
    // Groups: (visibility layer, object), in that order.
    let mut keys: Vec<(u32, u32)> = ordered
        .items
        .iter()
        .zip(&ordered.layer_of)
        .filter_map(|(it, l)| l.map(|l| (l, it.object())))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    let group_of_item: Vec<Option<usize>> = ordered
        .items
        .iter()
        .zip(&ordered.layer_of)
        .map(|(it, l)| l.and_then(|l| keys.binary_search(&(l, it.object())).ok()))
        .collect();
    let bboxes = group_boxes(ab, &group_of_item, keys.len());
    // Cluster each visibility layer's groups.
    let mut layer_of_group = vec![0u32; keys.len()];
    let mut layers = Vec::new();
    let mut start = 0;
    while start < keys.len() {
        let vis = keys[start].0;
        let end = start + keys[start..].iter().take_while(|k| k.0 == vis).count();
        let rects: Vec<Rect> = bboxes[start..end].to_vec();
        let clusters = if clustering {
            cluster(&rects)
        } else {
            (0..rects.len()).map(|i| vec![i]).collect()
        };
        for (m, members) in clusters.iter().enumerate() {
            let rect = members
                .iter()
                .map(|&i| rects[i])
                .reduce(Rect::union)
                .expect("a cluster has a member");
            let objects: Vec<u32> = members.iter().map(|&i| keys[start + i].1).collect();
            for &i in members {
                layer_of_group[start + i] = layers.len() as u32;
            }
            layers.push(ImageLayer {
                name: layer_name(vis, m, &objects, names),
                visibility: vis,
                rect,
                objects,
                image: Image::new(rect.w, rect.h, Vec4::ZERO)?,
            });
        }
        start = end;
    }
    let mut depth: Vec<Image<f32>> = layers
        .iter()
        .map(|l| Image::new(l.rect.w, l.rect.h, 0.0f32))
        .collect::<Result<_, _>>()?;
    let mut background = Image::new(w, h, Vec4::ZERO)?;
    for p in 0..ab.pixel_count() {
        let (x, y) = ((p % w as usize) as u32, (p / w as usize) as u32);
        let entries = ab.at(p);
        if entries.is_empty() {
            background.set(x, y, photo.get(x, y).truncate().extend(1.0));
            continue;
        }
        for (j, e) in entries.iter().enumerate() {
            let Some(g) = group_of_item[e.item as usize] else {
                continue;
            };
            let l = layer_of_group[g] as usize;
            let r = layers[l].rect;
            let (lx, ly) = (x - r.x, y - r.y);
            if e.gd > depth[l].get(lx, ly) {
                depth[l].set(lx, ly, e.gd);
            }
            if j == 0 {
                layers[l]
                    .image
                    .set(lx, ly, photo.get(x, y).truncate().extend(1.0));
            }
        }
    }
    let assignment = triangle_counts
        .iter()
        .enumerate()
        .map(|(o, &n)| {
            let layer = |t: u32| {
                index
                    .item_of(o as u32, t)
                    .and_then(|i| group_of_item[i as usize])
                    .map(|g| layer_of_group[g])
            };
            if index.is_opened(o as u32) {
                Assignment::Triangles((0..n as u32).map(layer).collect())
            } else {
                layer(0).map_or(Assignment::Unseen, Assignment::Whole)
            }
        })
        .collect();
    let memory = Memory {
        layers: layers.iter().map(|l| l.rect.p2_area() * 4).sum(),
        unclustered: bboxes.iter().map(|r| r.p2_area() * 4).sum(),
        per_triangle: 0,
        background: Rect { x: 0, y: 0, w, h }.p2_area() * 4,
    };
    Ok(ViewLayers {
        layers,
        background,
        depth,
        assignment,
        memory,
    })
}

/// The bounding box of each group's footprint.
fn group_boxes(ab: &ABuffer, group_of_item: &[Option<usize>], groups: usize) -> Vec<Rect> {
    let w = ab.size().0 as usize;
    let mut lo = vec![(u32::MAX, u32::MAX); groups];
    let mut hi = vec![(0u32, 0u32); groups];
    for p in 0..ab.pixel_count() {
        let (x, y) = ((p % w) as u32, (p / w) as u32);
        for e in ab.at(p) {
            if let Some(g) = group_of_item[e.item as usize] {
                lo[g] = (lo[g].0.min(x), lo[g].1.min(y));
                hi[g] = (hi[g].0.max(x), hi[g].1.max(y));
            }
        }
    }
    lo.iter()
        .zip(&hi)
        .map(|(&(x0, y0), &(x1, y1))| Rect {
            x: x0,
            y: y0,
            w: x1 + 1 - x0,
            h: y1 + 1 - y0,
        })
        .collect()
}

/// `L02.03 duck+bunny`: visibility layer 2, its third image layer, the objects it holds.
fn layer_name(vis: u32, m: usize, objects: &[u32], names: &[String]) -> String {
    let mut list: Vec<&str> = objects
        .iter()
        .take(3)
        .map(|&o| names.get(o as usize).map_or("?", String::as_str))
        .collect();
    if objects.len() > 3 {
        list.push("…");
    }
    format!("L{:02}.{:02} {}", vis + 1, m + 1, list.join("+"))
}

/// Texture memory of per-polygon extraction: one power-of-two texture for the bounding box of
/// each triangle the view shows (`item` is the view's item buffer).
pub fn per_triangle_memory(item: &Image<crate::raster::ItemId>) -> u64 {
    use std::collections::HashMap;
    let (w, _) = item.size();
    let mut boxes: HashMap<(u32, u32), (u32, u32, u32, u32)> = HashMap::new();
    for (p, id) in item.pixels().iter().enumerate() {
        if id.is_none() {
            continue;
        }
        let (x, y) = ((p % w as usize) as u32, (p / w as usize) as u32);
        let b = boxes
            .entry((id.object, id.triangle))
            .or_insert((x, y, x, y));
        *b = (b.0.min(x), b.1.min(y), b.2.max(x), b.3.max(y));
    }
    boxes
        .values()
        .map(|&(x0, y0, x1, y1)| p2(x1 + 1 - x0) * p2(y1 + 1 - y0) * 4)
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn p2_keeps_powers_of_two() {
        assert_eq!(p2(64), 64);
        assert_eq!(p2(65), 128);
        assert_eq!(p2(1), 1);
        assert_eq!(p2(0), 1);
    }

    #[test]
    fn near_rectangles_merge_far_ones_do_not_and_the_result_is_deterministic() {
        let r = |x, y, w, h| Rect { x, y, w, h };
        // Side by side, two 30 × 30 boxes need 64 × 32 together: no saving over 2 × 32 × 32.
        let rects = [r(0, 0, 30, 30), r(32, 0, 30, 30), r(500, 500, 10, 10)];
        let c = cluster(&rects);
        assert_eq!(c, vec![vec![0], vec![1], vec![2]]);
        // 17 × 17 boxes (32 × 32 each) overlapping: the union 20 × 20 fits 32 × 32.
        let rects = [r(0, 0, 17, 17), r(3, 3, 17, 17), r(400, 0, 5, 5)];
        assert_eq!(cluster(&rects), vec![vec![0, 1], vec![2]]);
        assert_eq!(cluster(&rects), cluster(&rects));
    }
}
