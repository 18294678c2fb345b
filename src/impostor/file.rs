//! Impostor files: a JSON sidecar (camera, bounds, format version) and an OpenEXR file with the
//! per-texel maps, so an impostor is baked once and used later.
//!
//! `NAME.json`:
//! ```json
//! { "format": "trompe-impostor", "version": 1, "exr": "NAME.exr",
//!   "width": 512, "height": 512,
//!   "bounds": { "min": [x, y, z], "max": [x, y, z] },
//!   "camera": { "type": "spoc", "position": [..], "a": [..], "b": [..], "c": [..],
//!               "near": 0.5, "pole": [u, v], "z_near": 1.0, "z_far": 2.0, "k": 0.8 } }
//! ```
//! Cameras: `pinhole` (`position`, McMillan `a`, `b`, `c`, `near`), `spoc` (the pinhole fields plus
//! `pole`, `z_near`, `z_far`, `k`), `orthographic` (`corner`, `a`, `b`, `dir`, `depth`), `graph`
//! (the root's pinhole fields plus `frusta`: for every frustum but the root, in creation order,
//! `{ "parent": i, "apex": [..], "face": [[..], ..] }` — its entry face; the matrices are
//! recomputed on load, docs/conventions.md §4).
//!
//! `NAME.exr` channels (32-bit float, lossless ZIP compression in blocks of 16 rows): `R G B A`
//! colour, `gd`, `N.X N.Y N.Z` shading normal, `Ng.X Ng.Y Ng.Z` face normal (toward the
//! camera), `P.X P.Y P.Z` world position, `id` = object id + 1 (0 where empty; ids below 2^24
//! are exact). Files written with another lossless encoding load the same.
//!
//! A layered impostor (`peel.rs`) says `"layers": L` in its sidecar (absent for one layer);
//! its first layer has the channels above, and layer `l` from 2 to `L` the same channels
//! prefixed `layer<l>.` (`layer2.R`, `layer2.gd`, …: OpenEXR's layer naming). A file whose
//! channels hold another number of layers than its sidecar says is refused, naming both.
//!
//! The channels hold the impostor's compact maps decoded (colour already in half precision,
//! normals from their octahedral codes, positions derived from `gd`), and loading packs them
//! again: a saved impostor reloads bit for bit. `P` is read and checked for every camera but
//! kept only for a graph camera (see [`Impostor::position_at`]).
//!
//! Loading validates everything: sizes against the camera, finite values, a sidecar of at most
//! 1 MiB; a corrupted file is an error naming the file and what is wrong.

use super::{Impostor, ImpostorCamera};
use crate::camera::{GraphCamera, Orthographic, Pinhole, Spoc};
use crate::frame::io::read_exr_channels;
use crate::frame::packed::{OctUnit, pack_rgba, pack_unit};
use crate::frame::{FrameError, Image};
use crate::geom::Aabb;
use crate::geom::NO_OBJECT;
use glam::{DVec2, DVec3, Vec3, Vec4};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The sidecar's `format` value.
pub const FORMAT: &str = "trompe-impostor";
/// The sidecar version this build writes and reads.
pub const VERSION: u32 = 1;
const MAX_SIDECAR_BYTES: u64 = 1 << 20;

/// Errors from saving or loading an impostor.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ImpostorFileError {
    /// The sidecar could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The sidecar is not valid.
    #[error("{path}: {reason}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// The image file could not be read or written.
    #[error(transparent)]
    Image(#[from] FrameError),
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Sidecar {
    format: String,
    version: u32,
    exr: String,
    width: u32,
    height: u32,
    bounds: BoundsFile,
    camera: CameraFile,
    /// Depth layers (`peel.rs`): layer 1's channels are unprefixed, layer `l ≥ 2`'s are
    /// prefixed `layer<l>.`. Absent for one layer.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    layers: Option<u32>,
    /// The EXR's size in bytes and FNV-1a 64 checksum (hex): a sidecar is only ever read with
    /// the EXR it was saved with. Absent in files written before they were recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    exr_bytes: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    exr_fnv1a: Option<String>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct BoundsFile {
    min: [f32; 3],
    max: [f32; 3],
}

#[derive(Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
enum CameraFile {
    Pinhole {
        position: [f64; 3],
        a: [f64; 3],
        b: [f64; 3],
        c: [f64; 3],
        near: f64,
    },
    Spoc {
        position: [f64; 3],
        a: [f64; 3],
        b: [f64; 3],
        c: [f64; 3],
        near: f64,
        pole: [f64; 2],
        z_near: f64,
        z_far: f64,
        k: f64,
    },
    Orthographic {
        corner: [f64; 3],
        a: [f64; 3],
        b: [f64; 3],
        dir: [f64; 3],
        depth: f64,
    },
    Graph {
        position: [f64; 3],
        a: [f64; 3],
        b: [f64; 3],
        c: [f64; 3],
        near: f64,
        frusta: Vec<FrustumFile>,
    },
}

/// One non-root frustum of a graph camera.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct FrustumFile {
    parent: usize,
    apex: [f64; 3],
    face: Vec<[f64; 3]>,
}

fn pinhole_file(p: &Pinhole) -> ([f64; 3], [f64; 3], [f64; 3], [f64; 3], f64) {
    let (a, b, c) = p.mcmillan();
    (
        p.position().to_array(),
        a.to_array(),
        b.to_array(),
        c.to_array(),
        p.near(),
    )
}

impl CameraFile {
    fn from_camera(camera: &ImpostorCamera) -> CameraFile {
        match camera {
            ImpostorCamera::Graph(g) => {
                let (position, a, b, c, near) = pinhole_file(g.root());
                let frusta = g
                    .parts()
                    .into_iter()
                    .map(|(parent, apex, face)| FrustumFile {
                        parent,
                        apex: apex.to_array(),
                        face: face.iter().map(|p| p.to_array()).collect(),
                    })
                    .collect();
                CameraFile::Graph {
                    position,
                    a,
                    b,
                    c,
                    near,
                    frusta,
                }
            }
            ImpostorCamera::Pinhole(p) => {
                let (position, a, b, c, near) = pinhole_file(p);
                CameraFile::Pinhole {
                    position,
                    a,
                    b,
                    c,
                    near,
                }
            }
            ImpostorCamera::Spoc(s) => {
                let (position, a, b, c, near) = pinhole_file(s.pinhole());
                let (z_near, z_far) = s.depth_range();
                CameraFile::Spoc {
                    position,
                    a,
                    b,
                    c,
                    near,
                    pole: s.pole().to_array(),
                    z_near,
                    z_far,
                    k: s.strength(),
                }
            }
            ImpostorCamera::Orthographic(o) => {
                let (corner, a, b, dir, depth) = o.parameters();
                CameraFile::Orthographic {
                    corner: corner.to_array(),
                    a: a.to_array(),
                    b: b.to_array(),
                    dir: dir.to_array(),
                    depth,
                }
            }
        }
    }

    fn to_camera(&self, w: u32, h: u32) -> Result<ImpostorCamera, String> {
        let v = DVec3::from_array;
        let pinhole = |position, a, b, c, near: f64| -> Result<Pinhole, String> {
            let (position, a, b, c) = (v(position), v(a), v(b), v(c));
            let m = glam::DMat3::from_cols(a, b, c);
            let finite = position.is_finite() && a.is_finite() && b.is_finite() && c.is_finite();
            let valid = finite && m.determinant().abs() > 1e-300 && near > 0.0 && near.is_finite();
            if !valid {
                return Err("camera: degenerate pinhole parameters".into());
            }
            crate::frame::check_size(w as u64, h as u64).map_err(|e| e.to_string())?;
            Ok(Pinhole::from_mcmillan(position, a, b, c, w, h).with_near(near))
        };
        Ok(match *self {
            CameraFile::Pinhole {
                position,
                a,
                b,
                c,
                near,
            } => ImpostorCamera::Pinhole(pinhole(position, a, b, c, near)?),
            CameraFile::Spoc {
                position,
                a,
                b,
                c,
                near,
                pole,
                z_near,
                z_far,
                k,
            } => ImpostorCamera::Spoc(
                Spoc::from_parts(
                    pinhole(position, a, b, c, near)?,
                    DVec2::from_array(pole),
                    z_near,
                    z_far,
                    k,
                )
                .map_err(|e| e.to_string())?,
            ),
            CameraFile::Orthographic {
                corner,
                a,
                b,
                dir,
                depth,
            } => ImpostorCamera::Orthographic(
                Orthographic::from_parameters(v(corner), v(a), v(b), v(dir), depth, w, h)
                    .map_err(|e| e.to_string())?,
            ),
            CameraFile::Graph {
                position,
                a,
                b,
                c,
                near,
                ref frusta,
            } => {
                let parts: Vec<_> = frusta
                    .iter()
                    .map(|f| (f.parent, v(f.apex), f.face.iter().map(|p| v(*p)).collect()))
                    .collect();
                ImpostorCamera::Graph(
                    GraphCamera::from_parts(pinhole(position, a, b, c, near)?, &parts)
                        .map_err(|e| e.to_string())?,
                )
            }
        })
    }
}

/// The channels of one depth layer, each name prefixed by `prefix`.
fn layer_channels(impostor: &Impostor, prefix: &str) -> Vec<(String, Vec<f32>)> {
    let split3 =
        |img: &Image<Vec3>, k: usize| img.pixels().iter().map(|v| v[k]).collect::<Vec<f32>>();
    let color_image = impostor.color_image();
    let color = |k: usize| {
        color_image
            .pixels()
            .iter()
            .map(|c| c[k])
            .collect::<Vec<f32>>()
    };
    let (normal, face_normal, position) = (
        impostor.normal_image(),
        impostor.face_normal_image(),
        impostor.position_image(),
    );
    let ids = impostor
        .object
        .pixels()
        .iter()
        .map(|&o| if o == NO_OBJECT { 0.0 } else { (o + 1) as f32 })
        .collect();
    [
        ("R", color(0)),
        ("G", color(1)),
        ("B", color(2)),
        ("A", color(3)),
        ("gd", impostor.gd.pixels().to_vec()),
        ("N.X", split3(&normal, 0)),
        ("N.Y", split3(&normal, 1)),
        ("N.Z", split3(&normal, 2)),
        ("Ng.X", split3(&face_normal, 0)),
        ("Ng.Y", split3(&face_normal, 1)),
        ("Ng.Z", split3(&face_normal, 2)),
        ("P.X", split3(&position, 0)),
        ("P.Y", split3(&position, 1)),
        ("P.Z", split3(&position, 2)),
        ("id", ids),
    ]
    .into_iter()
    .map(|(name, data)| (format!("{prefix}{name}"), data))
    .collect()
}

/// Writes `impostor` as `json_path` (sidecar) and the EXR beside it (same stem, `.exr`).
pub fn save(impostor: &Impostor, json_path: &Path) -> Result<(), ImpostorFileError> {
    let exr_path = json_path.with_extension("exr");
    let exr_name = exr_path
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| ImpostorFileError::Invalid {
            path: json_path.to_path_buf(),
            reason: "the file name is not valid UTF-8".into(),
        })?
        .to_string();
    let (w, h) = impostor.gd.size();
    if impostor.layers().any(|layer| {
        layer
            .object
            .pixels()
            .iter()
            .any(|&o| o != NO_OBJECT && o >= (1 << 24) - 1)
    }) {
        return Err(ImpostorFileError::Invalid {
            path: json_path.to_path_buf(),
            reason: "object ids must be below 2^24 - 1".into(),
        });
    }
    let mut channels = layer_channels(impostor, "");
    for (l, layer) in impostor.layers().enumerate().skip(1) {
        channels.extend(layer_channels(layer, &format!("layer{}.", l + 1)));
    }
    let channels: Vec<(&str, Vec<f32>)> = channels
        .iter()
        .map(|(name, data)| (name.as_str(), data.clone()))
        .collect();
    // The maps first, whole, then the sidecar that names them with their checksum: a reader sees
    // the old pair, or the new EXR with the old sidecar (refused by the checksum), never a
    // truncated file.
    let bytes = crate::frame::io::encode_exr(
        &exr_path,
        (w, h),
        channels,
        exr::prelude::Encoding::SMALL_LOSSLESS,
    )?;
    let io_at = |path: &Path| {
        let path = path.to_path_buf();
        move |source| ImpostorFileError::Io { path, source }
    };
    let _lock = crate::files::PublishLock::of(json_path);
    let exr = crate::files::StagedFile::write(&exr_path, &bytes).map_err(io_at(&exr_path))?;
    let exr_fnv1a = crate::files::Part::of_bytes(&exr_name, &bytes).fnv1a;
    let sidecar = Sidecar {
        format: FORMAT.into(),
        version: VERSION,
        exr: exr_name,
        width: w,
        height: h,
        bounds: BoundsFile {
            min: impostor.bounds.min.to_array(),
            max: impostor.bounds.max.to_array(),
        },
        camera: CameraFile::from_camera(&impostor.camera),
        layers: (impostor.layer_count() > 1).then_some(impostor.layer_count() as u32),
        exr_bytes: Some(bytes.len() as u64),
        exr_fnv1a: Some(exr_fnv1a),
    };
    let text = serde_json::to_string_pretty(&sidecar).map_err(|e| ImpostorFileError::Invalid {
        path: json_path.to_path_buf(),
        reason: e.to_string(),
    })?;
    // Both staged whole first: between the two renames only, a reader finds the new EXR beside
    // the old sidecar, and refuses it by its checksum.
    let index =
        crate::files::StagedFile::write(json_path, text.as_bytes()).map_err(io_at(json_path))?;
    exr.commit().map_err(io_at(&exr_path))?;
    pause_for_tests();
    index.commit().map_err(io_at(json_path))
}

/// A test hook: `TROMPE_TEST_PAUSE_BEFORE_SIDECAR_MS` (at most 10 s) holds a writer between
/// its EXR and its sidecar, so the tests can make two writers interleave there.
fn pause_for_tests() {
    if let Some(ms) = std::env::var("TROMPE_TEST_PAUSE_BEFORE_SIDECAR_MS")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    {
        std::thread::sleep(std::time::Duration::from_millis(ms.min(10_000)));
    }
}

/// Reads an impostor saved by [`save`], validating every field.
pub fn load(json_path: &Path) -> Result<Impostor, ImpostorFileError> {
    let invalid = |reason: String| ImpostorFileError::Invalid {
        path: json_path.to_path_buf(),
        reason,
    };
    let io = |source| ImpostorFileError::Io {
        path: json_path.to_path_buf(),
        source,
    };
    let len = std::fs::metadata(json_path).map_err(io)?.len();
    if len > MAX_SIDECAR_BYTES {
        return Err(invalid(format!(
            "sidecar is {len} bytes; at most 1 MiB expected"
        )));
    }
    // Read through a bound: a device or a pipe named like a sidecar reports no length.
    let mut text = String::new();
    {
        use std::io::Read as _;
        let f = std::fs::File::open(json_path).map_err(io)?;
        f.take(MAX_SIDECAR_BYTES + 1)
            .read_to_string(&mut text)
            .map_err(io)?;
    }
    if text.len() as u64 > MAX_SIDECAR_BYTES {
        return Err(invalid("sidecar is longer than 1 MiB".into()));
    }
    let sidecar: Sidecar = serde_json::from_str(&text).map_err(|e| invalid(e.to_string()))?;
    if sidecar.format != FORMAT || sidecar.version != VERSION {
        return Err(invalid(format!(
            "format {:?} version {} (expected {FORMAT:?} version {VERSION})",
            sidecar.format, sidecar.version
        )));
    }
    let camera = sidecar
        .camera
        .to_camera(sidecar.width, sidecar.height)
        .map_err(invalid)?;
    let bounds = Aabb {
        min: Vec3::from_array(sidecar.bounds.min),
        max: Vec3::from_array(sidecar.bounds.max),
    };
    if !(bounds.min.is_finite() && bounds.max.is_finite()) || bounds.is_empty() {
        return Err(invalid("bounds: empty or not finite".into()));
    }
    if sidecar.exr.contains('/') || sidecar.exr.contains('\\') {
        return Err(invalid("exr: must name a file beside the sidecar".into()));
    }
    let exr_path = json_path.with_file_name(&sidecar.exr);
    // That the EXR is the one this sidecar was saved with (where the sidecar says): a pair torn
    // by a killed or raced bake is named as such, whatever else about it disagrees.
    let same_exr = || -> Result<(), ImpostorFileError> {
        let (Some(size), Some(sum)) = (sidecar.exr_bytes, &sidecar.exr_fnv1a) else {
            return Ok(());
        };
        let (got_size, got) =
            crate::files::checksum_file(&exr_path).map_err(|source| ImpostorFileError::Io {
                path: exr_path.clone(),
                source,
            })?;
        if got_size != size || format!("{got:016x}") != *sum {
            return Err(invalid(format!(
                "{} is not the EXR this sidecar was saved with ({got_size} bytes, checksum {got:016x}; the sidecar says {size} bytes, {sum}): bake again",
                exr_path.display()
            )));
        }
        Ok(())
    };
    let ch = read_exr_channels(&exr_path)?;
    if (ch.width, ch.height) != (sidecar.width, sidecar.height) {
        same_exr()?;
        return Err(invalid(format!(
            "{}: image is {} × {} but the sidecar says {} × {}",
            exr_path.display(),
            ch.width,
            ch.height,
            sidecar.width,
            sidecar.height
        )));
    }
    let layers = sidecar.layers.unwrap_or(1);
    if !(1..=super::MAX_LAYERS).contains(&layers) {
        return Err(invalid(format!(
            "layers: {layers} (between 1 and {})",
            super::MAX_LAYERS
        )));
    }
    // The layers the channels hold must be the sidecar's: layer l ≥ 2's channels are
    // prefixed `layer<l>.`.
    let in_file = (2..=super::MAX_LAYERS + 1)
        .take_while(|l| {
            let prefix = format!("layer{l}.");
            ch.channels.iter().any(|(n, _)| n.starts_with(&prefix))
        })
        .count() as u32
        + 1;
    let stray = ch.channels.iter().find(|(n, _)| {
        n.strip_prefix("layer")
            .and_then(|rest| rest.split_once('.'))
            .and_then(|(l, _)| l.parse::<u32>().ok())
            .is_some_and(|l| l < 2 || l > layers)
    });
    if in_file != layers || stray.is_some() {
        same_exr()?;
        let found = stray.map_or(String::new(), |(n, _)| format!(", and channel {n:?}"));
        return Err(invalid(format!(
            "the sidecar says {layers} layer{} but {} holds channels of {in_file}{found}",
            if layers == 1 { "" } else { "s" },
            exr_path.display(),
        )));
    }
    let mut impostor = read_layer(&ch, "", &exr_path, (&camera, bounds))?;
    for l in 2..=layers {
        let layer = read_layer(&ch, &format!("layer{l}."), &exr_path, (&camera, bounds))?;
        impostor.deeper.push(layer);
    }
    // Last, once the EXR is known to be a readable impostor: that it is this sidecar's.
    same_exr()?;
    Ok(impostor)
}

/// One depth layer's maps from the channels named `prefix` + the single-layer names.
fn read_layer(
    ch: &crate::frame::io::ExrChannels,
    prefix: &str,
    exr_path: &Path,
    (camera, bounds): (&ImpostorCamera, Aabb),
) -> Result<Impostor, ImpostorFileError> {
    let invalid = |reason: String| ImpostorFileError::Invalid {
        path: exr_path.to_path_buf(),
        reason,
    };
    let get = |name: &str| -> Result<Vec<f32>, ImpostorFileError> {
        let name = &format!("{prefix}{name}");
        let img = ch.channel(name)?;
        if img.pixels().iter().any(|v| !v.is_finite()) {
            return Err(ImpostorFileError::Invalid {
                path: exr_path.to_path_buf(),
                reason: format!("channel {name:?} holds a value that is not finite"),
            });
        }
        Ok(img.into_vec())
    };
    let (w, h) = (ch.width, ch.height);
    let vec3 = |x: Vec<f32>, y: Vec<f32>, z: Vec<f32>| -> Result<Image<Vec3>, FrameError> {
        Image::from_vec(
            w,
            h,
            x.into_iter()
                .zip(y)
                .zip(z)
                .map(|((x, y), z)| Vec3::new(x, y, z))
                .collect(),
        )
    };
    let (r, g, b, a) = (get("R")?, get("G")?, get("B")?, get("A")?);
    let color = Image::from_vec(
        w,
        h,
        r.into_iter()
            .zip(g)
            .zip(b)
            .zip(a)
            .map(|(((r, g), b), a)| pack_rgba(Vec4::new(r, g, b, a)))
            .collect(),
    )?;
    let gd = Image::from_vec(w, h, get("gd")?)?;
    if gd.pixels().iter().any(|&g| g < 0.0) {
        return Err(invalid(format!(
            "channel \"{prefix}gd\" holds negative values"
        )));
    }
    let ids = get("id")?;
    if ids
        .iter()
        .any(|&i| i < 0.0 || i.fract() != 0.0 || i >= (1 << 24) as f32)
    {
        return Err(invalid(format!(
            "channel \"{prefix}id\" holds values that are not ids"
        )));
    }
    // Packed as a build packs them; empty texels hold the zero bits a fresh build leaves.
    let packed = |v: Image<Vec3>| -> Result<Image<OctUnit>, FrameError> {
        let codes = (v.pixels().iter().zip(gd.pixels()))
            .map(|(&n, &g)| if g > 0.0 { pack_unit(n) } else { [0, 0] })
            .collect();
        Image::from_vec(w, h, codes)
    };
    let normal = packed(vec3(get("N.X")?, get("N.Y")?, get("N.Z")?)?)?;
    let face_normal = packed(vec3(get("Ng.X")?, get("Ng.Y")?, get("Ng.Z")?)?)?;
    // Read (and checked finite) for every camera; kept only by a graph camera.
    let position = vec3(get("P.X")?, get("P.Y")?, get("P.Z")?)?;
    let object = Image::from_vec(
        w,
        h,
        ids.into_iter()
            .map(|i| if i == 0.0 { NO_OBJECT } else { i as u32 - 1 })
            .collect(),
    )?;
    Ok(Impostor::from_maps(
        camera.clone(),
        color,
        gd,
        normal,
        face_normal,
        Some(position),
        object,
        bounds,
    ))
}
