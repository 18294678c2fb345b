//! Layered view-dependent projective textures (paper 4: Reche and Drettakis, "Textures
//! projectives à calques dépendantes du point de vue", AFIG 2003; docs/conventions.md §9).
//!
//! For each calibrated view of a scene of several objects: the objects sorted into visibility
//! layers ([`order`], over the view's [`abuffer`], breaking cycles by [`split`]), each layer cut
//! into image layers of the photograph by the power-of-two clustering ([`image`]), written as
//! an OpenRaster file an artist edits in GIMP or Krita ([`ora`]) or filled automatically
//! ([`fill`]); then every object rendered from new viewpoints textured by its layers, each
//! through its asymmetric sub-frustum ([`frustum`]), blended across views ([`render`]).
//! A [`LayerSet`] is the whole of it in memory; [`file`](mod@file) saves and loads it.
//!
//! Invariants: meshes are in world space, in scene object order (object id = index); a view's
//! image layers are in its undistorted pinhole's pixels; the layers of a view composite back to
//! its photograph; Newell splits are recorded and replayed, so a loaded set has the built
//! set's triangles.

pub mod abuffer;
pub mod file;
pub mod fill;
pub mod frustum;
pub mod image;
pub mod ora;
pub mod order;
pub mod render;
pub mod split;

pub use image::{Assignment, ImageLayer, Memory, Rect, ViewLayers};
pub use order::{Item, OrderSettings, Ordering};

use crate::camera::Pinhole;
use crate::frame::FrameError;
use crate::geom::Mesh;
use crate::progress::Progress;
use crate::raster::{NoAttributes, rasterize};
use crate::views::CalibratedView;
use frustum::LayerProjector;
use serde::{Deserialize, Serialize};
use split::Split;
use std::path::PathBuf;
use thiserror::Error;

/// Errors from building, saving or loading layers.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum LayersError {
    /// The output folder cannot take the result, or publishing it failed.
    #[error(transparent)]
    Folder(#[from] crate::files::FolderError),
    /// An image could not be made (its size refused).
    #[error(transparent)]
    Frame(#[from] FrameError),
    /// A view has no image to cut into layers.
    #[error("view {view}: its image is not loaded")]
    NoImage {
        /// The view's name.
        view: String,
    },
    /// An OpenRaster file could not be read or written.
    #[error(transparent)]
    Ora(#[from] ora::OraError),
    /// The views' model could not be read or written.
    #[error(transparent)]
    Views(#[from] crate::views::ViewsError),
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A project file is malformed or disagrees with the scene or its images.
    #[error("{path}: {element}: {reason}")]
    Project {
        /// The file.
        path: PathBuf,
        /// Where (`object 2`, `view view0003.png`, `layer "L01.02 duck"` …).
        element: String,
        /// What is wrong.
        reason: String,
    },
    /// No view to build from.
    #[error("no views to build layers from")]
    NoViews,
}

/// How a set of layers is built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildSettings {
    /// The visibility ordering.
    pub order: OrderSettings,
    /// The power-of-two clustering of §4.2 (off: one image layer an object a visibility layer).
    pub clustering: bool,
    /// Fill every layer's hidden texels by push-pull ([`fill`]).
    pub fill: bool,
}

impl Default for BuildSettings {
    /// The paper's ordering and clustering, no fill (the artist's part).
    fn default() -> Self {
        BuildSettings {
            order: OrderSettings::default(),
            clustering: true,
            fill: false,
        }
    }
}

/// What building one view's layers made and cost.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ViewReport {
    /// The view's name.
    pub name: String,
    /// Visibility layers.
    pub visibility_layers: usize,
    /// Image layers (without the background).
    pub image_layers: usize,
    /// Objects the ordering replaced by their triangles.
    pub opened: usize,
    /// Newell splits.
    pub splits: usize,
    /// Items put in a layer by force (cycles left after the split budget).
    pub forced: usize,
    /// Item-buffer renders the ordering ran (first and reversed).
    pub renders: usize,
    /// Texels of the layers hidden in the photograph (what an artist fills).
    pub hidden_texels: usize,
    /// Of those, filled by push-pull.
    pub filled: usize,
    /// Texture memory.
    pub memory: Memory,
    /// Seconds: ordering.
    pub order_seconds: f64,
    /// Seconds: image layers (and fill).
    pub image_seconds: f64,
}

/// A scene's layers over all its views, ready to render.
#[derive(Clone, Debug)]
pub struct LayerSet {
    /// Object names, in scene order.
    pub names: Vec<String>,
    /// Triangle counts of the meshes as the scene gives them (before splits).
    pub source_triangles: Vec<usize>,
    /// World-space meshes, Newell splits applied.
    pub meshes: Vec<Mesh>,
    /// The views, as undistorted pinholes; their images (the photographs, undistorted) when
    /// built, absent when loaded.
    pub views: Vec<CalibratedView>,
    /// Each view's image layers.
    pub layers: Vec<ViewLayers>,
    /// Each view's layer projectors.
    pub projectors: Vec<Vec<LayerProjector>>,
    /// Newell splits, in the order they were made.
    pub splits: Vec<Split>,
    /// Each view's report.
    pub reports: Vec<ViewReport>,
}

/// Builds the layers of `views` (images loaded) for the world-space `meshes` named `names`.
pub fn build(
    meshes: Vec<Mesh>,
    names: Vec<String>,
    views: &[CalibratedView],
    settings: &BuildSettings,
    progress: &dyn Progress,
) -> Result<LayerSet, LayersError> {
    if views.is_empty() {
        return Err(LayersError::NoViews);
    }
    let source_triangles = meshes.iter().map(Mesh::triangle_count).collect();
    let mut meshes = meshes;
    let mut set_views = Vec::new();
    let mut layers: Vec<ViewLayers> = Vec::new();
    let mut splits = Vec::new();
    let mut reports = Vec::new();
    for view in views {
        let photo =
            crate::views::blend::undistorted_image(view).ok_or_else(|| LayersError::NoImage {
                view: view.name.clone(),
            })?;
        let camera = view.pinhole();
        let start = std::time::Instant::now();
        let (ordered, index) = order::order_view(&camera, &mut meshes, &settings.order)?;
        let order_seconds = start.elapsed().as_secs_f64();
        let start = std::time::Instant::now();
        for s in &ordered.splits {
            extend_assignments(&mut layers, s);
        }
        let counts: Vec<usize> = meshes.iter().map(Mesh::triangle_count).collect();
        let mut vl = image::image_layers(
            &ordered,
            &index,
            &counts,
            &photo,
            &names,
            settings.clustering,
        )?;
        vl.memory.per_triangle = per_triangle(&camera, &meshes)?;
        let hidden_texels = hidden(&vl);
        let filled = if settings.fill { fill_all(&mut vl) } else { 0 };
        let mut v = view.clone();
        v.intrinsics = view.intrinsics.undistorted();
        v.image = Some(photo);
        reports.push(ViewReport {
            name: view.name.clone(),
            visibility_layers: ordered.layers.len(),
            image_layers: vl.layers.len(),
            opened: ordered.opened.len(),
            splits: ordered.splits.len(),
            forced: ordered.forced.len(),
            renders: ordered.passes,
            hidden_texels,
            filled,
            memory: vl.memory,
            order_seconds,
            image_seconds: start.elapsed().as_secs_f64(),
        });
        splits.extend(ordered.splits);
        layers.push(vl);
        set_views.push(v);
        progress.advance(1);
    }
    let projectors = projectors(&set_views, &layers);
    Ok(LayerSet {
        names,
        source_triangles,
        meshes,
        views: set_views,
        layers,
        projectors,
        splits,
        reports,
    })
}

/// A split made in a later view: its new pieces take the layer of the triangle they came from
/// in every earlier view that assigns the object triangle by triangle.
fn extend_assignments(layers: &mut [ViewLayers], s: &Split) {
    for vl in layers {
        if let Some(Assignment::Triangles(v)) = vl.assignment.get_mut(s.object as usize) {
            let l = v.get(s.triangle as usize).copied().flatten();
            v.extend(std::iter::repeat_n(l, s.pieces.len() - 1));
        }
    }
}

/// Texture memory of per-triangle extraction through `camera`.
fn per_triangle(camera: &Pinhole, meshes: &[Mesh]) -> Result<u64, FrameError> {
    let refs: Vec<&Mesh> = meshes.iter().collect();
    let (target, _) = rasterize(camera, &refs, &NoAttributes, ())?;
    Ok(image::per_triangle_memory(&target.item))
}

/// Texels of a view's layers that its objects cover but the photograph does not show.
pub fn hidden(vl: &ViewLayers) -> usize {
    vl.layers
        .iter()
        .zip(&vl.depth)
        .map(|(l, d)| {
            l.image
                .pixels()
                .iter()
                .zip(d.pixels())
                .filter(|(c, g)| c.w < 0.5 && **g > 0.0)
                .count()
        })
        .sum()
}

/// Fills every layer of a view by push-pull; returns the texels filled.
pub fn fill_all(vl: &mut ViewLayers) -> usize {
    vl.layers
        .iter_mut()
        .zip(&vl.depth)
        .map(|(l, d)| fill::push_pull(&mut l.image, d))
        .sum()
}

/// The projectors of every view's layers.
fn projectors(views: &[CalibratedView], layers: &[ViewLayers]) -> Vec<Vec<LayerProjector>> {
    views
        .iter()
        .zip(layers)
        .map(|(v, vl)| {
            vl.layers
                .iter()
                .map(|l| LayerProjector::new(v, l.rect))
                .collect()
        })
        .collect()
}

impl LayerSet {
    /// The meshes as the rasterizer takes them.
    pub fn mesh_refs(&self) -> Vec<&Mesh> {
        self.meshes.iter().collect()
    }

    /// Fills every view's hidden texels by push-pull (in memory); returns the texels filled.
    pub fn fill(&mut self) -> usize {
        self.layers.iter_mut().map(fill_all).sum()
    }
}

/// A scene's objects at its time (`render.time`, when a capture photographs it) as the layers
/// take them: world-space meshes and names.
pub fn scene_objects(
    scene: &crate::scene::Scene,
) -> Result<(Vec<Mesh>, Vec<String>), crate::scene::ViewError> {
    let view = scene.view(scene.render.time)?;
    let meshes = view.meshes.iter().map(|m| (**m).clone()).collect();
    let names = scene.objects.iter().map(|o| o.name.clone()).collect();
    Ok((meshes, names))
}

impl std::fmt::Display for ViewReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mb = |b: u64| b as f64 / (1024.0 * 1024.0);
        write!(
            f,
            "{:<16} {:>4} {:>5} {:>6} {:>6} {:>6} {:>9} {:>8.2} {:>8.2} {:>8.2} {:>8.1}",
            self.name,
            self.visibility_layers,
            self.image_layers,
            self.opened,
            self.splits,
            self.forced,
            self.hidden_texels,
            mb(self.memory.layers),
            mb(self.memory.unclustered),
            mb(self.memory.per_triangle),
            (self.order_seconds + self.image_seconds) * 1e3
        )
    }
}

/// The header of [`ViewReport`]'s rows.
pub const REPORT_HEADER: &str = "view             vis. image opened splits forced    hidden   layers  unclust. per-tri.       ms\n                 lay. lay.                           texels       MB       MB       MB";
