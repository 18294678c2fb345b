//! A max pyramid (beyond paper 1): level 0 is an image — for impostors, the texels'
//! front bounds (`front.rs`; 0 where empty) — and each further level halves the resolution
//! keeping the largest value of the texels a node covers. A ray whose image path stays inside a
//! node while its `gd` exceeds the node's value is in front of every texel plane there and
//! cannot cross the stored surface; the texel walk (`texels.rs`) steps over such nodes.
//!
//! Invariant: a node's value is at least the value of every texel it covers.

use crate::frame::Image;
use glam::DVec2;

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
    /// Builds the pyramid again from a level 0 that `fill` writes (row-major, `width × height`),
    /// reusing the levels' memory when the size is unchanged.
    pub fn rebuild_with(&mut self, width: u32, height: u32, fill: impl FnOnce(&mut [f32])) {
        if self.levels.first().map(|l| l.size()) != Some((width, height)) {
            let mut base = Image::new(width, height, 0.0f32).expect("an impostor's size");
            fill(base.pixels_mut());
            *self = MaxPyramid::new(&base);
            return;
        }
        fill(self.levels[0].pixels_mut());
        for k in 1..self.levels.len() {
            let (done, rest) = self.levels.split_at_mut(k);
            reduce(&done[k - 1], &mut rest[0]);
        }
    }

    /// Builds every level down to 1 × 1.
    pub fn new(gd: &Image<f32>) -> MaxPyramid {
        let mut levels = vec![gd.clone()];
        while let Some(last) = levels.last() {
            let (w, h) = last.size();
            if w == 1 && h == 1 {
                break;
            }
            let (nw, nh) = (w.div_ceil(2), h.div_ceil(2));
            let mut next = Image::new(nw, nh, 0.0f32).expect("smaller than its parent");
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

    /// An upper bound of `gd` over the texels meeting the image box `[min, max]` (0 when the box
    /// lies outside the image), reading at most four nodes; `visits` counts them.
    pub fn max_over(&self, min: DVec2, max: DVec2, visits: &mut u64) -> f32 {
        let (w, h) = self.levels[0].size();
        let (x0, y0) = (min.x.floor(), min.y.floor());
        let (x1, y1) = (max.x.floor(), max.y.floor());
        if !(x0.is_finite() && y0.is_finite() && x1.is_finite() && y1.is_finite()) {
            return f32::INFINITY;
        }
        if x1 < 0.0 || y1 < 0.0 || x0 >= w as f64 || y0 >= h as f64 {
            return 0.0;
        }
        let clamp = |v: f64, n: u32| v.clamp(0.0, (n - 1) as f64) as u32;
        let (x0, x1, y0, y1) = (clamp(x0, w), clamp(x1, w), clamp(y0, h), clamp(y1, h));
        let mut level = 0;
        while level + 1 < self.levels.len()
            && ((x1 >> level) - (x0 >> level) > 1 || (y1 >> level) - (y0 >> level) > 1)
        {
            level += 1;
        }
        let img = &self.levels[level];
        let mut m = 0.0f32;
        for y in (y0 >> level)..=(y1 >> level) {
            for x in (x0 >> level)..=(x1 >> level) {
                *visits += 1;
                m = m.max(img.get(x, y));
            }
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn max_over_bounds_every_texel_in_the_box() {
        let (w, h) = (37u32, 23u32);
        let data: Vec<f32> = (0..w * h)
            .map(|i| if i % 7 == 0 { (i % 13) as f32 } else { 0.0 })
            .collect();
        let img = Image::from_vec(w, h, data).unwrap();
        let p = MaxPyramid::new(&img);
        let mut visits = 0;
        for (a, b) in [
            ((0.0, 0.0), (36.9, 22.9)),
            ((3.2, 4.7), (9.1, 5.0)),
            ((-5.0, -5.0), (2.0, 2.0)),
            ((40.0, 1.0), (50.0, 3.0)),
        ] {
            let (min, max) = (DVec2::new(a.0, a.1), DVec2::new(b.0, b.1));
            let got = p.max_over(min, max, &mut visits);
            let mut want = 0.0f32;
            for y in 0..h {
                for x in 0..w {
                    let inside = (x as f64) <= max.x
                        && (x as f64 + 1.0) > min.x
                        && (y as f64) <= max.y
                        && (y as f64 + 1.0) > min.y;
                    if inside {
                        want = want.max(img.get(x, y));
                    }
                }
            }
            assert!(got >= want, "{min} {max}: {got} < {want}");
        }
        assert!(visits <= 16);
    }
}
