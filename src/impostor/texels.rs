//! The texel walk (paper 1 §3.2, made exact; docs/conventions.md §2.3): the ray's image path in
//! closed form (`path.rs`) is followed texel by texel, every texel it crosses once and in
//! order (a grid traversal, Amanatides & Woo 1987, on each monotone piece), and the ray is
//! tested against the stored plane where it enters and leaves each texel. No point is
//! projected on the way and nothing between two samples is missed, for every camera: the
//! straight paths of pinholes, orthographic cameras and graph-camera frusta (§4.6's algorithm
//! 2), and the curved path of a SPOC (§3.4).
//!
//! Every layer of a layered impostor (`peel.rs`) is tested at each texel, each with its own
//! run of samples; the nearest crossing wins. Where the ray provably passes in front of every
//! layer — its `gd` over a pyramid node's stretch of path above the node's bound, the
//! largest front bound of any layer under it — the node is stepped over whole (the "maximum
//! mipmap" traversal of height-field ray casting: climb after a step, descend where the test
//! fails). A stepped-over run only holds samples in front of their planes, which can end no
//! crossing, so skipping changes no hit.
//!
//! Invariants: the samples of one layer are those of a walk of that layer alone; the last
//! sample before a skipped node's exit is read only when the next one ends a crossing.

use super::Impostor;
use super::path::{ImagePath, Piece};
use super::walk::{Sample, WalkStats};
use crate::camera::ImagePoint;
use crate::geom::Ray;
use crate::trace::Hit;
use glam::DVec2;

/// The most layers a walk follows at once (the peeling cap).
const LAYERS: usize = super::peel::MAX_LAYERS as usize;
/// Upper bound on the steps of one walk (bounds the work on degenerate input).
const MAX_STEPS: usize = 1 << 20;

/// One sample of one layer's run: where on the path, which texel, what it stores there and the
/// signed distance to its plane (`+∞` over empty texels). `stored` is NaN for the last sample
/// of a skipped node, known to be in front and read only if needed.
#[derive(Clone, Copy, Debug)]
struct Mark {
    s: f64,
    piece: usize,
    texel: Option<(u32, u32)>,
    stored: f32,
    delta: f64,
}

/// A walk over every layer at once: each layer's last sample, which layers are done, the best
/// hit so far.
struct Runs<'a> {
    impostor: &'a Impostor,
    ray: &'a Ray,
    path: &'a ImagePath,
    layers: usize,
    prev: [Option<Mark>; LAYERS],
    done: [bool; LAYERS],
    /// Layers not done.
    walking: usize,
    best: Option<Hit>,
    /// `best`'s ray parameter, in `f64`.
    best_t: f64,
    /// The ray parameter at path parameter `s` is `along.0 + along.1·s`.
    along: (f64, f64),
}

impl Runs<'_> {
    fn layer(&self, l: usize) -> &Impostor {
        if l == 0 {
            self.impostor
        } else {
            &self.impostor.deeper[l - 1]
        }
    }

    /// The walk can end: every layer has answered, or the path has passed the best hit.
    #[inline]
    fn finished(&self, s: f64) -> bool {
        self.walking == 0 || self.best.is_some() && self.along.0 + self.along.1 * s > self.best_t
    }

    /// Tests texel `(x, y)` of every layer still walking, from `s_in` to `s_out` of `piece`.
    fn texel(&mut self, (x, y): (u32, u32), piece: usize, s_in: f64, s_out: f64) {
        let (x0, x1) = self.path.world_line();
        for l in 0..self.layers {
            if self.done[l] {
                continue;
            }
            let layer = self.layer(l);
            let gd = layer.gd.get(x, y);
            let (d_in, d_out) = if gd > 0.0 {
                let t = layer.texel_planes().get(x, y);
                let n = t.normal.as_dvec3();
                let (base, rate) = ((x0 - t.point.as_dvec3()).dot(n), x1.dot(n));
                (base + rate * s_in, base + rate * s_out)
            } else {
                (f64::INFINITY, f64::INFINITY)
            };
            for (s, delta) in [(s_in, d_in), (s_out, d_out)] {
                let cur = Mark {
                    s,
                    piece,
                    texel: Some((x, y)),
                    stored: gd,
                    delta,
                };
                if let Some(prev) = self.prev[l]
                    && prev.delta > 0.0
                    && delta <= 0.0
                    && let Some(hit) = self.crossing(l, prev, cur)
                {
                    self.done[l] = true;
                    self.walking -= 1;
                    if self.best.is_none_or(|b| hit.t < b.t) {
                        self.best = Some(hit);
                        self.best_t = hit.t as f64;
                    }
                    break;
                }
                self.prev[l] = Some(cur);
            }
        }
    }

    /// Layer `l`'s verdict on a sign change from `a` to `b` (`walk.rs`'s rules).
    fn crossing(&self, l: usize, a: Mark, b: Mark) -> Option<Hit> {
        let layer = self.layer(l);
        let sample = |m: Mark| {
            let stored = match (m.stored.is_nan(), m.texel) {
                (true, Some((x, y))) => layer.gd.get(x, y),
                _ => m.stored,
            };
            Sample {
                p: ImagePoint {
                    uv: self.path.pieces()[m.piece].uv(m.s),
                    gd: self.path.gd(m.s),
                    inv_w: 0.0,
                },
                texel: m.texel,
                stored,
                delta: m.delta,
            }
        };
        layer.accept(self.ray, &sample(a), &sample(b))
    }

    /// Every layer still walking has passed in front of everything up to `mark`.
    fn in_front(&mut self, mark: Mark) {
        for l in 0..self.layers {
            if !self.done[l] {
                self.prev[l] = Some(mark);
            }
        }
    }

    /// Whether the ray at `gd` is in front of texel `(x, y)`'s bound in every layer walking.
    fn in_front_of_bounds(&self, (x, y): (u32, u32), gd: f64) -> bool {
        (0..self.layers).all(|l| {
            self.done[l] || {
                let layer = self.layer(l);
                layer.gd.get(x, y) <= 0.0 || gd > layer.texel_planes().get(x, y).front as f64
            }
        })
    }
}

impl Impostor {
    /// Walks `path` (part of `ray`) texel by texel through every layer, stepping over pyramid
    /// nodes the ray passes in front of when `skip`; the nearest accepted crossing.
    pub(super) fn walk_texels(
        &self,
        ray: &Ray,
        path: &ImagePath,
        skip: bool,
        stats: &mut WalkStats,
    ) -> Option<Hit> {
        let mut runs = Runs {
            impostor: self,
            ray,
            path,
            layers: self.layer_count().min(LAYERS),
            prev: [None; LAYERS],
            done: [false; LAYERS],
            walking: self.layer_count().min(LAYERS),
            best: None,
            best_t: f64::INFINITY,
            along: {
                let ((x0, x1), d) = (path.world_line(), ray.dir.as_dvec3());
                ((x0 - ray.origin.as_dvec3()).dot(d), x1.dot(d))
            },
        };
        let (w, h) = self.gd.size();
        let pyramid = self.pyramid();
        let top = pyramid.level_count() - 1;
        let mut steps = 0usize;
        let mut length = 0.0;
        let mut started = false;
        for (index, piece) in path.pieces().iter().enumerate() {
            length += (piece.uv(piece.to) - piece.uv(piece.from)).length();
            let Some((s_a, s_b)) = inside(piece, w, h) else {
                continue;
            };
            if started && s_a != piece.from {
                // The path left the image and comes back: outside, everything is empty.
                runs.in_front(Mark {
                    s: s_a,
                    piece: index,
                    texel: None,
                    stored: 0.0,
                    delta: f64::INFINITY,
                });
            }
            started = true;
            let forward = piece.to > piece.from;
            // `a` comes before `b` along the walk.
            let before = |a: f64, b: f64| if forward { a < b } else { a > b };
            let ends = (piece.uv(s_a), piece.uv(s_b));
            let sign = |d: f64| i64::from(d > 0.0) - i64::from(d < 0.0);
            let dir = [sign(ends.1.x - ends.0.x), sign(ends.1.y - ends.0.y)];
            let start = piece.uv(s_a + (s_b - s_a) * 1e-9);
            // Truncation is the floor for what the clamp keeps (`f64::floor` is a library call
            // without SSE 4.1).
            let mut cell = [
                (start.x as i64).clamp(0, w as i64 - 1),
                (start.y as i64).clamp(0, h as i64 - 1),
            ];
            // The last grid line each axis was solved for, and where the path meets it (a node
            // and its parent or child often share a side).
            let mut solved = [(f64::NAN, s_b); 2];
            // Where the path leaves the node of `level` holding `cell` along axis `k`.
            let mut leave = |k: usize, cell: [i64; 2], level: u32, s_in: f64| -> f64 {
                if dir[k] == 0 {
                    return s_b;
                }
                let node = cell[k] >> level;
                let line = (if dir[k] > 0 {
                    (node + 1) << level
                } else {
                    node << level
                }) as f64;
                if solved[k].0 != line {
                    solved[k] = (line, piece.crossing(k, line).unwrap_or(s_b));
                }
                let s = solved[k].1;
                if before(s, s_in) {
                    s_in
                } else if before(s, s_b) {
                    s
                } else {
                    s_b
                }
            };
            let mut s_in = s_a;
            let mut level = 0u32;
            // Where the path leaves the current node along each axis (`None`: not known yet).
            let mut exits: [Option<f64>; 2] = [None, None];
            // The level-1 node where climbing last failed: not tried again while in it.
            let mut failed: Option<(i64, i64)> = None;
            loop {
                steps += 1;
                if steps > MAX_STEPS || runs.finished(s_in) {
                    return runs.best;
                }
                let ex = exits[0].unwrap_or_else(|| leave(0, cell, level, s_in));
                let ey = exits[1].unwrap_or_else(|| leave(1, cell, level, s_in));
                let s_out = if before(ey, ex) { ey } else { ex };
                let crossed = [
                    dir[0] != 0 && ex == s_out && s_out != s_b,
                    dir[1] != 0 && ey == s_out && s_out != s_b,
                ];
                if level > 0 {
                    stats.texel_visits += 1;
                    let bound = pyramid.node(
                        level as usize,
                        (cell[0] >> level) as u32,
                        (cell[1] >> level) as u32,
                    ) as f64;
                    if path.gd(s_in).min(path.gd(s_out)) > bound {
                        // The whole stretch is in front of every plane: step over the node.
                        let last = last_texel(piece, cell, level, s_out, &crossed, &dir, (w, h));
                        runs.in_front(Mark {
                            s: s_out,
                            piece: index,
                            texel: Some(last),
                            stored: f32::NAN,
                            delta: f64::INFINITY,
                        });
                        if !(crossed[0] || crossed[1]) {
                            break;
                        }
                        let at = piece.uv(s_out);
                        for k in 0..2 {
                            let lo = (cell[k] >> level) << level;
                            cell[k] = if crossed[k] {
                                if dir[k] > 0 {
                                    lo + (1 << level)
                                } else {
                                    lo - 1
                                }
                            } else {
                                // From the image point where the path enters the next node.
                                let hi = (lo + (1 << level) - 1).min([w, h][k] as i64 - 1);
                                (at[k] as i64).clamp(lo, hi)
                            };
                        }
                        if cell[0] < 0 || cell[1] < 0 || cell[0] >= w as i64 || cell[1] >= h as i64
                        {
                            break;
                        }
                        s_in = s_out;
                        level = (level + 1).min(top as u32);
                    } else {
                        failed = (level == 1).then_some((cell[0] >> 1, cell[1] >> 1));
                        level -= 1;
                    }
                    exits = [None, None];
                    continue;
                }
                stats.texel_visits += 1;
                let texel = (cell[0] as u32, cell[1] as u32);
                runs.texel(texel, index, s_in, s_out);
                if !(crossed[0] || crossed[1]) {
                    break;
                }
                let climb = skip
                    && top > 0
                    && runs.in_front_of_bounds(texel, path.gd(s_out))
                    && failed != Some((cell[0] >> 1, cell[1] >> 1));
                for k in 0..2 {
                    if crossed[k] {
                        cell[k] += dir[k];
                    }
                }
                if cell[0] < 0 || cell[1] < 0 || cell[0] >= w as i64 || cell[1] >= h as i64 {
                    break;
                }
                s_in = s_out;
                if climb {
                    level = 1;
                    exits = [None, None];
                } else {
                    // Only the lines crossed change.
                    exits = [(!crossed[0]).then_some(ex), (!crossed[1]).then_some(ey)];
                }
            }
        }
        stats.projection_length += length.ceil() as u64;
        runs.best
    }
}

/// The stretch `[s_a, s_b]` of `piece` (walk order) whose image lies in the `w × h` image;
/// `None` when none does. Both coordinates are monotone on a piece, so it is one stretch.
fn inside(piece: &Piece, w: u32, h: u32) -> Option<(f64, f64)> {
    let forward = piece.to > piece.from;
    let later = |a: f64, b: f64| if forward { a.max(b) } else { a.min(b) };
    let sooner = |a: f64, b: f64| if forward { a.min(b) } else { a.max(b) };
    let (a, b) = (piece.uv(piece.from), piece.uv(piece.to));
    let (mut s_a, mut s_b) = (piece.from, piece.to);
    for (k, size) in [(0, w as f64), (1, h as f64)] {
        let (lo, hi) = (a[k].min(b[k]), a[k].max(b[k]));
        if hi < 0.0 || lo >= size {
            return None;
        }
        // Where the coordinate enters [0, size] and where it leaves it.
        let rising = b[k] > a[k];
        let (first, last) = if rising { (0.0, size) } else { (size, 0.0) };
        let out_at_start = if rising { a[k] < first } else { a[k] > first };
        if out_at_start && let Some(s) = piece.crossing(k, first) {
            s_a = later(s_a, s);
        }
        let out_at_end = if rising { b[k] > last } else { b[k] < last };
        if out_at_end && let Some(s) = piece.crossing(k, last) {
            s_b = sooner(s_b, s);
        }
    }
    let empty = if forward { s_a >= s_b } else { s_a <= s_b };
    (!empty).then_some((s_a, s_b))
}

/// The texel of the node of `level` holding `cell` where the path leaves it at `s_out`.
fn last_texel(
    piece: &Piece,
    cell: [i64; 2],
    level: u32,
    s_out: f64,
    crossed: &[bool; 2],
    dir: &[i64; 2],
    (w, h): (u32, u32),
) -> (u32, u32) {
    let at: DVec2 = piece.uv(s_out);
    let texel = [0, 1].map(|k| {
        let lo = (cell[k] >> level) << level;
        let hi = (lo + (1 << level) - 1).min([w, h][k] as i64 - 1);
        if crossed[k] {
            if dir[k] > 0 { hi } else { lo }
        } else {
            // Truncation is the floor for what the clamp to `lo ≥ 0` keeps.
            (at[k] as i64).clamp(lo, hi)
        }
    });
    (texel[0] as u32, texel[1] as u32)
}
