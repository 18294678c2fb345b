//! KTX2 textures as glTF's `KHR_texture_basisu` carries them: Basis Universal UASTC blocks,
//! Zstandard-supercompressed, with a mip chain the caller makes (so that it can keep each level
//! inside whatever tiles it holds — an octahedral atlas's frames). Each level is encoded by the
//! Basis Universal encoder (the `basisu_c_sys` crate, BinomialLLC's C API) as a one-level KTX2
//! file; this module joins those levels into one container as the KTX 2.0 specification lays it
//! out (identifier, header, index, level index largest first, the data format descriptor and
//! key/value data of the first level, then the levels' data smallest first), and reads level 0
//! back through the Basis Universal transcoder.
//!
//! Invariants: every level shares one data format descriptor (UASTC, sRGB or linear as asked);
//! a file is read back only after its header's size is checked against the caller's.

use super::{FrameError, Image, Rgba};
use basisu_c_sys::extra as basisu;
use std::path::Path;

/// The KTX 2.0 file identifier.
const IDENTIFIER: [u8; 12] = [
    0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
];

/// The supercompression scheme of Zstandard.
const ZSTANDARD: u32 = 2;

/// One mip level: its size and its 8-bit RGBA texels, rows top to bottom.
#[derive(Clone, Copy, Debug)]
pub struct Level<'a> {
    /// Texels across.
    pub width: u32,
    /// Texels down.
    pub height: u32,
    /// `width · height · 4` bytes.
    pub rgba8: &'a [u8],
}

/// How the texels are to be read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transfer {
    /// sRGB-encoded colour (the GPU decodes to linear).
    Srgb,
    /// Data, read as stored.
    Linear,
}

fn codec(path: &Path, reason: impl ToString) -> FrameError {
    FrameError::Codec {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}

/// A KTX2 file of `levels` (level 0 the largest, each half the one before, rounded down, at
/// least 1), UASTC and Zstandard-supercompressed (`path` only names it in errors).
pub fn encode_uastc(
    levels: &[Level],
    transfer: Transfer,
    path: &Path,
) -> Result<Vec<u8>, FrameError> {
    let Some(first) = levels.first() else {
        return Err(codec(path, "a KTX2 texture needs at least one level"));
    };
    basisu::basisu_encoder_init();
    let format = basisu_c_sys::BasisTextureFormat::UastcLdr4x4;
    let mut params = match transfer {
        Transfer::Srgb => basisu::BasisuEncoderParams::new_with_srgb_defaults(format),
        Transfer::Linear => basisu::BasisuEncoderParams::new_with_linear_defaults(format),
    };
    // UASTC's fastest level without rate-distortion optimisation: on atlases (frames filled
    // flat by dilation) Zstandard takes nearly all RDO would, at a third of the time.
    params.quality_level = -1;
    params.effort_level = -1;
    let mut files = Vec::with_capacity(levels.len());
    for (k, level) in levels.iter().enumerate() {
        let mut encoder = basisu::BasisuEncoder::new();
        let image = basisu::SourceImage {
            data: level.rgba8,
            format: basisu::SourceImageFormat::Rgba8,
            size: basisu::types::Extent3d {
                width: level.width,
                height: level.height,
                depth_or_array_layers: 1,
            },
        };
        encoder
            .set_image(image)
            .and_then(|()| encoder.compress(params))
            .map(|file| files.push(file))
            .map_err(|e| codec(path, format!("level {k}: {e}")))?;
    }
    let readers = files
        .iter()
        .map(|f| ktx2::Reader::new(&f[..]).map_err(|e| codec(path, format!("{e:?}"))))
        .collect::<Result<Vec<_>, _>>()?;
    // The descriptor and key/value data of the first level's file stand for all.
    let head = readers[0].header();
    let slice = |offset: u32, length: u32| -> Result<&[u8], FrameError> {
        files[0]
            .get(offset as usize..(offset + length) as usize)
            .ok_or_else(|| codec(path, "the encoder's KTX2 file is shorter than its index"))
    };
    let dfd = slice(head.index.dfd_byte_offset, head.index.dfd_byte_length)?;
    let kvd = slice(head.index.kvd_byte_offset, head.index.kvd_byte_length)?;
    let mut data = Vec::new();
    for (k, r) in readers.iter().enumerate() {
        let h = r.header();
        let one = r.levels().next();
        match (h.supercompression_scheme, h.level_count, one) {
            (Some(ktx2::SupercompressionScheme::Zstandard), 1, Some(level)) => {
                data.push((level.data, level.uncompressed_byte_length))
            }
            _ => {
                return Err(codec(
                    path,
                    format!(
                        "level {k}: the encoder did not write one Zstandard-supercompressed level"
                    ),
                ));
            }
        }
    }
    let count = levels.len() as u64;
    let level_index_at = 12 + 9 * 4 + 4 * 4 + 2 * 8;
    let dfd_at = (level_index_at + 24 * count).next_multiple_of(4);
    let kvd_at = dfd_at + dfd.len() as u64;
    let data_at = kvd_at + kvd.len() as u64;
    let mut out = Vec::new();
    out.extend_from_slice(&IDENTIFIER);
    for v in [
        0u32, // vkFormat: VK_FORMAT_UNDEFINED, the descriptor says what it is
        1,    // typeSize
        first.width,
        first.height,
        0, // pixelDepth
        0, // layerCount
        1, // faceCount
        levels.len() as u32,
        ZSTANDARD,
    ] {
        out.extend(v.to_le_bytes());
    }
    for v in [
        dfd_at as u32,
        dfd.len() as u32,
        kvd_at as u32,
        kvd.len() as u32,
    ] {
        out.extend(v.to_le_bytes());
    }
    out.extend(0u64.to_le_bytes()); // no supercompression global data
    out.extend(0u64.to_le_bytes());
    // Level data smallest first; the level index largest first.
    let mut offsets = vec![0u64; data.len()];
    let mut at = data_at;
    for k in (0..data.len()).rev() {
        offsets[k] = at;
        at += data[k].0.len() as u64;
    }
    for (k, (bytes, uncompressed)) in data.iter().enumerate() {
        out.extend(offsets[k].to_le_bytes());
        out.extend((bytes.len() as u64).to_le_bytes());
        out.extend(uncompressed.to_le_bytes());
    }
    out.resize(dfd_at as usize, 0);
    out.extend_from_slice(dfd);
    out.extend_from_slice(kvd);
    for (bytes, _) in data.iter().rev() {
        out.extend_from_slice(bytes);
    }
    Ok(out)
}

/// Level 0 of a KTX2 file of Basis Universal texels, `expected` in size, as stored (8-bit
/// values scaled to `[0, 1]`, not decoded from sRGB): refused, naming `path`, when it is not
/// one or is another size.
pub fn decode_level0(
    bytes: &[u8],
    expected: (u32, u32),
    path: &Path,
) -> Result<Image<Rgba>, FrameError> {
    let reader =
        ktx2::Reader::new(bytes).map_err(|e| codec(path, format!("not a KTX2 file: {e:?}")))?;
    let h = reader.header();
    if (h.pixel_width, h.pixel_height) != expected || h.face_count != 1 || h.layer_count > 1 {
        return Err(codec(
            path,
            format!(
                "a KTX2 texture of {} × {} ({} faces, {} layers), where {} × {} was expected",
                h.pixel_width, h.pixel_height, h.face_count, h.layer_count, expected.0, expected.1
            ),
        ));
    }
    super::check_size(u64::from(expected.0), u64::from(expected.1))?;
    basisu::basisu_transcoder_init();
    let transcoder = basisu::BasisuTranscoder::new(
        bytes,
        basisu::SupportedTextureCompression::empty(),
        basisu::ChannelType::Auto,
    )
    .map_err(|e| codec(path, e))?;
    let image = transcoder
        .transcode(
            Some(basisu_c_sys::TranscodeTargetFormat::RGBA32),
            Some(false),
        )
        .map_err(|e| codec(path, e))?;
    let (w, h) = expected;
    let texels = (w as usize) * (h as usize);
    let Some(level0) = image.data.get(..texels * 4) else {
        return Err(codec(path, "the transcoded level 0 is short"));
    };
    let pixels = level0
        .chunks_exact(4)
        .map(|p| Rgba::new(p[0] as f32, p[1] as f32, p[2] as f32, p[3] as f32) / 255.0)
        .collect();
    Image::from_vec(w, h, pixels)
}

/// The number of levels in a KTX2 file, and whether they are UASTC (for checks and reports).
pub fn describe(bytes: &[u8]) -> Option<(u32, u32, u32)> {
    let h = ktx2::Reader::new(bytes).ok()?.header();
    Some((h.pixel_width, h.pixel_height, h.level_count))
}
