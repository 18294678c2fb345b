//! Layered projective texture workloads (paper 4 §6: two 2160 × 1440 photographs of a street
//! model, "under three minutes" for its layers): building the visibility and image layers of a
//! 100k-triangle scene from two views, beside drawing the same views' depth and item buffers
//! alone.

use super::master::gradient;
use super::{BenchError, Figure};
use glam::DVec3;
use std::time::Instant;
use trompe::layers::{self, BuildSettings};
use trompe::raster::{NoAttributes, rasterize};
use trompe::scene::Scene;
use trompe::views::capture::{CaptureSettings, bounding_sphere, rig_centres};
use trompe::views::{CalibratedView, Intrinsics, Pose};

/// `count` views of `w × h` on the ring around `scene`'s objects, each with a gradient image.
pub fn ring_views(
    scene: &Scene,
    count: usize,
    (w, h): (u32, u32),
) -> Result<Vec<CalibratedView>, BenchError> {
    let settings = CaptureSettings {
        count,
        size: (w, h),
        distance: 1.4,
        fov_y: 50.0,
        ..CaptureSettings::default()
    };
    let Some((centre, radius)) = bounding_sphere(scene) else {
        return Ok(Vec::new());
    };
    let f = h as f64 * 0.5 / (settings.fov_y.to_radians() * 0.5).tan();
    let image = gradient(w, h)?;
    Ok(rig_centres(&settings, centre, radius)
        .into_iter()
        .enumerate()
        .filter_map(|(i, c)| {
            Some(CalibratedView {
                name: format!("view{i:04}.png"),
                image_id: i as u32 + 1,
                camera_id: 1,
                intrinsics: Intrinsics::pinhole(w, h, f, f, w as f64 * 0.5, h as f64 * 0.5),
                pose: Pose::looking_at(c, centre, DVec3::Y)?,
                image: Some(image.clone()),
            })
        })
        .collect())
}

/// The layers figures: `scenes/street-100k.toml` from two views, at 640 × 480 and at the
/// paper's 2160 × 1440.
pub fn layers(
    inputs: &trompe::eval::fixtures::Shipped,
    quick: bool,
) -> Result<Vec<Figure>, BenchError> {
    let scene = Scene::load(&inputs.scenes.join("street-100k.toml")).map_err(Box::new)?;
    let (meshes, names) = layers::scene_objects(&scene)?;
    let triangles: usize = meshes.iter().map(|m| m.triangle_count()).sum();
    let sizes: &[(u32, u32)] = if quick {
        &[(640, 480)]
    } else {
        &[(640, 480), (2160, 1440)]
    };
    let mut out = Vec::new();
    for &size in sizes {
        let views = ring_views(&scene, 2, size)?;
        let runs = if quick { 1 } else { 3 };
        let mut build = Vec::new();
        let mut set = None;
        for _ in 0..runs {
            let t = Instant::now();
            let s = layers::build(
                meshes.clone(),
                names.clone(),
                &views,
                &BuildSettings::default(),
                &(),
            )
            .map_err(Box::new)?;
            build.push(t.elapsed());
            set = Some(s);
        }
        let mut raster = Vec::new();
        let refs: Vec<&trompe::geom::Mesh> = meshes.iter().collect();
        for _ in 0..runs {
            let t = Instant::now();
            for v in &views {
                std::hint::black_box(rasterize(&v.pinhole(), &refs, &NoAttributes, ())?);
            }
            raster.push(t.elapsed());
        }
        build.sort();
        raster.sort();
        let (b, r) = (build[runs / 2], raster[runs / 2]);
        let (vis, img): (usize, usize) = set.as_ref().map_or((0, 0), |s| {
            (
                s.reports.iter().map(|r| r.visibility_layers).sum(),
                s.reports.iter().map(|r| r.image_layers).sum(),
            )
        });
        out.push(
            Figure::millis(
                format!(
                    "layers, street-100k ({triangles} triangles), 2 views {}×{}: {vis} visibility, {img} image layers",
                    size.0, size.1
                ),
                b,
            )
            .versus((b, r), "× drawing the views' depth and item buffers alone"),
        );
    }
    Ok(out)
}
