//! The A-buffer of one view: per pixel, every item that covers it with its nearest depth,
//! nearest first — what the item-buffer passes of "Layered view-dependent projective textures"
//! §4.1 read, here held once so that every pass is a walk over it.
//!
//! Invariants: a pixel lists each item once (its nearest fragment: a closed mesh overlapping
//! itself counts once, docs/conventions.md §9.1); entries are sorted by decreasing `gd` (nearest
//! first), ties by item index, so every pass is deterministic for any thread count.

use crate::raster::{Covered, ItemId};
use rayon::prelude::*;

/// One item at one pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entry {
    /// The item's index.
    pub item: u32,
    /// Its nearest generalized depth there (`1/z`: larger is nearer).
    pub gd: f32,
}

/// Per pixel, the items covering it, nearest first.
#[derive(Clone, Debug)]
pub struct ABuffer {
    width: u32,
    height: u32,
    /// `entries[offsets[p] .. offsets[p + 1]]` are pixel `p`'s.
    offsets: Vec<u32>,
    entries: Vec<Entry>,
}

impl ABuffer {
    /// Groups fragments (in bands of rows, as [`crate::raster::fragments`] gives them) into
    /// items: `item_of` names a fragment's item, or `None` to leave it out.
    pub fn build(
        (width, height): (u32, u32),
        bands: &[Vec<Covered>],
        item_of: &(dyn Fn(ItemId) -> Option<u32> + Sync),
    ) -> ABuffer {
        let sorted: Vec<Vec<(u32, Entry)>> = bands
            .par_iter()
            .map(|band| {
                let mut v: Vec<(u32, Entry)> = band
                    .iter()
                    .filter_map(|c| item_of(c.item).map(|item| (c.pixel, Entry { item, gd: c.gd })))
                    .collect();
                // By pixel, then item, nearest first: the first of each (pixel, item) run is
                // that item's nearest fragment there. gd > 0, so its bits order as its value.
                v.sort_unstable_by_key(|(p, e)| {
                    ((*p as u64) << 32 | e.item as u64, !e.gd.to_bits())
                });
                v.dedup_by_key(|(p, e)| (*p, e.item));
                // Then nearest first within each pixel.
                let mut start = 0;
                while start < v.len() {
                    let p = v[start].0;
                    let end = start + v[start..].iter().take_while(|x| x.0 == p).count();
                    v[start..end]
                        .sort_by(|a, b| b.1.gd.total_cmp(&a.1.gd).then(a.1.item.cmp(&b.1.item)));
                    start = end;
                }
                v
            })
            .collect();
        let pixels = width as usize * height as usize;
        let mut offsets = vec![0u32; pixels + 1];
        let mut entries = Vec::with_capacity(sorted.iter().map(Vec::len).sum());
        for band in &sorted {
            for &(p, e) in band {
                offsets[p as usize + 1] += 1;
                entries.push(e);
            }
        }
        for p in 0..pixels {
            offsets[p + 1] += offsets[p];
        }
        ABuffer {
            width,
            height,
            offsets,
            entries,
        }
    }

    /// Image size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Pixel `p`'s entries, nearest first.
    pub fn at(&self, p: usize) -> &[Entry] {
        &self.entries[self.offsets[p] as usize..self.offsets[p + 1] as usize]
    }

    /// Number of pixels.
    pub fn pixel_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Number of (pixel, item) entries.
    pub fn entry_count(&self) -> usize {
        self.entries.len()
    }

    /// Pixel ranges of about equal work, for parallel passes.
    pub fn chunks(&self) -> Vec<std::ops::Range<usize>> {
        let n = self.pixel_count();
        let step = 4096;
        (0..n.div_ceil(step))
            .map(|i| i * step..((i + 1) * step).min(n))
            .collect()
    }
}

/// Whether a surface at `front` hides one at `back` (both `gd`): nearer by more than the
/// relative depth `tolerance` — touching and coplanar surfaces do not hide each other
/// (docs/conventions.md §9.1).
pub fn hides(front: f32, back: f32, tolerance: f32) -> bool {
    front > back * (1.0 + tolerance)
}
