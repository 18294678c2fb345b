//! A layer set on disk: a folder holding `layers.json` (objects, Newell splits, and per view
//! its layers' names, visibility layers, objects and the object-to-layer assignment), the
//! views' calibration as a COLMAP text model (`cameras.txt`, `images.txt`: undistorted
//! pinholes) and one OpenRaster file a view holding its image layers, front on top, and the
//! background at the bottom (docs/conventions.md §9.5).
//!
//! Invariants: layers are matched by name, so an artist may repaint, resize or move a layer in
//! GIMP or Krita and its placement (offset and size, read from the file) still holds; what is
//! derived from geometry — each layer's depth — is recomputed on load, never trusted from disk;
//! a loaded set is checked against the scene's objects (names and triangle counts) and every
//! disagreement is an error that names the file and the element.

use super::image::{Assignment, ImageLayer, Memory, Rect, ViewLayers};
use super::ora::{self, Ora, OraLayer};
use super::split::{self, Split};
use super::{LayerSet, LayersError, ViewReport};
use crate::frame::{Image, Rgba};
use crate::geom::Mesh;
use crate::raster::fragments;
use glam::Vec4;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The project file's name in its folder.
pub const PROJECT: &str = "layers.json";
/// Its format tag.
pub const FORMAT: &str = "trompe-layers/1";
/// The name of the bottom layer of every view's file.
pub const BACKGROUND: &str = "background";

#[derive(Serialize, Deserialize)]
struct Project {
    format: String,
    objects: Vec<ObjectEntry>,
    splits: Vec<Split>,
    views: Vec<ViewEntry>,
}

#[derive(Serialize, Deserialize)]
struct ObjectEntry {
    name: String,
    triangles: usize,
}

#[derive(Serialize, Deserialize)]
struct ViewEntry {
    name: String,
    file: String,
    layers: Vec<LayerEntry>,
    assignment: Vec<Assignment>,
    report: ViewReport,
}

#[derive(Serialize, Deserialize)]
struct LayerEntry {
    name: String,
    visibility: u32,
    objects: Vec<u32>,
}

/// The OpenRaster file name of a view: its image name's stem, `.ora`.
pub fn ora_name(view: &str) -> String {
    let stem = Path::new(view)
        .file_stem()
        .map_or_else(|| view.to_string(), |s| s.to_string_lossy().into_owned());
    let safe: String = stem
        .chars()
        .map(|c| {
            if c.is_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("{safe}.ora")
}

/// Writes `set` into folder `dir` (created if needed), published whole: `dir` holds the earlier
/// layer set until the new one replaces it in one step.
pub fn save(dir: &Path, set: &LayerSet) -> Result<(), LayersError> {
    let staged = crate::files::StagedFolder::begin(dir, crate::files::FolderKind::LayerSet)?;
    save_into(staged.path(), set)?;
    Ok(staged.publish()?)
}

fn save_into(dir: &Path, set: &LayerSet) -> Result<(), LayersError> {
    let mut views = Vec::new();
    for ((v, vl), report) in set.views.iter().zip(&set.layers).zip(&set.reports) {
        let file = ora_name(&v.name);
        let (w, h) = v.intrinsics.size();
        let mut layers: Vec<OraLayer> = vl
            .layers
            .iter()
            .map(|l| OraLayer {
                name: l.name.clone(),
                x: l.rect.x as i32,
                y: l.rect.y as i32,
                image: l.image.clone(),
                visible: true,
            })
            .collect();
        layers.push(OraLayer {
            name: BACKGROUND.into(),
            x: 0,
            y: 0,
            image: vl.background.clone(),
            visible: true,
        });
        ora::write(
            &dir.join(&file),
            &Ora {
                width: w,
                height: h,
                layers,
            },
        )?;
        views.push(ViewEntry {
            name: v.name.clone(),
            file,
            layers: vl
                .layers
                .iter()
                .map(|l| LayerEntry {
                    name: l.name.clone(),
                    visibility: l.visibility,
                    objects: l.objects.clone(),
                })
                .collect(),
            assignment: vl.assignment.clone(),
            report: report.clone(),
        });
    }
    let mut model_views = set.views.clone();
    for v in &mut model_views {
        v.image = None;
    }
    crate::views::colmap::write_text(dir, &model_views)?;
    let project = Project {
        format: FORMAT.into(),
        objects: set
            .names
            .iter()
            .zip(&set.source_triangles)
            .map(|(n, &t)| ObjectEntry {
                name: n.clone(),
                triangles: t,
            })
            .collect(),
        splits: set.splits.clone(),
        views,
    };
    let path = dir.join(PROJECT);
    let json = serde_json::to_vec_pretty(&project).map_err(|e| LayersError::Project {
        path: path.clone(),
        element: "project".into(),
        reason: e.to_string(),
    })?;
    crate::files::write_atomically(&path, &json).map_err(|source| LayersError::Io { path, source })
}

/// Loads the layer set in `dir` for the world-space `meshes` named `names` (the scene it was
/// built from).
pub fn load(dir: &Path, meshes: Vec<Mesh>, names: Vec<String>) -> Result<LayerSet, LayersError> {
    let path = dir.join(PROJECT);
    let bad = |element: String, reason: String| LayersError::Project {
        path: path.clone(),
        element,
        reason,
    };
    let meta = std::fs::metadata(&path).map_err(|source| LayersError::Io {
        path: path.clone(),
        source,
    })?;
    crate::memory::check(
        || format!("{}", path.display()),
        meta.len().saturating_mul(8),
    )
    .map_err(|e| bad("file".into(), e.to_string()))?;
    let text = std::fs::read(&path).map_err(|source| LayersError::Io {
        path: path.clone(),
        source,
    })?;
    let project: Project =
        serde_json::from_slice(&text).map_err(|e| bad("project".into(), e.to_string()))?;
    if project.format != FORMAT {
        return Err(bad(
            "format".into(),
            format!("{:?}, expected {FORMAT:?}", project.format),
        ));
    }
    if project.objects.len() != meshes.len() {
        return Err(bad(
            "objects".into(),
            format!(
                "built for {} objects, the scene has {}",
                project.objects.len(),
                meshes.len()
            ),
        ));
    }
    for (i, (o, m)) in project.objects.iter().zip(&meshes).enumerate() {
        if o.name != names[i] || o.triangles != m.triangle_count() {
            return Err(bad(
                format!("object {i}"),
                format!(
                    "built for {:?} ({} triangles), the scene has {:?} ({} triangles)",
                    o.name,
                    o.triangles,
                    names[i],
                    m.triangle_count()
                ),
            ));
        }
    }
    let source_triangles = meshes.iter().map(Mesh::triangle_count).collect();
    let mut meshes = meshes;
    for (k, s) in project.splits.iter().enumerate() {
        meshes
            .get_mut(s.object as usize)
            .and_then(|m| split::replay(m, s))
            .ok_or_else(|| {
                bad(
                    format!("split {k}"),
                    "does not replay on the scene's mesh".into(),
                )
            })?;
    }
    let (model, _) = crate::views::colmap::read_model(dir)?;
    let mut views = Vec::new();
    let mut layers = Vec::new();
    let mut reports = Vec::new();
    for entry in &project.views {
        let view = model
            .iter()
            .find(|v| v.name == entry.name)
            .ok_or_else(|| {
                bad(
                    format!("view {}", entry.name),
                    "not in the COLMAP model".into(),
                )
            })?
            .clone();
        let vl = load_view(dir, entry, &view, &meshes, &bad)?;
        views.push(view);
        layers.push(vl);
        reports.push(entry.report.clone());
    }
    let projectors = super::projectors(&views, &layers);
    Ok(LayerSet {
        names,
        source_triangles,
        meshes,
        views,
        layers,
        projectors,
        splits: project.splits,
        reports,
    })
}

/// One view's layers from its OpenRaster file, their depth recomputed from the meshes.
fn load_view(
    dir: &Path,
    entry: &ViewEntry,
    view: &crate::views::CalibratedView,
    meshes: &[Mesh],
    bad: &dyn Fn(String, String) -> LayersError,
) -> Result<ViewLayers, LayersError> {
    let file = dir.join(&entry.file);
    let ora = ora::read(&file)?;
    let size = view.intrinsics.size();
    if (ora.width, ora.height) != size {
        return Err(bad(
            format!("view {}", entry.name),
            format!(
                "{} is {} × {}, the camera {} × {}",
                entry.file, ora.width, ora.height, size.0, size.1
            ),
        ));
    }
    if entry.assignment.len() != meshes.len() {
        return Err(bad(
            format!("view {}", entry.name),
            "the assignment does not list every object".into(),
        ));
    }
    let mut out = Vec::new();
    for l in &entry.layers {
        let found = ora
            .layers
            .iter()
            .find(|o| o.name == l.name)
            .ok_or_else(|| {
                bad(
                    format!("view {}, layer {:?}", entry.name, l.name),
                    format!("not in {}", entry.file),
                )
            })?;
        let (rect, image) = on_canvas(found, size);
        out.push(ImageLayer {
            name: l.name.clone(),
            visibility: l.visibility,
            rect,
            objects: l.objects.clone(),
            image,
        });
    }
    for a in &entry.assignment {
        let ok = match a {
            Assignment::Unseen => true,
            Assignment::Whole(l) => (*l as usize) < out.len(),
            Assignment::Triangles(v) => v.iter().flatten().all(|&l| (l as usize) < out.len()),
        };
        if !ok {
            return Err(bad(
                format!("view {}", entry.name),
                "the assignment names a layer that does not exist".into(),
            ));
        }
    }
    let background = ora
        .layers
        .iter()
        .find(|o| o.name == BACKGROUND)
        .map(|o| on_canvas(o, size).1)
        .unwrap_or(Image::new(size.0, size.1, Vec4::ZERO)?);
    let depth = layer_depth(view, meshes, &out, &entry.assignment)?;
    let memory = Memory {
        layers: out.iter().map(|l| l.rect.p2_area() * 4).sum(),
        ..entry.report.memory
    };
    Ok(ViewLayers {
        layers: out,
        background,
        depth,
        assignment: entry.assignment.clone(),
        memory,
    })
}

/// A layer cropped to the canvas: its rectangle there and its texels (placement kept).
fn on_canvas(layer: &OraLayer, (w, h): (u32, u32)) -> (Rect, Image<Rgba>) {
    let (lw, lh) = layer.image.size();
    let x0 = layer.x.max(0) as u32;
    let y0 = layer.y.max(0) as u32;
    let x1 = (layer.x as i64 + lw as i64).min(w as i64) as u32;
    let y1 = (layer.y as i64 + lh as i64).min(h as i64) as u32;
    let rect = Rect {
        x: x0,
        y: y0,
        w: x1.saturating_sub(x0).max(1),
        h: y1.saturating_sub(y0).max(1),
    };
    if (layer.x, layer.y) == (x0 as i32, y0 as i32) && (lw, lh) == (rect.w, rect.h) {
        return (rect, layer.image.clone());
    }
    let (dx, dy) = (
        (x0 as i64 - layer.x as i64) as u32,
        (y0 as i64 - layer.y as i64) as u32,
    );
    let mut img = Image::new(rect.w, rect.h, Vec4::ZERO).unwrap_or_else(|_| layer.image.clone());
    if img.size() == (rect.w, rect.h) {
        for y in 0..rect.h {
            for x in 0..rect.w {
                if x + dx < lw && y + dy < lh {
                    img.set(x, y, layer.image.get(x + dx, y + dy));
                }
            }
        }
    }
    (rect, img)
}

/// Each layer's depth: the nearest `gd` of the triangles assigned to it, over its rectangle.
fn layer_depth(
    view: &crate::views::CalibratedView,
    meshes: &[Mesh],
    layers: &[ImageLayer],
    assignment: &[Assignment],
) -> Result<Vec<Image<f32>>, LayersError> {
    let camera = view.pinhole();
    let refs: Vec<&Mesh> = meshes.iter().collect();
    let bands = fragments(&camera, &refs)?;
    let w = view.intrinsics.size().0;
    let mut depth: Vec<Image<f32>> = layers
        .iter()
        .map(|l| Image::new(l.rect.w, l.rect.h, 0.0f32))
        .collect::<Result<_, _>>()?;
    for c in bands.iter().flatten() {
        let Some(l) = assignment
            .get(c.item.object as usize)
            .and_then(|a| a.layer(c.item.triangle as usize))
        else {
            continue;
        };
        let r = layers[l as usize].rect;
        let (x, y) = (c.pixel % w, c.pixel / w);
        if r.contains(x, y) {
            let d = &mut depth[l as usize];
            if c.gd > d.get(x - r.x, y - r.y) {
                d.set(x - r.x, y - r.y, c.gd);
            }
        }
    }
    Ok(depth)
}

/// The set's views with their photographs: each view's OpenRaster file composited (as an
/// artist left it), for plain projective texturing.
pub fn photographs(
    dir: &Path,
    set: &LayerSet,
) -> Result<Vec<crate::views::CalibratedView>, LayersError> {
    set.views
        .iter()
        .map(|v| {
            let mut v = v.clone();
            let ora = ora::read(&dir.join(ora_name(&v.name)))?;
            v.image = Some(ora.composite()?);
            Ok(v)
        })
        .collect()
}
