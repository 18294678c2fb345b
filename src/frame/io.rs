//! Image files: PNG (8-bit sRGB) for colour, OpenEXR (32-bit float) for colour, depth and normals,
//! Radiance `.hdr` for environment maps.
//!
//! The sRGB ↔ linear conversion happens here and nowhere else. Every reader checks the declared
//! size against [`super::check_size`] before it allocates pixel memory.

use super::{FrameError, Image, Rgba, check_size, linear_to_srgb, srgb_to_linear};
use exr::prelude::{AnyChannel, AnyChannels, FlatSamples, ReadChannels, ReadLayers, WritableImage};
use glam::{Vec3, Vec4};
use std::path::{Path, PathBuf};

fn codec(path: &Path, reason: impl ToString) -> FrameError {
    FrameError::Codec {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}

/// Encodes a linear colour image as 8-bit sRGB RGBA bytes (alpha stays linear).
pub fn to_srgb8(image: &Image<Rgba>) -> Vec<u8> {
    let mut out = Vec::with_capacity(image.pixels().len() * 4);
    for p in image.pixels() {
        for c in [p.x, p.y, p.z] {
            out.push((linear_to_srgb(c) * 255.0 + 0.5) as u8);
        }
        out.push((p.w.clamp(0.0, 1.0) * 255.0 + 0.5) as u8);
    }
    out
}

/// Writes a linear colour image as an sRGB PNG, replacing `path` whole
/// ([`crate::files::write_atomically`]).
pub fn write_png(path: &Path, image: &Image<Rgba>) -> Result<(), FrameError> {
    let encoded = encode_png(image, path)?;
    publish(path, &encoded)
}

/// Encodes a linear colour image as sRGB PNG bytes (`path` only names it in errors).
pub fn encode_png(image: &Image<Rgba>, path: &Path) -> Result<Vec<u8>, FrameError> {
    let pixels = to_srgb8(image);
    png_bytes(&pixels, image.size(), image::ExtendedColorType::Rgba8, path)
}

/// PNG bytes of 8-bit `pixels` of `size`, `layout` their channels.
fn png_bytes(
    pixels: &[u8],
    (w, h): (u32, u32),
    layout: image::ExtendedColorType,
    path: &Path,
) -> Result<Vec<u8>, FrameError> {
    use image::ImageEncoder as _;
    let mut encoded = Vec::new();
    image::codecs::png::PngEncoder::new(&mut encoded)
        .write_image(pixels, w, h, layout)
        .map_err(|e| codec(path, e))?;
    Ok(encoded)
}

/// An image of data in `[0, 1]` (not colour: occlusion, roughness …) as an 8-bit RGB PNG, stored
/// linearly, as glTF's data textures are.
pub fn encode_png_data(image: &Image<Vec3>, path: &Path) -> Result<Vec<u8>, FrameError> {
    let pixels = data_bytes(image.pixels().iter().map(|p| p.to_array()));
    png_bytes(&pixels, image.size(), image::ExtendedColorType::Rgb8, path)
}

/// An image of four data channels in `[0, 1]` as an 8-bit RGBA PNG, stored linearly (alpha
/// too): packed maps such as the octahedral normal-depth texture.
pub fn encode_png_data_rgba(image: &Image<Rgba>, path: &Path) -> Result<Vec<u8>, FrameError> {
    let pixels = data_bytes(image.pixels().iter().map(|p| p.to_array()));
    png_bytes(&pixels, image.size(), image::ExtendedColorType::Rgba8, path)
}

/// Data values in `[0, 1]` as bytes, rounded to the nearest of 256 steps (clamped).
pub fn data_bytes<const N: usize>(texels: impl Iterator<Item = [f32; N]>) -> Vec<u8> {
    texels
        .flat_map(|t| t.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8))
        .collect()
}

/// Writes an image of data in `[0, 1]` as a linear 8-bit RGB PNG ([`encode_png_data`]).
pub fn write_png_data(path: &Path, image: &Image<Vec3>) -> Result<(), FrameError> {
    publish(path, &encode_png_data(image, path)?)
}

/// Replaces `path` whole with `bytes`.
fn publish(path: &Path, bytes: &[u8]) -> Result<(), FrameError> {
    crate::files::write_atomically(path, bytes).map_err(|source| FrameError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Reads a PNG (or any 8/16-bit image the `image` crate knows) as linear RGBA.
pub fn read_png(path: &Path) -> Result<Image<Rgba>, FrameError> {
    let bytes = std::fs::read(path).map_err(|source| FrameError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    decode_srgb_image(&bytes, path)
}

/// Decodes an encoded 8/16-bit colour image held in memory, its sRGB values to linear (`path`
/// only names it in errors).
pub fn decode_srgb_image(bytes: &[u8], path: &Path) -> Result<Image<Rgba>, FrameError> {
    decode_image(bytes, path, true)
}

/// Decodes an encoded 8/16-bit image of data (not colour: normals, roughness …) as it is
/// stored, scaled to `[0, 1]`.
pub fn decode_linear_image(bytes: &[u8], path: &Path) -> Result<Image<Rgba>, FrameError> {
    decode_image(bytes, path, false)
}

fn decode_image(bytes: &[u8], path: &Path, srgb: bool) -> Result<Image<Rgba>, FrameError> {
    // Every 8-bit value's decoding, once (the transfer function per pixel costs more than
    // reading the file).
    let table: [f32; 256] = std::array::from_fn(|v| {
        let v = v as f32 / 255.0;
        if srgb { srgb_to_linear(v) } else { v }
    });
    let decode = |v: u8| table[v as usize];
    let reader = || {
        image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| codec(path, e))
    };
    let (w, h) = reader()?.into_dimensions().map_err(|e| codec(path, e))?;
    check_size(w as u64, h as u64)?;
    decode_budget(path, w, h, DECODE_BYTES_PER_PIXEL)?;
    let img = reader()?.decode().map_err(|e| codec(path, e))?;
    let rgba = img.to_rgba8();
    let data = rgba
        .pixels()
        .map(|p| {
            Vec4::new(
                decode(p[0]),
                decode(p[1]),
                decode(p[2]),
                p[3] as f32 / 255.0,
            )
        })
        .collect();
    Image::from_vec(w, h, data)
}

/// Bytes a pixel costs while an 8/16-bit image is decoded to linear RGBA: the decoded image (up
/// to 8 bytes), its RGBA8 copy (4) and the linear result (16).
const DECODE_BYTES_PER_PIXEL: u64 = 28;

/// Refuses decoding a `w × h` image of `path` at `per_pixel` bytes past the memory budget.
fn decode_budget(path: &Path, w: u32, h: u32, per_pixel: u64) -> Result<(), FrameError> {
    crate::memory::check(
        || format!("{}, a {w} × {h} image,", path.display()),
        crate::memory::times(w as u64 * h as u64, per_pixel),
    )?;
    Ok(())
}

/// Writes a linear colour image as a float RGBA OpenEXR (channels `R G B A`).
pub fn write_exr_rgba(path: &Path, image: &Image<Rgba>) -> Result<(), FrameError> {
    let px = image.pixels();
    let channel = |k: usize| px.iter().map(|p| p[k]).collect::<Vec<f32>>();
    write_exr_channels(
        path,
        image.size(),
        vec![
            ("R", channel(0)),
            ("G", channel(1)),
            ("B", channel(2)),
            ("A", channel(3)),
        ],
    )
}

/// Writes named float channels of one size to an OpenEXR file (e.g. `Z` for depth, `N.X` …).
pub fn write_exr_channels(
    path: &Path,
    size: (u32, u32),
    channels: Vec<(&str, Vec<f32>)>,
) -> Result<(), FrameError> {
    write_exr_channels_encoded(path, size, channels, exr::prelude::Encoding::FAST_LOSSLESS)
}

/// [`write_exr_channels`] with ZIP compression (lossless, in blocks of 16 rows): slower to
/// write, smaller for images that are mostly empty or smooth (an impostor: about half the size).
pub fn write_exr_channels_small(
    path: &Path,
    size: (u32, u32),
    channels: Vec<(&str, Vec<f32>)>,
) -> Result<(), FrameError> {
    write_exr_channels_encoded(path, size, channels, exr::prelude::Encoding::SMALL_LOSSLESS)
}

fn write_exr_channels_encoded(
    path: &Path,
    size: (u32, u32),
    channels: Vec<(&str, Vec<f32>)>,
    encoding: exr::prelude::Encoding,
) -> Result<(), FrameError> {
    let bytes = encode_exr(path, size, channels, encoding)?;
    publish(path, &bytes)
}

/// Named float channels encoded as an OpenEXR file in memory. Blocks are written in increasing
/// order, so the same image always gives the same bytes (whatever the thread count).
pub fn encode_exr(
    path: &Path,
    size: (u32, u32),
    channels: Vec<(&str, Vec<f32>)>,
    encoding: exr::prelude::Encoding,
) -> Result<Vec<u8>, FrameError> {
    let encoding = exr::prelude::Encoding {
        line_order: exr::prelude::LineOrder::Increasing,
        ..encoding
    };
    let list = channels
        .into_iter()
        .map(|(name, data)| AnyChannel::new(name, FlatSamples::F32(data)))
        .collect();
    let image = exr::prelude::Image::from_encoded_channels(
        (size.0 as usize, size.1 as usize),
        encoding,
        AnyChannels::sort(list),
    );
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| codec(path, e))?;
    Ok(bytes.into_inner())
}

/// Writes a depth image as a single-channel (`Z`) float OpenEXR.
pub fn write_exr_depth(path: &Path, depth: &Image<f32>) -> Result<(), FrameError> {
    publish(path, &encode_exr_depth(path, depth)?)
}

/// [`write_exr_depth`]'s file, in memory (`path` only names it in errors).
pub fn encode_exr_depth(path: &Path, depth: &Image<f32>) -> Result<Vec<u8>, FrameError> {
    encode_exr(
        path,
        depth.size(),
        vec![("Z", depth.pixels().to_vec())],
        exr::prelude::Encoding::FAST_LOSSLESS,
    )
}

/// Writes a normal image as a three-channel (`N.X`, `N.Y`, `N.Z`) float OpenEXR.
pub fn write_exr_normals(path: &Path, normals: &Image<Vec3>) -> Result<(), FrameError> {
    publish(path, &encode_exr_normals(path, normals)?)
}

/// [`write_exr_normals`]'s file, in memory (`path` only names it in errors).
pub fn encode_exr_normals(path: &Path, normals: &Image<Vec3>) -> Result<Vec<u8>, FrameError> {
    let px = normals.pixels();
    encode_exr(
        path,
        normals.size(),
        vec![
            ("N.X", px.iter().map(|n| n.x).collect()),
            ("N.Y", px.iter().map(|n| n.y).collect()),
            ("N.Z", px.iter().map(|n| n.z).collect()),
        ],
        exr::prelude::Encoding::FAST_LOSSLESS,
    )
}

/// Reads every channel of the first layer of an OpenEXR file as `f32`.
pub fn read_exr_channels(path: &Path) -> Result<ExrChannels, FrameError> {
    check_exr_size(path)?;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| codec(path, e))?;
    let size = image.layer_data.size;
    let (w, h) = check_size(size.0 as u64, size.1 as u64)?;
    let channels = image
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| {
            let name = c.name.to_string();
            let values = c.sample_data.values_as_f32().collect();
            (name, values)
        })
        .collect();
    Ok(ExrChannels {
        path: path.to_path_buf(),
        width: w,
        height: h,
        channels,
    })
}

/// The float channels of one OpenEXR layer.
#[derive(Clone, Debug)]
pub struct ExrChannels {
    /// The file they came from (for errors).
    pub path: PathBuf,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `(name, row-major samples)` in file order.
    pub channels: Vec<(String, Vec<f32>)>,
}

impl ExrChannels {
    /// The channel called `name` as an image, or an error naming the file and the channel.
    pub fn channel(&self, name: &str) -> Result<Image<f32>, FrameError> {
        let data = self
            .channels
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, d)| d.clone())
            .ok_or_else(|| codec(&self.path, format!("no channel named {name:?}")))?;
        Image::from_vec(self.width, self.height, data)
    }
}

/// The most channels trompe reads from one EXR layer (an impostor has 15 a depth layer, and
/// at most 8 depth layers).
pub const MAX_EXR_CHANNELS: usize = 128;

fn check_exr_size(path: &Path) -> Result<(), FrameError> {
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| codec(path, e))?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| codec(path, "no layer in file"))?;
    let size = header.layer_size;
    let (w, h) = check_size(size.0 as u64, size.1 as u64)?;
    let channels = header.channels.list.len() as u64;
    if channels > MAX_EXR_CHANNELS as u64 {
        return Err(codec(
            path,
            format!("{channels} channels in one layer (trompe reads at most {MAX_EXR_CHANNELS})"),
        ));
    }
    // Each channel is read as f32 samples and may be copied once more by the caller.
    decode_budget(path, w, h, crate::memory::times(channels.max(4), 8))?;
    Ok(())
}

/// Reads an RGB(A) OpenEXR as linear RGBA (alpha 1 when the file has none).
pub fn read_exr_rgba(path: &Path) -> Result<Image<Rgba>, FrameError> {
    check_exr_size(path)?;
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |size, _| (size.0, vec![Vec4::ZERO; size.0 * size.1]),
        |(w, px): &mut (usize, Vec<Vec4>), pos, (r, g, b, a): (f32, f32, f32, f32)| {
            px[pos.1 * *w + pos.0] = Vec4::new(r, g, b, a);
        },
    )
    .map_err(|e| codec(path, e))?;
    let size = image.layer_data.size;
    let (_, pixels) = image.layer_data.channel_data.pixels;
    Image::from_vec(size.0 as u32, size.1 as u32, pixels)
}

/// Reads a Radiance RGBE (`.hdr`) file as linear RGBA.
pub fn read_hdr(path: &Path) -> Result<Image<Rgba>, FrameError> {
    let file = std::fs::File::open(path).map_err(|source| FrameError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let decoder = image::codecs::hdr::HdrDecoder::new(std::io::BufReader::new(file))
        .map_err(|e| codec(path, e))?;
    let meta = decoder.metadata();
    let (w, h) = check_size(meta.width as u64, meta.height as u64)?;
    // The decoded RGB f32 image (12 bytes), its RGB32F view (12) and the RGBA result (16).
    decode_budget(path, w, h, 40)?;
    let img = image::DynamicImage::from_decoder(decoder).map_err(|e| codec(path, e))?;
    let rgb = img.to_rgb32f();
    let data = rgb
        .pixels()
        .map(|p| Vec4::new(p[0], p[1], p[2], 1.0))
        .collect();
    Image::from_vec(w, h, data)
}

/// The width and height of the image at `path`, read from its header only (any format
/// [`read_color`] reads): what a command sums against the memory budget before decoding.
pub fn image_size(path: &Path) -> Result<(u32, u32), FrameError> {
    if extension(path) == "exr" {
        let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| codec(path, e))?;
        let size = meta
            .headers
            .first()
            .ok_or_else(|| codec(path, "no layer in file"))?
            .layer_size;
        return check_size(size.0 as u64, size.1 as u64);
    }
    let file = std::fs::File::open(path).map_err(|source| FrameError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    header_size(image::ImageReader::new(std::io::BufReader::new(file)), path)
}

/// [`image_size`] of an encoded image held in memory (`path` only names it in errors).
pub fn image_size_of(bytes: &[u8], path: &Path) -> Result<(u32, u32), FrameError> {
    header_size(image::ImageReader::new(std::io::Cursor::new(bytes)), path)
}

/// The size in an image's header, its format guessed from its first bytes.
fn header_size<R: std::io::BufRead + std::io::Seek>(
    reader: image::ImageReader<R>,
    path: &Path,
) -> Result<(u32, u32), FrameError> {
    let reader = reader
        .with_guessed_format()
        .map_err(|source| FrameError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    let (w, h) = reader.into_dimensions().map_err(|e| codec(path, e))?;
    check_size(w as u64, h as u64)
}

/// Reads a float colour image by extension: `.exr` or `.hdr`; anything else as sRGB.
pub fn read_color(path: &Path) -> Result<Image<Rgba>, FrameError> {
    match extension(path).as_str() {
        "exr" => read_exr_rgba(path),
        "hdr" => read_hdr(path),
        _ => read_png(path),
    }
}

/// Writes a colour image by extension: `.exr` as float, anything else as sRGB PNG.
pub fn write_color(path: &Path, image: &Image<Rgba>) -> Result<(), FrameError> {
    match extension(path).as_str() {
        "exr" => write_exr_rgba(path, image),
        _ => write_png(path, image),
    }
}

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trip_is_within_8_bit_quantisation() {
        let dir = crate::test_scratch::scratch("io-png-round-trip");
        let path = dir.join("rt.png");
        let img = Image::from_vec(
            3,
            1,
            vec![
                Vec4::new(0.0, 0.5, 1.0, 1.0),
                Vec4::new(0.2, 0.02, 0.7, 0.5),
                Vec4::ONE,
            ],
        )
        .unwrap();
        write_png(&path, &img).unwrap();
        let back = read_png(&path).unwrap();
        for (a, b) in img.pixels().iter().zip(back.pixels()) {
            assert!((*a - *b).abs().max_element() < 0.01, "{a} vs {b}");
        }
    }

    #[test]
    fn exr_depth_round_trips_exactly() {
        let dir = crate::test_scratch::scratch("io-exr-depth");
        let path = dir.join("depth.exr");
        let depth = Image::from_vec(2, 2, vec![1.0, 2.5, f32::INFINITY, 1e-3]).unwrap();
        write_exr_depth(&path, &depth).unwrap();
        let back = read_exr_channels(&path).unwrap().channel("Z").unwrap();
        assert_eq!(back, depth);
    }

    #[test]
    fn garbage_files_are_errors() {
        let dir = crate::test_scratch::scratch("io-garbage-files");
        for name in ["bad.png", "bad.exr", "bad.hdr"] {
            let path = dir.join(name);
            std::fs::write(&path, b"not an image at all").unwrap();
            assert!(read_color(&path).is_err(), "{name}");
        }
    }
}
