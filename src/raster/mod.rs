//! A triangle rasterizer generic over the camera's [`Projection`] (papers 1, 4, 5; the
//! impostor construction of paper 1 §3.1 / docs/conventions.md §2.2 runs through it).
//!
//! Pipeline: `setup` projects every mesh vertex once, clips each triangle where the camera's
//! `clip_distance` is negative (in world space), clips to a guard band, snaps the corners to
//! 1/256 pixel and bins the screen triangles into bands of [`BAND_ROWS`] rows; bands are
//! rasterized in parallel by `scan`, each owning its rows of every buffer. A [`RasterTarget`]
//! keeps the set-up triangles' memory, so drawing into it again allocates nothing; drawing over
//! it ([`rasterize_over`]) composes the images of several cameras (a graph camera's frusta).
//! Or set-up and drawing are two calls ([`set_up`], then [`draw_depth_then`]): the caller reads
//! set-up's counters before deciding what to draw, only a depth image is kept, and each band's
//! item and attribute rows are scratch, finished by the caller's pass as soon as the band is
//! drawn.
//!
//! Invariants:
//! - **Watertight, top-left rule**: coverage uses exact integer edge functions on snapped
//!   vertices; a pixel centre on an edge shared by two triangles belongs to exactly one of them.
//! - **Depth**: `gd` (docs/conventions.md §1.2) is interpolated linearly in image space from the
//!   unsnapped vertices; a fragment is kept when its `gd` is strictly larger (nearer) than the
//!   stored one, so the earlier triangle wins a tie. Empty pixels hold `gd = 0`.
//! - **Perspective-correct attributes**: `b/w` and `1/w` are interpolated linearly and divided,
//!   which is exact for any camera that is projective on planes (pinhole, orthographic, each
//!   graph-camera frustum).
//! - **Deterministic**: each band processes triangles in input order; the result is the same for
//!   any thread count.
//! - `raster` never knows which camera it projects through.

mod scan;
mod setup;

use crate::camera::Projection;
use crate::frame::{FrameError, Image};
use crate::geom::Mesh;
use glam::Vec3;
use rayon::prelude::*;

/// Rows per parallel band (the tile height).
pub const BAND_ROWS: u32 = 16;

/// How far, in pixels, a curved camera's image of an edge may stray from the straight edge the
/// rasterizer draws before the triangle counts as [`RasterStats::curved`] (the 0.5 px of
/// docs/conventions.md §2.2).
pub const STRAIGHT_EDGE_TOLERANCE_PX: f64 = 0.5;

/// Which triangle of which object covers a pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ItemId {
    /// Index of the object in the slice given to [`rasterize`].
    pub object: u32,
    /// Index of the triangle in that object's mesh.
    pub triangle: u32,
}

impl ItemId {
    /// The id of an empty pixel.
    pub const NONE: ItemId = ItemId {
        object: u32::MAX,
        triangle: u32::MAX,
    };
    /// True for [`ItemId::NONE`].
    pub fn is_none(&self) -> bool {
        *self == Self::NONE
    }
}

/// One covered pixel centre that passed the depth test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fragment {
    /// Column.
    pub x: u32,
    /// Row.
    pub y: u32,
    /// Generalized depth at the pixel centre.
    pub gd: f32,
    /// Perspective-correct barycentric weights of the source triangle's three corners.
    pub bary: Vec3,
    /// What was drawn.
    pub item: ItemId,
}

/// The per-fragment hook: computes what a fragment that passed the depth test writes into the
/// attribute image (a normal, a world position, a colour …).
pub trait FragmentShader: Sync {
    /// The per-pixel attribute.
    type Output: Copy + Send + Sync;
    /// The attribute of a fragment.
    fn shade(&self, fragment: &Fragment) -> Self::Output;
}

/// A shader that writes nothing: for depth and item buffers only.
pub struct NoAttributes;

impl FragmentShader for NoAttributes {
    type Output = ();
    fn shade(&self, _: &Fragment) {}
}

/// A shader that writes the fragment itself (a visibility buffer for deferred shading).
pub struct StoreFragment;

impl FragmentShader for StoreFragment {
    type Output = Option<Fragment>;
    fn shade(&self, f: &Fragment) -> Option<Fragment> {
        Some(*f)
    }
}

/// What a rasterization produces.
#[derive(Clone, Debug)]
pub struct RasterTarget<T> {
    /// Generalized depth (0 = empty).
    pub gd: Image<f32>,
    /// Item buffer.
    pub item: Image<ItemId>,
    /// The shader's output ([`FragmentShader::Output`]); `empty` where nothing was drawn.
    pub attributes: Image<T>,
    /// Set-up triangles: working memory kept for the next rasterization into this target.
    binned: setup::Binned,
}

impl<T: Copy + Send + Sync> RasterTarget<T> {
    /// An empty `width × height` target, attributes filled with `empty`.
    pub fn new(width: u32, height: u32, empty: T) -> Result<RasterTarget<T>, FrameError> {
        Ok(RasterTarget {
            gd: Image::new(width, height, 0.0f32)?,
            item: Image::new(width, height, ItemId::NONE)?,
            attributes: Image::new(width, height, empty)?,
            binned: setup::Binned::default(),
        })
    }
}

/// Counters of one rasterization (summed over bands in a fixed order).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RasterStats {
    /// Triangles given.
    pub triangles_in: u64,
    /// Screen triangles after clipping (a clipped triangle may become several).
    pub screen_triangles: u64,
    /// Triangles wholly outside the camera's domain or image.
    pub culled: u64,
    /// Pixel centres covered (before the depth test).
    pub fragments: u64,
    /// Fragments that passed the depth test.
    pub written: u64,
    /// Triangles with a corner outside the camera's domain or guard band (clipped in setup).
    pub clipped: u64,
    /// Wholly imaged triangles whose edges the camera may curve by more than
    /// [`STRAIGHT_EDGE_TOLERANCE_PX`] ([`Projection::midpoint_deviation_bound`]): drawn with
    /// straight edges, they may be misplaced. Always 0 for cameras projective on planes; a
    /// curved camera's caller tessellates when it is not (or when `clipped` is not).
    pub curved: u64,
}

impl RasterStats {
    /// Whether set-up found triangles a curved camera may misplace when drawn straight
    /// ([`RasterStats::curved`]) or that it had to clip ([`RasterStats::clipped`]): through a
    /// curved camera, a caller that tessellates then draws the tessellation instead.
    pub fn has_curved_or_clipped(&self) -> bool {
        self.curved + self.clipped > 0
    }
}

impl std::ops::Add for RasterStats {
    type Output = RasterStats;
    fn add(self, o: RasterStats) -> RasterStats {
        RasterStats {
            triangles_in: self.triangles_in + o.triangles_in,
            screen_triangles: self.screen_triangles + o.screen_triangles,
            culled: self.culled + o.culled,
            fragments: self.fragments + o.fragments,
            written: self.written + o.written,
            clipped: self.clipped + o.clipped,
            curved: self.curved + o.curved,
        }
    }
}

/// Rasterizes `objects` (object id = index) through `camera`, calling `shader` for each
/// fragment that passes the depth test. `empty` fills the attribute image where nothing is drawn.
pub fn rasterize<P: Projection, S: FragmentShader>(
    camera: &P,
    objects: &[&Mesh],
    shader: &S,
    empty: S::Output,
) -> Result<(RasterTarget<S::Output>, RasterStats), FrameError> {
    rasterize_new(camera, objects, (shader, empty), None)
}

/// Rasterizes into a new target, under `ceiling` if given ([`rasterize_behind`]).
fn rasterize_new<P: Projection, S: FragmentShader>(
    camera: &P,
    objects: &[&Mesh],
    (shader, empty): (&S, S::Output),
    ceiling: Option<&[f32]>,
) -> Result<(RasterTarget<S::Output>, RasterStats), FrameError> {
    let (w, h) = camera.resolution();
    let mut target = RasterTarget::new(w, h, empty)?;
    // New, so already clear.
    let stats = draw_target(
        camera,
        objects,
        (shader, empty),
        &mut target,
        (RowsHold::Empty, ceiling),
    )?;
    Ok((target, stats))
}

/// [`rasterize`] behind a layer already drawn, for depth peeling: a fragment is drawn only
/// where its `gd` is strictly below `ceiling`'s at its pixel (0 there: nothing is drawn), so
/// each pixel keeps the nearest surface behind the ceiling. With each layer's depth, a little
/// nearer the camera than drawn, as the next one's ceiling, the layers peel a scene front to
/// back (Everitt, "Interactive Order-Independent Transparency", 2001).
///
/// # Errors
/// When the ceiling is not of the camera's size, or the image size is refused.
pub fn rasterize_behind<P: Projection, S: FragmentShader>(
    camera: &P,
    objects: &[&Mesh],
    shader: &S,
    empty: S::Output,
    ceiling: &Image<f32>,
) -> Result<(RasterTarget<S::Output>, RasterStats), FrameError> {
    let (w, h) = camera.resolution();
    if ceiling.size() != (w, h) {
        let (cw, ch) = ceiling.size();
        return Err(FrameError::InvalidSize {
            width: cw as u64,
            height: ch as u64,
            reason: "the ceiling is not of the camera's size",
        });
    }
    rasterize_new(camera, objects, (shader, empty), Some(ceiling.pixels()))
}

/// [`rasterize`] into an existing target, reusing its memory (for images rebuilt every frame):
/// each band clears its rows in parallel before drawing. A target of another size is
/// reallocated.
pub fn rasterize_into<P: Projection, S: FragmentShader>(
    camera: &P,
    objects: &[&Mesh],
    shader: &S,
    empty: S::Output,
    target: &mut RasterTarget<S::Output>,
) -> Result<RasterStats, FrameError> {
    let (w, h) = camera.resolution();
    let rows = if target.gd.size() == (w, h) && target.attributes.size() == (w, h) {
        RowsHold::Old
    } else {
        *target = RasterTarget::new(w, h, empty)?;
        RowsHold::Empty
    };
    Ok(draw_target(
        camera,
        objects,
        (shader, empty),
        target,
        (rows, None),
    )?)
}

/// Rasterizes `objects` into `target` as it is, without clearing it: the depth test compares
/// with what it already holds, so draws through several cameras of one image compose — a
/// graph camera's frusta, each drawing the triangles clipped to it (paper 1 §4.5). A fragment
/// replaces a pixel only when strictly nearer, so ties keep the earlier draw.
///
/// # Errors
/// When `target` is not of the camera's size.
pub fn rasterize_over<P: Projection, S: FragmentShader>(
    camera: &P,
    objects: &[&Mesh],
    shader: &S,
    empty: S::Output,
    target: &mut RasterTarget<S::Output>,
) -> Result<RasterStats, FrameError> {
    let (w, h) = camera.resolution();
    if target.gd.size() != (w, h) || target.attributes.size() != (w, h) {
        let (tw, th) = target.gd.size();
        return Err(FrameError::InvalidSize {
            width: tw as u64,
            height: th as u64,
            reason: "the target is not of the camera's size",
        });
    }
    Ok(draw_target(
        camera,
        objects,
        (shader, empty),
        target,
        (RowsHold::Drawn, None),
    )?)
}

/// One covered pixel of [`fragments`]: no depth test decided it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Covered {
    /// Row-major pixel index.
    pub pixel: u32,
    /// Generalized depth at the pixel centre.
    pub gd: f32,
    /// What covers it.
    pub item: ItemId,
}

/// Every fragment of `objects` through `camera`, hidden or not — what an A-buffer holds — in
/// bands of [`BAND_ROWS`] rows, each band's fragments in input-triangle order (so the result
/// does not depend on the thread count). Coverage follows the same watertight top-left rule as
/// [`rasterize`]: the nearest of a pixel's fragments is the one `rasterize` keeps.
///
/// # Errors
/// When the camera's image size is refused.
pub fn fragments<P: Projection>(
    camera: &P,
    objects: &[&Mesh],
) -> Result<Vec<Vec<Covered>>, FrameError> {
    let (w, h) = camera.resolution();
    crate::frame::check_size(w as u64, h as u64)?;
    let mut binned = setup::Binned::default();
    setup::screen_triangles(camera, objects, BAND_ROWS, &mut binned)?;
    let bands = h.div_ceil(BAND_ROWS) as usize;
    Ok((0..bands)
        .into_par_iter()
        .map(|band| {
            let first = band as u32 * BAND_ROWS;
            let rows = (first, (first + BAND_ROWS).min(h) - 1);
            let mut out = Vec::new();
            for chunk in binned.chunks() {
                for t in chunk.band(band) {
                    scan::cover(t, w, rows, |pixel, gd| {
                        out.push(Covered {
                            pixel: pixel as u32,
                            gd,
                            item: t.item,
                        })
                    });
                }
            }
            out
        })
        .collect())
}

/// One band of rows just drawn, handed to the `finish` callback of [`draw_depth_then`].
pub struct FinishedBand<'a, T> {
    /// Index of the band's first pixel in the row-major image (`first row × width`).
    pub first_pixel: usize,
    /// The columns, inclusive, outside which no triangle was drawn in this band: every pixel
    /// there is as the band was before drawing (`None`: no triangle at all).
    pub columns: Option<(u32, u32)>,
    /// The band's depth, item and attribute pixels, row-major. The depth is the target's: a
    /// finishing pass may refine it (an impostor through a curved camera moves each texel's
    /// `gd` onto the surface it stores).
    pub gd: &'a mut [f32],
    /// Item buffer of the band.
    pub item: &'a [ItemId],
    /// Attributes of the band.
    pub attributes: &'a [T],
}

/// Working memory that one rasterization leaves to the next: the set-up triangles and the
/// scratch rows of [`draw_depth_then`]. Keep it to draw again without allocating.
pub struct RasterMemory<T> {
    binned: setup::Binned,
    /// Item and attribute rows of one band each, lent to the bands being drawn.
    rows: std::sync::Mutex<Vec<BandScratch<T>>>,
}

impl<T> Default for RasterMemory<T> {
    fn default() -> Self {
        RasterMemory {
            binned: setup::Binned::default(),
            rows: std::sync::Mutex::new(Vec::new()),
        }
    }
}

/// The item and attribute rows of one band, as scratch.
type BandScratch<T> = (Vec<ItemId>, Vec<T>);

/// Triangles set up through one camera — projected, clipped, snapped and binned into bands —
/// held in a [`RasterMemory`], with set-up's counters: the first half of a depth pass. A caller
/// reads [`SetUp::stats`] and then draws it ([`draw_depth_then`]) or drops it and sets up
/// something else (a builder tessellates what a curved camera would misplace,
/// [`RasterStats::has_curved_or_clipped`], without drawing the mesh as it is first).
pub struct SetUp<'a, T> {
    memory: &'a mut RasterMemory<T>,
    stats: RasterStats,
    size: (u32, u32),
}

impl<T> SetUp<'_, T> {
    /// Set-up's counters: triangles kept, clipped, and that the camera may curve.
    pub fn stats(&self) -> RasterStats {
        self.stats
    }
}

/// Sets up `objects` (object id = index) through `camera` into `memory`; refused when what
/// `memory` cannot already hold would pass the memory budget.
pub fn set_up<'a, P: Projection, T>(
    camera: &P,
    objects: &[&Mesh],
    memory: &'a mut RasterMemory<T>,
) -> Result<SetUp<'a, T>, crate::memory::OverBudget> {
    let stats = setup::screen_triangles(camera, objects, BAND_ROWS, &mut memory.binned)?;
    Ok(SetUp {
        memory,
        stats,
        size: camera.resolution(),
    })
}

/// A depth image to draw into, and what it holds.
pub struct DepthTarget<'a> {
    /// Generalized depth, of the camera's size.
    pub gd: &'a mut Image<f32>,
    /// True when `gd` is all zeros (for example fresh from [`Image::zeroed`]): its rows are
    /// then drawn without being cleared, and rows nothing covers are never written.
    pub zeroed: bool,
}

/// Draws what was set up into a depth image alone: each band's item and attribute rows exist
/// only while it is drawn and finished. `finish` is called on each band of [`BAND_ROWS`] rows
/// as soon as it is drawn, while its pixels are in cache, with `outputs[band]` — for instance
/// that band's rows of other images: the deferred shading of a visibility buffer that is never
/// whole in memory (a whole one cost more in memory traffic than the rasterization itself).
///
/// # Errors
/// When `target.gd` is not of the set-up camera's size.
///
/// # Panics
/// When `outputs` does not hold one entry per band (`height.div_ceil(BAND_ROWS)`): a caller's
/// bug, not bad input.
pub fn draw_depth_then<S, O, F>(
    setup: SetUp<'_, S::Output>,
    shader: &S,
    empty: S::Output,
    target: DepthTarget<'_>,
    outputs: Vec<O>,
    finish: F,
) -> Result<RasterStats, FrameError>
where
    S: FragmentShader,
    O: Send,
    F: Fn(FinishedBand<'_, S::Output>, &mut O) + Sync,
{
    let (w, h) = setup.size;
    if target.gd.size() != (w, h) {
        let (gw, gh) = target.gd.size();
        return Err(FrameError::InvalidSize {
            width: gw as u64,
            height: gh as u64,
            reason: "the depth image is not of the camera's size",
        });
    }
    let RasterMemory { binned, rows } = setup.memory;
    let pass = BandPass {
        shader,
        empty,
        rows: if target.zeroed {
            RowsHold::Empty
        } else {
            RowsHold::Old
        },
        width: w,
        binned,
        ceiling: None,
    };
    Ok(pass.draw(
        setup.stats,
        target.gd.pixels_mut(),
        BandRows::Scratch(rows),
        outputs,
        finish,
    ))
}

/// Where a band's item and attribute rows live while it is drawn.
enum BandRows<'a, T> {
    /// Rows of whole images, kept after the rasterization.
    Images(&'a mut [ItemId], &'a mut [T]),
    /// Scratch rows from a pool, given back when the band is finished.
    Scratch(&'a std::sync::Mutex<Vec<BandScratch<T>>>),
}

/// Bins the triangles of `objects` and draws the bands of `target` (of the camera's size) in
/// parallel; what their rows hold says whether they are cleared first.
fn draw_target<P: Projection, S: FragmentShader>(
    camera: &P,
    objects: &[&Mesh],
    (shader, empty): (&S, S::Output),
    target: &mut RasterTarget<S::Output>,
    (rows, ceiling): (RowsHold, Option<&[f32]>),
) -> Result<RasterStats, crate::memory::OverBudget> {
    let stats = setup::screen_triangles(camera, objects, BAND_ROWS, &mut target.binned)?;
    let RasterTarget {
        gd,
        item,
        attributes,
        binned,
    } = target;
    let pass = BandPass {
        shader,
        empty,
        rows,
        width: gd.size().0,
        binned,
        ceiling,
    };
    let bands = gd.size().1.div_ceil(BAND_ROWS) as usize;
    let images = BandRows::Images(item.pixels_mut(), attributes.pixels_mut());
    let no_finish = |_: FinishedBand<'_, S::Output>, _: &mut ()| {};
    Ok(pass.draw(stats, gd.pixels_mut(), images, vec![(); bands], no_finish))
}

/// What the rows of a target hold before a rasterization, so what it does to them first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RowsHold {
    /// Nothing yet (zeros, or freshly filled with empties): not cleared. A band with
    /// triangles still writes its `gd` zeros before drawing (see [`BandPass::band`]).
    Empty,
    /// An earlier image this one replaces: every row is cleared first.
    Old,
    /// An image this one is drawn over: left as it is.
    Drawn,
}

/// What every band of one rasterization shares.
struct BandPass<'a, S: FragmentShader> {
    shader: &'a S,
    /// The attribute of an empty pixel.
    empty: S::Output,
    /// What the target images' rows hold (scratch rows are always cleared).
    rows: RowsHold,
    width: u32,
    binned: &'a setup::Binned,
    /// A depth-peeling ceiling over the whole image ([`rasterize_behind`]).
    ceiling: Option<&'a [f32]>,
}

impl<S: FragmentShader> BandPass<'_, S> {
    /// Draws the bands of `gd` in parallel (each band's triangles in input order, so the result
    /// does not depend on the thread count), then calls `finish` on each drawn band.
    /// `outputs` holds one value per band (a `Vec<()>` allocates nothing when there are none).
    fn draw<O, F>(
        &self,
        mut stats: RasterStats,
        gd: &mut [f32],
        rows: BandRows<'_, S::Output>,
        outputs: Vec<O>,
        finish: F,
    ) -> RasterStats
    where
        O: Send,
        F: Fn(FinishedBand<'_, S::Output>, &mut O) + Sync,
    {
        let n = (BAND_ROWS * self.width) as usize;
        assert_eq!(outputs.len(), gd.len().div_ceil(n), "one output per band");
        let bands = gd.par_chunks_mut(n).zip(outputs).enumerate();
        let band_stats: Vec<RasterStats> = match rows {
            BandRows::Images(item, attributes) => bands
                .zip(item.par_chunks_mut(n).zip(attributes.par_chunks_mut(n)))
                .map(|((index, (gd, mut out)), (item, attr))| {
                    if self.rows == RowsHold::Old {
                        item.fill(ItemId::NONE);
                        attr.fill(self.empty);
                    }
                    self.band(index, gd, (item, attr), &finish, &mut out)
                })
                .collect(),
            BandRows::Scratch(pool) => bands
                .map(|(index, (gd, mut out))| {
                    let lock = || pool.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
                    let (mut item, mut attr) = lock().pop().unwrap_or_default();
                    item.clear();
                    item.resize(gd.len(), ItemId::NONE);
                    attr.clear();
                    attr.resize(gd.len(), self.empty);
                    let s = self.band(index, gd, (&mut item, &mut attr), &finish, &mut out);
                    lock().push((item, attr));
                    s
                })
                .collect(),
        };
        for s in band_stats {
            stats = stats + s;
        }
        stats
    }

    /// Draws band `index` (its rows of `gd`, item and attributes) and finishes it.
    fn band<O, F>(
        &self,
        index: usize,
        gd: &mut [f32],
        (item, attr): (&mut [ItemId], &mut [S::Output]),
        finish: &F,
        out: &mut O,
    ) -> RasterStats
    where
        F: Fn(FinishedBand<'_, S::Output>, &mut O),
    {
        // A zeroed target's rows still get written before they are drawn when the band has
        // triangles: the depth test reads a pixel before writing it, and a fresh page that is
        // read first maps the shared zero page, so the write after it pays a second fault and
        // a TLB flush on every core. Writing first takes one fault; bands with no triangles
        // are never touched.
        let clear_gd = match self.rows {
            RowsHold::Old => true,
            RowsHold::Empty => self
                .binned
                .chunks()
                .iter()
                .any(|c| c.band(index).next().is_some()),
            RowsHold::Drawn => false,
        };
        if clear_gd {
            gd.fill(0.0);
        }
        let first_pixel = index * (BAND_ROWS * self.width) as usize;
        let mut band = scan::Band {
            width: self.width,
            first_row: index as u32 * BAND_ROWS,
            ceiling: self
                .ceiling
                .map(|c| &c[first_pixel..first_pixel + gd.len()]),
            gd,
            item,
            attr,
        };
        let mut s = RasterStats::default();
        let mut columns: Option<(u32, u32)> = None;
        for chunk in self.binned.chunks() {
            for t in chunk.band(index) {
                band.draw(t, self.shader, &mut s);
                let (x0, x1) = columns.map_or(t.cols, |(a, b)| (a.min(t.cols.0), b.max(t.cols.1)));
                columns = Some((x0, x1));
            }
        }
        let finished = FinishedBand {
            first_pixel,
            columns,
            gd: band.gd,
            item: band.item,
            attributes: band.attr,
        };
        finish(finished, out);
        s
    }
}

#[cfg(test)]
mod tests;
