//! An octahedral atlas as a glTF 2.0 binary that engines load without trompe (Godot, Unity's
//! glTFast, Bevy, three.js): a camera-facing card — a quad of the bounding sphere's diameter in
//! the object's `xy` plane, facing `+z`, centred on the sphere, which the engine turns toward
//! the camera — whose material's base colour is the colour atlas, embedded as PNG, alpha-masked,
//! its occlusion and metallic-roughness textures the ORM atlas (embedded PNG, linear); and the
//! layout in the material's `extras.trompe_octahedral`, the sidecar's fields (grid,
//! frame size, sphere, the normal and depth maps' OpenEXR file names beside the file, which glTF
//! cannot hold as images) — the schema of docs/conventions.md §8.
//!
//! Invariants: valid glTF 2.0 (the Khronos validator reports no errors; CI runs it); the card's
//! UVs span the whole atlas, so a shader picks frames in texture space.

use super::file::Sidecar;
use std::path::Path;

/// The GLB of the atlas described by `sidecar`, with `color_png` the colour atlas's PNG bytes
/// and `orm_png` the ORM atlas's, if it has one.
pub fn glb(
    sidecar: &Sidecar,
    color_png: &[u8],
    orm_png: Option<&[u8]>,
) -> Result<Vec<u8>, ::gltf::Error> {
    let [cx, cy, cz] = sidecar.centre;
    let r = sidecar.radius;
    let positions = [
        [cx - r, cy - r, cz],
        [cx + r, cy - r, cz],
        [cx + r, cy + r, cz],
        [cx - r, cy + r, cz],
    ];
    let uvs = [[0.0f32, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let mut bin: Vec<u8> = Vec::new();
    for p in positions {
        bin.extend(p.iter().flat_map(|v| v.to_le_bytes()));
    }
    let normals_at = bin.len();
    for _ in 0..4 {
        bin.extend([0.0f32, 0.0, 1.0].iter().flat_map(|v| v.to_le_bytes()));
    }
    let uvs_at = bin.len();
    for uv in uvs {
        bin.extend(uv.iter().flat_map(|v| v.to_le_bytes()));
    }
    let indices_at = bin.len();
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    let image_at = bin.len().next_multiple_of(4);
    bin.resize(image_at, 0);
    bin.extend_from_slice(color_png);
    let orm_at = bin.len().next_multiple_of(4);
    if let Some(orm) = orm_png {
        bin.resize(orm_at, 0);
        bin.extend_from_slice(orm);
    }
    let length = bin.len();
    // The layout a shader needs; the maps' checksums name files the .glb does not hold.
    let layout = Sidecar {
        parts: None,
        ..sidecar.clone()
    };
    let layout = serde_json::to_value(layout).unwrap_or(serde_json::Value::Null);
    let doc = serde_json::json!({
        "asset": { "version": "2.0", "generator": "trompe impostor bake --octahedral" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0, "name": "octahedral impostor card" }],
        "meshes": [{ "primitives": [{
            "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 },
            "indices": 3,
            "material": 0
        }]}],
        "materials": [{
            "name": "octahedral impostor",
            "pbrMetallicRoughness": {
                "baseColorTexture": { "index": 0 }, "metallicFactor": 0.0, "roughnessFactor": 1.0
            },
            "alphaMode": "MASK",
            "alphaCutoff": 0.5,
            "doubleSided": true,
            "extras": { "trompe_octahedral": layout }
        }],
        "textures": [{ "source": 0, "sampler": 0 }],
        "samplers": [{ "magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071 }],
        "images": [{ "bufferView": 4, "mimeType": "image/png" }],
        "buffers": [{ "byteLength": length }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": normals_at, "target": 34962 },
            { "buffer": 0, "byteOffset": normals_at, "byteLength": uvs_at - normals_at, "target": 34962 },
            { "buffer": 0, "byteOffset": uvs_at, "byteLength": indices_at - uvs_at, "target": 34962 },
            { "buffer": 0, "byteOffset": indices_at, "byteLength": 12, "target": 34963 },
            { "buffer": 0, "byteOffset": image_at, "byteLength": color_png.len() }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
              "min": [cx - r, cy - r, cz], "max": [cx + r, cy + r, cz] },
            { "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2" },
            { "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ]
    });
    let mut doc = doc;
    if let Some(orm) = orm_png {
        // Factors of 1 leave the map's own roughness and metalness.
        let material = &mut doc["materials"][0];
        material["pbrMetallicRoughness"]["metallicRoughnessTexture"] =
            serde_json::json!({ "index": 1 });
        material["pbrMetallicRoughness"]["metallicFactor"] = 1.0.into();
        material["occlusionTexture"] = serde_json::json!({ "index": 1 });
        if let Some(a) = doc["textures"].as_array_mut() {
            a.push(serde_json::json!({ "source": 1, "sampler": 0 }));
        }
        if let Some(a) = doc["images"].as_array_mut() {
            a.push(serde_json::json!({ "bufferView": 5, "mimeType": "image/png" }));
        }
        if let Some(a) = doc["bufferViews"].as_array_mut() {
            a.push(
                serde_json::json!({ "buffer": 0, "byteOffset": orm_at, "byteLength": orm.len() }),
            );
        }
    }
    let json = serde_json::to_vec(&doc).map_err(|e| ::gltf::Error::Io(std::io::Error::other(e)))?;
    crate::geom::io::glb_bytes(json, bin)
}

/// Writes `out` (a `.glb`) from the atlas whose sidecar is `sidecar_path`.
pub fn export(sidecar_path: &Path, out: &Path) -> Result<(), super::file::OctahedralFileError> {
    use super::file::OctahedralFileError as E;
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| E::Io { path, source }
    };
    let sidecar = super::file::read_sidecar(sidecar_path)?;
    super::file::verify_maps(sidecar_path, &sidecar)?;
    let dir = sidecar_path.parent().unwrap_or(Path::new(""));
    let color = dir.join(&sidecar.color);
    let png = std::fs::read(&color).map_err(io(&color))?;
    let orm = match &sidecar.orm {
        Some(name) => {
            let path = dir.join(name);
            Some(std::fs::read(&path).map_err(io(&path))?)
        }
        None => None,
    };
    let bytes = glb(&sidecar, &png, orm.as_deref()).map_err(|e| E::Io {
        path: out.to_path_buf(),
        source: std::io::Error::other(e.to_string()),
    })?;
    crate::files::write_atomically(out, &bytes).map_err(io(out))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::octahedral::{BakeSettings, Coverage, Grid, bake};

    #[test]
    fn the_glb_loads_back_with_its_atlas_and_layout() {
        let mesh = crate::geom::icosphere(2);
        let settings = BakeSettings {
            grid: Grid {
                n: 4,
                coverage: Coverage::Hemisphere,
            },
            frame_size: 16,
            dilation: 2,
            projection: Default::default(),
        };
        let atlas = bake(&mesh, &crate::scene::Surface::Diffuse(None), settings).unwrap();
        let dir = crate::test_scratch::scratch("octahedral_glb");
        let sidecar_path = dir.join("ball.json");
        let sidecar = crate::octahedral::file::save(&atlas, &sidecar_path).unwrap();
        let glb_path = dir.join("ball.glb");
        export(&sidecar_path, &glb_path).unwrap();
        let (doc, buffers, images) = ::gltf::import(&glb_path).unwrap();
        // The colour atlas, then the ORM atlas (occlusion and metallic-roughness).
        assert_eq!(images.len(), 2);
        assert_eq!((images[0].width, images[0].height), (64, 64));
        assert_eq!((images[1].width, images[1].height), (64, 64));
        let material = doc.materials().next().unwrap();
        assert_eq!(material.occlusion_texture().unwrap().texture().index(), 1);
        let pbr = material.pbr_metallic_roughness();
        assert_eq!(
            pbr.metallic_roughness_texture().unwrap().texture().index(),
            1
        );
        let bytes = std::fs::read(&glb_path).unwrap();
        let chunk = ::gltf::binary::Glb::from_slice(&bytes).unwrap().json;
        let json: serde_json::Value = serde_json::from_slice(&chunk).unwrap();
        let layout = json["materials"][0]["extras"]["trompe_octahedral"].clone();
        let back: Sidecar = serde_json::from_value(layout).unwrap();
        assert_eq!(
            back,
            Sidecar {
                parts: None,
                ..sidecar
            }
        );
        let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
        let reader = prim.reader(|b| Some(&buffers[b.index()]));
        assert_eq!(reader.read_positions().unwrap().count(), 4);
        assert_eq!(reader.read_indices().unwrap().into_u32().count(), 6);
        // Another bake's atlas beside this sidecar (a torn or raced bake) is refused by name.
        let other = bake(
            &mesh,
            &crate::scene::Surface::Diffuse(None),
            BakeSettings {
                frame_size: 8,
                ..settings
            },
        )
        .unwrap();
        crate::octahedral::file::save(&other, &dir.join("small.json")).unwrap();
        std::fs::copy(dir.join("small.png"), dir.join("ball.png")).unwrap();
        let err = export(&sidecar_path, &glb_path).unwrap_err().to_string();
        assert!(
            err.contains("ball.png") && err.contains("not the file its index was written with"),
            "{err}"
        );
    }
}
