//! Stanford PLY reader: `ascii`, `binary_little_endian` and `binary_big_endian`, version 1.0.
//!
//! Reads the `vertex` element (`x y z`, optional `nx ny nz`, optional `u v` / `s t` /
//! `texture_u texture_v`) and the `face` element (list property `vertex_indices` or
//! `vertex_index`); other elements and properties are skipped. Declared counts are checked
//! against the bytes left before any storage is reserved.

use super::{LoadedMesh, malformed, read_file};
use crate::geom::{Mesh, MeshError, SourceCounts, Warning};
use glam::{Vec2, Vec3};
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Format {
    Ascii,
    BinaryLe,
    BinaryBe,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Clone, Debug)]
enum Property {
    Scalar {
        name: String,
        ty: Scalar,
    },
    List {
        name: String,
        count: Scalar,
        item: Scalar,
    },
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

impl Element {
    /// Fewest bytes one instance can take (binary), to bound declared counts.
    fn min_size(&self, format: Format) -> usize {
        match format {
            Format::Ascii => self.properties.len().max(1) * 2, // "0 " per property at least
            _ => self
                .properties
                .iter()
                .map(|p| match p {
                    Property::Scalar { ty, .. } => ty.size(),
                    Property::List { count, .. } => count.size(),
                })
                .sum::<usize>()
                .max(1),
        }
    }
}

/// Reads numbers one at a time from the body, in either encoding.
struct Body<'a> {
    path: &'a Path,
    format: Format,
    bytes: &'a [u8],
    pos: usize,
    /// The kind of element being read (`vertex`, `face` …) and its index: named in errors,
    /// formatted only when one occurs.
    kind: String,
    index: usize,
}

impl Body<'_> {
    /// The element being read, as errors name it (`vertex 12`).
    fn element(&self) -> String {
        format!("{} {}", self.kind, self.index)
    }

    /// Starts reading the elements of one kind.
    fn start(&mut self, kind: &str) {
        self.kind = kind.to_string();
        self.index = 0;
    }

    fn truncated(&self) -> MeshError {
        malformed(self.path, self.element(), "file ends early (truncated)")
    }

    fn read(&mut self, ty: Scalar) -> Result<f64, MeshError> {
        match self.format {
            Format::Ascii => {
                while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
                    self.pos += 1;
                }
                let start = self.pos;
                while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
                    self.pos += 1;
                }
                if start == self.pos {
                    return Err(self.truncated());
                }
                let tok = std::str::from_utf8(&self.bytes[start..self.pos]).unwrap_or("?");
                tok.parse::<f64>().map_err(|_| {
                    malformed(
                        self.path,
                        self.element(),
                        format!("{tok:?} is not a number"),
                    )
                })
            }
            Format::BinaryLe | Format::BinaryBe => {
                let n = ty.size();
                let Some(raw) = self.bytes.get(self.pos..self.pos + n) else {
                    return Err(self.truncated());
                };
                self.pos += n;
                let mut b = [0u8; 8];
                b[..n].copy_from_slice(raw);
                if self.format == Format::BinaryBe {
                    b[..n].reverse();
                }
                Ok(match ty {
                    Scalar::I8 => b[0] as i8 as f64,
                    Scalar::U8 => b[0] as f64,
                    Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
                    Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
                    Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::F64 => f64::from_le_bytes(b),
                })
            }
        }
    }
}

/// Largest polygon a face may declare (bounds the per-face allocation).
const MAX_FACE_VERTICES: usize = 1024;

/// Loads a PLY file.
pub fn load(path: &Path) -> Result<LoadedMesh, MeshError> {
    let bytes = read_file(path)?;
    let (format, elements, body_start) = parse_header(path, &bytes)?;
    let mut body = Body {
        path,
        format,
        bytes: &bytes,
        pos: body_start,
        kind: String::new(),
        index: 0,
    };
    let mut warnings = Vec::new();
    let mut positions: Vec<Vec3> = Vec::new();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut uvs: Vec<Vec2> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut vertex_count = 0;
    let (mut has_normals, mut has_uvs) = (false, false);

    for el in &elements {
        let left = bytes.len().saturating_sub(body.pos);
        if el.count.saturating_mul(el.min_size(format)) > left.saturating_add(1) {
            return Err(malformed(
                path,
                format!("element {}", el.name),
                format!(
                    "declares {} items but only {left} bytes follow (truncated)",
                    el.count
                ),
            ));
        }
        match el.name.as_str() {
            "vertex" => {
                vertex_count = el.count;
                let find = |names: &[&str]| {
                    el.properties.iter().position(|p| matches!(p, Property::Scalar { name, .. } if names.contains(&name.as_str())))
                };
                let xyz = [find(&["x"]), find(&["y"]), find(&["z"])];
                let [Some(ix), Some(iy), Some(iz)] = xyz else {
                    return Err(malformed(
                        path,
                        "element vertex",
                        "needs scalar properties x, y and z",
                    ));
                };
                let nrm = [find(&["nx"]), find(&["ny"]), find(&["nz"])];
                let uv = [
                    find(&["u", "s", "texture_u"]),
                    find(&["v", "t", "texture_v"]),
                ];
                has_normals = nrm.iter().all(Option::is_some);
                has_uvs = uv.iter().all(Option::is_some);
                positions.reserve(el.count);
                let mut values = vec![0.0f64; el.properties.len()];
                body.start("vertex");
                for i in 0..el.count {
                    body.index = i;
                    for (k, p) in el.properties.iter().enumerate() {
                        values[k] = read_property(&mut body, p)?;
                    }
                    let p = Vec3::new(values[ix] as f32, values[iy] as f32, values[iz] as f32);
                    if !p.is_finite() {
                        return Err(MeshError::NonFinite {
                            path: path.to_path_buf(),
                            element: body.element(),
                        });
                    }
                    positions.push(p);
                    if let [Some(a), Some(b), Some(c)] = nrm {
                        normals.push(Vec3::new(
                            values[a] as f32,
                            values[b] as f32,
                            values[c] as f32,
                        ));
                    }
                    if let [Some(a), Some(b)] = uv {
                        uvs.push(Vec2::new(values[a] as f32, 1.0 - values[b] as f32));
                    }
                }
            }
            "face" => {
                let list = el.properties.iter().position(|p| {
                    matches!(p, Property::List { name, .. } if name == "vertex_indices" || name == "vertex_index")
                });
                let Some(list) = list else {
                    return Err(malformed(
                        path,
                        "element face",
                        "needs a list property vertex_indices",
                    ));
                };
                triangles.reserve(el.count);
                body.start("face");
                for f in 0..el.count {
                    body.index = f;
                    for (k, p) in el.properties.iter().enumerate() {
                        if k != list {
                            read_property(&mut body, p)?;
                            continue;
                        }
                        let Property::List { count, item, .. } = p else {
                            continue;
                        };
                        let n = body.read(*count)?;
                        if !(3.0..=MAX_FACE_VERTICES as f64).contains(&n) {
                            return Err(malformed(
                                path,
                                body.element(),
                                format!("a face with {n} vertices"),
                            ));
                        }
                        let mut poly = Vec::with_capacity(n as usize);
                        for _ in 0..n as usize {
                            let i = body.read(*item)?;
                            if i.fract() != 0.0 || !i.is_finite() {
                                return Err(malformed(
                                    path,
                                    body.element(),
                                    format!("vertex index {i} is not a whole number"),
                                ));
                            }
                            if i < 0.0 || i >= vertex_count as f64 {
                                return Err(MeshError::IndexOutOfRange {
                                    path: path.to_path_buf(),
                                    kind: "vertex",
                                    element: body.element(),
                                    index: i as i64,
                                    count: vertex_count,
                                });
                            }
                            poly.push(i as u32);
                        }
                        for k in 1..poly.len() - 1 {
                            triangles.push([poly[0], poly[k], poly[k + 1]]);
                        }
                    }
                }
            }
            other => {
                warnings.push(Warning::Skipped {
                    path: path.to_path_buf(),
                    what: format!("element {other:?} ({} items)", el.count),
                });
                body.start(other);
                for i in 0..el.count {
                    body.index = i;
                    for p in &el.properties {
                        read_property(&mut body, p)?;
                    }
                }
            }
        }
    }
    let source = SourceCounts {
        vertices: positions.len(),
        triangles: triangles.len(),
    };
    let n = triangles.len();
    let mesh = Mesh::from_parts(
        path,
        positions,
        has_normals.then_some(normals),
        has_uvs.then_some(uvs),
        triangles,
        vec![0; n],
        Vec::new(),
        &mut warnings,
    )?;
    Ok(LoadedMesh {
        mesh,
        source,
        warnings,
        files: vec![path.to_path_buf()],
    })
}

fn read_property(body: &mut Body, p: &Property) -> Result<f64, MeshError> {
    match p {
        Property::Scalar { ty, .. } => body.read(*ty),
        Property::List { count, item, .. } => {
            let n = body.read(*count)?;
            if !(0.0..=MAX_FACE_VERTICES as f64).contains(&n) {
                return Err(malformed(
                    body.path,
                    body.element(),
                    format!("a list of {n} items"),
                ));
            }
            for _ in 0..n as usize {
                body.read(*item)?;
            }
            Ok(n)
        }
    }
}

fn parse_header(path: &Path, bytes: &[u8]) -> Result<(Format, Vec<Element>, usize), MeshError> {
    if !bytes.starts_with(b"ply") {
        return Err(malformed(path, "line 1", "not a PLY file (no 'ply' magic)"));
    }
    let end = find(bytes, b"end_header")
        .ok_or_else(|| malformed(path, "header", "no end_header (truncated)"))?;
    let mut body_start = end + b"end_header".len();
    // The body starts after the end_header line's terminator (\n or \r\n).
    if bytes.get(body_start) == Some(&b'\r') {
        body_start += 1;
    }
    if bytes.get(body_start) == Some(&b'\n') {
        body_start += 1;
    }
    let header = String::from_utf8_lossy(&bytes[..end]);
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for (line_no, line) in header.lines().enumerate().skip(1) {
        let element = format!("header line {}", line_no + 1);
        let t: Vec<&str> = line.split_whitespace().collect();
        match t.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, _version] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLe,
                    "binary_big_endian" => Format::BinaryBe,
                    other => {
                        return Err(malformed(
                            path,
                            element,
                            format!("unknown format {other:?}"),
                        ));
                    }
                })
            }
            ["element", name, count] => {
                let count = count.parse().map_err(|_| {
                    malformed(path, element.clone(), format!("bad count {count:?}"))
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            ["property", "list", c, i, name] => {
                let (Some(count), Some(item)) = (Scalar::parse(c), Scalar::parse(i)) else {
                    return Err(malformed(
                        path,
                        element,
                        format!("unknown list types {c:?} {i:?}"),
                    ));
                };
                let el = elements.last_mut().ok_or_else(|| {
                    malformed(path, element.clone(), "property before any element")
                })?;
                el.properties.push(Property::List {
                    name: name.to_string(),
                    count,
                    item,
                });
            }
            ["property", ty, name] => {
                let ty = Scalar::parse(ty).ok_or_else(|| {
                    malformed(path, element.clone(), format!("unknown type {ty:?}"))
                })?;
                let el = elements.last_mut().ok_or_else(|| {
                    malformed(path, element.clone(), "property before any element")
                })?;
                el.properties.push(Property::Scalar {
                    name: name.to_string(),
                    ty,
                });
            }
            _ => return Err(malformed(path, element, format!("cannot read {line:?}"))),
        }
    }
    let format = format.ok_or_else(|| malformed(path, "header", "no format line"))?;
    Ok((format, elements, body_start))
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}
