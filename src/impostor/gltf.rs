//! A depth-image impostor (pinhole, orthographic, SPOC or graph camera; paper 1 §3–5) as a glTF
//! 2.0 binary that any viewer or engine loads without trompe: its proxy geometry is the
//! impostor's own surface — a grid mesh through the world positions of its covered texels, at
//! most [`MAX_GRID`] vertices a side, quantized and meshopt-compressed by default
//! ([`GeometryEncoding`], `geom::io::compressed`) — textured with the colour map (embedded PNG,
//! alpha = coverage, masked); the camera and maps are in the node's `extras.trompe_impostor`, the
//! sidecar's fields as `impostor::file` documents them, whose `exr` names the OpenEXR file of
//! every map (`gd`, normals, face normals, positions, ids) beside the `.glb` — glTF images are
//! PNG or JPEG and cannot hold them. Of a layered impostor the surface is its first layer's;
//! the sidecar in `extras` says how many layers the EXR holds.
//!
//! Invariants: valid glTF 2.0 (the Khronos validator reports no errors; CI runs it); a vertex
//! is a covered texel's stored position, its UV that texel's centre; no triangle spans a depth
//! discontinuity (an edge longer than [`MAX_STRETCH`] texel footprints is cut).

use super::Impostor;
use super::file::ImpostorFileError;
use crate::frame::{Image, Rgba};
pub use crate::geom::io::compressed::GeometryEncoding;
use crate::geom::io::compressed::{MeshStreams, write_mesh};
use glam::Vec3;
use std::path::Path;

/// Most grid vertices a side of the exported surface (a larger impostor is sampled every few
/// texels).
pub const MAX_GRID: u32 = 256;

/// An edge between two grid vertices longer than this many texel footprints (times the grid
/// step) crosses a depth discontinuity: no triangle is made across it.
pub const MAX_STRETCH: f32 = 4.0;

/// A surface sampled on a grid of texels, with its colour map: what [`surface_glb`] writes.
pub struct SurfaceGrid {
    /// Vertices a side.
    pub size: (u32, u32),
    /// Per vertex, row by row: its position, normal and UV, or `None` where nothing is.
    pub vertices: Vec<Option<(Vec3, Vec3, [f32; 2])>>,
    /// Per vertex, the longest edge to a neighbour that still joins the same surface.
    pub reach: Vec<f32>,
}

impl SurfaceGrid {
    /// The grid of `impostor`'s covered texels, every `step` texels.
    pub fn of_impostor(impostor: &Impostor) -> Self {
        let (w, h) = impostor.camera().resolution();
        let step = w.max(h).div_ceil(MAX_GRID).max(1);
        let size = (w.div_ceil(step), h.div_ceil(step));
        let mut vertices = Vec::with_capacity(size.0 as usize * size.1 as usize);
        let mut reach = Vec::with_capacity(vertices.capacity());
        for gy in 0..size.1 {
            for gx in 0..size.0 {
                let (x, y) = (gx * step, gy * step);
                let gd = impostor.gd().get(x, y);
                if gd <= 0.0 {
                    vertices.push(None);
                    reach.push(0.0);
                    continue;
                }
                let uv = crate::frame::pixel_centre(x as f64, y as f64);
                let texel = [(uv.x / w as f64) as f32, (uv.y / h as f64) as f32];
                vertices.push(Some((
                    impostor.position_at(x, y),
                    impostor.normal_at(x, y),
                    texel,
                )));
                let footprint = impostor.footprint(uv, gd as f64) as f32;
                reach.push(MAX_STRETCH * step as f32 * footprint);
            }
        }
        Self {
            size,
            vertices,
            reach,
        }
    }

    /// Triangles (vertex indices into the covered vertices) of every grid cell whose corners
    /// are all present and joined.
    fn triangles(&self) -> (Vec<u32>, Vec<u32>) {
        let (w, h) = (self.size.0 as usize, self.size.1 as usize);
        let mut index = vec![u32::MAX; self.vertices.len()];
        let mut n = 0;
        for (i, v) in self.vertices.iter().enumerate() {
            if v.is_some() {
                index[i] = n;
                n += 1;
            }
        }
        let joined = |a: usize, b: usize| match (self.vertices[a], self.vertices[b]) {
            (Some(p), Some(q)) => p.0.distance(q.0) <= self.reach[a].max(self.reach[b]),
            _ => false,
        };
        let mut out = Vec::new();
        for y in 0..h.saturating_sub(1) {
            for x in 0..w.saturating_sub(1) {
                let (a, b, c, d) = (
                    y * w + x,
                    y * w + x + 1,
                    (y + 1) * w + x,
                    (y + 1) * w + x + 1,
                );
                if joined(a, b) && joined(a, c) && joined(b, c) {
                    out.extend([index[a], index[c], index[b]]);
                }
                if joined(b, c) && joined(b, d) && joined(c, d) {
                    out.extend([index[b], index[c], index[d]]);
                }
            }
        }
        (index, out)
    }
}

/// The GLB of `grid` textured with `color` (embedded as PNG), its geometry stored as `encoding`
/// says, its node's `extras` holding `extras` under the key `key`; `generator` names what made
/// it.
pub fn surface_glb(
    grid: &SurfaceGrid,
    color: &Image<Rgba>,
    encoding: GeometryEncoding,
    (key, extras): (&str, serde_json::Value),
    generator: &str,
) -> Result<Vec<u8>, ::gltf::Error> {
    let other = |e: String| ::gltf::Error::Io(std::io::Error::other(e));
    let png = crate::frame::io::encode_png(color, Path::new("the colour map"))
        .map_err(|e| other(e.to_string()))?;
    let (_, triangles) = grid.triangles();
    let present: Vec<_> = grid.vertices.iter().flatten().collect();
    let positions: Vec<Vec3> = present.iter().map(|v| v.0).collect();
    let normals: Vec<Vec3> = present.iter().map(|v| v.1).collect();
    let uvs: Vec<[f32; 2]> = present.iter().map(|v| v.2).collect();
    let mut bin: Vec<u8> = Vec::new();
    let mut node = serde_json::json!({ "name": generator, "extras": { key: extras } });
    let mut doc = serde_json::json!({
        "asset": { "version": "2.0", "generator": generator },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "materials": [{
            "name": "impostor colour",
            "pbrMetallicRoughness": {
                "baseColorTexture": { "index": 0 }, "metallicFactor": 0.0, "roughnessFactor": 1.0
            },
            "alphaMode": "MASK",
            "alphaCutoff": 0.5,
            "doubleSided": true
        }],
        "textures": [{ "source": 0, "sampler": 0 }],
        "samplers": [{ "magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071 }],
        "images": [{ "bufferView": 0, "mimeType": "image/png" }],
        "bufferViews": [],
    });
    let mut buffers = Vec::new();
    // A mesh only when there is a triangle (glTF has no empty primitive).
    if !triangles.is_empty() {
        let streams = MeshStreams {
            positions: &positions,
            normals: &normals,
            uvs: &uvs,
            indices: &triangles,
        };
        let mesh =
            write_mesh(&streams, encoding, &mut bin, 1, 0).map_err(|e| other(e.to_string()))?;
        node["mesh"] = 0.into();
        if let Some((translation, scale)) = mesh.placement {
            node["translation"] = serde_json::json!(translation.to_array());
            node["scale"] = serde_json::json!([scale, scale, scale]);
        }
        doc["meshes"] = serde_json::json!([{ "primitives": [{
            "attributes": mesh.attributes,
            "indices": mesh.indices,
            "material": 0
        }]}]);
        doc["accessors"] = mesh.accessors.into();
        doc["bufferViews"] = mesh.buffer_views.into();
        buffers = mesh.buffers;
        if !mesh.extensions.is_empty() {
            doc["extensionsUsed"] = serde_json::json!(mesh.extensions);
            doc["extensionsRequired"] = serde_json::json!(mesh.extensions);
        }
    }
    let image_at = bin.len().next_multiple_of(4);
    bin.resize(image_at, 0);
    bin.extend_from_slice(&png);
    let image = serde_json::json!({ "buffer": 0, "byteOffset": image_at, "byteLength": png.len() });
    if let Some(views) = doc["bufferViews"].as_array_mut() {
        views.insert(0, image);
    }
    buffers.insert(0, serde_json::json!({ "byteLength": bin.len() }));
    doc["buffers"] = buffers.into();
    doc["nodes"] = serde_json::json!([node]);
    let json = serde_json::to_vec(&doc).map_err(|e| other(e.to_string()))?;
    crate::geom::io::glb_bytes(json, bin)
}

/// Writes `out` (a `.glb`) from the impostor whose sidecar is `json` (its maps checked on load
/// as `impostor::file::load` checks them), its surface stored as `encoding` says.
pub fn export(
    json: &Path,
    out: &Path,
    encoding: GeometryEncoding,
) -> Result<(), ImpostorFileError> {
    let impostor = super::file::load(json)?;
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| ImpostorFileError::Io { path, source }
    };
    let text = std::fs::read_to_string(json).map_err(io(json))?;
    let sidecar: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| ImpostorFileError::Invalid {
            path: json.to_path_buf(),
            reason: e.to_string(),
        })?;
    let grid = SurfaceGrid::of_impostor(&impostor);
    let generator = format!(
        "trompe impostor export ({} impostor)",
        impostor.camera().kind()
    );
    let bytes = surface_glb(
        &grid,
        &impostor.color_image(),
        encoding,
        ("trompe_impostor", sidecar),
        &generator,
    )
    .map_err(|e| ImpostorFileError::Io {
        path: out.to_path_buf(),
        source: std::io::Error::other(e.to_string()),
    })?;
    crate::files::write_atomically(out, &bytes).map_err(io(out))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::impostor::{ImpostorCamera, ViewCamera};

    /// A SPOC impostor of a ball (radius ½), `side` texels a side, saved in the scratch folder
    /// `name` as `ball.json`: the impostor, the folder and the sidecar.
    fn ball(side: u32, name: &str) -> (Impostor, std::path::PathBuf, std::path::PathBuf) {
        let mesh = crate::geom::icosphere(3);
        let camera = ImpostorCamera::around(
            ViewCamera::Spoc(None),
            Vec3::new(0.0, 0.5, 1.5),
            Vec3::ZERO,
            0.5,
            0.5,
            side,
        )
        .unwrap();
        let impostor = crate::impostor::build(camera, &mesh, 0, &|_| Vec3::ONE).unwrap();
        let dir = crate::test_scratch::scratch(name);
        let json = dir.join("ball.json");
        crate::impostor::file::save(&impostor, &json).unwrap();
        (impostor, dir, json)
    }

    #[test]
    fn an_impostor_exports_as_its_surface_and_loads_back_with_its_camera() {
        let (impostor, dir, json) = ball(64, "impostor_glb");
        let glb = dir.join("ball.glb");
        export(&json, &glb, GeometryEncoding::Float).unwrap();
        let (doc, buffers, images) = ::gltf::import(&glb).unwrap();
        assert_eq!((images[0].width, images[0].height), (64, 64));
        let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
        let reader = prim.reader(|b| Some(&buffers[b.index()]));
        let positions: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        let covered = impostor.gd().pixels().iter().filter(|g| **g > 0.0).count();
        assert_eq!(positions.len(), covered);
        // Every vertex lies on the sphere (radius ½) the impostor holds.
        for p in &positions {
            let r = Vec3::from(*p).length();
            assert!((r - 0.5).abs() < 0.01, "{r}");
        }
        let triangles = reader.read_indices().unwrap().into_u32().count() / 3;
        assert!(
            triangles > covered,
            "{triangles} triangles for {covered} texels"
        );
        let bytes = std::fs::read(&glb).unwrap();
        let chunk = ::gltf::binary::Glb::from_slice(&bytes).unwrap().json;
        let doc: serde_json::Value = serde_json::from_slice(&chunk).unwrap();
        let extras = doc["nodes"][0]["extras"].clone();
        let sidecar: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert_eq!(extras["trompe_impostor"], sidecar);
        assert_eq!(extras["trompe_impostor"]["camera"]["type"], "spoc");
    }

    #[test]
    fn a_compressed_surface_loads_back_as_the_float_one_within_its_quantization() {
        let (_, dir, json) = ball(48, "impostor_glb_compressed");
        let (plain, packed) = (dir.join("plain.glb"), dir.join("packed.glb"));
        export(&json, &plain, GeometryEncoding::Float).unwrap();
        export(&json, &packed, GeometryEncoding::Compressed).unwrap();
        let size = |p: &Path| std::fs::metadata(p).unwrap().len();
        assert!(
            size(&packed) * 3 < size(&plain),
            "{} against {}",
            size(&packed),
            size(&plain)
        );
        // trompe's own loader decodes the extensions the `gltf` crate refuses.
        let a = crate::geom::io::load(&plain).unwrap().mesh;
        let b = crate::geom::io::load(&packed).unwrap().mesh;
        assert_eq!(a.triangles.len(), b.triangles.len());
        // Every decoded vertex is a written one, within half a 16-bit step of the longest side
        // (one step of slack for the float arithmetic), with its UV and normal.
        let side = (0..3)
            .map(|k| {
                let c = a.positions.iter().map(|p| p[k]);
                c.clone().fold(f32::MIN, f32::max) - c.fold(f32::MAX, f32::min)
            })
            .fold(0.0, f32::max);
        let tolerance = side / 65535.0 * 1.5;
        let a_uvs = a.uvs.as_ref().unwrap();
        let b_uvs = b.uvs.as_ref().unwrap();
        let matched: Vec<usize> = b
            .positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let (j, d) = a
                    .positions
                    .iter()
                    .map(|q| q.distance(*p))
                    .enumerate()
                    .min_by(|x, y| x.1.total_cmp(&y.1))
                    .unwrap();
                assert!(
                    d <= tolerance,
                    "vertex {i} is {d} from the nearest written one"
                );
                assert!((a_uvs[j] - b_uvs[i]).abs().max_element() <= 1.0 / 65535.0);
                assert!(a.normals[j].dot(b.normals[i]) > 0.9999 - 1.0 / 127.0);
                j
            })
            .collect();
        // The same triangles, in another order.
        let sorted = |t: [u32; 3]| {
            let mut t = t;
            t.sort_unstable();
            t
        };
        let mut written: Vec<_> = a.triangles.iter().map(|t| sorted(*t)).collect();
        let mut read: Vec<_> = b
            .triangles
            .iter()
            .map(|t| sorted(t.map(|i| matched[i as usize] as u32)))
            .collect();
        written.sort_unstable();
        read.sort_unstable();
        assert_eq!(written, read);
    }
}
