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
use crate::frame::{FrameError, Image, io};
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
    /// The card's outline ([`super::card`]): 3 to 8 points `[x, y]` in units of the radius,
    /// counter-clockwise in the card's axes; the whole square when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub card: Option<Vec<[f32; 2]>>,
    /// The glTF texture indices of the maps.
    pub textures: Textures,
    /// Distance (object units) from which one atlas texel covers one pixel of a 1080-row, 60°
    /// view: where a renderer can switch from the mesh to the impostor.
    pub switch_distance: f32,
    /// The dithered cross-fade from the mesh to the impostor ([`super::lod`]); none in files
    /// written before it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cross_fade: Option<super::CrossFade>,
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

/// How the `.glb` holds its textures.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TextureFormat {
    /// PNG, one level (engines make the mip levels).
    #[default]
    Png,
    /// KTX2, Basis Universal UASTC supercompressed with Zstandard (glTF's
    /// `KHR_texture_basisu`), with the frame-by-frame mip chain of [`super::mips`]: what a GPU
    /// transcodes to its own block format.
    Ktx2,
}

impl TextureFormat {
    /// The images' MIME type.
    pub fn mime(self) -> &'static str {
        match self {
            TextureFormat::Png => "image/png",
            TextureFormat::Ktx2 => "image/ktx2",
        }
    }
}

/// The three maps of an atlas, encoded as `format` says.
#[derive(Clone, Copy, Debug)]
pub struct EncodedMaps<'a> {
    /// How they are encoded.
    pub format: TextureFormat,
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
    for encoded in [maps.color, maps.orm, maps.normal_depth] {
        let at = bin.len().next_multiple_of(4);
        bin.resize(at, 0);
        bin.extend_from_slice(encoded);
        images
            .push(serde_json::json!({ "bufferView": views.len(), "mimeType": maps.format.mime() }));
        views.push(
            serde_json::json!({ "buffer": 0, "byteOffset": at, "byteLength": encoded.len() }),
        );
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
        card: sidecar.card.clone(),
        textures,
        switch_distance: super::file::switch_distance(sidecar.radius, sidecar.frame_size),
        cross_fade: Some(super::CrossFade::of(sidecar.radius, sidecar.frame_size)),
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
        "textures": (0..3).map(|k| match maps.format {
            TextureFormat::Png => serde_json::json!({ "source": k, "sampler": 0 }),
            TextureFormat::Ktx2 => serde_json::json!({
                "sampler": 0, "extensions": { "KHR_texture_basisu": { "source": k } }
            }),
        }).collect::<Vec<_>>(),
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
    let mut doc = doc;
    if maps.format == TextureFormat::Ktx2 {
        doc["extensionsUsed"] = serde_json::json!(["KHR_texture_basisu"]);
        doc["extensionsRequired"] = serde_json::json!(["KHR_texture_basisu"]);
    }
    let json = serde_json::to_vec(&doc).map_err(|e| ::gltf::Error::Io(std::io::Error::other(e)))?;
    crate::geom::io::glb_bytes(json, bin)
}

/// The colour, normal-depth and ORM maps of `atlas` encoded as `format` says (`path` only
/// names them in errors): PNG, or KTX2 with each map's frame-by-frame mip chain, down to the
/// last level whose side block compression accepts — refused where the atlas side itself is
/// not a multiple of 4.
pub fn encode_maps(
    atlas: &OctahedralAtlas,
    format: TextureFormat,
    path: &Path,
) -> Result<[Vec<u8>; 3], OctahedralFileError> {
    use crate::frame::Rgba;
    use crate::frame::ktx2::{Level, Transfer, encode_uastc};
    let packed = super::packing::pack(&atlas.normal, &atlas.depth)?;
    if format == TextureFormat::Png {
        return Ok([
            io::encode_png(&atlas.color, path)?,
            io::encode_png_data_rgba(&packed, path)?,
            io::encode_png_data(&atlas.orm, path)?,
        ]);
    }
    let side = atlas.side();
    if !side.is_multiple_of(4) {
        return Err(OctahedralFileError::Frame(FrameError::InvalidSize {
            width: u64::from(side),
            height: u64::from(side),
            reason: "a KTX2 atlas is block-compressed: its side (frames a side × texels a \
                     frame) must be a multiple of 4",
        }));
    }
    let frame_size = atlas.settings.frame_size;
    let linear = |img: &Image<Rgba>| io::data_bytes(img.pixels().iter().map(|p| p.to_array()));
    let encode = |map: &Image<Rgba>, transfer: Transfer| -> Result<Vec<u8>, OctahedralFileError> {
        let texels: Vec<(u32, Vec<u8>)> = super::mips::frame_mips(map, frame_size)?
            .iter()
            .take_while(|l| l.width().is_multiple_of(4))
            .map(|l| {
                let bytes = match transfer {
                    Transfer::Srgb => io::to_srgb8(l),
                    Transfer::Linear => linear(l),
                };
                (l.width(), bytes)
            })
            .collect();
        let levels: Vec<Level> = (texels.iter())
            .map(|(w, rgba8)| Level {
                width: *w,
                height: *w,
                rgba8,
            })
            .collect();
        Ok(encode_uastc(&levels, transfer, path)?)
    };
    Ok([
        encode(&atlas.color, Transfer::Srgb)?,
        encode(&packed, Transfer::Linear)?,
        encode(&atlas.orm.map(|o| o.extend(1.0)), Transfer::Linear)?,
    ])
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
        format: TextureFormat::Png,
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

/// Writes `atlas` as one self-contained `.glb` at `out`, its textures as `format` says (no
/// sidecar, no maps beside it).
pub fn save(
    atlas: &OctahedralAtlas,
    out: &Path,
    format: TextureFormat,
) -> Result<Sidecar, OctahedralFileError> {
    let (bytes, sidecar) = encode(atlas, format, out)?;
    crate::files::write_atomically(out, &bytes).map_err(|source| OctahedralFileError::Io {
        path: out.to_path_buf(),
        source,
    })?;
    Ok(sidecar)
}

/// The self-contained `.glb` of `atlas`, its textures as `format` says, in memory (`path` only
/// names it in errors), and its layout.
pub fn encode(
    atlas: &OctahedralAtlas,
    format: TextureFormat,
    path: &Path,
) -> Result<(Vec<u8>, Sidecar), OctahedralFileError> {
    let [color, normal_depth, orm] = encode_maps(atlas, format, path)?;
    let sidecar = super::file::sidecar_of(atlas, path, super::file::FloatMaps::Omitted);
    let maps = EncodedMaps {
        format,
        color: &color,
        normal_depth: &normal_depth,
        orm: &orm,
    };
    let bytes = glb(&sidecar, maps).map_err(|e| OctahedralFileError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(e.to_string()),
    })?;
    Ok((bytes, sidecar))
}

/// A `.glb` read far enough to find an octahedral impostor's layout: its JSON, its binary
/// chunk and the layout (`None` for any other glTF binary).
struct Opened {
    doc: serde_json::Value,
    blob: Vec<u8>,
    layout: Option<Layout>,
}

/// The error of `path` holding invalid data, for `reason`.
fn invalid(path: &Path, reason: String) -> OctahedralFileError {
    OctahedralFileError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, reason),
    }
}

fn open(path: &Path) -> Result<Opened, OctahedralFileError> {
    let bytes = std::fs::read(path).map_err(|source| OctahedralFileError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let glb = ::gltf::binary::Glb::from_slice(&bytes).map_err(|e| invalid(path, e.to_string()))?;
    let doc: serde_json::Value =
        serde_json::from_slice(&glb.json).map_err(|e| invalid(path, e.to_string()))?;
    let blob = glb.bin.map(|b| b.into_owned()).unwrap_or_default();
    let materials = doc["materials"]
        .as_array()
        .map(Vec::as_slice)
        .unwrap_or(&[]);
    let layout = match materials
        .iter()
        .find_map(|m| m["extras"].get("trompe_octahedral"))
    {
        None => None,
        Some(extra) => Some(
            serde_json::from_value(extra.clone())
                .map_err(|e| invalid(path, format!("materials[].extras.trompe_octahedral: {e}")))?,
        ),
    };
    Ok(Opened { doc, blob, layout })
}

/// What a `.glb` holds when trompe baked an octahedral impostor into it: its layout and how its
/// textures are encoded (`None` for any other glTF binary).
pub fn read_layout(path: &Path) -> Result<Option<(Layout, TextureFormat)>, OctahedralFileError> {
    let opened = open(path)?;
    let format = match opened.doc["images"][0]["mimeType"].as_str() {
        Some("image/ktx2") => TextureFormat::Ktx2,
        _ => TextureFormat::Png,
    };
    Ok(opened.layout.map(|l| (l, format)))
}

impl std::fmt::Display for Layout {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let side = self.grid.n * self.frame_size;
        writeln!(f, "octahedral impostor (layout version {})", self.version)?;
        writeln!(
            f,
            "  frames: {n} × {n} ({coverage:?}), {fs} texels a side, atlas {side} × {side}",
            n = self.grid.n,
            coverage = self.grid.coverage,
            fs = self.frame_size,
        )?;
        writeln!(
            f,
            "  bounding sphere: centre ({:.4}, {:.4}, {:.4}), radius {:.4}",
            self.centre[0], self.centre[1], self.centre[2], self.radius
        )?;
        if let Some(card) = &self.card {
            writeln!(f, "  cut-out card: {} vertices", card.len())?;
        }
        write!(
            f,
            "  switch distance: {:.2} units (one texel a pixel at 1080 rows, 60° field of view)",
            self.switch_distance
        )?;
        if let Some(fade) = &self.cross_fade {
            write!(
                f,
                "\n  cross-fade: from {:.2} to {:.2} units, dithered 4 × 4",
                fade.start, fade.end
            )?;
        }
        Ok(())
    }
}

/// Loads the atlas of a `.glb` trompe wrote: its layout and its three maps (the normal and
/// depth unpacked, so within [`super::packing`]'s bounds of the bake).
pub fn load(path: &Path) -> Result<OctahedralAtlas, OctahedralFileError> {
    let invalid = |reason: String| invalid(path, reason);
    let Opened { doc, blob, layout } = open(path)?;
    let Some(layout) = layout else {
        return Err(invalid(
            "no material has extras.trompe_octahedral: not an octahedral impostor trompe baked"
                .into(),
        ));
    };
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
    crate::frame::check_size(side, side)?;
    // The image of texture `index` (PNG, or KTX2 through KHR_texture_basisu), decoded as
    // stored: 8-bit values scaled to [0, 1].
    let image = |index: usize| -> Result<Image<crate::frame::Rgba>, OctahedralFileError> {
        let at = |what: String| invalid(format!("textures[{index}]: {what}"));
        let texture = &doc["textures"][index];
        let source = texture["extensions"]["KHR_texture_basisu"]["source"]
            .as_u64()
            .or(texture["source"].as_u64())
            .ok_or_else(|| at("no such texture, or no source".into()))?;
        let view = doc["images"][source as usize]["bufferView"]
            .as_u64()
            .ok_or_else(|| at(format!("images[{source}] is not held in the file")))?;
        let view = &doc["bufferViews"][view as usize];
        let offset = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        let length = view["byteLength"].as_u64().unwrap_or(0) as usize;
        let bytes = blob
            .get(offset..offset.saturating_add(length))
            .ok_or_else(|| at(format!("its bytes {offset}..+{length} are past the buffer")))?;
        let side = side as u32;
        Ok(match doc["images"][source as usize]["mimeType"].as_str() {
            Some("image/ktx2") => crate::frame::ktx2::decode_level0(bytes, (side, side), path)?,
            _ => io::decode_linear_image(bytes, path)?,
        })
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
    let color = sized(image(t.color)?, "colour")?.map(|c| {
        let l = crate::frame::srgb_to_linear;
        crate::frame::Rgba::new(l(c.x), l(c.y), l(c.z), c.w)
    });
    let packed = sized(image(t.normal_depth)?, "normal-depth")?;
    let orm = sized(image(t.orm)?, "ORM")?;
    let (normal, depth) = super::packing::unpack(&packed)?;
    let orm = orm.map(|o| o.truncate());
    let card = match layout.card {
        None => super::Card::default(),
        Some(outline) => super::Card::from_outline(outline).ok_or_else(|| {
            invalid(
                "the card's outline is not 3 to 8 points in [-1, 1]², convex, \
                 counter-clockwise, round the centre"
                    .into(),
            )
        })?,
    };
    Ok(OctahedralAtlas {
        settings,
        centre,
        radius: layout.radius,
        color,
        normal,
        depth,
        orm,
        card,
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

    /// A 96² view of `atlas` from above and aside.
    fn camera_on(atlas: &OctahedralAtlas) -> crate::camera::Pinhole {
        crate::camera::Pinhole::look_at(
            atlas.centre + glam::Vec3::new(1.0, 2.5, 3.0),
            atlas.centre,
            glam::Vec3::Y,
            35.0,
            96,
            96,
        )
        .unwrap()
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
        save(&atlas, &path, TextureFormat::Png).unwrap();
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
        let camera = camera_on(&atlas);
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

    #[test]
    fn a_ktx2_glb_holds_uastc_mip_chains_and_loads_back_near_the_bake() {
        let atlas = ball(32);
        let dir = crate::test_scratch::scratch("octahedral_glb_ktx2");
        let path = dir.join("ball.glb");
        save(&atlas, &path, TextureFormat::Ktx2).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let glb = ::gltf::binary::Glb::from_slice(&bytes).unwrap();
        let json: serde_json::Value = serde_json::from_slice(&glb.json).unwrap();
        assert_eq!(json["extensionsRequired"][0], "KHR_texture_basisu");
        let blob = glb.bin.unwrap();
        for k in 0..3 {
            assert_eq!(json["images"][k]["mimeType"], "image/ktx2");
            let view =
                &json["bufferViews"][json["images"][k]["bufferView"].as_u64().unwrap() as usize];
            let at = view["byteOffset"].as_u64().unwrap() as usize;
            let len = view["byteLength"].as_u64().unwrap() as usize;
            let reader = ::ktx2::Reader::new(&blob[at..at + len]).unwrap();
            let h = reader.header();
            // Frames of 32 down to 1 texel: sides 128 … 4, six levels, UASTC under Zstandard.
            assert_eq!(
                (h.pixel_width, h.pixel_height, h.level_count),
                (128, 128, 6)
            );
            assert_eq!(
                h.supercompression_scheme,
                Some(::ktx2::SupercompressionScheme::Zstandard)
            );
            let sizes: Vec<usize> = reader
                .levels()
                .map(|l| l.uncompressed_byte_length as usize)
                .collect();
            // 16 bytes a 4 × 4 block.
            assert_eq!(sizes, [1024, 256, 64, 16, 4, 1].map(|blocks| blocks * 16));
            assert_eq!(reader.color_model(), Some(::ktx2::ColorModel::UASTC));
        }
        let back = load(&path).unwrap();
        let camera = camera_on(&atlas);
        let lighting = crate::scene::Lighting {
            environment: crate::frame::envmap::EnvMap::constant(glam::Vec3::splat(0.3)),
            light: None,
        };
        let flip = crate::frame::metrics::flip(
            &atlas.render(&camera, &lighting, 4),
            &back.render(&camera, &lighting, 4),
            None,
        )
        .unwrap();
        assert!(flip < 0.02, "FLIP {flip}");
        // A KTX2 atlas must tile into 4 × 4 blocks.
        let odd = bake(
            &crate::geom::icosphere(1),
            &crate::scene::Surface::Diffuse(None),
            BakeSettings::new(
                Grid {
                    n: 3,
                    coverage: Coverage::Sphere,
                },
                9,
            ),
        )
        .unwrap();
        let err = save(&odd, &dir.join("odd.glb"), TextureFormat::Ktx2)
            .unwrap_err()
            .to_string();
        assert!(err.contains("multiple of 4"), "{err}");
    }
}
