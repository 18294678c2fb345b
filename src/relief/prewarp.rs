//! The relief pre-warp (paper 3 §2, Eq. 2–3, after Oliveira, Bishop and McAllister's "Relief
//! Texture Mapping"; docs/conventions.md §5.2–5.3): every texel of a relief impostor slides on
//! its base plane to where the line from the eye through its 3-D point meets the plane, so that
//! an ordinary texture map of the result shows the relief in perspective.
//!
//! With `c = origin − eye`, texel `(u, v)` at displacement `d` lands at
//! `u' = (u + k1·d) / (1 + k3·d)` and `v' = (v + k2·d) / (1 + k3·d)`, where
//! `k1 = f·(b×c) / a·(b×c)`, `k2 = f·(c×a) / b·(c×a)`, `k3 = f·(a×b) / c·(a×b)` (the paper's
//! Eq. 2 prints `u − k1·d`; with `d` a height toward the eye the signs are `+`, which the
//! collinearity test below checks). `u'` depends on `u` and `d` alone, so the warp runs as two
//! 1-D passes — rows, then columns — each traversed toward the epipole (the eye's foot on the
//! plane), so that a later write is always the nearer surface and no z-buffer is needed. Between
//! two neighbours of a pass, the columns they leave empty are filled by interpolating the two
//! (paper §3) and flagged: the count of those texels is the brute-force validity measure. A
//! run's first and last texels, where the warp stretches them apart from their neighbour, also
//! cover the empty texels of their own warped half-footprint (flagged extended, not counted):
//! otherwise a stretched silhouette loses that half-footprint.
//!
//! Invariants: a texel lands at index `floor(x)` of its pass, `x` the warped continuous
//! coordinate of its centre; the output is the base plane extended by a margin on every side
//! (texels that would land past it are counted as dropped); the lookup-table warp gives
//! bit-identical images to the direct one.

use super::{ReliefImpostor, Srgba8};
use crate::frame::texel_centre;
use glam::DVec3;
use rayon::prelude::*;

/// Where the warp's target eye is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Eye {
    /// A centre of projection (a perspective view).
    Point(DVec3),
    /// A direction toward an eye at infinity (a parallel view); along the base plane's normal,
    /// the warp is the identity.
    Direction(DVec3),
}

/// The pre-warp's constants for one frame and eye, and the epipole that orders the passes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coefficients {
    /// `k1`: shift in `u` per unit of displacement, before the `1 + k3·d` division.
    pub k1: f64,
    /// `k2`: the same in `v`.
    pub k2: f64,
    /// `k3`: `−1/h` for an eye `h` above the plane; 0 for an eye at infinity.
    pub k3: f64,
    /// Where each pass turns round: texels whose centre is below this coordinate are swept
    /// ascending, the rest descending (`±∞` for an eye at infinity).
    pub epipole: (f64, f64),
}

impl Coefficients {
    /// The constants for `eye` over `frame`; `None` when the eye is on or behind the base plane
    /// (no warp shows a relief from behind).
    pub fn new(frame: &super::ReliefFrame, eye: Eye) -> Option<Self> {
        let (a, b, f) = (frame.a, frame.b, frame.f);
        match eye {
            Eye::Point(e) => {
                let c = frame.origin - e;
                if -c.dot(f) <= frame.texel_size() * 1e-6 {
                    return None;
                }
                let k1 = f.dot(b.cross(c)) / a.dot(b.cross(c));
                let k2 = f.dot(c.cross(a)) / b.dot(c.cross(a));
                let k3 = f.dot(a.cross(b)) / c.dot(a.cross(b));
                let foot = frame.coordinates(e);
                Some(Self {
                    k1,
                    k2,
                    k3,
                    epipole: (foot.x, foot.y),
                })
            }
            Eye::Direction(w) => {
                let w = w.normalize_or_zero();
                let wf = w.dot(f);
                if wf <= 1e-9 {
                    return None;
                }
                let k1 = -w.dot(a) / (a.length_squared() * wf);
                let k2 = -w.dot(b) / (b.length_squared() * wf);
                // Shifts of sign k: toward −∞ (sweep ascending) when k < 0.
                let turn = |k: f64| {
                    if k < 0.0 {
                        f64::INFINITY
                    } else {
                        f64::NEG_INFINITY
                    }
                };
                Some(Self {
                    k1,
                    k2,
                    k3: 0.0,
                    epipole: (turn(k1), turn(k2)),
                })
            }
        }
    }

    /// The warped `u` of a texel coordinate `u` at displacement `d`; `None` when the point is
    /// level with or above the eye (its line never meets the plane in front of the eye).
    #[inline]
    pub fn warp_u(&self, u: f64, d: f64) -> Option<f64> {
        let w = 1.0 + self.k3 * d;
        (w > 1e-9).then(|| (u + self.k1 * d) * (1.0 / w))
    }

    /// The warped `v` of a texel coordinate `v` at displacement `d`.
    #[inline]
    pub fn warp_v(&self, v: f64, d: f64) -> Option<f64> {
        let w = 1.0 + self.k3 * d;
        (w > 1e-9).then(|| (v + self.k2 * d) * (1.0 / w))
    }
}

/// The lookup tables of paper §5 for eight-bit displacements: `Coef1[D] = k1·d`,
/// `Coef2[D] = k2·d`, `Coef3[D] = 1/(1 + k3·d)` with `d = −D·max_depth/255` (`D` the depth into
/// the impostor), rebuilt for each eye.
#[derive(Clone, Debug)]
pub struct Lut {
    coef1: [f64; 256],
    coef2: [f64; 256],
    coef3: [f64; 256],
}

impl Lut {
    /// The tables for `k` over depths up to `max_depth`.
    pub fn new(k: &Coefficients, max_depth: f64) -> Self {
        let mut lut = Lut {
            coef1: [0.0; 256],
            coef2: [0.0; 256],
            coef3: [0.0; 256],
        };
        for code in 0..256 {
            // The displacement exactly as a texel carries it (f32).
            let d = (-(code as f64) * max_depth / 255.0) as f32 as f64;
            let w = 1.0 + k.k3 * d;
            lut.coef1[code] = k.k1 * d;
            lut.coef2[code] = k.k2 * d;
            // Past the eye's height: marked, never used to place a texel.
            lut.coef3[code] = if w > 1e-9 { 1.0 / w } else { f64::NAN };
        }
        lut
    }
}

/// How a pre-warped texel was made.
pub mod flag {
    /// Nothing landed here.
    pub const EMPTY: u8 = 0;
    /// A source texel landed here.
    pub const DIRECT: u8 = 1;
    /// Filled by interpolating two neighbours (in either pass).
    pub const INTERPOLATED: u8 = 2;
    /// Covered by the warped footprint of the texel that ends a run (in either pass): where the
    /// warp stretches the surface at a silhouette, the last texel's own footprint grows past
    /// its centre. Not counted as direct or interpolated (the validity measure is the paper's).
    pub const EXTENDED: u8 = 3;
}

/// The most texels a run's end grows by ([`flag::EXTENDED`]): a spacing wider than twice this
/// is a step between two surfaces more than a stretched one.
const MAX_EXTENSION: f64 = 2.0;

/// Flag bit of a displacement that is not an eight-bit step (interpolated between two).
const OFF_GRID: u8 = 4;
/// The bits of a flag that say how a texel was made ([`flag`]).
const KIND: u8 = 3;

/// `floor(x)` as an integer, without a libm call (x86-64's baseline has no rounding
/// instruction); exact for |x| < 2⁵³.
#[inline]
fn floor_i64(x: f64) -> i64 {
    let i = x as i64;
    i - ((i as f64) > x) as i64
}

/// One image of a pass, row-major; texels as compact as an engine's (sRGB8 colour, f32
/// displacement, its eight-bit code, a flag).
#[derive(Clone, Debug, Default)]
struct Plane {
    width: usize,
    height: usize,
    color: Vec<Srgba8>,
    d: Vec<f32>,
    code: Vec<u8>,
    flag: Vec<u8>,
}

impl Plane {
    fn empty(width: usize, height: usize) -> Self {
        let n = width * height;
        Plane {
            width,
            height,
            color: vec![[0; 4]; n],
            d: vec![0.0; n],
            code: vec![0; n],
            flag: vec![flag::EMPTY; n],
        }
    }

    fn transposed(&self) -> Plane {
        let mut t = Plane::empty(self.height, self.width);
        let (w, h) = (self.width, self.height);
        t.color
            .par_chunks_mut(h)
            .zip(t.d.par_chunks_mut(h))
            .zip(t.code.par_chunks_mut(h))
            .zip(t.flag.par_chunks_mut(h))
            .enumerate()
            .for_each(|(x, (((c, d), k), f))| {
                for y in 0..h {
                    let i = y * w + x;
                    f[y] = self.flag[i];
                    if self.flag[i] != flag::EMPTY {
                        c[y] = self.color[i];
                        d[y] = self.d[i];
                        k[y] = self.code[i];
                    }
                }
            });
        t
    }
}

/// A pre-warped image: the base plane extended by `margin` texels on each side.
#[derive(Clone, Debug)]
pub struct Prewarped {
    /// Width, texels (`source width + 2·margin.0`).
    pub width: u32,
    /// Height, texels (`source height + 2·margin.1`).
    pub height: u32,
    /// Extra texels left and right, top and bottom: output texel `(i, j)` is base-plane texel
    /// `(i − margin.0, j − margin.1)`.
    pub margin: (u32, u32),
    /// Colour, sRGB8 ([`super::decode`] gives it linear), alpha 0 where empty.
    pub color: Vec<Srgba8>,
    /// Displacement carried with each texel, world units.
    pub displacement: Vec<f32>,
    /// [`flag`] of each texel.
    pub flags: Vec<u8>,
    /// Texels a source texel landed on.
    pub direct: usize,
    /// Texels filled by interpolation.
    pub interpolated: usize,
    /// Source texels that fell past the margin or above the eye.
    pub dropped: usize,
}

impl Prewarped {
    /// The brute-force validity measure of paper §3: interpolated texels over direct ones.
    pub fn interpolated_ratio(&self) -> f64 {
        if self.direct == 0 {
            f64::INFINITY
        } else {
            self.interpolated as f64 / self.direct as f64
        }
    }
}

/// The largest margin a warp allocates, as a fraction of the source side: texels shifted
/// further are dropped (the impostor is long invalid by then).
pub const MAX_MARGIN_FRACTION: f64 = 1.0;

/// Pre-warps `impostor` for `eye`. `lut` uses paper §5's lookup tables for eight-bit
/// displacements (the result is the same; f32 displacements always use the direct formula).
/// `None` when the eye is on or behind the base plane.
pub fn prewarp(impostor: &ReliefImpostor, eye: Eye, lut: bool) -> Option<Prewarped> {
    let fr = &impostor.frame;
    let k = Coefficients::new(fr, eye)?;
    let (w, h) = (fr.width as usize, fr.height as usize);
    let codes = match &impostor.depth {
        super::Displacements::U8(c) => Some(c),
        super::Displacements::F32(_) => None,
    };
    let table = if lut && codes.is_some() {
        Some(Lut::new(&k, fr.max_depth))
    } else {
        None
    };

    // The source as a plane, and its range of displacements.
    let mut src = Plane::empty(w, h);
    let (mut d_min, mut d_max): (f64, f64) = (0.0, 0.0);
    for i in 0..w * h {
        if impostor.covered(i) {
            let d = impostor.displacement(i) as f32;
            src.color[i] = impostor.color[i];
            src.d[i] = d;
            src.flag[i] = flag::DIRECT;
            if let Some(c) = codes {
                src.code[i] = c[i];
            }
            d_min = d_min.min(d as f64);
            d_max = d_max.max(d as f64);
        }
    }
    let margin = |n: usize, shift: &dyn Fn(f64, f64) -> Option<f64>| -> usize {
        let mut m: f64 = 0.0;
        for x in [0.5, n as f64 - 0.5] {
            for d in [d_min, 0.0, d_max] {
                if let Some(y) = shift(x, d) {
                    m = m.max((y - x).abs());
                }
            }
        }
        (m.ceil() as usize + 1).min((n as f64 * MAX_MARGIN_FRACTION).ceil() as usize)
    };
    let mx = margin(w, &|x, d| k.warp_u(x, d));
    let my = margin(h, &|y, d| k.warp_v(y, d));

    let (pass1, pass2) = match &table {
        Some(t) => {
            let (a, b) = (
                |i: usize, d: f32, code: u8, off: bool| {
                    let u = texel_centre(i as f64);
                    if off {
                        return k.warp_u(u, d as f64);
                    }
                    let s = t.coef3[code as usize];
                    (!s.is_nan()).then(|| (u + t.coef1[code as usize]) * s)
                },
                |i: usize, d: f32, code: u8, off: bool| {
                    let v = texel_centre(i as f64);
                    if off {
                        return k.warp_v(v, d as f64);
                    }
                    let s = t.coef3[code as usize];
                    (!s.is_nan()).then(|| (v + t.coef2[code as usize]) * s)
                },
            );
            let p1 = pass(&src, w + 2 * mx, mx, k.epipole.0, &a);
            let p2 = pass(&p1.0.transposed(), h + 2 * my, my, k.epipole.1, &b);
            (p1.1, p2)
        }
        None => {
            let a = |i: usize, d: f32, _: u8, _: bool| k.warp_u(texel_centre(i as f64), d as f64);
            let b = |i: usize, d: f32, _: u8, _: bool| k.warp_v(texel_centre(i as f64), d as f64);
            let p1 = pass(&src, w + 2 * mx, mx, k.epipole.0, &a);
            let p2 = pass(&p1.0.transposed(), h + 2 * my, my, k.epipole.1, &b);
            (p1.1, p2)
        }
    };
    let (out, dropped2) = pass2;
    let mut out = out.transposed();
    let (mut direct, mut interpolated) = (0, 0);
    for f in &mut out.flag {
        *f &= KIND;
        direct += (*f == flag::DIRECT) as usize;
        interpolated += (*f == flag::INTERPOLATED) as usize;
    }
    Some(Prewarped {
        width: out.width as u32,
        height: out.height as u32,
        margin: (mx as u32, my as u32),
        color: out.color,
        displacement: out.d,
        flags: out.flag,
        direct,
        interpolated,
        dropped: pass1 + dropped2,
    })
}

/// One texel on its way through a pass.
#[derive(Clone, Copy)]
struct Moved {
    x: f64,
    color: Srgba8,
    d: f32,
    code: u8,
    flag: u8,
}

/// One 1-D pass over every row of `src` into rows `out_width` long, texel `i` of a row landing
/// at `floor(map(i, d, code, off_grid)) + offset`; rows turn round at the texel centre
/// `epipole`.
fn pass<M>(src: &Plane, out_width: usize, offset: usize, epipole: f64, map: &M) -> (Plane, usize)
where
    M: Fn(usize, f32, u8, bool) -> Option<f64> + Sync,
{
    let n = src.width;
    // Texels whose centre is left of the epipole: 0..split, swept ascending.
    let split = if epipole.is_finite() {
        (epipole - 0.5).ceil().clamp(0.0, n as f64) as usize
    } else if epipole > 0.0 {
        n
    } else {
        0
    };
    let mut out = Plane::empty(out_width, src.height);
    let dropped: usize = out
        .color
        .par_chunks_mut(out_width)
        .zip(out.d.par_chunks_mut(out_width))
        .zip(out.code.par_chunks_mut(out_width))
        .zip(out.flag.par_chunks_mut(out_width))
        .enumerate()
        .map(|(row, (((color, d), code), fl))| {
            let base = row * n;
            let mut line = Line {
                color,
                d,
                code,
                flag: fl,
                offset: offset as i64,
                dropped: 0,
            };
            let take = |i: usize| -> Option<Moved> {
                let j = base + i;
                (src.flag[j] != flag::EMPTY).then(|| Moved {
                    x: 0.0,
                    color: src.color[j],
                    d: src.d[j],
                    code: src.code[j],
                    flag: src.flag[j],
                })
            };
            let left = line.sweep((0..split).map(|i| (i, take(i))), true, map);
            let right = line.sweep((split..n).rev().map(|i| (i, take(i))), false, map);
            // The two sweeps meet at the epipole: join their last texels if they are neighbours.
            if let (Some((il, l)), Some((ir, r))) = (left, right)
                && ir == il + 1
                && l.x < r.x
            {
                line.fill(&l, &r);
            }
            line.dropped
        })
        .sum();
    (out, dropped)
}

/// One output row of a pass.
struct Line<'a> {
    color: &'a mut [Srgba8],
    d: &'a mut [f32],
    code: &'a mut [u8],
    flag: &'a mut [u8],
    offset: i64,
    dropped: usize,
}

impl Line<'_> {
    /// Moves the texels of `order` in turn (later writes win), filling the gaps between
    /// neighbours that spread apart in the sweep's direction. Returns the last texel moved, if
    /// the sweep ended on one.
    fn sweep<M>(
        &mut self,
        order: impl Iterator<Item = (usize, Option<Moved>)>,
        ascending: bool,
        map: &M,
    ) -> Option<(usize, Moved)>
    where
        M: Fn(usize, f32, u8, bool) -> Option<f64>,
    {
        let spreads = |a: &Moved, b: &Moved| if ascending { b.x > a.x } else { b.x < a.x };
        // The last texel moved in the current run, and the one before it.
        let (mut prev, mut before): (Option<Moved>, Option<Moved>) = (None, None);
        let mut last = None;
        for (i, texel) in order {
            last = None;
            let Some(mut t) = texel else {
                self.end_run(before, prev, &spreads);
                (prev, before) = (None, None);
                continue;
            };
            let Some(x) = map(i, t.d, t.code, t.flag & OFF_GRID != 0) else {
                self.dropped += 1;
                self.end_run(before, prev, &spreads);
                (prev, before) = (None, None);
                continue;
            };
            t.x = x;
            if let Some(p) = prev
                && spreads(&p, &t)
            {
                self.fill(&p, &t);
                if before.is_none() {
                    // `p` starts the run: its footprint grows backward.
                    self.extend(&p, &t);
                }
            }
            self.put(&t);
            (before, prev) = (prev, Some(t));
            last = Some((i, t));
        }
        // A run still open here goes on past the epipole, where the two sweeps are joined.
        last
    }

    /// At the end of a run whose last two texels spread apart, the last one's footprint grows
    /// forward.
    fn end_run(
        &mut self,
        before: Option<Moved>,
        last: Option<Moved>,
        spreads: &impl Fn(&Moved, &Moved) -> bool,
    ) {
        if let (Some(b), Some(e)) = (before, last)
            && spreads(&b, &e)
        {
            self.extend(&e, &b);
        }
    }

    /// Covers the empty texels within the warped half-footprint of `e`, the texel ending a run,
    /// on the side away from its neighbour `n`: as far as half the spacing between the two, at
    /// most [`MAX_EXTENSION`] texels.
    fn extend(&mut self, e: &Moved, n: &Moved) {
        let reach = ((e.x - n.x).abs() * 0.5).min(MAX_EXTENSION);
        if reach <= 0.5 {
            return;
        }
        let dir = (e.x - n.x).signum();
        let own = floor_i64(e.x);
        let far = e.x + dir * reach;
        let (lo, hi) = (floor_i64(e.x.min(far)), floor_i64(e.x.max(far)));
        for j in lo..=hi {
            let along = (texel_centre(j as f64) - e.x) * dir;
            let k = j + self.offset;
            if j == own || along <= 0.0 || along > reach || k < 0 || k >= self.color.len() as i64 {
                continue;
            }
            let k = k as usize;
            if self.flag[k] == flag::EMPTY {
                self.color[k] = e.color;
                self.d[k] = e.d;
                self.code[k] = e.code;
                self.flag[k] = flag::EXTENDED | (e.flag & OFF_GRID);
            }
        }
    }

    /// Writes `t` where it lands.
    #[inline]
    fn put(&mut self, t: &Moved) {
        let j = floor_i64(t.x) + self.offset;
        if j < 0 || j >= self.color.len() as i64 {
            self.dropped += 1;
            return;
        }
        let j = j as usize;
        self.color[j] = t.color;
        self.d[j] = t.d;
        self.code[j] = t.code;
        self.flag[j] = t.flag;
    }

    /// Fills the texels strictly between where `p` and `q` land by interpolating the two.
    fn fill(&mut self, p: &Moved, q: &Moved) {
        let (lo, hi) = if p.x < q.x { (p.x, q.x) } else { (q.x, p.x) };
        let first = (floor_i64(lo) + 1 + self.offset).max(0);
        let end = (floor_i64(hi) + self.offset).min(self.color.len() as i64);
        if first >= end {
            return;
        }
        let inv = 1.0 / (q.x - p.x);
        for j in first..end {
            let centre = texel_centre((j - self.offset) as f64);
            let s = ((centre - p.x) * inv).clamp(0.0, 1.0) as f32;
            let j = j as usize;
            self.color[j] = lerp8(p.color, q.color, s);
            self.d[j] = p.d + (q.d - p.d) * s;
            self.code[j] = 0;
            // What lies between an extended texel and another is extended too.
            let extended = (p.flag & KIND) == flag::EXTENDED || (q.flag & KIND) == flag::EXTENDED;
            let kind = if extended {
                flag::EXTENDED
            } else {
                flag::INTERPOLATED
            };
            self.flag[j] = kind | OFF_GRID;
        }
    }
}

/// Per-channel interpolation of two encoded colours.
#[inline]
fn lerp8(a: Srgba8, b: Srgba8, s: f32) -> Srgba8 {
    std::array::from_fn(|c| (a[c] as f32 + (b[c] as f32 - a[c] as f32) * s + 0.5) as u8)
}

#[cfg(test)]
pub(crate) mod tests_support {
    use super::super::{Displacements, ReliefFrame, ReliefImpostor};
    use glam::DVec3;

    /// A frame with unit texels on z = 0, `f = +z`, and an impostor of `n²` texels with the
    /// given displacements (`None`: background).
    pub(crate) fn bumped(n: u32, height: impl Fn(u32, u32) -> Option<f32>) -> ReliefImpostor {
        let frame = ReliefFrame {
            origin: DVec3::ZERO,
            a: DVec3::X,
            b: DVec3::NEG_Y,
            f: DVec3::Z,
            width: n,
            height: n,
            max_depth: 4.0,
        };
        let mut color = Vec::new();
        let mut depth = Vec::new();
        for v in 0..n {
            for u in 0..n {
                match height(u, v) {
                    Some(d) => {
                        // Blue holds the height (of 4), for the tests to read back.
                        let q = |x: f32| (x * 255.0).round() as u8;
                        color.push([
                            q(u as f32 / n as f32),
                            q(v as f32 / n as f32),
                            q(d / 4.0),
                            255,
                        ]);
                        depth.push(d);
                    }
                    None => {
                        color.push([0; 4]);
                        depth.push(0.0);
                    }
                }
            }
        }
        ReliefImpostor {
            frame,
            eye: DVec3::new(0.0, 0.0, 10.0),
            color,
            depth: Displacements::F32(depth),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::Displacements;
    use super::tests_support::bumped;
    use super::*;

    #[test]
    fn the_paper_case_and_collinearity() {
        // a = x̂, b = −ŷ here; the check case of docs/conventions.md §5.2 in this frame, and
        // random points: eye, texel point and warped base point lie on one line.
        let imp = bumped(8, |_, _| Some(0.0));
        let fr = imp.frame;
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..1000 {
            let eye = DVec3::new(rnd() * 20.0 - 10.0, rnd() * 20.0 - 10.0, 1.0 + rnd() * 10.0);
            let k = Coefficients::new(&fr, Eye::Point(eye)).unwrap();
            let (u, v) = (rnd() * 8.0, rnd() * 8.0);
            let d = rnd() * (eye.z - 0.1).min(4.0);
            let (ui, vi) = (k.warp_u(u, d).unwrap(), k.warp_v(v, d).unwrap());
            let x = fr.point(u, v, d);
            let base = fr.point(ui, vi, 0.0);
            let off_line = (x - eye).cross(base - eye).length() / (base - eye).length();
            assert!(off_line < 1e-9, "{off_line}");
            // k3 = −1/h and the closed form u_i = (u h − u_e d)/(h − d).
            assert!((k.k3 + 1.0 / eye.z).abs() < 1e-12);
            let ue = fr.coordinates(eye).x;
            assert!((ui - (u * eye.z - ue * d) / (eye.z - d)).abs() < 1e-9);
        }
        // Zero displacement: the identity.
        let k = Coefficients::new(&fr, Eye::Point(DVec3::new(3.0, -2.0, 5.0))).unwrap();
        assert_eq!(k.warp_u(2.5, 0.0), Some(2.5));
        // Behind the plane: no warp.
        assert!(Coefficients::new(&fr, Eye::Point(DVec3::new(3.0, 2.0, -1.0))).is_none());
    }

    #[test]
    fn warping_to_the_source_view_is_the_identity() {
        let imp = bumped(32, |u, v| {
            let (x, y) = (u as f32 - 16.0, v as f32 - 16.0);
            (x * x + y * y < 150.0).then(|| (3.0 - (x * x + y * y) / 50.0).max(0.0))
        });
        let p = prewarp(&imp, Eye::Direction(DVec3::Z), false).unwrap();
        assert_eq!(p.interpolated, 0);
        let (mx, my) = (p.margin.0 as usize, p.margin.1 as usize);
        for v in 0..32 {
            for u in 0..32 {
                let i = v * 32 + u;
                let j = (v + my) * p.width as usize + u + mx;
                assert_eq!(p.color[j], imp.color[i]);
                let expect = if imp.covered(i) {
                    flag::DIRECT
                } else {
                    flag::EMPTY
                };
                assert_eq!(p.flags[j], expect);
            }
        }
    }

    #[test]
    fn a_step_keeps_the_taller_texel_from_both_sides() {
        // A row: a tall block in the middle of a flat floor. From either side, the block's top
        // texels survive where they overlap the floor (occlusion-compatible order).
        let imp = bumped(16, |u, _| {
            Some(if (6..10).contains(&u) { 3.0 } else { 0.0 })
        });
        for ex in [-20.0, 40.0] {
            let eye = DVec3::new(ex, -8.0, 8.0);
            let p = prewarp(&imp, Eye::Point(eye), false).unwrap();
            let k = Coefficients::new(&imp.frame, Eye::Point(eye)).unwrap();
            // Every block texel's warped position holds a block texel (b = 3.0 in blue).
            for u in 6..10 {
                let x = k.warp_u(u as f64 + 0.5, 3.0).unwrap().floor() as i64 + p.margin.0 as i64;
                let y = k.warp_v(8.5, 3.0).unwrap().floor() as i64 + p.margin.1 as i64;
                let j = y as usize * p.width as usize + x as usize;
                assert_eq!(p.color[j][2], 191, "eye x {ex}, texel {u}");
            }
        }
    }

    #[test]
    fn interpolated_texels_are_counted_as_a_hand_count_says() {
        // One row of 4 texels, heights 0, 0, 2, 2, eye straight above texel 0.5 at height 4:
        // u' = (u h − u_e d)/(h − d) with u_e = 0.5, h = 4. Centres 0.5, 1.5 stay; 2.5 → 4.5,
        // 3.5 → 6.5. So columns 0, 1, 4, 6 are direct, 2, 3 (between 1.5 and 4.5) and 5 are
        // interpolated; texel 3, the run's end, covers [5.5, 7.5] once warped, so column 7
        // (centre 7.5) is extended, and counted as neither.
        let imp = bumped(4, |u, v| (v == 1).then_some(if u < 2 { 0.0 } else { 2.0 }));
        // Rows: the eye sits above row 1's centre, so v is not moved.
        let eye = imp.frame.point(0.5, 1.5, 4.0);
        let p = prewarp(&imp, Eye::Point(eye), false).unwrap();
        let row = (1 + p.margin.1 as usize) * p.width as usize;
        let flags: Vec<u8> = (0..8)
            .map(|u| p.flags[row + p.margin.0 as usize + u])
            .collect();
        use flag::{DIRECT as D, EXTENDED as X, INTERPOLATED as I};
        assert_eq!(flags, vec![D, D, I, I, D, I, D, X]);
        assert_eq!((p.direct, p.interpolated, p.dropped), (4, 3, 0));
        assert!((p.interpolated_ratio() - 0.75).abs() < 1e-12);
    }

    #[test]
    fn the_lookup_table_warp_equals_the_direct_one() {
        let mut imp = bumped(48, |u, v| {
            let (x, y) = (u as f32 - 24.0, v as f32 - 20.0);
            (x * x + y * y < 400.0).then(|| 4.0 * (1.0 - (x * x + y * y) / 400.0))
        });
        // Quantise to eight bits.
        let codes: Vec<u8> = match &imp.depth {
            Displacements::F32(d) => d.iter().map(|&d| (d / 4.0 * 255.0).round() as u8).collect(),
            Displacements::U8(_) => unreachable!(),
        };
        imp.depth = Displacements::U8(codes);
        for eye in [
            DVec3::new(10.0, -30.0, 12.0),
            DVec3::new(-20.0, 5.0, 30.0),
            DVec3::new(24.0, -24.0, 9.0),
        ] {
            let a = prewarp(&imp, Eye::Point(eye), false).unwrap();
            let b = prewarp(&imp, Eye::Point(eye), true).unwrap();
            assert!(a.interpolated > 0);
            assert_eq!(a.color, b.color);
            assert_eq!(a.displacement, b.displacement);
            assert_eq!(a.flags, b.flags);
        }
    }

    #[test]
    fn thread_count_does_not_change_the_warp() {
        let imp = bumped(64, |u, v| Some(((u * 7 + v * 3) % 11) as f32 * 0.3));
        let eye = Eye::Point(DVec3::new(20.0, -40.0, 25.0));
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let a = one.install(|| prewarp(&imp, eye, false).unwrap());
        let b = prewarp(&imp, eye, false).unwrap();
        assert_eq!(a.color, b.color);
        assert_eq!(a.flags, b.flags);
    }
}
