//! Compressed glTF geometry: vertex attributes stored as small integers
//! (`KHR_mesh_quantization`) and buffer views packed by meshoptimizer's codecs
//! (`EXT_meshopt_compression`), as engines stream meshes.
//!
//! [`write_mesh`] writes one triangle mesh, plain or compressed, into a GLB's binary chunk and
//! returns the document's entries for it; [`decode_glb`] turns a GLB that uses either extension
//! back into plain glTF 2.0 (float attributes, one buffer) for the loader beside it, since the
//! `gltf` crate refuses both.
//!
//! Invariants: the vertex codec is written at bitstream version 0 and the index codec at
//! version 1, the versions `EXT_meshopt_compression` specifies; compressed positions are 16-bit
//! steps of the mesh's longest side, placed by the node's uniform scale and translation, so a
//! decoded position is within half a step of the written one; nothing decoded is larger than
//! the file's declared buffers, and those pass the memory budget before they are allocated.

use super::malformed;
use crate::geom::MeshError;
use glam::Vec3;
use serde_json::{Value, json};
use std::path::Path;

/// The two extensions a compressed mesh requires.
pub const EXTENSIONS: [&str; 2] = ["KHR_mesh_quantization", "EXT_meshopt_compression"];

/// How a mesh's vertices and indices are stored in a `.glb`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GeometryEncoding {
    /// 32-bit float attributes and 32-bit indices: what every glTF reader loads.
    Float,
    /// 16-bit positions, 8-bit normals, 16-bit texture coordinates and 16- or 32-bit indices,
    /// ordered for the vertex cache and compressed by meshoptimizer: what engines stream
    /// (three.js, Babylon.js, Unity's glTFast, Godot), about five times smaller.
    #[default]
    Compressed,
}

/// One triangle mesh's vertex streams (equal lengths) and triangle list.
pub struct MeshStreams<'a> {
    /// Positions.
    pub positions: &'a [Vec3],
    /// Unit normals.
    pub normals: &'a [Vec3],
    /// Texture coordinates in [0, 1].
    pub uvs: &'a [[f32; 2]],
    /// Three vertex indices a triangle.
    pub indices: &'a [u32],
}

/// What a written mesh adds to the document.
#[derive(Debug)]
pub struct WrittenMesh {
    /// Buffer views, to be placed at the `first_view` given to [`write_mesh`].
    pub buffer_views: Vec<Value>,
    /// Accessors, to be placed at the `first_accessor` given.
    pub accessors: Vec<Value>,
    /// The primitive's `attributes`.
    pub attributes: Value,
    /// The primitive's `indices` accessor.
    pub indices: usize,
    /// The node's `translation` and uniform `scale` that place quantized positions.
    pub placement: Option<(Vec3, f32)>,
    /// Buffers after the binary chunk's (index 1 on).
    pub buffers: Vec<Value>,
    /// Extensions used, and required.
    pub extensions: &'static [&'static str],
}

/// Appends `mesh` to `bin` (the GLB's buffer 0) as `encoding` says.
pub fn write_mesh(
    mesh: &MeshStreams,
    encoding: GeometryEncoding,
    bin: &mut Vec<u8>,
    first_view: usize,
    first_accessor: usize,
) -> Result<WrittenMesh, meshopt::Error> {
    match encoding {
        GeometryEncoding::Float => Ok(write_float(mesh, bin, first_view, first_accessor)),
        GeometryEncoding::Compressed => write_compressed(mesh, bin, first_view, first_accessor),
    }
}

fn bounds(points: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    let (lo, hi) = points.fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    );
    if lo.cmple(hi).all() {
        (lo, hi)
    } else {
        (Vec3::ZERO, Vec3::ZERO)
    }
}

fn align(bin: &mut Vec<u8>) -> usize {
    bin.resize(bin.len().next_multiple_of(4), 0);
    bin.len()
}

fn write_float(mesh: &MeshStreams, bin: &mut Vec<u8>, v: usize, a: usize) -> WrittenMesh {
    let count = mesh.positions.len();
    let (lo, hi) = bounds(mesh.positions.iter().copied());
    let mut views = Vec::new();
    let mut stream = |bin: &mut Vec<u8>, bytes: &mut dyn Iterator<Item = u8>, target: u32| {
        let start = align(bin);
        bin.extend(bytes);
        views.push(json!({ "buffer": 0, "byteOffset": start, "byteLength": bin.len() - start, "target": target }));
    };
    let le = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    stream(
        bin,
        &mut mesh.positions.iter().flat_map(|p| le(&p.to_array())),
        34962,
    );
    stream(
        bin,
        &mut mesh
            .normals
            .iter()
            .flat_map(|n| le(&n.normalize_or(Vec3::Z).to_array())),
        34962,
    );
    stream(bin, &mut mesh.uvs.iter().flat_map(|t| le(t)), 34962);
    stream(
        bin,
        &mut mesh.indices.iter().flat_map(|i| i.to_le_bytes()),
        34963,
    );
    WrittenMesh {
        buffer_views: views,
        accessors: vec![
            json!({ "bufferView": v, "componentType": 5126, "count": count, "type": "VEC3",
                    "min": lo.to_array(), "max": hi.to_array() }),
            json!({ "bufferView": v + 1, "componentType": 5126, "count": count, "type": "VEC3" }),
            json!({ "bufferView": v + 2, "componentType": 5126, "count": count, "type": "VEC2" }),
            json!({ "bufferView": v + 3, "componentType": 5125, "count": mesh.indices.len(), "type": "SCALAR" }),
        ],
        attributes: json!({ "POSITION": a, "NORMAL": a + 1, "TEXCOORD_0": a + 2 }),
        indices: a + 3,
        placement: None,
        buffers: Vec::new(),
        extensions: &[],
    }
}

/// Largest 16-bit position step.
const STEPS: f32 = 65535.0;

fn write_compressed(
    mesh: &MeshStreams,
    bin: &mut Vec<u8>,
    v: usize,
    a: usize,
) -> Result<WrittenMesh, meshopt::Error> {
    let n = mesh.positions.len();
    // Triangles in vertex-cache order, vertices in first-use order (unused ones dropped): what
    // lets the codecs find their deltas.
    let mut indices = meshopt::optimize_vertex_cache(mesh.indices, n);
    let mut remap = vec![u32::MAX; n];
    let mut order = Vec::new();
    for i in &mut indices {
        let slot = &mut remap[*i as usize];
        if *slot == u32::MAX {
            *slot = order.len() as u32;
            order.push(*i as usize);
        }
        *i = *slot;
    }
    let count = order.len();
    let (lo, hi) = bounds(order.iter().map(|&o| mesh.positions[o]));
    let side = (hi - lo).max_element().max(f32::MIN_POSITIVE);
    let quantize = |x: f32, max: f32| x.round().clamp(0.0, max);
    let positions: Vec<[u16; 4]> = order
        .iter()
        .map(|&o| {
            let q = (mesh.positions[o] - lo) / side * STEPS;
            [q.x, q.y, q.z, 0.0].map(|c| quantize(c, STEPS) as u16)
        })
        .collect();
    let normals: Vec<[i8; 4]> = order
        .iter()
        .map(|&o| {
            let n = mesh.normals[o].normalize_or(Vec3::Z) * 127.0;
            [n.x, n.y, n.z, 0.0].map(|c| c.round().clamp(-127.0, 127.0) as i8)
        })
        .collect();
    let uvs: Vec<[u16; 2]> = order
        .iter()
        .map(|&o| mesh.uvs[o].map(|c| quantize(c * STEPS, STEPS) as u16))
        .collect();
    let (qlo, qhi) = bounds(
        positions
            .iter()
            .map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)),
    );
    // glTF forbids an index equal to its type's maximum (primitive restart).
    let index_size = if count < u16::MAX as usize { 2 } else { 4 };
    let streams: [(Vec<u8>, usize, usize, &str, u32); 4] = [
        (
            meshopt::encode_vertex_buffer_level(&positions, 2, Some(0))?,
            8,
            count,
            "ATTRIBUTES",
            34962,
        ),
        (
            meshopt::encode_vertex_buffer_level(&normals, 2, Some(0))?,
            4,
            count,
            "ATTRIBUTES",
            34962,
        ),
        (
            meshopt::encode_vertex_buffer_level(&uvs, 2, Some(0))?,
            4,
            count,
            "ATTRIBUTES",
            34962,
        ),
        (
            meshopt::encode_index_buffer(&indices, count)?,
            index_size,
            indices.len(),
            "TRIANGLES",
            34963,
        ),
    ];
    let mut views = Vec::new();
    let mut fallback = 0;
    for (encoded, stride, items, mode, target) in streams {
        let start = align(bin);
        bin.extend_from_slice(&encoded);
        let length = stride * items;
        let mut view = json!({
            "buffer": 1, "byteOffset": fallback, "byteLength": length, "target": target,
            "extensions": { "EXT_meshopt_compression": {
                "buffer": 0, "byteOffset": start, "byteLength": encoded.len(),
                "byteStride": stride, "count": items, "mode": mode
            }}
        });
        if mode == "ATTRIBUTES" {
            view["byteStride"] = stride.into();
        }
        views.push(view);
        fallback += length.next_multiple_of(4);
    }
    Ok(WrittenMesh {
        buffer_views: views,
        accessors: vec![
            json!({ "bufferView": v, "componentType": 5123, "count": count, "type": "VEC3",
                    "min": qlo.to_array(), "max": qhi.to_array() }),
            json!({ "bufferView": v + 1, "componentType": 5120, "normalized": true, "count": count, "type": "VEC3" }),
            json!({ "bufferView": v + 2, "componentType": 5123, "normalized": true, "count": count, "type": "VEC2" }),
            json!({ "bufferView": v + 3, "componentType": if index_size == 2 { 5123 } else { 5125 },
                    "count": indices.len(), "type": "SCALAR" }),
        ],
        attributes: json!({ "POSITION": a, "NORMAL": a + 1, "TEXCOORD_0": a + 2 }),
        indices: a + 3,
        placement: Some((lo, side / STEPS)),
        buffers: vec![json!({
            "byteLength": fallback,
            "extensions": { "EXT_meshopt_compression": { "fallback": true } }
        })],
        extensions: &EXTENSIONS,
    })
}

/// A GLB that uses `KHR_mesh_quantization` or `EXT_meshopt_compression`, rewritten as plain
/// glTF 2.0: compressed views decoded, every buffer joined into the binary chunk, quantized
/// positions, normals, tangents and texture coordinates turned into floats. `None` when the
/// file uses neither (or is not a GLB).
pub fn decode_glb(path: &Path, bytes: &[u8]) -> Result<Option<Vec<u8>>, MeshError> {
    let Ok(glb) = ::gltf::binary::Glb::from_slice(bytes) else {
        return Ok(None);
    };
    let bad = |element: &str, reason: String| malformed(path, element, reason);
    let Ok(mut root) = serde_json::from_slice::<Value>(&glb.json) else {
        return Ok(None);
    };
    let used: Vec<String> = root["extensionsUsed"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|e| e.as_str().map(str::to_owned))
                .collect()
        })
        .unwrap_or_default();
    if !used.iter().any(|e| EXTENSIONS.contains(&e.as_str())) {
        return Ok(None);
    }
    let chunk = glb.bin.as_deref().unwrap_or(&[]);
    let mut buffers = read_buffers(path, &root, chunk)?;
    decode_views(path, &mut root, &mut buffers)?;
    // One buffer: each old one at an offset of the new binary chunk.
    let mut bin = Vec::new();
    let mut base = Vec::new();
    for data in &buffers {
        base.push(align(&mut bin));
        bin.extend_from_slice(data);
    }
    for view in root["bufferViews"].as_array_mut().into_iter().flatten() {
        let buffer = view["buffer"].as_u64().unwrap_or(0) as usize;
        let offset = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        view["buffer"] = 0.into();
        view["byteOffset"] = (base.get(buffer).copied().unwrap_or(0) + offset).into();
    }
    dequantize(path, &mut root, &mut bin)?;
    root["buffers"] = json!([{ "byteLength": bin.len() }]);
    for key in ["extensionsUsed", "extensionsRequired"] {
        if let Some(list) = root[key].as_array_mut() {
            list.retain(|e| !e.as_str().is_some_and(|e| EXTENSIONS.contains(&e)));
        }
    }
    let json = serde_json::to_vec(&root).map_err(|e| bad("document", e.to_string()))?;
    crate::geom::io::glb_bytes(json, bin)
        .map(Some)
        .map_err(|e| bad("document", e.to_string()))
}

fn usize_at(value: &Value, key: &str) -> Option<usize> {
    value
        .get(key)?
        .as_u64()
        .and_then(|v| usize::try_from(v).ok())
}

/// Every buffer's bytes: the binary chunk for the first, zeros for a meshopt fallback (what
/// the compressed views decode into).
fn read_buffers(path: &Path, root: &Value, chunk: &[u8]) -> Result<Vec<Vec<u8>>, MeshError> {
    let mut out = Vec::new();
    for (i, buffer) in root["buffers"].as_array().into_iter().flatten().enumerate() {
        let element = format!("buffer {i}");
        let length = usize_at(buffer, "byteLength")
            .ok_or_else(|| malformed(path, &element, "no byteLength"))?;
        if buffer.get("uri").is_some() {
            return Err(MeshError::Unsupported {
                path: path.to_path_buf(),
                reason: format!(
                    "{element} is an external file; trompe reads compressed geometry from a \
                     self-contained .glb only"
                ),
            });
        }
        if i == 0 {
            if chunk.len() < length {
                return Err(malformed(
                    path,
                    &element,
                    format!(
                        "{length} bytes declared but the binary chunk holds {}",
                        chunk.len()
                    ),
                ));
            }
            out.push(chunk[..length].to_vec());
        } else if buffer["extensions"]["EXT_meshopt_compression"]["fallback"] == true {
            crate::memory::check(|| element.clone(), length as u64).map_err(|source| {
                MeshError::Memory {
                    path: path.to_path_buf(),
                    source,
                }
            })?;
            out.push(vec![0; length]);
        } else {
            return Err(malformed(
                path,
                &element,
                "neither the binary chunk nor a meshopt fallback",
            ));
        }
    }
    Ok(out)
}

/// Decodes every `EXT_meshopt_compression` view into its place in its own buffer.
fn decode_views(path: &Path, root: &mut Value, buffers: &mut [Vec<u8>]) -> Result<(), MeshError> {
    for (v, view) in root["bufferViews"]
        .as_array_mut()
        .into_iter()
        .flatten()
        .enumerate()
    {
        let Some(ext) = view
            .get_mut("extensions")
            .and_then(|e| e.as_object_mut())
            .and_then(|e| e.remove("EXT_meshopt_compression"))
        else {
            continue;
        };
        let element = format!("bufferView {v} (EXT_meshopt_compression)");
        let bad = |reason: String| malformed(path, &element, reason);
        let field = |key: &str| usize_at(&ext, key).ok_or_else(|| bad(format!("no {key}")));
        let (source, length) = (field("buffer")?, field("byteLength")?);
        let (stride, count) = (field("byteStride")?, field("count")?);
        let offset = usize_at(&ext, "byteOffset").unwrap_or(0);
        let encoded = buffers
            .get(source)
            .and_then(|b| b.get(offset..offset.checked_add(length)?))
            .ok_or_else(|| {
                bad(format!(
                    "bytes {offset}+{length} are not in buffer {source}"
                ))
            })?
            .to_vec();
        let target = usize_at(view, "buffer").unwrap_or(usize::MAX);
        let at = usize_at(view, "byteOffset").unwrap_or(0);
        let size = stride
            .checked_mul(count)
            .filter(|&s| s <= usize_at(view, "byteLength").unwrap_or(0))
            .ok_or_else(|| bad(format!("{count} items of {stride} bytes overflow the view")))?;
        let place = buffers
            .get_mut(target)
            .and_then(|b| b.get_mut(at..at.checked_add(size)?))
            .ok_or_else(|| bad(format!("the view's bytes are not in buffer {target}")))?;
        let mode = ext["mode"].as_str().unwrap_or("");
        let filter = ext["filter"].as_str().unwrap_or("NONE");
        let codec = |e: meshopt::Error| bad(format!("the {mode} data does not decode: {e}"));
        let decoded = match (mode, stride) {
            ("ATTRIBUTES", _) => {
                let mut data = decode_vertices(&encoded, stride, count)
                    .ok_or_else(|| {
                        bad(format!(
                            "byteStride {stride} is not a multiple of 4 up to 256"
                        ))
                    })?
                    .map_err(codec)?;
                unfilter(filter, stride, &mut data).map_err(bad)?;
                data
            }
            ("TRIANGLES", 2) => {
                le(&meshopt::decode_index_buffer::<u16>(&encoded, count).map_err(codec)?)
            }
            ("TRIANGLES", 4) => {
                le(&meshopt::decode_index_buffer::<u32>(&encoded, count).map_err(codec)?)
            }
            ("INDICES", 2) => {
                le(&meshopt::decode_index_sequence::<u16>(&encoded, count).map_err(codec)?)
            }
            ("INDICES", 4) => {
                le(&meshopt::decode_index_sequence::<u32>(&encoded, count).map_err(codec)?)
            }
            _ => {
                return Err(bad(format!(
                    "mode {mode:?} with byteStride {stride} is not one the extension defines"
                )));
            }
        };
        place.copy_from_slice(&decoded);
    }
    Ok(())
}

fn le<T: bytemuck::Pod>(values: &[T]) -> Vec<u8> {
    bytemuck::cast_slice(values).to_vec()
}

/// One vertex of `N` bytes, as the vertex codec sees it.
#[derive(Clone, Copy)]
struct Vertex<const N: usize>([u8; N]);

impl<const N: usize> Default for Vertex<N> {
    fn default() -> Self {
        Self([0; N])
    }
}

fn decode_n<const N: usize>(encoded: &[u8], count: usize) -> Result<Vec<u8>, meshopt::Error> {
    let vertices: Vec<Vertex<N>> = meshopt::decode_vertex_buffer(encoded, count)?;
    Ok(vertices.into_iter().flat_map(|v| v.0).collect())
}

/// The vertex codec's output for a stride it allows (a multiple of 4 up to 256).
fn decode_vertices(
    encoded: &[u8],
    stride: usize,
    count: usize,
) -> Option<Result<Vec<u8>, meshopt::Error>> {
    macro_rules! by_stride {
        ($($n:literal)*) => {
            match stride {
                $($n => Some(decode_n::<$n>(encoded, count)),)*
                _ => None,
            }
        };
    }
    by_stride!(4 8 12 16 20 24 28 32 36 40 44 48 52 56 60 64 68 72 76 80 84 88 92 96 100 104 108 112 116 120 124 128 132 136 140 144 148 152 156 160 164 168 172 176 180 184 188 192 196 200 204 208 212 216 220 224 228 232 236 240 244 248 252 256)
}

/// Undoes a view's meshopt filter in place.
fn unfilter(filter: &str, stride: usize, data: &mut [u8]) -> Result<(), String> {
    fn apply<T: bytemuck::Pod>(data: &mut [u8], f: impl FnOnce(&mut [T])) {
        let mut typed: Vec<T> = bytemuck::pod_collect_to_vec(data);
        f(&mut typed);
        data.copy_from_slice(bytemuck::cast_slice(&typed));
    }
    match (filter, stride) {
        ("NONE", _) => {}
        ("OCTAHEDRAL", 4) => apply::<[i8; 4]>(data, meshopt::decode_filter_oct),
        ("OCTAHEDRAL", 8) => apply::<[i16; 4]>(data, meshopt::decode_filter_oct),
        ("QUATERNION", 8) => apply::<[i16; 4]>(data, meshopt::decode_filter_quat),
        ("EXPONENTIAL", s) if s % 4 == 0 => {
            apply::<[u32; 1]>(data, meshopt::decode_filter_exp::<1>)
        }
        ("COLOR", 4) => apply::<[u8; 4]>(data, meshopt::decode_filter_color),
        ("COLOR", 8) => apply::<[u16; 4]>(data, meshopt::decode_filter_color),
        _ => {
            return Err(format!(
                "filter {filter:?} with byteStride {stride} is not one the extension defines"
            ));
        }
    }
    Ok(())
}

/// A component type's size and its value as a float (normalized or not).
/// A component's bytes as a float, normalized or not.
type Read = fn(&[u8], bool) -> f32;

fn component(kind: u64) -> Option<(usize, Read)> {
    fn read<const N: usize>(b: &[u8]) -> [u8; N] {
        let mut a = [0; N];
        a.copy_from_slice(&b[..N]);
        a
    }
    Some(match kind {
        5120 => (1, |b, n| {
            let v = b[0] as i8 as f32;
            if n { (v / 127.0).max(-1.0) } else { v }
        }),
        5121 => (1, |b, n| {
            let v = b[0] as f32;
            if n { v / 255.0 } else { v }
        }),
        5122 => (2, |b, n| {
            let v = i16::from_le_bytes(read(b)) as f32;
            if n { (v / 32767.0).max(-1.0) } else { v }
        }),
        5123 => (2, |b, n| {
            let v = u16::from_le_bytes(read(b)) as f32;
            if n { v / 65535.0 } else { v }
        }),
        5126 => (4, |b, _| f32::from_le_bytes(read(b))),
        _ => return None,
    })
}

/// Quantized vertex attributes as floats: each such accessor is given a float view of its own
/// at the end of `bin`.
fn dequantize(path: &Path, root: &mut Value, bin: &mut Vec<u8>) -> Result<(), MeshError> {
    let mut quantized = Vec::new();
    for mesh in root["meshes"].as_array().into_iter().flatten() {
        for prim in mesh["primitives"].as_array().into_iter().flatten() {
            for (semantic, accessor) in prim["attributes"].as_object().into_iter().flatten() {
                let floats = ["POSITION", "NORMAL", "TANGENT"].contains(&semantic.as_str())
                    || semantic.starts_with("TEXCOORD_");
                if let (true, Some(a)) = (floats, accessor.as_u64()) {
                    quantized.push(a as usize);
                }
            }
        }
    }
    quantized.sort_unstable();
    quantized.dedup();
    for a in quantized {
        let views = root["bufferViews"].as_array().map_or(0, Vec::len);
        let Some(accessor) = root["accessors"].get(a).cloned() else {
            continue; // the loader's own checks name a missing accessor
        };
        let kind = accessor["componentType"].as_u64().unwrap_or(5126);
        if kind == 5126 {
            continue;
        }
        let element = format!("accessor {a}");
        let bad = |reason: String| malformed(path, &element, reason);
        if accessor.get("sparse").is_some() {
            return Err(bad("a sparse quantized attribute is not supported".into()));
        }
        let normalized = accessor["normalized"] == true;
        let (size, value) = component(kind).ok_or_else(|| {
            bad(format!(
                "componentType {kind} is not one a vertex attribute may have"
            ))
        })?;
        let width = match accessor["type"].as_str() {
            Some("SCALAR") => 1,
            Some("VEC2") => 2,
            Some("VEC3") => 3,
            Some("VEC4") => 4,
            other => return Err(bad(format!("type {other:?} is not a vertex attribute's"))),
        };
        let count = usize_at(&accessor, "count").ok_or_else(|| bad("no count".into()))?;
        let v = usize_at(&accessor, "bufferView").ok_or_else(|| bad("no bufferView".into()))?;
        let view = root["bufferViews"]
            .get(v)
            .ok_or_else(|| bad(format!("bufferView {v} does not exist")))?;
        let stride = usize_at(view, "byteStride").unwrap_or(size * width);
        let at = |value: &Value| usize_at(value, "byteOffset").unwrap_or(0);
        let (Some(start), Some(end)) = (
            at(view).checked_add(at(&accessor)),
            at(view).checked_add(usize_at(view, "byteLength").unwrap_or(0)),
        ) else {
            return Err(bad(format!("bufferView {v}'s offsets overflow")));
        };
        let need = count
            .checked_sub(1)
            .map_or(Some(0), |n| {
                n.checked_mul(stride)?.checked_add(size * width)
            })
            .and_then(|n| n.checked_add(start));
        if need.is_none_or(|need| need > end || end > bin.len()) {
            return Err(bad(format!("{count} items do not fit bufferView {v}")));
        }
        let mut lo = vec![f32::INFINITY; width];
        let mut hi = vec![f32::NEG_INFINITY; width];
        let mut floats = Vec::with_capacity(count * width);
        for i in 0..count {
            for c in 0..width {
                let o = start + i * stride + c * size;
                let x = value(&bin[o..o + size], normalized);
                lo[c] = lo[c].min(x);
                hi[c] = hi[c].max(x);
                floats.push(x);
            }
        }
        let at = align(bin);
        bin.extend(floats.iter().flat_map(|x| x.to_le_bytes()));
        root["bufferViews"].as_array_mut().into_iter().for_each(|list| {
            list.push(json!({ "buffer": 0, "byteOffset": at, "byteLength": count * width * 4, "target": 34962 }))
        });
        let accessor = &mut root["accessors"][a];
        accessor["bufferView"] = views.into();
        accessor["componentType"] = 5126.into();
        if let Some(o) = accessor.as_object_mut() {
            o.remove("byteOffset");
            o.remove("normalized");
        }
        if count > 0 && accessor.get("min").is_some() {
            accessor["min"] = json!(lo);
            accessor["max"] = json!(hi);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An icosphere as a compressed GLB's JSON document and binary chunk.
    fn sphere() -> (Value, Vec<u8>) {
        let mesh = crate::geom::icosphere(2);
        let uvs: Vec<[f32; 2]> = mesh
            .positions
            .iter()
            .map(|p| [p.x * 0.5 + 0.5, p.y * 0.5 + 0.5])
            .collect();
        let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        let streams = MeshStreams {
            positions: &mesh.positions,
            normals: &mesh.positions,
            uvs: &uvs,
            indices: &indices,
        };
        let mut bin = Vec::new();
        let written = write_mesh(&streams, GeometryEncoding::Compressed, &mut bin, 0, 0).unwrap();
        let (t, s) = written.placement.unwrap();
        let mut buffers = vec![json!({ "byteLength": bin.len() })];
        buffers.extend(written.buffers);
        let doc = json!({
            "asset": { "version": "2.0" },
            "extensionsUsed": EXTENSIONS, "extensionsRequired": EXTENSIONS,
            "scene": 0, "scenes": [{ "nodes": [0] }],
            "nodes": [{ "mesh": 0, "translation": t.to_array(), "scale": [s, s, s] }],
            "meshes": [{ "primitives": [{ "attributes": written.attributes, "indices": written.indices }] }],
            "accessors": written.accessors, "bufferViews": written.buffer_views, "buffers": buffers,
        });
        (doc, bin)
    }

    fn load(
        dir: &Path,
        name: &str,
        (doc, bin): (Value, Vec<u8>),
    ) -> Result<crate::geom::Mesh, MeshError> {
        let path = dir.join(name);
        let bytes = crate::geom::io::glb_bytes(serde_json::to_vec(&doc).unwrap(), bin).unwrap();
        std::fs::write(&path, bytes).unwrap();
        crate::geom::io::load(&path).map(|l| l.mesh)
    }

    #[test]
    fn a_compressed_sphere_loads_back_within_half_a_step() {
        let dir = crate::test_scratch::scratch("compressed_sphere");
        let mesh = load(&dir, "sphere.glb", sphere()).unwrap();
        let original = crate::geom::icosphere(2);
        assert_eq!(mesh.triangles.len(), original.triangles.len());
        // A step is the diameter / 65535: every vertex within one of the sphere.
        let r = original.positions[0].length();
        for p in &mesh.positions {
            assert!((p.length() - r).abs() < 2.0 * r / 65535.0, "{p}");
        }
    }

    #[test]
    fn damaged_compressed_views_are_errors_that_name_them() {
        let dir = crate::test_scratch::scratch("compressed_damaged");
        type Damage = fn(&mut Value, &mut Vec<u8>);
        let cases: [(&str, Damage, &str); 4] = [
            (
                "short.glb",
                |doc, _| {
                    let ext = &mut doc["bufferViews"][0]["extensions"]["EXT_meshopt_compression"];
                    ext["byteLength"] = (ext["byteLength"].as_u64().unwrap() / 2).into();
                },
                "bufferView 0",
            ),
            (
                "outside.glb",
                |doc, _| {
                    doc["bufferViews"][3]["extensions"]["EXT_meshopt_compression"]["byteOffset"] =
                        1_000_000.into();
                },
                "bufferView 3",
            ),
            (
                "huge.glb",
                |doc, _| {
                    doc["buffers"][1]["byteLength"] = (1u64 << 50).into();
                },
                "buffer 1",
            ),
            (
                "garbled.glb",
                |_, bin| {
                    for b in bin.iter_mut().skip(1) {
                        *b = b.wrapping_mul(31).wrapping_add(7);
                    }
                },
                "",
            ),
        ];
        for (name, damage, element) in cases {
            let (mut doc, mut bin) = sphere();
            damage(&mut doc, &mut bin);
            let error = load(&dir, name, (doc, bin)).expect_err(name).to_string();
            assert!(error.contains(name) && error.contains(element), "{error}");
        }
    }
}
