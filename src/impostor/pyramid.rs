//! A max pyramid (beyond paper 1): level 0 is an image — for impostors, the texels'
//! front bounds (`front.rs`; 0 where empty) — and each further level halves the resolution
//! keeping the largest value of the texels a node covers. A ray whose image path stays inside a
//! node while its `gd` exceeds the node's value is in front of every texel plane there and
//! cannot cross the stored surface; the texel walk (`texels.rs`) steps over such nodes.
//!
//! Invariant: a node's value is at least the value of every texel it covers.

use crate::frame::Image;

/// Writes into `next` (half the size of `level`, rounded up) the maximum of each 2 × 2 block.
fn reduce(level: &Image<f32>, next: &mut Image<f32>) {
    let (w, h) = level.size();
    let (nw, nh) = next.size();
    for y in 0..nh {
        for x in 0..nw {
            let mut m = 0.0f32;
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let (cx, cy) = (2 * x + dx, 2 * y + dy);
                if cx < w && cy < h {
                    m = m.max(level.get(cx, cy));
                }
            }
            next.set(x, y, m);
        }
    }
}

/// Levels of maxima, finest first.
#[derive(Clone, Debug, Default)]
pub struct MaxPyramid {
    levels: Vec<Image<f32>>,
}

impl MaxPyramid {
    /// Builds every level down to 1 × 1.
    pub fn new(gd: &Image<f32>) -> MaxPyramid {
        let mut levels = vec![gd.clone()];
        while let Some(last) = levels.last() {
            let (w, h) = last.size();
            if w == 1 && h == 1 {
                break;
            }
            let (nw, nh) = (w.div_ceil(2), h.div_ceil(2));
            let mut next = Image::derived(nw, nh, 0.0f32);
            reduce(last, &mut next);
            levels.push(next);
        }
        MaxPyramid { levels }
    }

    /// Level `l` (0 = the texels).
    pub fn level(&self, l: usize) -> &Image<f32> {
        &self.levels[l]
    }

    /// Number of levels (the last is 1 × 1).
    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// The largest `gd` under node `(x, y)` of `level` (level 0 = texels).
    pub fn node(&self, level: usize, x: u32, y: u32) -> f32 {
        self.levels[level].get(x, y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_node_is_the_largest_texel_it_covers() {
        // An odd size, so the last row and column of each level cover fewer texels.
        let (w, h) = (37u32, 23u32);
        let data: Vec<f32> = (0..w * h)
            .map(|i| if i % 7 == 0 { (i % 13) as f32 } else { 0.0 })
            .collect();
        let img = Image::from_vec(w, h, data).unwrap();
        let p = MaxPyramid::new(&img);
        assert_eq!(p.level(p.level_count() - 1).size(), (1, 1));
        for l in 0..p.level_count() {
            let (nw, nh) = p.level(l).size();
            for (nx, ny) in (0..nh).flat_map(|y| (0..nw).map(move |x| (x, y))) {
                let mut want = 0.0f32;
                for y in (ny << l)..((ny + 1) << l).min(h) {
                    for x in (nx << l)..((nx + 1) << l).min(w) {
                        want = want.max(img.get(x, y));
                    }
                }
                assert_eq!(p.node(l, nx, ny), want, "level {l} node {nx} {ny}");
            }
        }
    }
}
