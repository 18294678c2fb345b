//! Octahedral impostor workloads (the goals engines' bakers are judged by): a 16 × 16 atlas of
//! 2048² with every channel for the bunny and for the bunny subdivided once (a ~225 k-triangle
//! mesh), beside rasterizing the same 256 frames' depth alone; and 64-view turntables of the
//! Duck and the milk truck at 16 × 16 against the exact render, with and without parallax.

use super::BenchError;
use glam::Vec3;
use rayon::prelude::*;
use std::path::Path;
use std::time::{Duration, Instant};
use trompe::eval::fixtures::Shipped;
use trompe::frame::envmap::EnvMap;
use trompe::octahedral::{BakeSettings, Coverage, FrameCamera, Grid, bake, turntable};
use trompe::raster::{NoAttributes, rasterize};
use trompe::scene::{Light, Lighting, Surface};

/// One bake.
#[derive(Clone, Debug, serde::Serialize)]
pub struct BakeRow {
    /// The model.
    pub name: String,
    /// Its triangles.
    pub triangles: usize,
    /// The bake's wall time (colour, normal, depth, ORM, dilation).
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub bake: Duration,
    /// Rasterizing the 256 frames' depth alone, the peer.
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub depth_only: Duration,
}

/// One turntable.
#[derive(Clone, Debug, serde::Serialize)]
pub struct TurntableRow {
    /// The model.
    pub name: String,
    /// Mean FLIP with parallax.
    pub mean: f64,
    /// The worst view's.
    pub worst: f64,
    /// The worst view's direction: degrees of azimuth about `+y` and of elevation.
    pub worst_view: (f64, f64),
    /// Mean FLIP without parallax.
    pub flat: f64,
}

/// Every figure.
#[derive(Clone, Debug, serde::Serialize)]
pub struct OctahedralFigures {
    /// Bakes.
    pub bakes: Vec<BakeRow>,
    /// Turntables.
    pub turntables: Vec<TurntableRow>,
}

fn settings(n: u32, side: u32) -> BakeSettings {
    BakeSettings::new(
        Grid {
            n,
            coverage: Coverage::Sphere,
        },
        side / n,
    )
}

/// The figures; the milk truck is read from `../shared/data` beside the checkout when present.
pub fn octahedral(inputs: &Shipped, quick: bool) -> Result<OctahedralFigures, BenchError> {
    let bunny = trompe::geom::io::load(&inputs.assets.join("meshes/bunny.obj"))?.mesh;
    let mut bakes = Vec::new();
    for (name, mesh) in [
        ("bunny", bunny.clone()),
        ("bunny subdivided", bunny.subdivided()),
    ] {
        let s = settings(16, 2048);
        let start = Instant::now();
        let atlas = bake(&mesh, &Surface::Diffuse(None), s)?;
        let bake_time = start.elapsed();
        // The peer draws the same frames, as the bake does: frames in parallel.
        let start = Instant::now();
        (0..256u32)
            .into_par_iter()
            .map(|k| {
                match atlas.frame_camera(k % 16, k / 16) {
                    FrameCamera::Orthographic(c) => rasterize(&c, &[&mesh], &NoAttributes, ()),
                    FrameCamera::Pinhole(c) => rasterize(&c, &[&mesh], &NoAttributes, ()),
                }
                .map(|_| ())
            })
            .collect::<Result<Vec<()>, _>>()?;
        bakes.push(BakeRow {
            name: name.into(),
            triangles: mesh.triangle_count(),
            bake: bake_time,
            depth_only: start.elapsed(),
        });
    }
    let lighting = Lighting {
        environment: EnvMap::constant(Vec3::new(0.25, 0.3, 0.35)),
        light: Some(Light {
            direction: Vec3::new(0.4, 1.0, 0.6).normalize(),
            irradiance: Vec3::splat(0.9 * std::f32::consts::PI),
        }),
    };
    let truck = inputs
        .assets
        .join("../../shared/data/gltf/CesiumMilkTruck/CesiumMilkTruck.gltf");
    let mut models = vec![("Duck", inputs.assets.join("gltf/Duck.glb"))];
    if Path::new(&truck).is_file() {
        models.push(("milk truck", truck));
    }
    let views = if quick { 16 } else { 64 };
    let mut turntables = Vec::new();
    for (name, path) in models {
        let mesh = trompe::geom::io::load(&path)?.mesh;
        let atlas = bake(&mesh, &Surface::Diffuse(None), settings(16, 2048))?;
        let t = turntable(
            &atlas,
            &mesh,
            &Surface::Diffuse(None),
            &lighting,
            views,
            256,
        )?;
        let n = t.len() as f64;
        // (A turntable always holds the straight-down and straight-up views.)
        let (worst, worst_view) = t
            .iter()
            .max_by(|a, b| a.flip.total_cmp(&b.flip))
            .map_or((0.0, (0.0, 0.0)), |v| (v.flip, (v.azimuth, v.elevation)));
        turntables.push(TurntableRow {
            name: name.into(),
            mean: t.iter().map(|v| v.flip).sum::<f64>() / n,
            worst,
            worst_view,
            flat: t.iter().map(|v| v.flip_flat).sum::<f64>() / n,
        });
    }
    Ok(OctahedralFigures { bakes, turntables })
}

impl std::fmt::Display for OctahedralFigures {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "trompe bench octahedral: 16 × 16 frames, 2048² atlas, {} threads",
            rayon::current_num_threads()
        )?;
        writeln!(
            f,
            "| model | triangles | bake (colour, normal, depth, ORM, dilation) | peer: depth of the 256 frames alone | ratio |"
        )?;
        writeln!(f, "|---|---|---|---|---|")?;
        for b in &self.bakes {
            writeln!(
                f,
                "| {} | {} | {:.2} s | {:.2} s | {:.2} × |",
                b.name,
                b.triangles,
                b.bake.as_secs_f64(),
                b.depth_only.as_secs_f64(),
                b.bake.as_secs_f64() / b.depth_only.as_secs_f64().max(1e-9)
            )?;
        }
        writeln!(
            f,
            "\n| turntable (256² views + straight down and up) | mean FLIP, parallax | worst view | mean FLIP, no parallax |"
        )?;
        writeln!(f, "|---|---|---|---|")?;
        for t in &self.turntables {
            writeln!(
                f,
                "| {} | {:.4} | {:.4} (azimuth {:.0}°, elevation {:.0}°) | {:.4} |",
                t.name, t.mean, t.worst, t.worst_view.0, t.worst_view.1, t.flat
            )?;
        }
        Ok(())
    }
}
