//! Scan conversion of one band of rows: integer edge functions with the top-left rule, depth
//! test, attribute interpolation and the fragment hook.

use super::setup::{ONE, ScreenTri};
use super::{Fragment, FragmentShader, ItemId, RasterStats};
use crate::frame::texel_centre;
use glam::Vec3;

/// The rows `first_row ..` of every target buffer, owned by one worker.
pub(super) struct Band<'a, T> {
    pub width: u32,
    pub first_row: u32,
    pub gd: &'a mut [f32],
    pub item: &'a mut [ItemId],
    pub attr: &'a mut [T],
    /// The band's rows of a depth-peeling ceiling: a fragment is drawn only where its `gd` is
    /// strictly below the ceiling's (behind the layer peeled before). `None`: no ceiling.
    pub ceiling: Option<&'a [f32]>,
}

/// An edge function `E(p) = dx·(p.y − a.y) − dy·(p.x − a.x)` of the directed edge `a → b`,
/// with the top-left bias folded in: a pixel is inside when every biased `E ≥ 0`.
struct Edge {
    value: i64,
    step_x: i64,
    step_y: i64,
}

impl Edge {
    fn new(a: [i64; 2], b: [i64; 2], px: i64, py: i64) -> Edge {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        // Top-left rule for triangles oriented with positive doubled area (y down): an edge owns
        // the pixel centres on it when it is a left edge (dy < 0) or a top edge (dy = 0, dx > 0).
        // The rule is antisymmetric, so of two triangles sharing an edge exactly one owns it.
        let owned = dy < 0 || (dy == 0 && dx > 0);
        let bias = if owned { 0 } else { -1 };
        Edge {
            value: dx * (py - a[1]) - dy * (px - a[0]) + bias,
            step_x: -dy * ONE,
            step_y: dx * ONE,
        }
    }
}

impl<T: Copy> Band<'_, T> {
    pub fn draw<S: FragmentShader<Output = T>>(
        &mut self,
        t: &ScreenTri,
        shader: &S,
        stats: &mut RasterStats,
    ) {
        let rows_here = (self.gd.len() / self.width as usize) as u32;
        let last_row = self.first_row + rows_here - 1;
        let (y0, y1) = (t.rows.0.max(self.first_row), t.rows.1.min(last_row));
        if y0 > y1 {
            return;
        }
        let (x0, x1) = t.cols;
        let [a, b, c] = t.fixed;
        let px = x0 as i64 * ONE + ONE / 2;
        let py = y0 as i64 * ONE + ONE / 2;
        // Weight of corner 0 comes from the opposite edge b → c, and so on.
        let mut e = [
            Edge::new(b, c, px, py),
            Edge::new(c, a, px, py),
            Edge::new(a, b, px, py),
        ];
        let [gd_p, w_p, q0, q1, q2] = t.planes;
        for y in y0..=y1 {
            let mut w = [e[0].value, e[1].value, e[2].value];
            let row = (y - self.first_row) as usize * self.width as usize;
            let dy = texel_centre(f64::from(y)) - t.origin.y;
            for x in x0..=x1 {
                if (w[0] | w[1] | w[2]) >= 0 {
                    stats.fragments += 1;
                    let dx = texel_centre(f64::from(x)) - t.origin.x;
                    let gd = gd_p.f0 + gd_p.dfdx * dx + gd_p.dfdy * dy;
                    let idx = row + x as usize;
                    let gd32 = gd as f32;
                    if gd32 > self.gd[idx] && self.ceiling.is_none_or(|c| gd32 < c[idx]) {
                        let [inv_w, q0, q1, q2] =
                            [w_p, q0, q1, q2].map(|p| p.f0 + p.dfdx * dx + p.dfdy * dy);
                        // One division for the three weights.
                        let w = 1.0 / inv_w;
                        let bary = Vec3::new((q0 * w) as f32, (q1 * w) as f32, (q2 * w) as f32);
                        let fragment = Fragment {
                            x,
                            y,
                            gd: gd32,
                            bary,
                            item: t.item,
                        };
                        self.gd[idx] = gd32;
                        self.item[idx] = t.item;
                        self.attr[idx] = shader.shade(&fragment);
                        stats.written += 1;
                    }
                }
                for k in 0..3 {
                    w[k] += e[k].step_x;
                }
            }
            for edge in &mut e {
                edge.value += edge.step_y;
            }
        }
    }
}

/// Every pixel centre a triangle covers, with its `gd`, without a depth test: the fragments an
/// A-buffer keeps (appended to `out` as `(pixel index, gd)`, row-major in the whole image).
pub(super) fn cover(
    t: &ScreenTri,
    width: u32,
    band_rows: (u32, u32),
    mut out: impl FnMut(usize, f32),
) {
    let (y0, y1) = (t.rows.0.max(band_rows.0), t.rows.1.min(band_rows.1));
    if y0 > y1 {
        return;
    }
    let (x0, x1) = t.cols;
    let [a, b, c] = t.fixed;
    let px = x0 as i64 * ONE + ONE / 2;
    let py = y0 as i64 * ONE + ONE / 2;
    let mut e = [
        Edge::new(b, c, px, py),
        Edge::new(c, a, px, py),
        Edge::new(a, b, px, py),
    ];
    let gd_p = t.planes[0];
    for y in y0..=y1 {
        let mut w = [e[0].value, e[1].value, e[2].value];
        let dy = texel_centre(f64::from(y)) - t.origin.y;
        for x in x0..=x1 {
            if (w[0] | w[1] | w[2]) >= 0 {
                let dx = texel_centre(f64::from(x)) - t.origin.x;
                let gd = gd_p.f0 + gd_p.dfdx * dx + gd_p.dfdy * dy;
                out(y as usize * width as usize + x as usize, gd as f32);
            }
            for k in 0..3 {
                w[k] += e[k].step_x;
            }
        }
        for edge in &mut e {
            edge.value += edge.step_y;
        }
    }
}
