//! Mesh loaders: Wavefront OBJ + MTL, Stanford PLY (ASCII and binary), glTF 2.0 / GLB.
//!
//! Each loader reads the whole file, validates every index and coordinate, and returns a
//! [`LoadedMesh`]: the mesh in one coordinate frame (glTF node transforms applied), the counts
//! as stored, and warnings. Nothing here panics on bad input, and no allocation is sized by a
//! count the file declares without first checking the file holds that much data.

pub mod compressed;
mod gltf;
mod obj;
mod ply;

use super::{Mesh, MeshError, SourceCounts, Warning};
use std::path::{Path, PathBuf};

/// A mesh as loaded from a file.
#[derive(Clone, Debug)]
pub struct LoadedMesh {
    /// The validated mesh.
    pub mesh: Mesh,
    /// Counts as the file stores them.
    pub source: SourceCounts,
    /// Problems survived while loading.
    pub warnings: Vec<Warning>,
    /// Every file read: the mesh file, then what it names (material libraries, textures,
    /// buffers, images) — what a command must never overwrite.
    pub files: Vec<PathBuf>,
}

/// A binary glTF (GLB) of a JSON document and its binary chunk, each padded to four bytes as the
/// container requires (JSON with spaces, binary with zeros).
pub fn glb_bytes(json: Vec<u8>, bin: Vec<u8>) -> Result<Vec<u8>, ::gltf::Error> {
    fn pad(mut bytes: Vec<u8>, with: u8) -> Vec<u8> {
        while !bytes.len().is_multiple_of(4) {
            bytes.push(with);
        }
        bytes
    }
    ::gltf::binary::Glb {
        header: ::gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: 0,
        },
        json: std::borrow::Cow::Owned(pad(json, b' ')),
        bin: Some(std::borrow::Cow::Owned(pad(bin, 0))),
    }
    .to_vec()
}

/// Loads a mesh, choosing the format by extension (`.obj`, `.ply`, `.gltf`, `.glb`).
pub fn load(path: &Path) -> Result<LoadedMesh, MeshError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "obj" => obj::load(path),
        "ply" => ply::load(path),
        "gltf" | "glb" => gltf::load(path),
        _ => Err(MeshError::Unsupported {
            path: path.to_path_buf(),
            reason: format!("unknown extension {ext:?} (expected obj, ply, gltf or glb)"),
        }),
    }
}

fn read_file(path: &Path) -> Result<Vec<u8>, MeshError> {
    std::fs::read(path).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })
}

fn malformed(path: &Path, element: impl Into<String>, reason: impl Into<String>) -> MeshError {
    MeshError::Malformed {
        path: path.to_path_buf(),
        element: element.into(),
        reason: reason.into(),
    }
}

/// What one load has read: every file, and the textures decoded so far (one decode a path,
/// however many materials name it).
#[derive(Default)]
struct Reads {
    files: Vec<PathBuf>,
    textures: std::collections::HashMap<PathBuf, super::Texture>,
}

/// Bytes one texture pixel costs while it is decoded: the file's pixels, an RGBA8 copy and the
/// linear result, as `frame::io` decodes.
const TEXTURE_DECODE_BYTES: u64 = 28;

/// Refuses decoding a `w × h` texture `what` when it and what the process holds (the mesh's
/// textures decoded before it among them) pass the memory budget together.
fn budget_texture(
    what: impl Fn() -> String,
    (w, h): (u32, u32),
) -> Result<(), crate::memory::OverBudget> {
    let pixels = u64::from(w) * u64::from(h);
    crate::memory::check(
        || format!("{}, a {w} × {h} texture of this mesh,", what()),
        crate::memory::times(pixels, TEXTURE_DECODE_BYTES),
    )
}

fn load_texture(
    mesh_path: &Path,
    name: &str,
    reads: &mut Reads,
) -> Result<super::Texture, MeshError> {
    let dir = mesh_path.parent().unwrap_or(Path::new("."));
    let at = dir.join(name);
    if let Some(t) = reads.textures.get(&at) {
        return Ok(t.clone());
    }
    reads.files.push(at.clone());
    let texture_error = |source| MeshError::Texture {
        path: mesh_path.to_path_buf(),
        texture: name.to_string(),
        source,
    };
    let size = crate::frame::io::image_size(&at).map_err(texture_error)?;
    budget_texture(|| at.display().to_string(), size).map_err(|e| texture_error(e.into()))?;
    let image = crate::frame::io::read_png(&at).map_err(texture_error)?;
    let texture = std::sync::Arc::new(image);
    reads.textures.insert(at, texture.clone());
    Ok(texture)
}

/// What `trompe info` says of a loaded mesh file ([`LoadedMesh::summary`]).
pub struct MeshSummary<'a> {
    path: &'a Path,
    loaded: &'a LoadedMesh,
}

impl LoadedMesh {
    /// Counts, bounds, surface, materials and textures, for printing.
    pub fn summary<'a>(&'a self, path: &'a Path) -> MeshSummary<'a> {
        MeshSummary { path, loaded: self }
    }
}

/// As JSON: every figure the text shows.
impl serde::Serialize for MeshSummary<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let (loaded, m) = (self.loaded, &self.loaded.mesh);
        let b = m.bounds();
        let materials: Vec<_> = (m.materials.iter())
            .map(|mat| {
                serde_json::json!({
                    "name": mat.name,
                    "base_color": mat.base_color.to_array(),
                    "texture": mat.texture.as_ref().map(|t| [t.width(), t.height()]),
                })
            })
            .collect();
        serde_json::json!({
            "kind": "mesh",
            "path": self.path,
            "vertices_in_file": loaded.source.vertices,
            "vertices": m.positions.len(),
            "triangles_in_file": loaded.source.triangles,
            "triangles": m.triangle_count(),
            "bounds": { "min": b.min.to_array(), "max": b.max.to_array() },
            "surface_area": m.area(),
            "uvs": m.uvs.is_some(),
            "materials": materials,
        })
        .serialize(s)
    }
}

impl std::fmt::Display for MeshSummary<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (loaded, m) = (self.loaded, &self.loaded.mesh);
        let b = m.bounds();
        writeln!(f, "{}", self.path.display())?;
        writeln!(
            f,
            "  vertices   {} in the file, {} after splitting by attribute",
            loaded.source.vertices,
            m.positions.len()
        )?;
        writeln!(
            f,
            "  triangles  {} in the file, {} kept",
            loaded.source.triangles,
            m.triangle_count()
        )?;
        writeln!(
            f,
            "  bounds     [{:.4}, {:.4}, {:.4}] .. [{:.4}, {:.4}, {:.4}]",
            b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
        )?;
        writeln!(f, "  surface    {:.6} square units", m.area())?;
        writeln!(
            f,
            "  UVs        {}",
            if m.uvs.is_some() { "yes" } else { "no" }
        )?;
        write!(f, "  materials  {}", m.materials.len())?;
        for mat in &m.materials {
            let c = mat.base_color;
            let tex = mat.texture.as_ref().map_or("no texture".to_string(), |t| {
                format!("texture {}×{}", t.width(), t.height())
            });
            write!(
                f,
                "\n    {:<24} colour [{:.3}, {:.3}, {:.3}], {tex}",
                mat.name, c.x, c.y, c.z
            )?;
        }
        Ok(())
    }
}
