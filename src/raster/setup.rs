//! Triangle setup: world-space clipping against the camera's near boundary, projection (once
//! per mesh vertex), guard-band clipping in image space, snapping to fixed point, attribute
//! planes, and binning into bands of rows.

use super::{ItemId, RasterStats, STRAIGHT_EDGE_TOLERANCE_PX};
use crate::camera::{ImagePoint, Projection};
use crate::geom::Mesh;
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// Sub-pixel precision: vertices snap to 1/2^SUBPIXEL_BITS of a pixel.
pub(super) const SUBPIXEL_BITS: u32 = 8;
/// One pixel in fixed point.
pub(super) const ONE: i64 = 1 << SUBPIXEL_BITS;
/// Half the guard band, in pixels: vertices are clipped to `[-GUARD, size + GUARD]` so the
/// integer edge functions (products of two coordinate differences) stay below 2^62.
pub(super) const GUARD: f64 = (1u64 << 20) as f64;

/// An affine function of image position: `f(x, y) = f0 + dfdx·(x − x0) + dfdy·(y − y0)`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Plane {
    pub f0: f64,
    pub dfdx: f64,
    pub dfdy: f64,
}

/// A triangle ready for scan conversion.
#[derive(Clone, Debug)]
pub(super) struct ScreenTri {
    /// Snapped corners, ordered so the doubled signed area is positive.
    pub fixed: [[i64; 2]; 3],
    /// Rows whose centres may be covered, inclusive, within the image.
    pub rows: (u32, u32),
    /// Columns whose centres may be covered, inclusive, within the image.
    pub cols: (u32, u32),
    /// Image position `(x0, y0)` the attribute planes are anchored at.
    pub origin: DVec2,
    /// `gd`, `inv_w`, then `inv_w·b0`, `inv_w·b1`, `inv_w·b2` (b = barycentrics of the source
    /// triangle).
    pub planes: [Plane; 5],
    /// Source object and triangle.
    pub item: ItemId,
}

/// A polygon corner during clipping: world point (before projection) or image point (after),
/// with the source triangle's barycentrics.
#[derive(Clone, Copy, Debug)]
struct Corner {
    world: DVec3,
    uv: DVec2,
    gd: f64,
    inv_w: f64,
    /// `inv_w·b` after projection; `b` before.
    q: DVec3,
}

/// Screen triangles binned by band, and the working memory that produces them — kept in the
/// [`super::RasterTarget`] so that rasterizing again into it allocates nothing (fresh
/// allocations of this size cost page faults that rival the rasterization itself).
///
/// Each input chunk of [`SETUP_CHUNK`] triangles holds its screen triangles once and, per band,
/// the indices of those touching it in input order: walking the chunks in order visits a band's
/// triangles in input order.
#[derive(Clone, Debug, Default)]
pub(super) struct Binned {
    chunks: Vec<BinnedChunk>,
    /// Per object, its vertices seen through the camera.
    seen: Vec<Vec<SeenVertex>>,
    /// The account's share for the arrays above, as large as they are.
    held: crate::memory::Held,
}

impl Binned {
    /// The input chunks, in input order.
    pub fn chunks(&self) -> &[BinnedChunk] {
        &self.chunks
    }

    /// Bytes its arrays hold now (what setting up again may reuse without allocating).
    fn bytes(&self) -> u64 {
        let seen: usize = self
            .seen
            .iter()
            .map(|s| s.capacity() * size_of::<SeenVertex>())
            .sum();
        let chunks: usize = (self.chunks.iter())
            .map(|c| c.tris.capacity() * size_of::<ScreenTri>() + c.order.capacity() * 4)
            .sum();
        (seen + chunks) as u64
    }
}

/// Bytes setting up `objects` takes: every vertex seen through the camera, every triangle set
/// up and listed in its band (most triangles touch one band; the estimate allows two).
fn setup_bytes(objects: &[&Mesh]) -> u64 {
    use crate::memory::times;
    let vertices: u64 = objects.iter().map(|m| m.positions.len() as u64).sum();
    let triangles: u64 = objects.iter().map(|m| m.triangles.len() as u64).sum();
    times(vertices, size_of::<SeenVertex>() as u64)
        .saturating_add(times(triangles, (size_of::<ScreenTri>() + 8) as u64))
}

/// The screen triangles of one input chunk, in input order, and their order by band.
#[derive(Clone, Debug, Default)]
pub(super) struct BinnedChunk {
    tris: Vec<ScreenTri>,
    /// Indices into `tris`, sorted by band (stable): band `b` is
    /// `order[band_start[b] .. band_start[b + 1]]`. A triangle spanning several bands appears
    /// in each.
    order: Vec<u32>,
    band_start: Vec<u32>,
}

impl BinnedChunk {
    /// The triangles of this chunk that touch band `band`, in input order.
    pub fn band(&self, band: usize) -> impl Iterator<Item = &ScreenTri> {
        self.order[self.band_start[band] as usize..self.band_start[band + 1] as usize]
            .iter()
            .map(|&i| &self.tris[i as usize])
    }

    /// Sets up the triangles `first .. first + count` of the concatenated objects and sorts
    /// them by band; returns the setup counters (`screen_triangles`, `clipped`, `curved`).
    fn fill<P: Projection>(
        &mut self,
        camera: &P,
        objects: &[&Mesh],
        seen: &[Vec<SeenVertex>],
        (first, count): (usize, usize),
        band_rows: u32,
    ) -> RasterStats {
        let (w, h) = camera.resolution();
        let band_count = h.div_ceil(band_rows) as usize;
        self.tris.clear();
        self.tris.reserve(count);
        let mut skip = first;
        let mut left = count;
        let mut stats = RasterStats::default();
        for (o, mesh) in objects.iter().enumerate() {
            let n = mesh.triangles.len();
            if skip >= n {
                skip -= n;
                continue;
            }
            let here = (n - skip).min(left);
            for t in skip..skip + here {
                let corners = mesh.triangles[t].map(|i| i as usize);
                let item = ItemId {
                    object: o as u32,
                    triangle: t as u32,
                };
                // Gathered one by one: as `corners.map(…)` this was a call writing the three
                // corners to memory, and set-up then waited on reading them back — about a
                // tenth of a plain rasterization of the bunny.
                let seen = &seen[o];
                let corner = |i: usize| (mesh.positions[i].as_dvec3(), seen[i]);
                let corners = [corner(corners[0]), corner(corners[1]), corner(corners[2])];
                match corners.map(|c| c.1.image) {
                    [Some(a), Some(b), Some(c)] => {
                        let bound = camera.midpoint_deviation_bound(&[a, b, c]);
                        stats.curved += u64::from(bound > STRAIGHT_EDGE_TOLERANCE_PX);
                    }
                    _ => stats.clipped += 1,
                }
                setup_triangle(camera, corners, item, w, h, &mut self.tris);
            }
            (skip, left) = (0, left - here);
            if left == 0 {
                break;
            }
        }
        // Counting sort of (triangle, band) pairs by band, stable in input order.
        let bands_of =
            |t: &ScreenTri| (t.rows.0 / band_rows) as usize..=(t.rows.1 / band_rows) as usize;
        self.band_start.clear();
        self.band_start.resize(band_count + 1, 0);
        for t in &self.tris {
            for b in bands_of(t) {
                self.band_start[b + 1] += 1;
            }
        }
        for b in 0..band_count {
            self.band_start[b + 1] += self.band_start[b];
        }
        self.order.clear();
        self.order.resize(self.band_start[band_count] as usize, 0);
        // The next free slot of each band in `order`.
        let mut next_slot = self.band_start.clone();
        for (i, t) in self.tris.iter().enumerate() {
            for b in bands_of(t) {
                self.order[next_slot[b] as usize] = i as u32;
                next_slot[b] += 1;
            }
        }
        stats.screen_triangles = self.tris.len() as u64;
        stats
    }
}

/// A mesh vertex seen through the camera, computed once per vertex rather than once per
/// triangle corner (each vertex of a closed mesh is a corner of about six triangles).
#[derive(Clone, Copy, Debug)]
struct SeenVertex {
    /// `clip_distance` of the vertex.
    clip: f64,
    /// Its image, when it projects inside the guard band with a finite, positive `gd`.
    image: Option<ImagePoint>,
}

/// Sets up every triangle of every object and bins it into bands of `band_rows` rows, into
/// `binned` (parallel over fixed chunks of the input, so the result does not depend on the
/// thread count).
pub(super) fn screen_triangles<P: Projection>(
    camera: &P,
    objects: &[&Mesh],
    band_rows: u32,
    binned: &mut Binned,
) -> Result<RasterStats, crate::memory::OverBudget> {
    // What the arrays kept from the last set-up cannot hold is checked before it is allocated.
    let (needed, kept) = (setup_bytes(objects), binned.bytes());
    if needed > kept {
        let triangles: usize = objects.iter().map(|m| m.triangles.len()).sum();
        crate::memory::check(
            || format!("rasterizing {triangles} triangles"),
            needed - kept,
        )?;
    }
    let stats = set_up_all(camera, objects, band_rows, binned);
    binned.held.set(binned.bytes());
    Ok(stats)
}

fn set_up_all<P: Projection>(
    camera: &P,
    objects: &[&Mesh],
    band_rows: u32,
    binned: &mut Binned,
) -> RasterStats {
    binned.seen.resize_with(objects.len(), Vec::new);
    for (seen, m) in binned.seen.iter_mut().zip(objects) {
        seen.clear();
        seen.par_extend(m.positions.par_iter().map(|p| {
            let x = p.as_dvec3();
            let (clip, image) = camera.clip_and_project(x);
            let image = image.filter(|q| {
                q.gd > 0.0 && q.gd.is_finite() && q.uv.x.abs() < GUARD && q.uv.y.abs() < GUARD
            });
            SeenVertex { clip, image }
        }));
    }
    let total: usize = objects.iter().map(|m| m.triangles.len()).sum();
    let chunk_count = total.div_ceil(SETUP_CHUNK);
    binned.chunks.resize_with(chunk_count, BinnedChunk::default);
    let seen = &binned.seen;
    let per_chunk: Vec<RasterStats> = binned
        .chunks
        .par_iter_mut()
        .enumerate()
        .map(|(c, chunk)| {
            let first = c * SETUP_CHUNK;
            let range = (first, SETUP_CHUNK.min(total - first));
            chunk.fill(camera, objects, seen, range, band_rows)
        })
        .collect();
    per_chunk.into_iter().fold(
        RasterStats {
            triangles_in: total as u64,
            ..RasterStats::default()
        },
        |a, b| a + b,
    )
}

/// Triangles set up per parallel task. Small enough that a chunk's screen triangles (about
/// 100 kB) stay below the size at which the system allocator maps fresh pages: with 2048 a
/// fresh rasterization of the bunny spent more time in page faults than in drawing.
const SETUP_CHUNK: usize = 512;

fn setup_triangle<P: Projection>(
    camera: &P,
    corners: [(DVec3, SeenVertex); 3],
    item: ItemId,
    w: u32,
    h: u32,
    out: &mut Vec<ScreenTri>,
) {
    // Fast path: wholly inside the near boundary and the guard band — no clipping.
    let [(pa, a), (pb, b), (pc, c)] = corners;
    if let (Some(ia), Some(ib), Some(ic)) = (a.image, b.image, c.image) {
        let corner = |q: ImagePoint, world, b: DVec3| Corner {
            world,
            uv: q.uv,
            gd: q.gd,
            inv_w: q.inv_w,
            q: b * q.inv_w,
        };
        let c3 = [
            corner(ia, pa, DVec3::X),
            corner(ib, pb, DVec3::Y),
            corner(ic, pc, DVec3::Z),
        ];
        out.extend(screen_triangle(c3, item, w, h));
        return;
    }
    setup_clipped(
        camera,
        corners.map(|c| c.0),
        corners.map(|c| c.1.clip),
        item,
        w,
        h,
        out,
    );
}

/// The general path: clip to the near boundary in world space, then to the guard band.
fn setup_clipped<P: Projection>(
    camera: &P,
    p: [DVec3; 3],
    d: [f64; 3],
    item: ItemId,
    w: u32,
    h: u32,
    out: &mut Vec<ScreenTri>,
) {
    let corner = |world, b| Corner {
        world,
        uv: DVec2::ZERO,
        gd: 0.0,
        inv_w: 0.0,
        q: b,
    };
    let mut poly = vec![
        corner(p[0], DVec3::X),
        corner(p[1], DVec3::Y),
        corner(p[2], DVec3::Z),
    ];
    // 1. Near boundary, in world space (clip_distance is affine, so linear interpolation is exact).
    if d.iter().any(|&x| x < 0.0) {
        if d.iter().all(|&x| x < 0.0) {
            return;
        }
        poly = crate::geom::clip_polygon(
            &poly,
            |c| camera.clip_distance(c.world),
            |a, b, s| Corner {
                world: a.world + (b.world - a.world) * s,
                q: a.q + (b.q - a.q) * s,
                ..*a
            },
        );
        if poly.len() < 3 {
            return;
        }
    }
    // 2. Project.
    for c in &mut poly {
        let Some(ip) = camera.project(c.world) else {
            return;
        };
        if !(ip.uv.is_finite() && ip.gd.is_finite() && ip.gd > 0.0) {
            return;
        }
        c.uv = ip.uv;
        c.gd = ip.gd;
        c.inv_w = ip.inv_w;
        c.q *= ip.inv_w;
    }
    // 3. Guard band, in image space (gd, 1/w and b/w are affine in image space).
    let (wf, hf) = (w as f64, h as f64);
    let bounds = [
        (DVec2::X, GUARD),       // x ≥ −G
        (-DVec2::X, wf + GUARD), // x ≤ w + G
        (DVec2::Y, GUARD),       // y ≥ −G
        (-DVec2::Y, hf + GUARD), // y ≤ h + G
    ];
    for (n, off) in bounds {
        if poly.iter().any(|c| n.dot(c.uv) + off < 0.0) {
            poly = crate::geom::clip_polygon(
                &poly,
                |c| n.dot(c.uv) + off,
                |a, b, s| Corner {
                    uv: a.uv + (b.uv - a.uv) * s,
                    gd: a.gd + (b.gd - a.gd) * s,
                    inv_w: a.inv_w + (b.inv_w - a.inv_w) * s,
                    q: a.q + (b.q - a.q) * s,
                    ..*a
                },
            );
            if poly.len() < 3 {
                return;
            }
        }
    }
    // 4. Fan-triangulate, snap, orient, bound.
    for k in 1..poly.len() - 1 {
        out.extend(screen_triangle([poly[0], poly[k], poly[k + 1]], item, w, h));
    }
}

/// `x` on the sub-pixel grid, to the nearest step (ties away from zero, to within an ulp).
/// Added and truncated rather than `f64::round`, which without SSE 4.1 is a library call — one
/// per corner coordinate of every triangle. `|x| <` [`GUARD`] keeps it well inside `i64`.
fn snap(x: f64) -> i64 {
    let steps = x * ONE as f64;
    (steps + 0.5f64.copysign(steps)) as i64
}

fn screen_triangle(c: [Corner; 3], item: ItemId, w: u32, h: u32) -> Option<ScreenTri> {
    let mut fixed = c.map(|c| [snap(c.uv.x), snap(c.uv.y)]);
    let area2 = (fixed[1][0] - fixed[0][0]) * (fixed[2][1] - fixed[0][1])
        - (fixed[1][1] - fixed[0][1]) * (fixed[2][0] - fixed[0][0]);
    if area2 == 0 {
        return None;
    }
    if area2 < 0 {
        fixed.swap(1, 2);
    }
    // Pixel (i, j) is a candidate when its centre (i + ½, j + ½) lies in the snapped box.
    let min = |k: usize| fixed.iter().map(|v| v[k]).min().unwrap_or(0);
    let max = |k: usize| fixed.iter().map(|v| v[k]).max().unwrap_or(0);
    let first = |lo: i64| (lo - ONE / 2 + ONE - 1).div_euclid(ONE); // ceil((lo − ½)/1)
    let last = |hi: i64| (hi - ONE / 2).div_euclid(ONE); // floor(hi − ½)
    let (x0, x1) = (first(min(0)).max(0), last(max(0)).min(w as i64 - 1));
    let (y0, y1) = (first(min(1)).max(0), last(max(1)).min(h as i64 - 1));
    if x0 > x1 || y0 > y1 {
        return None;
    }
    let origin = c[0].uv;
    let values = |c: &Corner| [c.gd, c.inv_w, c.q.x, c.q.y, c.q.z];
    Some(ScreenTri {
        fixed,
        rows: (y0 as u32, y1 as u32),
        cols: (x0 as u32, x1 as u32),
        origin,
        planes: planes(
            [c[1].uv - origin, c[2].uv - origin],
            [values(&c[0]), values(&c[1]), values(&c[2])],
        ),
        item,
    })
}

/// The affine functions through the corners' values `f[corner][k]`, from unsnapped positions
/// (`e` = corners 1 and 2 relative to corner 0).
fn planes(e: [DVec2; 2], f: [[f64; 5]; 3]) -> [Plane; 5] {
    let [e1, e2] = e;
    let det = e1.x * e2.y - e1.y * e2.x;
    if det.abs() < 1e-12 {
        // Sliver: degenerate in image space; use constants, the corners' means.
        return std::array::from_fn(|k| Plane {
            f0: (f[0][k] + f[1][k] + f[2][k]) / 3.0,
            dfdx: 0.0,
            dfdy: 0.0,
        });
    }
    // One division for the ten gradients.
    let inv_det = 1.0 / det;
    std::array::from_fn(|k| {
        let (f0, f1, f2) = (f[0][k], f[1][k], f[2][k]);
        Plane {
            f0,
            dfdx: ((f1 - f0) * e2.y - (f2 - f0) * e1.y) * inv_det,
            dfdy: ((f2 - f0) * e1.x - (f1 - f0) * e2.x) * inv_det,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snapping_rounds_to_the_nearest_sub_pixel_step() {
        let step = 1.0 / ONE as f64;
        for &x in &[0.0, 0.3, 1.0, 511.49, -0.3, -7.77, 1234.567, -65_000.123] {
            let expected = (x * ONE as f64).round() as i64;
            assert_eq!(snap(x), expected, "{x}");
            // Just either side of a half step: the nearer grid point.
            let half = (expected as f64 + 0.5) * step;
            assert_eq!(snap(half - 1e-6), expected, "{x}");
            assert_eq!(snap(half + 1e-6), expected + 1, "{x}");
        }
        assert_eq!(snap(0.5 * step), 1);
        assert_eq!(snap(-0.5 * step), -1);
    }
}
