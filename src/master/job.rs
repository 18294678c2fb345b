//! The three jobs of `trompe master`: encode a COLMAP model's views of a mesh into a folder,
//! render from a folder through a new camera, propagate an edit (of one view, or seen from a new camera) to every view.
//! Each returns a summary the command line prints.

use super::bake::BakeReport;
use super::edit::{Apply, delta, propagate};
use super::file::{Manifest, load, load_manifest, load_master, master_name, save_manifest};
use super::layout::TexelBudget;
use super::{Atlas, DEFAULT_SCALE, MasterError, encode, encode_stream};
use crate::camera::Pinhole;
use crate::files::{FolderKind, StagedFolder};
use crate::frame::{FrameError, Image, Rgba, io};
use crate::geom::Mesh;
use crate::progress::Progress;
use crate::texturing::{Blend, BlendSettings};
use crate::views::visibility::DepthMap;
use std::path::{Path, PathBuf};

/// What an encoding stored, against storing the exemplars (paper 5 Table 1). As JSON, every
/// field and the compression ratio.
#[derive(Clone, Debug)]
pub struct EncodeSummary {
    /// Views encoded.
    pub views: usize,
    /// Faces of the mesh.
    pub faces: usize,
    /// Atlas size.
    pub atlas: (u32, u32),
    /// Atlas texels that hold a face.
    pub used: usize,
    /// Bytes of the exemplars as 8-bit RGB, and of their per-view texture coordinates
    /// (`3m·n` pairs of f32).
    pub exemplar_bytes: (u64, u64),
    /// Bytes of the master textures as 8-bit RGB, and of the one UV set (`3m` pairs).
    pub master_bytes: (u64, u64),
    /// Where the atlas's texels go.
    pub budget: TexelBudget,
    /// What the view-independent bake did.
    pub bake: BakeReport,
    /// Files written.
    pub files: Vec<PathBuf>,
}

impl EncodeSummary {
    /// Exemplars' bytes over masters' bytes (above 1: the encoding is smaller).
    pub fn compression(&self) -> f64 {
        let e = self.exemplar_bytes.0 + self.exemplar_bytes.1;
        let m = self.master_bytes.0 + self.master_bytes.1;
        e as f64 / m.max(1) as f64
    }
}

impl serde::Serialize for EncodeSummary {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        serde_json::json!({
            "views": self.views,
            "faces": self.faces,
            "atlas": [self.atlas.0, self.atlas.1],
            "used_texels": self.used,
            "exemplar_bytes": { "images": self.exemplar_bytes.0, "uvs": self.exemplar_bytes.1 },
            "master_bytes": { "textures": self.master_bytes.0, "uvs": self.master_bytes.1 },
            "compression": self.compression(),
            "texel_budget": self.budget,
            "bake": {
                "whole_faces": self.bake.whole,
                "outlier_looks": self.bake.seams.outliers,
                "seam_edges": self.bake.seams.edges,
                "seam_step_gains": self.bake.seams.step_gains,
                "seam_step_levelled": self.bake.seams.step_levelled,
                "filled_texels": self.bake.filled,
                "empty_texels": self.bake.empty,
            },
            "files": self.files,
        })
        .serialize(s)
    }
}

impl std::fmt::Display for EncodeSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mb = |b: u64| b as f64 / 1e6;
        writeln!(
            f,
            "{} views of {} faces encoded in a {} × {} atlas ({:.0} % of its texels hold a face)",
            self.views,
            self.faces,
            self.atlas.0,
            self.atlas.1,
            100.0 * self.used as f64 / (self.atlas.0 as f64 * self.atlas.1 as f64).max(1.0)
        )?;
        writeln!(
            f,
            "storage: exemplars {:.2} MB + per-view UVs {:.2} MB, master textures {:.2} MB + one UV set {:.3} MB: {:.2} : 1",
            mb(self.exemplar_bytes.0),
            mb(self.exemplar_bytes.1),
            mb(self.master_bytes.0),
            mb(self.master_bytes.1),
            self.compression()
        )?;
        writeln!(f, "texels: {}", self.budget)?;
        write!(f, "view-independent bake: {}", self.bake.told(self.faces))
    }
}

/// The storage figures of `n` exemplars of `sizes` against their master textures in `atlas`:
/// `((exemplar bytes, their UV bytes), (master bytes, one UV set's bytes))`.
pub fn storage(atlas: &Atlas, sizes: &[(u32, u32)]) -> ((u64, u64), (u64, u64)) {
    let n = sizes.len() as u64;
    let corners = atlas.layout.faces.len() as u64 * 3;
    let exemplars: u64 = sizes.iter().map(|&(w, h)| w as u64 * h as u64 * 3).sum();
    let (aw, ah) = atlas.size();
    (
        (exemplars, corners * n * 8),
        (n * aw as u64 * ah as u64 * 3, corners * 8),
    )
}

/// Encodes the views of the COLMAP model `model` (images in `images`, or found beside it) of
/// `mesh` into `out`, one view in memory at a time: master textures, `masters.json`, the
/// view-independent `bake.png` and `mesh.glb` textured by it.
pub fn encode_folder(
    model: &Path,
    images: Option<&Path>,
    mesh: &Mesh,
    scale: Option<f64>,
    out: &Path,
    progress: &dyn Progress,
) -> Result<EncodeSummary, MasterError> {
    let set = crate::views::ViewSet::load(model, images)?;
    let staged = StagedFolder::begin(out, FolderKind::MasterEncoding)?;
    let staging = staged.path();
    let sizes: Vec<(u32, u32)> = set.views.iter().map(|v| v.intrinsics.size()).collect();
    let cameras: Vec<(String, Pinhole)> = set
        .views
        .iter()
        .map(|v| (v.name.clone(), v.pinhole()))
        .collect();
    let mut files = Vec::new();
    let (atlas, baker) = encode_stream(
        mesh,
        &cameras,
        scale.unwrap_or(DEFAULT_SCALE),
        &mut |v| {
            let mut view = set.views[v].clone();
            let img = set.read_image(&view)?;
            view.image = Some(img);
            crate::views::blend::undistorted_image(&view).ok_or(MasterError::NothingSeen)
        },
        &mut |v, master| {
            let path = staging.join(master_name(v));
            io::write_png(&path, &master)?;
            files.push(path);
            Ok(())
        },
        progress,
    )?;
    let baked = baker.bake(&atlas, mesh, &mut |v| {
        Ok(io::read_png(&staging.join(master_name(v)))?)
    })?;
    files.extend(finish_folder(
        staging,
        &atlas,
        &cameras,
        mesh,
        &baked.image,
    )?);
    let files = published(staged, files)?;
    let (exemplar_bytes, master_bytes) = storage(&atlas, &sizes);
    let pinholes: Vec<Pinhole> = cameras.iter().map(|(_, c)| c.clone()).collect();
    let surface = super::face_surface(mesh, &pinholes, scale.unwrap_or(DEFAULT_SCALE));
    Ok(EncodeSummary {
        views: cameras.len(),
        faces: mesh.triangle_count(),
        atlas: atlas.size(),
        used: atlas.used(),
        exemplar_bytes,
        master_bytes,
        budget: TexelBudget::of(&atlas.layout, surface),
        bake: baked.report,
        files,
    })
}

/// Writes what follows the master textures into `out`: the bake, `masters.json` and
/// `mesh.glb` textured by the bake. Returns the files written.
fn finish_folder(
    out: &Path,
    atlas: &Atlas,
    cameras: &[(String, Pinhole)],
    mesh: &Mesh,
    baked: &Image<Rgba>,
) -> Result<Vec<PathBuf>, MasterError> {
    let bake_path = out.join("bake.png");
    let png = io::encode_png(baked, &bake_path)?;
    crate::files::write_atomically(&bake_path, &png).map_err(|source| FrameError::Io {
        path: bake_path.clone(),
        source,
    })?;
    let mut files = save_manifest(out, &atlas.layout, cameras, mesh, &png)?;
    files.push(bake_path);
    Ok(files)
}

/// Renders `mesh` through `camera` from the encoding in `dir`.
pub fn render_folder(
    dir: &Path,
    mesh: &Mesh,
    camera: (&Pinhole, Option<&crate::camera::Intrinsics>),
    settings: &BlendSettings,
) -> Result<Blend, MasterError> {
    let (manifest, masters) = load(dir)?;
    let cameras: Vec<Pinhole> = manifest.views.iter().map(|v| v.pinhole()).collect();
    super::render::render_through(camera, mesh, &manifest.layout, &cameras, &masters, settings)
}

/// What an edit changed.
#[derive(Clone, Debug)]
pub struct EditSummary {
    /// Texels of the edited view's master texture the edit changed.
    pub edited: usize,
    /// Texels changed over every master texture.
    pub changed: usize,
    /// Views.
    pub views: usize,
    /// Files written.
    pub files: Vec<PathBuf>,
}

impl std::fmt::Display for EditSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the edit changed {} texels of its view's master texture; propagated to {} views, {} texels in all",
            self.edited, self.views, self.changed
        )
    }
}

/// Where an edit comes from.
#[derive(Clone, Debug)]
pub enum EditSource {
    /// View `N`'s image as an artist changed it: compared with its master texture.
    View(usize),
    /// A render through a new camera without the effect (the edited image is the render with
    /// it): a shadow, a decal seen from anywhere.
    Camera {
        /// The camera (undistorted) both renders were made through.
        camera: Box<Pinhole>,
        /// The render without the effect.
        without: Image<Rgba>,
    },
}

/// Propagates an edit: `edited` is, per `source`, view N's image as changed or a new camera's
/// render with the effect; the difference of its encoding (from the view's master texture, or
/// from the encoding of the render without the effect) is applied to every master texture —
/// read, edited and written one at a time — and the edited encoding written into `out` (a
/// folder other than `dir`).
pub fn edit_folder(
    dir: &Path,
    mesh: &Mesh,
    source: &EditSource,
    edited: &Image<Rgba>,
    apply: Apply,
    out: &Path,
) -> Result<EditSummary, MasterError> {
    let manifest = load_manifest(dir)?;
    if manifest.layout.faces.len() != mesh.triangle_count() {
        return Err(MasterError::Faces {
            mesh: mesh.triangle_count(),
            map: manifest.layout.faces.len(),
        });
    }
    let (camera, index) = match source {
        EditSource::View(view) => {
            let stored = manifest.views.get(*view).ok_or(MasterError::NoView {
                view: *view,
                count: manifest.views.len(),
            })?;
            (stored.pinhole(), *view)
        }
        EditSource::Camera { camera, .. } => ((**camera).clone(), manifest.views.len()),
    };
    let expected = crate::camera::Projection::resolution(&camera);
    for image in [
        Some(edited),
        match source {
            EditSource::Camera { without, .. } => Some(without),
            EditSource::View(_) => None,
        },
    ]
    .into_iter()
    .flatten()
    {
        if image.size() != expected {
            return Err(MasterError::Size {
                index,
                got: image.size(),
                expected,
            });
        }
    }
    let atlas = Atlas::from_layout(mesh, manifest.layout.clone())?;
    let depth = DepthMap::through(&camera, mesh)?;
    let after = encode(&atlas, &camera, edited, &depth)?;
    let before = match source {
        EditSource::View(view) => load_master(dir, &manifest, *view)?,
        EditSource::Camera { without, .. } => encode(&atlas, &camera, without, &depth)?,
    };
    let d = delta(&before, &after, EDIT_THRESHOLD)?;
    drop(before);
    let edited_texels = d.pixels().iter().filter(|p| p.w > 0.0).count();
    let cameras: Vec<(String, Pinhole)> = manifest
        .views
        .iter()
        .map(|v| (v.name.clone(), v.pinhole()))
        .collect();
    let mut baker = super::bake::Baker::new(&atlas, cameras.len())?;
    let staged = StagedFolder::begin(out, FolderKind::MasterEncoding)?;
    let (mut changed, mut files) = (0, Vec::new());
    for (i, (_, cam)) in cameras.iter().enumerate() {
        let mut m = [load_master(dir, &manifest, i)?];
        changed += propagate(&mut m, &d, &after, apply)?;
        baker.add(&atlas, mesh, i, cam, &m[0]);
        let path = staged.path().join(master_name(i));
        io::write_png(&path, &m[0])?;
        files.push(path);
    }
    let baked = baker.bake(&atlas, mesh, &mut |v| {
        Ok(io::read_png(&staged.path().join(master_name(v)))?)
    })?;
    files.extend(finish_folder(
        staged.path(),
        &atlas,
        &cameras,
        mesh,
        &baked.image,
    )?);
    let files = published(staged, files)?;
    Ok(EditSummary {
        edited: edited_texels,
        changed,
        views: manifest.views.len(),
        files,
    })
}

/// Publishes a staged encoding whose `files` were written into it; returns where they are now.
fn published(staged: StagedFolder, files: Vec<PathBuf>) -> Result<Vec<PathBuf>, MasterError> {
    let files = files
        .iter()
        .filter_map(|f| f.strip_prefix(staged.path()).ok())
        .map(|f| staged.target().join(f))
        .collect();
    staged.publish()?;
    Ok(files)
}

/// Smallest per-channel change an edit carries (linear): below it, resampling noise.
pub const EDIT_THRESHOLD: f32 = 0.02;

/// The files of the encoding in `dir` a render reads (for an output plan): its manifest and
/// master textures, as far as the manifest can be read.
pub fn files_of(dir: &Path) -> Vec<PathBuf> {
    let mut files = vec![dir.join("masters.json")];
    if let Ok(m) = load_manifest(dir) {
        files.extend(m.views.iter().map(|v| dir.join(&v.master)));
    }
    files
}

/// Reads `masters.json` of `dir` only.
pub fn manifest(dir: &Path) -> Result<Manifest, MasterError> {
    load_manifest(dir)
}
