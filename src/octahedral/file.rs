//! An octahedral atlas on disk: `NAME.json` (the layout, below), `NAME.png` (base colour, sRGB,
//! alpha = coverage), `NAME-normal-depth.png` (the object-space normal and the depth packed in
//! one linear RGBA8 texture, [`super::packing`]) and `NAME-orm.png` (linear 8-bit: red ambient
//! occlusion, green roughness, blue metalness — glTF's packing); with [`FloatMaps::OpenExr`]
//! also `NAME-normal.exr` and `NAME-depth.exr`, the same two maps as 32-bit floats, for
//! pipelines that want them unquantized. The JSON says everything a shader needs to read the
//! maps: the grid (`n` frames a side, `sphere` or `hemisphere`), the frame size, the bounding
//! sphere in the object's own space, and the maps' file names; the mapping is
//! docs/conventions.md §8's.
//!
//! Invariants: written through [`crate::files::write_atomically`]-backed writers; nothing but
//! the files [`files`] lists is written, and the sidecar names exactly the maps written with it.

use super::bake::OctahedralAtlas;
use super::mapping::Grid;
use crate::frame::{FrameError, io};
use std::path::{Path, PathBuf};
use std::time::Duration;
use thiserror::Error;

/// The sidecar's `format`.
pub const FORMAT: &str = "trompe-octahedral-impostor";

/// The JSON sidecar of an octahedral atlas.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sidecar {
    /// Always `"trompe-octahedral-impostor"`.
    pub format: String,
    /// Layout version: 3 (2 had float normal and depth maps only, 1 no ORM map either).
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
    /// How each frame sees the object: `{ "type": "orthographic" }` or
    /// `{ "type": "pinhole", "distance": D }` (eye `D` radii from the centre, field of view
    /// `2·atan(1/√(D² − 1))`); orthographic when absent.
    #[serde(default)]
    pub projection: super::FrameProjection,
    /// The card's outline ([`super::card`]): 3 to 8 points `[x, y]` in units of the radius,
    /// counter-clockwise in the card's axes; the whole square when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub card: Option<Vec<[f32; 2]>>,
    /// Base colour + coverage (PNG, sRGB).
    pub color: String,
    /// Normal and depth packed in one linear RGBA8 PNG ([`super::packing`]); absent before
    /// version 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal_depth: Option<String>,
    /// Object-space normals (OpenEXR, float RGB): always before version 3, then only when
    /// asked for ([`FloatMaps::OpenExr`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal: Option<String>,
    /// Depth over the sphere's diameter from each frame's front plane (OpenEXR, float): as
    /// `normal`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth: Option<String>,
    /// Occlusion, roughness, metalness (PNG, linear); absent in version 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orm: Option<String>,
    /// The maps' sizes and checksums, recorded when the sidecar is written last, so that a
    /// sidecar is read only with the maps it was written with; absent in older files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parts: Option<Vec<crate::files::Part>>,
}

/// The layout version this build writes.
pub const VERSION: u32 = 3;

/// Whether the normal and depth maps are also written as 32-bit float OpenEXR files.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FloatMaps {
    /// The packed 8-bit map only.
    #[default]
    Omitted,
    /// `NAME-normal.exr` and `NAME-depth.exr` beside it.
    OpenExr,
}

/// Errors writing an atlas.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum OctahedralFileError {
    /// A map could not be written.
    #[error(transparent)]
    Frame(#[from] FrameError),
    /// The sidecar could not be written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The sidecar's path has no file name.
    #[error("{0}: not a file name")]
    NotAFile(PathBuf),
    /// A file an atlas would be written over is not part of an earlier atlas.
    #[error(
        "{path}: a file of the user's is where the atlas {sidecar} would write (no octahedral \
         sidecar of that name records it); move it or choose another output name"
    )]
    NotAnAtlas {
        /// The file.
        path: PathBuf,
        /// The sidecar the atlas would have.
        sidecar: PathBuf,
    },
    /// A map is not the one its sidecar records.
    #[error(transparent)]
    Part(#[from] crate::files::PartError),
}

/// Reads and checks the sidecar of an octahedral atlas (its maps are not read).
pub fn read_sidecar(path: &Path) -> Result<Sidecar, OctahedralFileError> {
    let invalid = |reason: String| OctahedralFileError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, reason),
    };
    let text = std::fs::read_to_string(path).map_err(|source| OctahedralFileError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let sidecar: Sidecar = serde_json::from_str(&text).map_err(|e| invalid(e.to_string()))?;
    if sidecar.format != FORMAT {
        return Err(invalid(format!(
            "format {:?} is not an octahedral impostor's ({FORMAT:?})",
            sidecar.format
        )));
    }
    // The sphere places every frame: a radius of 0 (or one not finite) makes no atlas.
    if !(sidecar.radius.is_finite() && sidecar.radius > 0.0) {
        return Err(invalid(format!(
            "radius {}: the bounding sphere's radius must be a positive number",
            sidecar.radius
        )));
    }
    if let Some(c) = sidecar
        .centre
        .iter()
        .find(|c| crate::geom::out_of_range(c.abs()))
    {
        return Err(invalid(format!(
            "centre coordinate {c}: must be a number within ±{:e}",
            crate::geom::MAX_COORDINATE
        )));
    }
    Ok(sidecar)
}

/// A test hook: `TROMPE_TEST_PAUSE_BEFORE_SIDECAR_MS` (at most 10 s) holds a writer between
/// its maps and its sidecar, so that tests can race two writers there.
fn pause_for_tests() {
    if let Some(ms) = std::env::var("TROMPE_TEST_PAUSE_BEFORE_SIDECAR_MS")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    {
        std::thread::sleep(std::time::Duration::from_millis(ms.min(10_000)));
    }
}

/// Refuses the maps beside `path` that its sidecar does not record (another bake's, or a bake
/// torn by a kill).
pub fn verify_maps(path: &Path, sidecar: &Sidecar) -> Result<(), OctahedralFileError> {
    let dir = path.parent().unwrap_or(Path::new(""));
    for part in sidecar.parts.iter().flatten() {
        part.verify(dir)?;
    }
    Ok(())
}

impl std::fmt::Display for Sidecar {
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
        writeln!(f, "  dilation: {} texels", self.dilation)?;
        match self.projection {
            super::FrameProjection::Orthographic => writeln!(f, "  frames: orthographic")?,
            super::FrameProjection::Pinhole { distance } => {
                writeln!(f, "  frames: pinhole, {distance} bounding radii out")?
            }
        }
        writeln!(
            f,
            "  bounding sphere: centre ({:.4}, {:.4}, {:.4}), radius {:.4}",
            self.centre[0], self.centre[1], self.centre[2], self.radius
        )?;
        write!(f, "  maps: {}", self.maps().join(", "))
    }
}

impl Sidecar {
    /// The file names of the maps this sidecar names, colour first.
    pub fn maps(&self) -> Vec<String> {
        [
            Some(&self.color),
            self.normal_depth.as_ref(),
            self.orm.as_ref(),
            self.normal.as_ref(),
            self.depth.as_ref(),
        ]
        .into_iter()
        .flatten()
        .cloned()
        .collect()
    }
}

/// Every file an atlas whose sidecar is `json` may have: the sidecar, the colour, packed
/// normal-depth and ORM maps, and the two OpenEXR maps [`FloatMaps::OpenExr`] adds.
pub fn files(json: &Path) -> [PathBuf; 6] {
    let stem = json
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let dir = json.parent().unwrap_or(Path::new(""));
    [
        json.to_path_buf(),
        dir.join(format!("{stem}.png")),
        dir.join(format!("{stem}-normal-depth.png")),
        dir.join(format!("{stem}-orm.png")),
        dir.join(format!("{stem}-normal.exr")),
        dir.join(format!("{stem}-depth.exr")),
    ]
}

/// The files the atlas of `sidecar`, written as `json`, has: the sidecar and its maps.
pub fn written(json: &Path, sidecar: &Sidecar) -> Vec<PathBuf> {
    let dir = json.parent().unwrap_or(Path::new(""));
    std::iter::once(json.to_path_buf())
        .chain(sidecar.maps().into_iter().map(|m| dir.join(m)))
        .collect()
}

/// Refuses to write an atlas as `json` (its OpenEXR maps as `floats` says) where one of the
/// files it writes exists but is not part of an earlier atlas of that name (a texture of a
/// user's named like a map): checked before work.
pub fn check_replaceable(json: &Path, floats: FloatMaps) -> Result<(), OctahedralFileError> {
    let files = files(json);
    let writes = match floats {
        FloatMaps::Omitted => &files[..4],
        FloatMaps::OpenExr => &files[..],
    };
    let existing: Vec<&PathBuf> = writes.iter().filter(|f| f.exists()).collect();
    if existing.is_empty() {
        return Ok(());
    }
    let earlier = read_sidecar(json).ok();
    for f in existing {
        let name = f.file_name().map(|n| n.to_string_lossy().into_owned());
        let recorded = earlier.as_ref().is_some_and(|s| {
            f.as_path() == json || s.maps().iter().any(|m| Some(m) == name.as_ref())
        });
        if !recorded {
            return Err(OctahedralFileError::NotAnAtlas {
                path: f.clone(),
                sidecar: json.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Writes `atlas` as `json` and its maps beside it (the OpenEXR ones as `floats` says).
pub fn save(
    atlas: &OctahedralAtlas,
    json: &Path,
    floats: FloatMaps,
) -> Result<Sidecar, OctahedralFileError> {
    if json.file_stem().is_none() {
        return Err(OctahedralFileError::NotAFile(json.to_path_buf()));
    }
    let [_, color, normal_depth, orm, normal, depth] = files(json);
    // Every map encoded, then staged whole beside its name, then the maps and last the sidecar
    // naming them with their checksums renamed into place, under the folder's lock: a second
    // writer waits, a kill leaves at most a few renames undone, and a reader refuses maps that
    // are not its sidecar's.
    let packed = super::packing::pack(&atlas.normal, &atlas.depth)?;
    let mut maps = vec![
        (&color, io::encode_png(&atlas.color, &color)?),
        (
            &normal_depth,
            io::encode_png_data_rgba(&packed, &normal_depth)?,
        ),
        (&orm, io::encode_png_data(&atlas.orm, &orm)?),
    ];
    if floats == FloatMaps::OpenExr {
        maps.push((&normal, io::encode_exr_normals(&normal, &atlas.normal)?));
        maps.push((&depth, io::encode_exr_depth(&depth, &atlas.depth)?));
    }
    let _lock = crate::files::PublishLock::of(json);
    let earlier = read_sidecar(json).ok();
    let io_at = |path: &Path| {
        let path = path.to_path_buf();
        move |source| OctahedralFileError::Io { path, source }
    };
    let mut staged = Vec::new();
    for (path, bytes) in &maps {
        staged.push(crate::files::StagedFile::write(path, bytes).map_err(io_at(path))?);
    }
    let name = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let sidecar = sidecar_of(atlas, json, floats);
    let parts = maps
        .iter()
        .map(|(p, bytes)| crate::files::Part::of_bytes(&name(p), bytes))
        .collect();
    let sidecar = Sidecar {
        parts: Some(parts),
        ..sidecar
    };
    let text = serde_json::to_string_pretty(&sidecar).map_err(|e| OctahedralFileError::Io {
        path: json.to_path_buf(),
        source: std::io::Error::other(e),
    })?;
    let index = crate::files::StagedFile::write(json, text.as_bytes()).map_err(io_at(json))?;
    for (part, (path, _)) in staged.into_iter().zip(&maps) {
        part.commit().map_err(io_at(path))?;
    }
    pause_for_tests();
    index.commit().map_err(io_at(json))?;
    // An earlier bake's maps this one does not write (its OpenEXR files, say) go, where they
    // are still the files that bake recorded: never a file of the user's.
    if let Some(earlier) = earlier {
        let dir = json.parent().unwrap_or(Path::new(""));
        let now = sidecar.maps();
        for part in earlier.parts.iter().flatten() {
            if !now.contains(&part.file) && part.verify(dir).is_ok() {
                let _ = std::fs::remove_file(dir.join(&part.file));
            }
        }
    }
    Ok(sidecar)
}

/// The sidecar of `atlas` written as `json` with its maps (no checksums yet).
pub fn sidecar_of(atlas: &OctahedralAtlas, json: &Path, floats: FloatMaps) -> Sidecar {
    let [_, color, normal_depth, orm, normal, depth] = files(json);
    let name = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let exr = floats == FloatMaps::OpenExr;
    Sidecar {
        format: FORMAT.into(),
        version: VERSION,
        grid: atlas.settings.grid,
        frame_size: atlas.settings.frame_size,
        dilation: atlas.settings.dilation,
        centre: atlas.centre.to_array(),
        radius: atlas.radius,
        projection: atlas.settings.projection,
        card: Some(atlas.card.outline().to_vec()),
        color: name(&color),
        normal_depth: Some(name(&normal_depth)),
        normal: exr.then(|| name(&normal)),
        depth: exr.then(|| name(&depth)),
        orm: Some(name(&orm)),
        parts: None,
    }
}

/// Distance (object units) from which one texel of frames `frame_size` texels across a sphere
/// of `radius` covers one pixel of a 1080-row, 60° view: where a renderer can switch from the
/// mesh to the impostor.
pub fn switch_distance(radius: f32, frame_size: u32) -> f32 {
    let texel = 2.0 * radius / frame_size.max(1) as f32;
    let pixel_angle = 60f32.to_radians() / 1080.0;
    texel / pixel_angle
}

/// What a bake did.
#[derive(Clone, Debug)]
pub struct OctahedralReport {
    /// The sidecar written.
    pub sidecar: Sidecar,
    /// Its path and the maps'.
    pub files: Vec<PathBuf>,
    /// Time to bake.
    pub bake_time: Duration,
    /// Bytes of each file written.
    pub bytes: Vec<u64>,
    /// Distance (in object units) from which one atlas texel covers one pixel of a 1080-row,
    /// 60° view: where a renderer can switch from the mesh to the impostor.
    pub switch_distance: f32,
    /// The cut-out card's vertices and its share of the square card's area: the share of the
    /// square's fragments a runtime still shades.
    pub card: (usize, f64),
}

impl OctahedralReport {
    /// The report of `atlas` written to `files` in `bake_time`.
    pub fn new(
        atlas: &OctahedralAtlas,
        sidecar: Sidecar,
        files: Vec<PathBuf>,
        bake_time: Duration,
    ) -> Self {
        let bytes = (files.iter())
            .map(|f| std::fs::metadata(f).map(|m| m.len()).unwrap_or(0))
            .collect();
        OctahedralReport {
            sidecar,
            files,
            bake_time,
            bytes,
            switch_distance: switch_distance(atlas.radius, atlas.settings.frame_size),
            card: (atlas.card.outline().len(), atlas.card.area_share()),
        }
    }
}

/// As JSON: the sidecar, the files and their bytes, the bake's seconds, the switch distance.
impl serde::Serialize for OctahedralReport {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let files: Vec<_> = (self.files.iter().zip(&self.bytes))
            .map(|(path, bytes)| serde_json::json!({ "path": path, "bytes": bytes }))
            .collect();
        serde_json::json!({
            "sidecar": self.sidecar,
            "atlas_side": self.sidecar.grid.n * self.sidecar.frame_size,
            "files": files,
            "bake_seconds": self.bake_time.as_secs_f64(),
            "switch_distance": self.switch_distance,
            "card": { "vertices": self.card.0, "area_share": self.card.1 },
        })
        .serialize(s)
    }
}

impl std::fmt::Display for OctahedralReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = &self.sidecar;
        let side = s.grid.n * s.frame_size;
        let projection = match s.projection {
            super::FrameProjection::Orthographic => "orthographic".to_string(),
            super::FrameProjection::Pinhole { distance } => format!("pinhole at {distance} radii"),
        };
        writeln!(
            f,
            "octahedral impostor: {n} × {n} {projection} frames ({:?}) of {fs}², atlas {side}², baked in {:.2} s",
            s.grid.coverage,
            self.bake_time.as_secs_f64(),
            n = s.grid.n,
            fs = s.frame_size
        )?;
        for (path, bytes) in self.files.iter().zip(&self.bytes) {
            writeln!(f, "  {} ({:.1} MB)", path.display(), *bytes as f64 / 1e6)?;
        }
        writeln!(
            f,
            "cut-out card: {} vertices, {:.0} % of the square card's area ({:.0} % fewer fragments)",
            self.card.0,
            100.0 * self.card.1,
            100.0 * (1.0 - self.card.1)
        )?;
        write!(
            f,
            "switch distance: {:.2} units (one texel a pixel at 1080 rows, 60° field of view)",
            self.switch_distance
        )
    }
}
