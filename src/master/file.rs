//! Storage of a Master Texture encoding, engine-neutral: one PNG per view (`master_NNNN.png`,
//! alpha = the view sees the texel, ½ at its edge), the packing map and the one UV set as JSON (`masters.json`),
//! and the mesh with that single UV set as glTF 2.0 binary (`mesh.glb`: one primitive of
//! unwelded corners, three a face in face order, its texture embedded) — written with
//! `serde_json` and the `gltf` crate's GLB container, and read back by the `gltf` crate to
//! check it.
//!
//! Invariant: every file is written whole or not at all (`files::write_atomically`); the same
//! encoding gives the same bytes.

use super::layout::Layout;
use super::{Encoding, MasterError};
use crate::frame::{Image, Rgba, io};
use crate::geom::Mesh;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// What `masters.json` holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Manifest {
    /// Format version.
    pub version: u32,
    /// The packing map.
    pub layout: Layout,
    /// Per face, its three corners' texture coordinates (`[0, 1]²`, origin top-left).
    pub uvs: Vec<[f32; 2]>,
    /// Per view: its name, master texture file and camera.
    pub views: Vec<StoredView>,
}

/// One view in `masters.json`: its undistorted pinhole in McMillan's form (docs/conventions.md
/// §1.1): centre `C`, pixel steps `a`, `b`, corner vector `c`, size.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StoredView {
    /// The view's image name.
    pub name: String,
    /// Its master texture, a file name beside `masters.json`.
    pub master: String,
    /// `[C, a, b, c]`.
    pub camera: [[f64; 3]; 4],
    /// Width and height, pixels.
    pub size: [u32; 2],
}

impl StoredView {
    /// The view's pinhole.
    pub fn pinhole(&self) -> crate::camera::Pinhole {
        let [c, a, b, k] = self.camera.map(glam::DVec3::from_array);
        crate::camera::Pinhole::from_mcmillan(c, a, b, k, self.size[0], self.size[1])
    }
}

fn err(path: &Path, reason: impl std::fmt::Display) -> MasterError {
    MasterError::File {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}

/// The file name of view `i`'s master texture.
pub fn master_name(i: usize) -> String {
    format!("master_{i:04}.png")
}

/// The stored form of views `cameras`.
pub fn stored_views(cameras: &[(String, crate::camera::Pinhole)]) -> Vec<StoredView> {
    cameras
        .iter()
        .enumerate()
        .map(|(i, (name, cam))| {
            let (a, b, c) = cam.mcmillan();
            let (w, h) = crate::camera::Projection::resolution(cam);
            StoredView {
                name: name.clone(),
                master: master_name(i),
                camera: [cam.position(), a, b, c].map(|v| v.to_array()),
                size: [w, h],
            }
        })
        .collect()
}

/// Writes `masters.json` and `mesh.glb` (textured by `texture`, PNG bytes it embeds) into
/// `dir`; the master textures are written apart ([`master_name`]). Returns the files written.
pub fn save_manifest(
    dir: &Path,
    layout: &Layout,
    cameras: &[(String, crate::camera::Pinhole)],
    mesh: &Mesh,
    texture: &[u8],
) -> Result<Vec<PathBuf>, MasterError> {
    let manifest = Manifest {
        version: 1,
        layout: layout.clone(),
        uvs: layout.uvs(),
        views: stored_views(cameras),
    };
    let path = dir.join("masters.json");
    let json = serde_json::to_vec_pretty(&manifest).map_err(|e| err(&path, e))?;
    crate::files::write_atomically(&path, &json).map_err(|e| err(&path, e))?;
    let glb = dir.join("mesh.glb");
    crate::files::write_atomically(&glb, &gltf_bytes(mesh, &manifest.uvs, texture)?)
        .map_err(|e| err(&glb, e))?;
    Ok(vec![path, glb])
}

/// Writes `encoding` into `dir`: the master textures, `masters.json` and `mesh.glb` (textured
/// by `texture`, PNG bytes it embeds). Returns the files written.
pub fn save(
    dir: &Path,
    encoding: &Encoding,
    mesh: &Mesh,
    texture: &[u8],
) -> Result<Vec<PathBuf>, MasterError> {
    let mut written = Vec::new();
    for (i, m) in encoding.masters.iter().enumerate() {
        let path = dir.join(master_name(i));
        io::write_png(&path, m)?;
        written.push(path);
    }
    written.extend(save_manifest(
        dir,
        &encoding.atlas.layout,
        &encoding.cameras,
        mesh,
        texture,
    )?);
    Ok(written)
}

/// Reads and checks `masters.json` of `dir`.
pub fn load_manifest(dir: &Path) -> Result<Manifest, MasterError> {
    let path = dir.join("masters.json");
    let bytes = std::fs::read(&path).map_err(|e| err(&path, e))?;
    let manifest: Manifest = serde_json::from_slice(&bytes).map_err(|e| err(&path, e))?;
    if manifest.uvs.len() != manifest.layout.faces.len() * 3 {
        return Err(err(
            &path,
            format!(
                "{} texture coordinates for {} faces (3 a face)",
                manifest.uvs.len(),
                manifest.layout.faces.len()
            ),
        ));
    }
    crate::frame::check_size(manifest.layout.width as u64, manifest.layout.height as u64)?;
    for (face, f) in manifest.layout.faces.iter().enumerate() {
        let [x, y, w, h] = f.bbox.map(u64::from);
        let legs_ok = f
            .size
            .iter()
            .all(|&s| (2..=super::layout::MAX_FACE_SIDE).contains(&s));
        if !legs_ok || x + w > manifest.layout.width as u64 || y + h > manifest.layout.height as u64
        {
            return Err(err(
                &path,
                format!("face {face}: its box or legs do not fit the packing map"),
            ));
        }
        if f.corner > 2 {
            return Err(err(
                &path,
                format!(
                    "face {face}: its right angle is at corner {}, not 0, 1 or 2",
                    f.corner
                ),
            ));
        }
    }
    for (index, view) in manifest.views.iter().enumerate() {
        let file = &view.master;
        if file.contains(['/', '\\']) || file == ".." {
            return Err(err(
                &path,
                format!("view {index}: {file:?} is not a file name"),
            ));
        }
        if !view.camera.iter().flatten().all(|v| v.is_finite()) || view.size.contains(&0) {
            return Err(err(
                &path,
                format!("view {index}: its camera is not finite or has no size"),
            ));
        }
    }
    Ok(manifest)
}

/// Reads master texture `index` of the encoding in `dir`, checking its size.
pub fn load_master(
    dir: &Path,
    manifest: &Manifest,
    index: usize,
) -> Result<Image<Rgba>, MasterError> {
    let m = io::read_png(&dir.join(&manifest.views[index].master))?;
    let expected = (manifest.layout.width, manifest.layout.height);
    if m.size() != expected {
        return Err(MasterError::Size {
            index,
            got: m.size(),
            expected,
        });
    }
    Ok(m)
}

/// Reads `masters.json` and every master texture from `dir`.
pub fn load(dir: &Path) -> Result<(Manifest, Vec<Image<Rgba>>), MasterError> {
    let manifest = load_manifest(dir)?;
    let masters = (0..manifest.views.len())
        .map(|i| load_master(dir, &manifest, i))
        .collect::<Result<_, _>>()?;
    Ok((manifest, masters))
}

/// The mesh as a GLB: positions, normals and the one UV set per face corner, a material whose
/// base colour is `texture` (PNG bytes, embedded: the file needs nothing beside it).
pub fn gltf_bytes(mesh: &Mesh, uvs: &[[f32; 2]], texture: &[u8]) -> Result<Vec<u8>, MasterError> {
    let n = mesh.triangle_count() * 3;
    let mut bin: Vec<u8> = Vec::with_capacity(n * 32);
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for t in 0..mesh.triangle_count() {
        for p in mesh.corners(t) {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
            bin.extend(p.to_array().iter().flat_map(|v| v.to_le_bytes()));
        }
    }
    let normals_at = bin.len();
    for tri in &mesh.triangles {
        for &i in tri {
            let nrm = mesh.normals[i as usize].normalize_or_zero();
            bin.extend(nrm.to_array().iter().flat_map(|v| v.to_le_bytes()));
        }
    }
    let uvs_at = bin.len();
    for uv in uvs.iter().take(n) {
        bin.extend(uv.iter().flat_map(|v| v.to_le_bytes()));
    }
    let image_at = bin.len();
    bin.extend_from_slice(texture);
    let length = bin.len();
    let doc = serde_json::json!({
        "asset": { "version": "2.0", "generator": "trompe master encode" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{
            "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 },
            "material": 0
        }]}],
        "materials": [{ "pbrMetallicRoughness": {
            "baseColorTexture": { "index": 0 }, "metallicFactor": 0.0, "roughnessFactor": 1.0
        }}],
        "textures": [{ "source": 0, "sampler": 0 }],
        "samplers": [{ "magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071 }],
        "images": [{ "bufferView": 3, "mimeType": "image/png" }],
        "buffers": [{ "byteLength": length }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": normals_at, "target": 34962 },
            { "buffer": 0, "byteOffset": normals_at, "byteLength": uvs_at - normals_at, "target": 34962 },
            { "buffer": 0, "byteOffset": uvs_at, "byteLength": image_at - uvs_at, "target": 34962 },
            { "buffer": 0, "byteOffset": image_at, "byteLength": texture.len() }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3", "min": lo, "max": hi },
            { "bufferView": 1, "componentType": 5126, "count": n, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5126, "count": n, "type": "VEC2" }
        ]
    });
    let json = serde_json::to_vec(&doc).map_err(|e| err(Path::new("mesh.glb"), e))?;
    crate::geom::io::glb_bytes(json, bin).map_err(|e| err(Path::new("mesh.glb"), e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_packing_map_without_corners_is_the_papers_corner_0() {
        let place: super::super::layout::FacePlace =
            serde_json::from_str(r#"{"bbox": [0, 0, 9, 7], "slot_b": true, "size": [6, 4]}"#)
                .unwrap();
        assert_eq!(place.corner, 0);
        // Its corner 0 at the right angle: the box's bottom-right, the border within.
        assert_eq!(place.at(0.0, 0.0), glam::DVec2::new(8.0, 6.0));
    }

    #[test]
    fn the_glb_loads_back_with_its_one_uv_set() {
        let mesh = crate::geom::icosphere(1);
        let shapes: Vec<_> = (0..mesh.triangle_count())
            .map(|t| super::super::layout::FaceShape {
                corner: (t % 3) as u8,
                legs: [6, 4],
            })
            .collect();
        let layout = Layout::new(&shapes);
        let uvs = layout.uvs();
        let png = io::encode_png(
            &Image::new(layout.width, layout.height, Rgba::ONE).unwrap(),
            Path::new("bake.png"),
        )
        .unwrap();
        let bytes = gltf_bytes(&mesh, &uvs, &png).unwrap();
        let g = gltf::Gltf::from_slice(&bytes).unwrap();
        let blob = g.blob.as_deref().unwrap();
        let prim = g.meshes().next().unwrap().primitives().next().unwrap();
        let reader = prim.reader(|_| Some(blob));
        let read: Vec<[f32; 2]> = reader.read_tex_coords(0).unwrap().into_f32().collect();
        assert_eq!(read, uvs);
        let positions: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        assert_eq!(positions.len(), mesh.triangle_count() * 3);
        assert_eq!(positions[4], mesh.corners(1)[1].to_array());
        // The bake embedded, and the atlas's sides block-compressible.
        let image = g.images().next().unwrap();
        assert!(matches!(
            image.source(),
            gltf::image::Source::View {
                mime_type: "image/png",
                ..
            }
        ));
        assert!(layout.width.is_multiple_of(4) && layout.height.is_multiple_of(4));
    }
}
