//! OpenRaster (`.ora`), the layered image format GIMP and Krita open and save: a zip whose
//! first entry is `mimetype` (stored, `image/openraster`), a `stack.xml` listing the layers top
//! first with their offsets, one PNG a layer under `data/`, `mergedimage.png` (the composite)
//! and `Thumbnails/thumbnail.png` (at most 256 pixels a side). This is how image layers reach
//! an artist ("Layered view-dependent projective textures" §4.2) and come back.
//!
//! Invariants: a file written and read back gives the same layers, names, offsets and 8-bit
//! pixels; reading never panics and never allocates more than the memory budget allows —
//! a missing or malformed entry is an error that names it.

use crate::frame::io::{decode_srgb_image, encode_png};
use crate::frame::{FrameError, Image, Rgba};
use glam::Vec4;
use quick_xml::events::Event;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The `mimetype` of an OpenRaster file.
pub const MIMETYPE: &str = "image/openraster";

/// One layer: its name, where its top-left texel sits on the canvas, its pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct OraLayer {
    /// The layer's name (unique names are what trompe matches layers by).
    pub name: String,
    /// Canvas column of its left edge (may be negative).
    pub x: i32,
    /// Canvas row of its top edge (may be negative).
    pub y: i32,
    /// Linear RGBA.
    pub image: Image<Rgba>,
    /// Whether it is shown.
    pub visible: bool,
}

/// A layered image: the canvas size and the layers, top first.
#[derive(Clone, Debug, PartialEq)]
pub struct Ora {
    /// Canvas width.
    pub width: u32,
    /// Canvas height.
    pub height: u32,
    /// Layers, top of the stack first.
    pub layers: Vec<OraLayer>,
}

/// Errors reading or writing an OpenRaster file.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum OraError {
    /// The file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not a readable zip archive.
    #[error("{path}: not an OpenRaster file: {source}")]
    Zip {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: zip::result::ZipError,
    },
    /// An entry the format requires is missing.
    #[error("{path}: entry {entry} is missing")]
    Missing {
        /// The file.
        path: PathBuf,
        /// The entry.
        entry: String,
    },
    /// An entry is malformed.
    #[error("{path}: {entry}: {reason}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// The entry (`stack.xml`, `data/layer3.png` …).
        entry: String,
        /// What is wrong.
        reason: String,
    },
    /// A layer's PNG could not be decoded.
    #[error("{path}: {entry}: {source}")]
    Image {
        /// The file.
        path: PathBuf,
        /// The entry.
        entry: String,
        /// The cause.
        source: FrameError,
    },
    /// A layer lies wholly outside the canvas.
    #[error(
        "{path}: layer {layer:?} at ({x}, {y}), {w} × {h}, lies outside the {width} × {height} canvas"
    )]
    OutsideCanvas {
        /// The file.
        path: PathBuf,
        /// The layer's name.
        layer: String,
        /// Its offset.
        x: i32,
        /// Its offset.
        y: i32,
        /// Its size.
        w: u32,
        /// Its size.
        h: u32,
        /// The canvas.
        width: u32,
        /// The canvas.
        height: u32,
    },
}

impl Ora {
    /// The visible layers composited over transparency (source-over, bottom up, in linear
    /// colour).
    pub fn composite(&self) -> Result<Image<Rgba>, FrameError> {
        let mut out = Image::new(self.width, self.height, Vec4::ZERO)?;
        for l in self.layers.iter().rev().filter(|l| l.visible) {
            let (lw, lh) = l.image.size();
            for ly in 0..lh {
                let y = l.y as i64 + ly as i64;
                if y < 0 || y >= self.height as i64 {
                    continue;
                }
                for lx in 0..lw {
                    let x = l.x as i64 + lx as i64;
                    if x < 0 || x >= self.width as i64 {
                        continue;
                    }
                    let src = l.image.get(lx, ly);
                    let dst = out.get(x as u32, y as u32);
                    let a = src.w + dst.w * (1.0 - src.w);
                    let c = if a > 0.0 {
                        (src.truncate() * src.w + dst.truncate() * dst.w * (1.0 - src.w)) / a
                    } else {
                        glam::Vec3::ZERO
                    };
                    out.set(x as u32, y as u32, c.extend(a));
                }
            }
        }
        Ok(out)
    }
}

/// Writes `ora` to `path` (replacing it whole).
pub fn write(path: &Path, ora: &Ora) -> Result<(), OraError> {
    let zip_err = |source| OraError::Zip {
        path: path.to_path_buf(),
        source,
    };
    let io_err = |source| OraError::Io {
        path: path.to_path_buf(),
        source,
    };
    let png = |img: &Image<Rgba>, entry: &str| {
        encode_png(img, Path::new(entry)).map_err(|source| OraError::Image {
            path: path.to_path_buf(),
            entry: entry.to_string(),
            source,
        })
    };
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let stored =
        zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    let deflated = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    zip.start_file("mimetype", stored).map_err(zip_err)?;
    zip.write_all(MIMETYPE.as_bytes()).map_err(io_err)?;
    let mut xml = format!(
        "<?xml version='1.0' encoding='UTF-8'?>\n<image version=\"0.0.5\" w=\"{}\" h=\"{}\">\n <stack>\n",
        ora.width, ora.height
    );
    for (i, l) in ora.layers.iter().enumerate() {
        let src = format!("data/layer{i:03}.png");
        xml.push_str(&format!(
            "  <layer name=\"{}\" src=\"{src}\" x=\"{}\" y=\"{}\" opacity=\"1.0\" visibility=\"{}\" composite-op=\"svg:src-over\"/>\n",
            quick_xml::escape::escape(l.name.as_str()),
            l.x,
            l.y,
            if l.visible { "visible" } else { "hidden" }
        ));
        let bytes = png(&l.image, &src)?;
        // PNGs are compressed already.
        zip.start_file(src, stored).map_err(zip_err)?;
        zip.write_all(&bytes).map_err(io_err)?;
    }
    xml.push_str(" </stack>\n</image>\n");
    zip.start_file("stack.xml", deflated).map_err(zip_err)?;
    zip.write_all(xml.as_bytes()).map_err(io_err)?;
    let merged = ora.composite().map_err(|source| OraError::Image {
        path: path.to_path_buf(),
        entry: "mergedimage.png".into(),
        source,
    })?;
    let bytes = png(&merged, "mergedimage.png")?;
    zip.start_file("mergedimage.png", stored).map_err(zip_err)?;
    zip.write_all(&bytes).map_err(io_err)?;
    let bytes = png(&thumbnail(&merged), "Thumbnails/thumbnail.png")?;
    zip.start_file("Thumbnails/thumbnail.png", stored)
        .map_err(zip_err)?;
    zip.write_all(&bytes).map_err(io_err)?;
    let bytes = zip.finish().map_err(zip_err)?.into_inner();
    crate::files::write_atomically(path, &bytes).map_err(io_err)
}

/// `img` scaled (box filter) to at most 256 pixels on its longer side.
fn thumbnail(img: &Image<Rgba>) -> Image<Rgba> {
    let (w, h) = img.size();
    let scale = (w.max(h) as f64 / 256.0).max(1.0);
    let (tw, th) = (
        ((w as f64 / scale) as u32).max(1),
        ((h as f64 / scale) as u32).max(1),
    );
    let mut out = Image::new(tw, th, Vec4::ZERO).unwrap_or_else(|_| img.clone());
    if out.size() == img.size() {
        return img.clone();
    }
    for ty in 0..th {
        for tx in 0..tw {
            let (x0, x1) = ((tx * w) / tw, ((tx + 1) * w).div_ceil(tw).min(w));
            let (y0, y1) = ((ty * h) / th, ((ty + 1) * h).div_ceil(th).min(h));
            let mut sum = Vec4::ZERO;
            for y in y0..y1 {
                for x in x0..x1 {
                    sum += img.get(x, y);
                }
            }
            out.set(tx, ty, sum / ((x1 - x0) * (y1 - y0)).max(1) as f32);
        }
    }
    out
}

/// Reads an OpenRaster file: its canvas and layers (nested stacks flattened, their offsets
/// added).
pub fn read(path: &Path) -> Result<Ora, OraError> {
    let file = std::fs::File::open(path).map_err(|source| OraError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut zip =
        zip::ZipArchive::new(std::io::BufReader::new(file)).map_err(|source| OraError::Zip {
            path: path.to_path_buf(),
            source,
        })?;
    let malformed = |entry: &str, reason: String| OraError::Malformed {
        path: path.to_path_buf(),
        entry: entry.to_string(),
        reason,
    };
    let mimetype = entry_bytes(&mut zip, path, "mimetype")?;
    if mimetype.trim_ascii() != MIMETYPE.as_bytes() {
        return Err(malformed(
            "mimetype",
            format!(
                "is {:?}, not {MIMETYPE:?}",
                String::from_utf8_lossy(&mimetype)
            ),
        ));
    }
    let xml = entry_bytes(&mut zip, path, "stack.xml")?;
    let xml =
        String::from_utf8(xml).map_err(|_| malformed("stack.xml", "is not UTF-8 text".into()))?;
    let (width, height, specs) = parse_stack(&xml).map_err(|r| malformed("stack.xml", r))?;
    let mut layers = Vec::new();
    for s in specs {
        let bytes = entry_bytes(&mut zip, path, &s.src)?;
        let image =
            decode_srgb_image(&bytes, Path::new(&s.src)).map_err(|source| OraError::Image {
                path: path.to_path_buf(),
                entry: s.src.clone(),
                source,
            })?;
        let (w, h) = image.size();
        let outside = s.x >= width as i64
            || s.y >= height as i64
            || s.x + w as i64 <= 0
            || s.y + h as i64 <= 0;
        let x = i32::try_from(s.x).ok();
        let y = i32::try_from(s.y).ok();
        let (Some(x), Some(y), false) = (x, y, outside) else {
            return Err(OraError::OutsideCanvas {
                path: path.to_path_buf(),
                layer: s.name,
                x: s.x.clamp(i32::MIN as i64, i32::MAX as i64) as i32,
                y: s.y.clamp(i32::MIN as i64, i32::MAX as i64) as i32,
                w,
                h,
                width,
                height,
            });
        };
        layers.push(OraLayer {
            name: s.name,
            x,
            y,
            image,
            visible: s.visible,
        });
    }
    Ok(Ora {
        width,
        height,
        layers,
    })
}

/// The whole of entry `name`, its declared size checked against the memory budget first.
fn entry_bytes<R: Read + std::io::Seek>(
    zip: &mut zip::ZipArchive<R>,
    path: &Path,
    name: &str,
) -> Result<Vec<u8>, OraError> {
    let mut f = match zip.by_name(name) {
        Ok(f) => f,
        Err(zip::result::ZipError::FileNotFound) => {
            return Err(OraError::Missing {
                path: path.to_path_buf(),
                entry: name.to_string(),
            });
        }
        Err(source) => {
            return Err(OraError::Zip {
                path: path.to_path_buf(),
                source,
            });
        }
    };
    let size = f.size();
    crate::memory::check(|| format!("{}: entry {name}", path.display()), size).map_err(|e| {
        OraError::Malformed {
            path: path.to_path_buf(),
            entry: name.to_string(),
            reason: e.to_string(),
        }
    })?;
    let mut out = Vec::with_capacity(size as usize);
    (&mut f)
        .take(size + 1)
        .read_to_end(&mut out)
        .map_err(|e| OraError::Malformed {
            path: path.to_path_buf(),
            entry: name.to_string(),
            reason: format!("cannot be read: {e}"),
        })?;
    Ok(out)
}

/// A `<layer>` of `stack.xml`, its offset made absolute.
struct LayerSpec {
    name: String,
    src: String,
    x: i64,
    y: i64,
    visible: bool,
}

/// The canvas size and the layers of a `stack.xml`, top first.
fn parse_stack(xml: &str) -> Result<(u32, u32, Vec<LayerSpec>), String> {
    let mut reader = quick_xml::Reader::from_str(xml);
    let mut size = None;
    let mut layers = Vec::new();
    // Offsets of the enclosing stacks.
    let mut offsets: Vec<(i64, i64)> = vec![(0, 0)];
    let mut open = 0usize;
    loop {
        let event = reader
            .read_event()
            .map_err(|e| format!("not well-formed XML: {e}"))?;
        let (e, empty) = match &event {
            Event::Start(e) => {
                open += 1;
                (e, false)
            }
            Event::Empty(e) => (e, true),
            Event::End(e) => {
                open = open.saturating_sub(1);
                if e.name().as_ref() == "stack" && offsets.len() > 1 {
                    offsets.pop();
                }
                continue;
            }
            Event::Eof if open > 0 => return Err("ends before its elements are closed".into()),
            Event::Eof => break,
            _ => continue,
        };
        let mut attrs = std::collections::HashMap::new();
        for a in e.attributes() {
            let a = a.map_err(|e| format!("bad attribute: {e}"))?;
            let key = a.key.as_ref().to_string();
            let value = a
                .normalized_value(quick_xml::XmlVersion::Implicit1_0)
                .map_err(|e| format!("bad attribute {key}: {e}"))?
                .into_owned();
            attrs.insert(key, value);
        }
        let int = |key: &str, default: i64| -> Result<i64, String> {
            attrs.get(key).map_or(Ok(default), |v| {
                v.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|f| f.is_finite() && f.abs() < 1e9)
                    .map(|f| f as i64)
                    .ok_or_else(|| format!("{key}={v:?} is not a number"))
            })
        };
        let base = *offsets.last().unwrap_or(&(0, 0));
        match e.name().as_ref() {
            "image" => {
                let (w, h) = (int("w", -1)?, int("h", -1)?);
                let checked = crate::frame::check_size(w.max(0) as u64, h.max(0) as u64);
                match checked {
                    Ok(s) if w > 0 && h > 0 => size = Some(s),
                    _ => return Err(format!("canvas w={w} h={h} is not a valid size")),
                }
            }
            "stack" if !empty => {
                offsets.push((base.0 + int("x", 0)?, base.1 + int("y", 0)?));
            }
            "layer" => {
                let src = attrs
                    .get("src")
                    .ok_or_else(|| "a layer has no src".to_string())?
                    .clone();
                layers.push(LayerSpec {
                    name: attrs.get("name").cloned().unwrap_or_else(|| src.clone()),
                    x: base.0 + int("x", 0)?,
                    y: base.1 + int("y", 0)?,
                    visible: attrs.get("visibility").is_none_or(|v| v != "hidden"),
                    src,
                });
            }
            _ => {}
        }
    }
    let (w, h) = size.ok_or_else(|| "no <image> element".to_string())?;
    Ok((w, h, layers))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_nested_stack_adds_its_offset() {
        let xml = r#"<image w="10" h="8"><stack><stack x="2" y="3"><layer src="a.png" x="1" y="1" name="a &amp; b"/></stack><layer src="b.png"/></stack></image>"#;
        let (w, h, l) = parse_stack(xml).expect("valid");
        assert_eq!((w, h), (10, 8));
        assert_eq!((l[0].x, l[0].y, l[0].name.as_str()), (3, 4, "a & b"));
        assert_eq!((l[1].x, l[1].y), (0, 0));
    }

    #[test]
    fn a_canvas_without_size_is_refused() {
        assert!(parse_stack("<image><stack/></image>").is_err());
        assert!(parse_stack("<image w='0' h='5'/>").is_err());
        assert!(parse_stack("<image w='5' h='5'><layer x='1'/></image>").is_err());
    }
}
