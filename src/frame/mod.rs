//! Typed image buffers: linear colour with alpha, depth, normals and ids (all papers).
//!
//! An [`Image<T>`] is a row-major grid of `T`, origin top-left; pixel `(i, j)` covers
//! `[i, i+1) × [j, j+1)` and its centre is `(i + 0.5, j + 0.5)` ([`PIXEL_CENTER`]). Colours are
//! linear `f32` RGBA inside trompe; sRGB appears only at the PNG boundary ([`io`]).
//!
//! Invariants: `data.len() == width * height`, `1 ≤ width, height ≤` [`MAX_DIMENSION`] and
//! `width * height ≤` [`MAX_PIXELS`], checked by [`Image::new`] before anything is allocated.

pub mod envmap;
pub mod io;
pub mod ktx2;
pub mod metrics;
pub mod packed;

use glam::{DVec2, Vec2, Vec3, Vec4};
use std::ops::{Add, Mul};
use thiserror::Error;

/// Offset of a pixel's centre from its integer corner (docs/conventions.md §1.1).
pub const PIXEL_CENTER: f32 = 0.5;

/// The centre of pixel (or texel) `(x, y)`: `(x + ½, y + ½)` ([`PIXEL_CENTER`]).
#[inline]
pub fn pixel_centre(x: f64, y: f64) -> glam::DVec2 {
    glam::DVec2::new(texel_centre(x), texel_centre(y))
}

/// The centre of texel `i` along one axis: `i + ½` ([`PIXEL_CENTER`]).
#[inline]
pub fn texel_centre(i: f64) -> f64 {
    i + f64::from(PIXEL_CENTER)
}
/// Object id of "nothing": an empty pixel or texel.
pub const NO_OBJECT: u32 = u32::MAX;
/// Object id of the environment (a hit at infinity).
pub const ENVIRONMENT: u32 = u32::MAX - 1;
/// Largest width or height trompe allocates.
pub const MAX_DIMENSION: u32 = 16_384;
/// Largest pixel count trompe allocates (8192 × 8192).
pub const MAX_PIXELS: u64 = 1 << 26;

/// Linear RGBA colour, premultiplied by nothing: `(r, g, b, a)`.
pub type Rgba = Vec4;

/// Errors from image buffers and image files.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum FrameError {
    /// A width or height of zero, or a size past [`MAX_DIMENSION`] / [`MAX_PIXELS`].
    #[error("invalid image size {width} × {height}: {reason}")]
    InvalidSize {
        /// Requested width.
        width: u64,
        /// Requested height.
        height: u64,
        /// Why it was refused.
        reason: &'static str,
    },
    /// Reading or writing a file failed at the operating-system level.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A file could not be decoded or encoded.
    #[error("{path}: {reason}")]
    Codec {
        /// The file.
        path: std::path::PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// An image the memory budget refuses ([`crate::memory`]).
    #[error(transparent)]
    Memory(#[from] crate::memory::OverBudget),
    /// An image size written other than `WIDTHxHEIGHT`.
    #[error("{text:?}: expected an image size WIDTHxHEIGHT, e.g. 640x480")]
    SizeText {
        /// What was written.
        text: String,
    },
    /// Two images that must have the same size do not.
    #[error("image sizes differ: {a:?} vs {b:?}")]
    SizeMismatch {
        /// First size.
        a: (u32, u32),
        /// Second size.
        b: (u32, u32),
    },
    /// A pixel that must be a number is not (a score of it would be NaN).
    #[error("the {image} image's pixel ({x}, {y}) is not a number")]
    NotANumber {
        /// Which image ("reference", "test").
        image: &'static str,
        /// Column.
        x: u32,
        /// Row.
        y: u32,
    },
}

/// Parses an image size written `WIDTHxHEIGHT` (`x`, `X` or `×` between the sides), checked by
/// [`check_size`].
///
/// ```
/// assert_eq!(trompe::frame::parse_size("640x480").unwrap(), (640, 480));
/// assert!(trompe::frame::parse_size("640").is_err());
/// assert!(trompe::frame::parse_size("0x480").is_err());
/// ```
pub fn parse_size(text: &str) -> Result<(u32, u32), FrameError> {
    let bad = || FrameError::SizeText {
        text: text.to_owned(),
    };
    let (w, h) = text.split_once(['x', 'X', '×']).ok_or_else(bad)?;
    let (w, h): (u64, u64) = (
        w.trim().parse().map_err(|_| bad())?,
        h.trim().parse().map_err(|_| bad())?,
    );
    check_size(w, h)
}

/// Checks a requested image size against the allocation limits.
pub fn check_size(width: u64, height: u64) -> Result<(u32, u32), FrameError> {
    let err = |reason| FrameError::InvalidSize {
        width,
        height,
        reason,
    };
    if width == 0 || height == 0 {
        return Err(err("width and height must be at least 1"));
    }
    if width > MAX_DIMENSION as u64 || height > MAX_DIMENSION as u64 {
        return Err(err("a side is larger than 16384 pixels"));
    }
    if width * height > MAX_PIXELS {
        return Err(err("more than 8192 × 8192 pixels"));
    }
    Ok((width as u32, height as u32))
}

/// A row-major image of `T`. Its pixels are held in the process's memory account
/// ([`crate::memory::Held`]) while it lives.
#[derive(Clone, Debug)]
pub struct Image<T> {
    width: u32,
    height: u32,
    data: Vec<T>,
    _held: crate::memory::Held,
}

impl<T: PartialEq> PartialEq for Image<T> {
    fn eq(&self, other: &Self) -> bool {
        (self.width, self.height) == (other.width, other.height) && self.data == other.data
    }
}

/// The account's share for `data`.
fn held<T>(data: &[T]) -> crate::memory::Held {
    crate::memory::Held::new(std::mem::size_of_val(data) as u64)
}

impl<T: Copy + Send + Sync> Image<T> {
    /// A `width × height` image filled with `fill`; refuses empty and absurd sizes.
    ///
    /// A large image is filled by every worker thread, each writing its own stretch: the
    /// first write to a fresh page of memory is a page fault, and those are served in parallel.
    pub fn new(width: u32, height: u32, fill: T) -> Result<Self, FrameError> {
        let (w, h) = check_size(width as u64, height as u64)?;
        check_budget::<T>(w, h)?;
        let n = w as usize * h as usize;
        let data = if n * std::mem::size_of::<T>() < PARALLEL_FILL_BYTES {
            vec![fill; n]
        } else {
            let mut data = Vec::with_capacity(n);
            rayon::iter::ParallelExtend::par_extend(&mut data, rayon::iter::repeat_n(fill, n));
            data
        };
        Ok(Self {
            width: w,
            height: h,
            _held: held(&data),
            data,
        })
    }
}

impl<T: Copy + bytemuck::Zeroable> Image<T> {
    /// A `width × height` image of all-zero pixels, asked of the allocator as zeroed memory.
    /// A large buffer new to the process comes from the operating system already zero and
    /// untouched: a producer that writes its pixels in parallel bands then takes their page
    /// faults in parallel, and pages it never writes cost nothing. (Memory the allocator
    /// recycles, it clears itself.)
    pub fn zeroed(width: u32, height: u32) -> Result<Self, FrameError> {
        let (w, h) = check_size(width as u64, height as u64)?;
        check_budget::<T>(w, h)?;
        let data = bytemuck::allocation::try_zeroed_vec(w as usize * h as usize).map_err(|()| {
            FrameError::InvalidSize {
                width: width as u64,
                height: height as u64,
                reason: "out of memory",
            }
        })?;
        Ok(Self {
            width: w,
            height: h,
            _held: held(&data),
            data,
        })
    }
}

/// Refuses a `w × h` image of `T` past the memory budget.
fn check_budget<T>(w: u32, h: u32) -> Result<(), FrameError> {
    let bytes = crate::memory::times(w as u64 * h as u64, std::mem::size_of::<T>() as u64);
    crate::memory::check(
        || {
            format!(
                "a {w} × {h} image of {}-byte pixels",
                std::mem::size_of::<T>()
            )
        },
        bytes,
    )?;
    Ok(())
}

/// Images at least this large are filled in parallel ([`Image::new`]).
const PARALLEL_FILL_BYTES: usize = 1 << 20;

impl<T: Copy> Image<T> {
    /// A `width × height` image filled with `fill` whose size derives from memory already held
    /// (a smaller level of a pyramid, a fixed-size resample): counted in the memory account but
    /// not refused by it. Panics only on a programming error: a zero or absurd size.
    pub fn derived(width: u32, height: u32, fill: T) -> Self {
        let n = width as usize * height as usize;
        Image::from_vec(width, height, vec![fill; n]).expect("a derived image has a valid size")
    }

    /// Wraps existing pixels; `data.len()` must equal `width * height`.
    pub fn from_vec(width: u32, height: u32, data: Vec<T>) -> Result<Self, FrameError> {
        check_size(width as u64, height as u64)?;
        if data.len() != width as usize * height as usize {
            return Err(FrameError::InvalidSize {
                width: width as u64,
                height: height as u64,
                reason: "pixel count does not match the size",
            });
        }
        Ok(Self {
            width,
            height,
            _held: held(&data),
            data,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }
    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }
    /// `(width, height)`.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }
    /// All pixels, row-major.
    pub fn pixels(&self) -> &[T] {
        &self.data
    }
    /// All pixels, row-major, mutable.
    pub fn pixels_mut(&mut self) -> &mut [T] {
        &mut self.data
    }
    /// Consumes the image, returning its pixels.
    pub fn into_vec(self) -> Vec<T> {
        self.data
    }
    /// The pixel at column `x`, row `y` (panics only on a programming error: out of bounds).
    pub fn get(&self, x: u32, y: u32) -> T {
        self.data[y as usize * self.width as usize + x as usize]
    }
    /// Sets the pixel at column `x`, row `y`.
    pub fn set(&mut self, x: u32, y: u32, value: T) {
        let w = self.width as usize;
        self.data[y as usize * w + x as usize] = value;
    }
    /// Rows of `rows_per_band` rows each, mutable and disjoint: the unit of parallel work.
    pub fn bands_mut(&mut self, rows_per_band: u32) -> std::slice::ChunksMut<'_, T> {
        let n = (rows_per_band.max(1) as usize) * self.width as usize;
        self.data.chunks_mut(n)
    }
    /// A new image with `f` applied to each pixel.
    pub fn map<U: Copy>(&self, f: impl Fn(T) -> U) -> Image<U> {
        let data: Vec<U> = self.data.iter().map(|&p| f(p)).collect();
        Image {
            width: self.width,
            height: self.height,
            _held: held(&data),
            data,
        }
    }

    /// Nearest-texel lookup at continuous image coordinates (clamped to the border).
    pub fn sample_nearest(&self, uv: Vec2) -> T {
        let x = (uv.x.floor() as i64).clamp(0, self.width as i64 - 1) as u32;
        let y = (uv.y.floor() as i64).clamp(0, self.height as i64 - 1) as u32;
        self.get(x, y)
    }
}

/// Values that can be blended linearly: the bound for bilinear sampling and interpolation.
pub trait Lerp: Copy + Add<Output = Self> + Mul<f32, Output = Self> {}
impl<T: Copy + Add<Output = T> + Mul<f32, Output = T>> Lerp for T {}

/// How a lookup outside `[0, 1]` texture coordinates behaves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    /// Clamp to the border texel.
    Clamp,
    /// Repeat the image (texture tiling, the longitude of an environment map).
    Repeat,
}

impl<T: Lerp> Image<T> {
    /// Bilinear lookup at continuous image coordinates (pixel centres at `+0.5`).
    pub fn sample_bilinear(&self, uv: Vec2, wrap_x: Wrap, wrap_y: Wrap) -> T {
        let (x0, tx) = floor_and_fraction(uv.x - PIXEL_CENTER);
        let (y0, ty) = floor_and_fraction(uv.y - PIXEL_CENTER);
        let (xa, xb) = texel_pair(x0, self.width, wrap_x);
        let (ya, yb) = texel_pair(y0, self.height, wrap_y);
        self.blend_taps((xa, xb), (ya, yb), (tx, ty))
    }

    /// Bilinear lookup inside one tile of an atlas, as if the tile were the whole image: the
    /// `size` texels from `origin`, at tile texel coordinates `uv` (centres at `+½`), clamped to
    /// the tile's border texels so that a lookup never reads a neighbouring tile.
    ///
    /// Panics if the tile is empty or does not lie inside the image.
    pub fn sample_bilinear_tile(&self, origin: (u32, u32), size: (u32, u32), uv: DVec2) -> T {
        assert!(size.0 > 0 && size.1 > 0, "a tile holds at least one texel");
        assert!(
            u64::from(origin.0) + u64::from(size.0) <= u64::from(self.width)
                && u64::from(origin.1) + u64::from(size.1) <= u64::from(self.height),
            "the tile lies inside the image"
        );
        let axis = |c: f64, n: u32, o: u32| {
            let f = c - f64::from(PIXEL_CENTER);
            let i = f.floor();
            // Clamp in floats first: a coordinate far outside stays a valid integer.
            let i0 = i.clamp(-1.0, f64::from(n)) as i64;
            let (a, b) = texel_pair(i0, n, Wrap::Clamp);
            ((a + o, b + o), (f - i) as f32)
        };
        let (xs, tx) = axis(uv.x, size.0, origin.0);
        let (ys, ty) = axis(uv.y, size.1, origin.1);
        self.blend_taps(xs, ys, (tx, ty))
    }

    /// The four taps `(xa | xb) × (ya | yb)` blended with weights `t`.
    #[inline]
    fn blend_taps(&self, (xa, xb): (u32, u32), (ya, yb): (u32, u32), (tx, ty): (f32, f32)) -> T {
        let top = self.get(xa, ya) * (1.0 - tx) + self.get(xb, ya) * tx;
        let bottom = self.get(xa, yb) * (1.0 - tx) + self.get(xb, yb) * tx;
        top * (1.0 - ty) + bottom * ty
    }

    /// Bilinear lookup at texture coordinates `st ∈ [0, 1]²` (`t = 0` is the top row).
    pub fn sample_uv(&self, st: Vec2, wrap: Wrap) -> T {
        let uv = Vec2::new(st.x * self.width as f32, st.y * self.height as f32);
        self.sample_bilinear(uv, wrap, wrap)
    }
}

/// `⌊x⌋` and `x − ⌊x⌋`, by a conversion: `f32::floor` is a library call on baseline x86-64,
/// and bilinear texture lookups make two a texel. The integer saturates beyond `i64`, and
/// a NaN gives 0 (its fraction stays NaN).
fn floor_and_fraction(x: f32) -> (i64, f32) {
    let toward_zero = x as i64;
    let floor = if (toward_zero as f32) > x {
        toward_zero.saturating_sub(1)
    } else {
        toward_zero
    };
    (floor, x - floor as f32)
}

/// The texels `i` and `i + 1` of a row (or column) of `n`, wrapped: one division for the
/// pair where two `rem_euclid` took two.
fn texel_pair(i: i64, n: u32, wrap: Wrap) -> (u32, u32) {
    let n = n as i64;
    match wrap {
        Wrap::Clamp => (
            i.clamp(0, n - 1) as u32,
            i.saturating_add(1).clamp(0, n - 1) as u32,
        ),
        Wrap::Repeat => {
            let a = i.rem_euclid(n);
            (a as u32, if a + 1 == n { 0 } else { a as u32 + 1 })
        }
    }
}

/// The buffers a renderer produces for one view.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Linear RGBA colour.
    pub color: Image<Rgba>,
    /// Distance from the eye along each pixel's ray; `f32::INFINITY` where nothing was hit.
    pub depth: Image<f32>,
    /// Shading normal (zero where nothing was hit).
    pub normal: Image<Vec3>,
    /// Object id ([`NO_OBJECT`] where nothing was hit).
    pub object_id: Image<u32>,
}

impl Frame {
    /// An empty frame: transparent black, infinite depth, no normals, no ids.
    pub fn new(width: u32, height: u32) -> Result<Self, FrameError> {
        Ok(Self {
            color: Image::new(width, height, Vec4::ZERO)?,
            depth: Image::new(width, height, f32::INFINITY)?,
            normal: Image::new(width, height, Vec3::ZERO)?,
            object_id: Image::new(width, height, NO_OBJECT)?,
        })
    }
}

/// One row of every buffer of a [`Frame`]: colour, depth, normal, object id.
pub type FrameRow<'a> = (&'a mut [Rgba], &'a mut [f32], &'a mut [Vec3], &'a mut [u32]);

impl Frame {
    /// The rows of every buffer, in parallel, with their index: each row is owned by one worker.
    pub fn par_rows_mut(
        &mut self,
    ) -> impl rayon::iter::IndexedParallelIterator<Item = (usize, FrameRow<'_>)> {
        use rayon::prelude::*;
        let w = self.color.width() as usize;
        self.color
            .pixels_mut()
            .par_chunks_mut(w)
            .zip(self.depth.pixels_mut().par_chunks_mut(w))
            .zip(self.normal.pixels_mut().par_chunks_mut(w))
            .zip(self.object_id.pixels_mut().par_chunks_mut(w))
            .map(|(((c, d), n), i)| (c, d, n, i))
            .enumerate()
    }
}

/// sRGB transfer function: linear `[0, 1]` → encoded `[0, 1]`.
pub fn linear_to_srgb(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Inverse sRGB transfer function: encoded `[0, 1]` → linear.
pub fn srgb_to_linear(x: f32) -> f32 {
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// Rec. 709 luminance of a linear colour.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

impl Image<Rgba> {
    /// A bilinear lookup at pixel point `p` (texel centres at `+½`) over only the taps
    /// `keep(x, y, texel)` accepts, their weights renormalized; taps outside the image are
    /// skipped. `None` when no tap with a weight is accepted — a lookup that never mixes in
    /// what is not the surface (transparent texels, another depth).
    pub fn sample_bilinear_where(
        &self,
        p: glam::DVec2,
        keep: impl Fn(u32, u32, Rgba) -> bool,
    ) -> Option<Rgba> {
        let (w, h) = self.size();
        let (fx, fy) = (p.x - 0.5, p.y - 0.5);
        // floor without a libm call (x86-64's baseline has no rounding instruction): this
        // runs for every pixel of a view-dependent blend.
        let floor = |v: f64| {
            let i = v as i64 as f64;
            if i > v { i - 1.0 } else { i }
        };
        let (x0, y0) = (floor(fx), floor(fy));
        let (tx, ty) = ((fx - x0) as f32, (fy - y0) as f32);
        let mut sum = Vec4::ZERO;
        let mut weight = 0.0f32;
        for (dx, dy, wgt) in [
            (0.0, 0.0, (1.0 - tx) * (1.0 - ty)),
            (1.0, 0.0, tx * (1.0 - ty)),
            (0.0, 1.0, (1.0 - tx) * ty),
            (1.0, 1.0, tx * ty),
        ] {
            let (x, y) = (x0 + dx, y0 + dy);
            if wgt <= 0.0 || x < 0.0 || y < 0.0 || x >= w as f64 || y >= h as f64 {
                continue;
            }
            let (x, y) = (x as u32, y as u32);
            let c = self.get(x, y);
            if keep(x, y, c) {
                sum += c * wgt;
                weight += wgt;
            }
        }
        (weight > 0.0).then(|| sum / weight)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absurd_sizes_are_refused_before_allocating() {
        assert!(Image::new(0, 10, 0.0f32).is_err());
        assert!(Image::new(1_000_000, 1_000_000, 0.0f32).is_err());
        assert!(Image::new(16_384, 16_384, 0u8).is_err());
        assert!(Image::new(8192, 8192, 0u8).is_ok());
        assert!(Image::<Vec3>::zeroed(0, 10).is_err());
        assert!(Image::<Vec4>::zeroed(1_000_000, 1_000_000).is_err());
    }

    #[test]
    fn images_filled_in_parallel_hold_the_fill_everywhere() {
        // 1024² Vec4 is 16 MiB: past the parallel-fill size.
        let fill = Vec4::new(1.0, -2.0, 3.5, 0.25);
        let img = Image::new(1024, 1024, fill).unwrap();
        assert_eq!(img.pixels().len(), 1024 * 1024);
        assert!(img.pixels().iter().all(|&p| p == fill));
        let zeros = Image::<Vec3>::zeroed(1024, 768).unwrap();
        assert_eq!(zeros.size(), (1024, 768));
        assert!(zeros.pixels().iter().all(|&p| p == Vec3::ZERO));
    }

    #[test]
    fn bilinear_reproduces_texels_at_centres_and_blends_between() {
        let img = Image::from_vec(2, 1, vec![0.0f32, 1.0]).unwrap();
        assert_eq!(
            img.sample_bilinear(Vec2::new(0.5, 0.5), Wrap::Clamp, Wrap::Clamp),
            0.0
        );
        assert_eq!(
            img.sample_bilinear(Vec2::new(1.5, 0.5), Wrap::Clamp, Wrap::Clamp),
            1.0
        );
        assert!(
            (img.sample_bilinear(Vec2::new(1.0, 0.5), Wrap::Clamp, Wrap::Clamp) - 0.5).abs() < 1e-6
        );
        // Repeat wraps the left neighbour of texel 0 to texel 1.
        assert!(
            (img.sample_bilinear(Vec2::new(0.0, 0.5), Wrap::Repeat, Wrap::Clamp) - 0.5).abs()
                < 1e-6
        );
        assert_eq!(img.sample_nearest(Vec2::new(1.9, 0.2)), 1.0);
    }

    #[test]
    fn a_tile_lookup_is_the_lookup_of_the_tile_cut_out_and_never_reads_its_neighbours() {
        // A 3 × 2 atlas of 4 × 3 tiles, each texel a distinct value.
        let texel = |x: u32, y: u32| Vec3::new(x as f32, y as f32, (x * 7 + y) as f32);
        let image = |w: u32, h: u32, at: &dyn Fn(u32, u32) -> Vec3| {
            let data = (0..w * h).map(|i| at(i % w, i / w)).collect();
            Image::from_vec(w, h, data).unwrap()
        };
        let atlas = image(12, 6, &texel);
        let (origin, size) = ((4, 3), (4, 3));
        let tile = image(4, 3, &|x, y| texel(x + 4, y + 3));
        for uv in [
            DVec2::new(0.5, 0.5),
            DVec2::new(1.25, 2.0),
            DVec2::new(3.9, 0.1),
            DVec2::new(-5.0, 1.5),
            DVec2::new(2.2, 40.0),
            DVec2::new(f64::NAN, 1.0),
        ] {
            let in_atlas = atlas.sample_bilinear_tile(origin, size, uv);
            let alone = tile.sample_bilinear(uv.as_vec2(), Wrap::Clamp, Wrap::Clamp);
            if uv.x.is_nan() {
                // A NaN coordinate blends to NaN, as the whole-image lookup does: no panic.
                assert!(in_atlas.is_nan() && alone.is_nan());
                continue;
            }
            assert!(
                (in_atlas - alone).abs().max_element() < 1e-5,
                "{uv}: {in_atlas} {alone}"
            );
            // Inside the tile's value range: no neighbour's texel mixed in.
            assert!((4.0..=7.0).contains(&in_atlas.x) && (3.0..=5.0).contains(&in_atlas.y));
        }
    }

    #[test]
    fn bilinear_lookups_match_the_floor_and_remainder_definition() {
        // The cast-based floor and one-division wrap against `f32::floor` and `rem_euclid` per
        // texel, at coordinates on and between texel centres, negative, past the edge and far
        // out; and no panic at non-finite ones.
        let (w, h) = (5u32, 3u32);
        let texels: Vec<f32> = (0..w * h).map(|i| (i * i % 17) as f32).collect();
        let img = Image::from_vec(w, h, texels).unwrap();
        let reference = |uv: Vec2, wrap: Wrap| {
            let (fx, fy) = (uv.x - PIXEL_CENTER, uv.y - PIXEL_CENTER);
            let (x0, y0) = (fx.floor(), fy.floor());
            let (tx, ty) = (fx - x0, fy - y0);
            let at = |i: i64, n: u32| match wrap {
                Wrap::Clamp => i.clamp(0, n as i64 - 1) as u32,
                Wrap::Repeat => i.rem_euclid(n as i64) as u32,
            };
            let (x0, y0) = (x0 as i64, y0 as i64);
            let (xa, xb, ya, yb) = (at(x0, w), at(x0 + 1, w), at(y0, h), at(y0 + 1, h));
            let top = img.get(xa, ya) * (1.0 - tx) + img.get(xb, ya) * tx;
            let bottom = img.get(xa, yb) * (1.0 - tx) + img.get(xb, yb) * tx;
            top * (1.0 - ty) + bottom * ty
        };
        let mut rng = crate::geom::SplitMix64::new(11);
        let mut coords: Vec<f32> = vec![0.0, 0.5, 1.0, -0.5, -1.0, 4.5, 5.0, 5.5, -7.25, 1e6 + 0.5];
        coords.extend((0..200).map(|_| rng.next_f32() * 40.0 - 20.0));
        for wrap in [Wrap::Clamp, Wrap::Repeat] {
            for (&x, &y) in coords.iter().zip(coords.iter().rev()) {
                let uv = Vec2::new(x, y);
                assert_eq!(
                    img.sample_bilinear(uv, wrap, wrap),
                    reference(uv, wrap),
                    "{uv}"
                );
            }
            for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 3e19, -3e19] {
                let _ = img.sample_bilinear(Vec2::new(bad, 1.0), wrap, wrap);
                let _ = img.sample_bilinear(Vec2::new(1.0, bad), wrap, wrap);
            }
        }
    }

    #[test]
    fn srgb_round_trips() {
        for i in 0..=100 {
            let x = i as f32 / 100.0;
            assert!((srgb_to_linear(linear_to_srgb(x)) - x).abs() < 1e-5);
        }
    }
}
