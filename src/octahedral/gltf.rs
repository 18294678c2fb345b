//! An octahedral atlas as one self-contained glTF 2.0 binary that engines load without trompe
//! (Godot, Unity's glTFast, Bevy, three.js) and trompe loads back ([`load`]): a camera-facing
//! card — a quad of the bounding sphere's diameter in the object's `xy` plane, facing `+z`,
//! centred on the sphere, which a runtime turns toward the camera — whose material's base colour
//! is the colour atlas (embedded PNG, sRGB, alpha-masked), its occlusion and metallic-roughness
//! textures the ORM atlas (embedded PNG, linear); the normal and depth packed in a third embedded
//! texture ([`super::packing`]); and the layout, the textures' indices and the switch distance in
//! the material's `extras.trompe_octahedral` ([`Layout`], docs/conventions.md §8).
//!
//! Invariants: valid glTF 2.0 (the Khronos validator reports no errors or warnings; CI runs it);
//! nothing outside the file is referenced; the card's UVs span the whole atlas, so a shader picks
//! frames in texture space; [`load`] reads back exactly the maps [`glb`] was given.

use super::bake::{BakeSettings, FrameProjection, OctahedralAtlas};
use super::file::{OctahedralFileError, Sidecar};
use super::mapping::Grid;
use crate::frame::{Image, io};
use glam::Vec3;
use std::path::Path;

/// The material extra's `format`.
pub const FORMAT: &str = "trompe-octahedral-impostor";

/// What a runtime needs to draw the card: the material's `extras.trompe_octahedral`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Layout {
    /// Always `"trompe-octahedral-impostor"`.
    pub format: String,
    /// The atlas layout version ([`super::file::VERSION`]).
    pub version: u32,
    /// Frames a side and the directions covered.
    pub grid: Grid,
    /// Texels a frame side; the atlas is `n · frame_size` square.
    pub frame_size: u32,
    /// Texels of dilation around the object in each frame.
    pub dilation: u32,
    /// Bounding sphere centre, object space.
    pub centre: [f32; 3],
    /// Bounding sphere radius.
    pub radius: f32,
    /// How each frame sees the object (as the sidecar says).
    #[serde(default)]
    pub projection: FrameProjection,
    /// The glTF texture indices of the maps.
    pub textures: Textures,
    /// Distance (object units) from which one atlas texel covers one pixel of a 1080-row, 60°
    /// view: where a renderer can switch from the mesh to the impostor.
    pub switch_distance: f32,
}

/// Indices into the file's `textures` of the three maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Textures {
    /// Base colour + coverage (sRGB).
    pub color: usize,
    /// Normal and depth, packed (linear).
    pub normal_depth: usize,
    /// Occlusion, roughness, metalness (linear).
    pub orm: usize,
}

/// The three maps of an atlas, encoded as PNG.
#[derive(Clone, Copy, Debug)]
pub struct EncodedMaps<'a> {
    /// Colour + coverage (sRGB).
    pub color: &'a [u8],
    /// Normal + depth ([`super::packing`], linear).
    pub normal_depth: &'a [u8],
    /// Occlusion, roughness, metalness (linear).
    pub orm: &'a [u8],
}

/// The GLB of the atlas described by `sidecar`, its maps `maps`.
pub fn glb(sidecar: &Sidecar, maps: EncodedMaps) -> Result<Vec<u8>, ::gltf::Error> {
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
    let mut views = vec![
        serde_json::json!({ "buffer": 0, "byteOffset": 0, "byteLength": normals_at, "target": 34962 }),
        serde_json::json!({ "buffer": 0, "byteOffset": normals_at, "byteLength": uvs_at - normals_at, "target": 34962 }),
        serde_json::json!({ "buffer": 0, "byteOffset": uvs_at, "byteLength": indices_at - uvs_at, "target": 34962 }),
        serde_json::json!({ "buffer": 0, "byteOffset": indices_at, "byteLength": 12, "target": 34963 }),
    ];
    let mut images = Vec::new();
    for png in [maps.color, maps.orm, maps.normal_depth] {
        let at = bin.len().next_multiple_of(4);
        bin.resize(at, 0);
        bin.extend_from_slice(png);
        images.push(serde_json::json!({ "bufferView": views.len(), "mimeType": "image/png" }));
        views.push(serde_json::json!({ "buffer": 0, "byteOffset": at, "byteLength": png.len() }));
    }
    let textures = Textures {
        color: 0,
        orm: 1,
        normal_depth: 2,
    };
    let layout = Layout {
        format: FORMAT.into(),
        version: sidecar.version,
        grid: sidecar.grid,
        frame_size: sidecar.frame_size,
        dilation: sidecar.dilation,
        centre: sidecar.centre,
        radius: sidecar.radius,
        projection: sidecar.projection,
        textures,
        switch_distance: super::file::switch_distance(sidecar.radius, sidecar.frame_size),
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
                "baseColorTexture": { "index": textures.color },
                "metallicRoughnessTexture": { "index": textures.orm },
                "metallicFactor": 1.0,
                "roughnessFactor": 1.0
            },
            "occlusionTexture": { "index": textures.orm },
            "alphaMode": "MASK",
            "alphaCutoff": 0.5,
            "doubleSided": true,
            "extras": { "trompe_octahedral": layout }
        }],
        "textures": [
            { "source": 0, "sampler": 0 },
            { "source": 1, "sampler": 0 },
            { "source": 2, "sampler": 0 }
        ],
        "samplers": [{ "magFilter": 9729, "minFilter": 9987, "wrapS": 33071, "wrapT": 33071 }],
        "images": images,
        "buffers": [{ "byteLength": bin.len() }],
        "bufferViews": views,
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
              "min": [cx - r, cy - r, cz], "max": [cx + r, cy + r, cz] },
            { "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2" },
            { "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ]
    });
    let json = serde_json::to_vec(&doc).map_err(|e| ::gltf::Error::Io(std::io::Error::other(e)))?;
    crate::geom::io::glb_bytes(json, bin)
}

/// Writes `out` (a `.glb`) from the atlas whose sidecar is `sidecar_path`; an atlas of an
/// older layout (float normal and depth maps only) is packed on the way.
pub fn export(sidecar_path: &Path, out: &Path) -> Result<(), OctahedralFileError> {
    use OctahedralFileError as E;
    let io_at = |path: &Path| {
        let path = path.to_path_buf();
        move |source| E::Io { path, source }
    };
    let sidecar = super::file::read_sidecar(sidecar_path)?;
    super::file::verify_maps(sidecar_path, &sidecar)?;
    let dir = sidecar_path.parent().unwrap_or(Path::new(""));
    let read = |name: &str| {
        let path = dir.join(name);
        std::fs::read(&path).map_err(io_at(&path))
    };
    let color = read(&sidecar.color)?;
    let normal_depth = match (&sidecar.normal_depth, &sidecar.normal, &sidecar.depth) {
        (Some(packed), _, _) => read(packed)?,
        (None, Some(normal), Some(depth)) => {
            let (normal, depth) = (dir.join(normal), dir.join(depth));
            let n = io::read_exr_channels(&normal)?;
            let (x, y, z) = (n.channel("N.X")?, n.channel("N.Y")?, n.channel("N.Z")?);
            let normals = (x.pixels().iter().zip(y.pixels()).zip(z.pixels()))
                .map(|((&x, &y), &z)| Vec3::new(x, y, z))
                .collect();
            let normals = Image::from_vec(x.width(), x.height(), normals)?;
            let depths = io::read_exr_channels(&depth)?.channel("Z")?;
            let packed = super::packing::pack(&normals, &depths)?;
            io::encode_png_data_rgba(&packed, out)?
        }
        _ => {
            return Err(E::Io {
                path: sidecar_path.to_path_buf(),
                source: std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    "names neither a packed normal-depth map nor float normal and depth maps",
                ),
            });
        }
    };
    let orm = match &sidecar.orm {
        Some(name) => read(name)?,
        // Layout 1 had none: no occlusion, fully rough, not metal.
        None => {
            let side = sidecar.grid.n * sidecar.frame_size;
            let orm = Image::new(side, side, Vec3::new(1.0, 1.0, 0.0))?;
            io::encode_png_data(&orm, out)?
        }
    };
    let maps = EncodedMaps {
        color: &color,
        normal_depth: &normal_depth,
        orm: &orm,
    };
    let bytes = glb(&sidecar, maps).map_err(|e| E::Io {
        path: out.to_path_buf(),
        source: std::io::Error::other(e.to_string()),
    })?;
    crate::files::write_atomically(out, &bytes).map_err(io_at(out))
}

/// Writes `atlas` as one self-contained `.glb` at `out` (no sidecar, no maps beside it).
pub fn save(atlas: &OctahedralAtlas, out: &Path) -> Result<Sidecar, OctahedralFileError> {
    let color = io::encode_png(&atlas.color, out)?;
    let packed = super::packing::pack(&atlas.normal, &atlas.depth)?;
    let normal_depth = io::encode_png_data_rgba(&packed, out)?;
    let orm = io::encode_png_data(&atlas.orm, out)?;
    let sidecar = super::file::sidecar_of(atlas, out, super::file::FloatMaps::Omitted);
    let maps = EncodedMaps {
        color: &color,
        normal_depth: &normal_depth,
        orm: &orm,
    };
    let bytes = glb(&sidecar, maps).map_err(|e| OctahedralFileError::Io {
        path: out.to_path_buf(),
        source: std::io::Error::other(e.to_string()),
    })?;
    crate::files::write_atomically(out, &bytes).map_err(|source| OctahedralFileError::Io {
        path: out.to_path_buf(),
        source,
    })?;
    Ok(sidecar)
}

/// Loads the atlas of a `.glb` trompe wrote: its layout and its three maps (the normal and
/// depth unpacked, so within [`super::packing`]'s bounds of the bake).
pub fn load(path: &Path) -> Result<OctahedralAtlas, OctahedralFileError> {
    let invalid = |reason: String| OctahedralFileError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, reason),
    };
    let bytes = std::fs::read(path).map_err(|source| OctahedralFileError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let glb = ::gltf::binary::Glb::from_slice(&bytes).map_err(|e| invalid(e.to_string()))?;
    let doc: serde_json::Value =
        serde_json::from_slice(&glb.json).map_err(|e| invalid(e.to_string()))?;
    let blob = glb.bin.as_deref().unwrap_or(&[]);
    let materials = doc["materials"]
        .as_array()
        .map(Vec::as_slice)
        .unwrap_or(&[]);
    let Some(extra) = materials
        .iter()
        .find_map(|m| m["extras"].get("trompe_octahedral"))
    else {
        return Err(invalid(
            "no material has extras.trompe_octahedral: not an octahedral impostor trompe baked"
                .into(),
        ));
    };
    let layout: Layout = serde_json::from_value(extra.clone())
        .map_err(|e| invalid(format!("materials[].extras.trompe_octahedral: {e}")))?;
    if layout.format != FORMAT {
        return Err(invalid(format!(
            "format {:?} is not {FORMAT:?}",
            layout.format
        )));
    }
    let settings = BakeSettings {
        grid: layout.grid,
        frame_size: layout.frame_size,
        dilation: layout.dilation,
        projection: layout.projection,
    };
    let centre = Vec3::from_array(layout.centre);
    let valid = layout.radius.is_finite()
        && layout.radius > 0.0
        && centre.is_finite()
        && super::mapping::FRAMES_RANGE.contains(&layout.grid.n)
        && layout.frame_size > 0;
    if !valid {
        return Err(invalid(format!(
            "materials[].extras.trompe_octahedral: no atlas has {} frames a side of {} texels \
             on a sphere of radius {} at {:?}",
            layout.grid.n, layout.frame_size, layout.radius, layout.centre
        )));
    }
    let side = u64::from(layout.grid.n) * u64::from(layout.frame_size);
    // The PNG bytes of texture `index`, found through its image's buffer view.
    let png = |index: usize| -> Result<&[u8], OctahedralFileError> {
        let at = |what: String| invalid(format!("textures[{index}]: {what}"));
        let source = doc["textures"][index]["source"]
            .as_u64()
            .ok_or_else(|| at("no such texture, or no source".into()))?;
        let view = doc["images"][source as usize]["bufferView"]
            .as_u64()
            .ok_or_else(|| at(format!("images[{source}] is not held in the file")))?;
        let view = &doc["bufferViews"][view as usize];
        let offset = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        let length = view["byteLength"].as_u64().unwrap_or(0) as usize;
        blob.get(offset..offset.saturating_add(length))
            .ok_or_else(|| at(format!("its bytes {offset}..+{length} are past the buffer")))
    };
    let sized = |img: Image<crate::frame::Rgba>, what: &str| {
        if img.size() != (side as u32, side as u32) {
            return Err(invalid(format!(
                "the {what} map is {} × {}, the layout's atlas {side} × {side}",
                img.width(),
                img.height()
            )));
        }
        Ok(img)
    };
    let t = layout.textures;
    let color = sized(io::decode_srgb_image(png(t.color)?, path)?, "colour")?;
    let packed = sized(
        io::decode_linear_image(png(t.normal_depth)?, path)?,
        "normal-depth",
    )?;
    let orm = sized(io::decode_linear_image(png(t.orm)?, path)?, "ORM")?;
    let (normal, depth) = super::packing::unpack(&packed)?;
    let orm = orm.map(|o| o.truncate());
    Ok(OctahedralAtlas {
        settings,
        centre,
        radius: layout.radius,
        color,
        normal,
        depth,
        orm,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::octahedral::file::FloatMaps;
    use crate::octahedral::{BakeSettings, Coverage, Grid, bake};

    fn ball(frame_size: u32) -> OctahedralAtlas {
        let mesh = crate::geom::icosphere(2);
        let settings = BakeSettings {
            grid: Grid {
                n: 4,
                coverage: Coverage::Hemisphere,
            },
            frame_size,
            dilation: 2,
            projection: Default::default(),
        };
        bake(&mesh, &crate::scene::Surface::Diffuse(None), settings).unwrap()
    }

    #[test]
    fn the_glb_holds_its_three_maps_and_its_layout() {
        let atlas = ball(16);
        let dir = crate::test_scratch::scratch("octahedral_glb");
        let sidecar_path = dir.join("ball.json");
        let sidecar =
            crate::octahedral::file::save(&atlas, &sidecar_path, FloatMaps::Omitted).unwrap();
        let glb_path = dir.join("ball.glb");
        export(&sidecar_path, &glb_path).unwrap();
        let (doc, buffers, images) = ::gltf::import(&glb_path).unwrap();
        // Colour, ORM (occlusion and metallic-roughness), normal-depth: all embedded.
        assert_eq!(images.len(), 3);
        for image in &images {
            assert_eq!((image.width, image.height), (64, 64));
        }
        assert!(
            doc.images()
                .all(|i| matches!(i.source(), ::gltf::image::Source::View { .. }))
        );
        let material = doc.materials().next().unwrap();
        assert_eq!(material.occlusion_texture().unwrap().texture().index(), 1);
        let pbr = material.pbr_metallic_roughness();
        assert_eq!(pbr.base_color_texture().unwrap().texture().index(), 0);
        assert_eq!(
            pbr.metallic_roughness_texture().unwrap().texture().index(),
            1
        );
        let bytes = std::fs::read(&glb_path).unwrap();
        let chunk = ::gltf::binary::Glb::from_slice(&bytes).unwrap().json;
        let json: serde_json::Value = serde_json::from_slice(&chunk).unwrap();
        let layout: Layout =
            serde_json::from_value(json["materials"][0]["extras"]["trompe_octahedral"].clone())
                .unwrap();
        assert_eq!(
            (layout.grid, layout.frame_size, layout.radius, layout.centre),
            (sidecar.grid, 16, sidecar.radius, sidecar.centre)
        );
        assert_eq!(layout.textures.normal_depth, 2);
        let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
        let reader = prim.reader(|b| Some(&buffers[b.index()]));
        assert_eq!(reader.read_positions().unwrap().count(), 4);
        assert_eq!(reader.read_indices().unwrap().into_u32().count(), 6);
        // Another bake's atlas beside this sidecar (a torn or raced bake) is refused by name.
        crate::octahedral::file::save(&ball(8), &dir.join("small.json"), FloatMaps::Omitted)
            .unwrap();
        std::fs::copy(dir.join("small.png"), dir.join("ball.png")).unwrap();
        let err = export(&sidecar_path, &glb_path).unwrap_err().to_string();
        assert!(
            err.contains("ball.png") && err.contains("not the file its index was written with"),
            "{err}"
        );
    }

    #[test]
    fn a_glb_loads_back_to_the_bake_within_the_packings_bounds() {
        let atlas = ball(32);
        let dir = crate::test_scratch::scratch("octahedral_glb_round_trip");
        let path = dir.join("ball.glb");
        save(&atlas, &path).unwrap();
        let back = load(&path).unwrap();
        assert_eq!(back.settings, atlas.settings);
        assert_eq!((back.centre, back.radius), (atlas.centre, atlas.radius));
        let covered = |k: usize| atlas.color.pixels()[k].w > 0.0;
        for k in (0..atlas.depth.pixels().len()).filter(|&k| covered(k)) {
            let (n, n2) = (atlas.normal.pixels()[k], back.normal.pixels()[k]);
            assert!(n.angle_between(n2) <= super::super::packing::NORMAL_BOUND);
            let (d, d2) = (atlas.depth.pixels()[k], back.depth.pixels()[k]);
            assert!((d - d2).abs() <= super::super::packing::DEPTH_BOUND + 1e-6);
            // Colour and coverage through 8-bit sRGB: within a step of 8 bits (linear).
            let (c, c2) = (atlas.color.pixels()[k], back.color.pixels()[k]);
            assert!((c - c2).abs().max_element() < 1.0 / 64.0, "{c} {c2}");
        }
        // The renders agree: every pixel within FLIP's noise of 8-bit maps.
        let camera = crate::camera::Pinhole::look_at(
            atlas.centre + glam::Vec3::new(1.0, 2.5, 3.0),
            atlas.centre,
            glam::Vec3::Y,
            35.0,
            96,
            96,
        )
        .unwrap();
        let lighting = crate::scene::Lighting {
            environment: crate::frame::envmap::EnvMap::constant(glam::Vec3::splat(0.3)),
            light: Some(crate::scene::Light {
                direction: glam::Vec3::new(0.3, 1.0, 0.5).normalize(),
                irradiance: glam::Vec3::splat(3.0),
            }),
        };
        let a = atlas.render(&camera, &lighting, 4);
        let b = back.render(&camera, &lighting, 4);
        let flip = crate::frame::metrics::flip(&a, &b, None).unwrap();
        assert!(flip < 0.01, "FLIP {flip}");
        // Not a tautology: a grid read as the wrong atlas is far off.
        let mut wrong = back.clone();
        wrong.depth = wrong.depth.map(|d| 1.0 - d);
        let c = wrong.render(&camera, &lighting, 4);
        assert!(crate::frame::metrics::flip(&a, &c, None).unwrap() > 2.0 * flip);
        // A glb that is not an impostor's is refused by what it lacks.
        let mut doc = serde_json::json!({"asset": {"version": "2.0"}});
        doc["materials"] = serde_json::json!([{ "name": "plain" }]);
        let plain = crate::geom::io::glb_bytes(serde_json::to_vec(&doc).unwrap(), vec![]).unwrap();
        std::fs::write(dir.join("plain.glb"), plain).unwrap();
        let err = load(&dir.join("plain.glb")).unwrap_err().to_string();
        assert!(
            err.contains("plain.glb") && err.contains("trompe_octahedral"),
            "{err}"
        );
    }
}
