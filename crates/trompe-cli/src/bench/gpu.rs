//! The GPU beside the CPU in one run, on the adapter `--device gpu` opens (named in the
//! heading): the `trace` and `raster` methods' frames on every reflection scene, the scene kept on each
//! device (the CPU keeps its BVH, the GPU its uploaded scene); that frame against output
//! resolution (paper 1's Table 1 axis); and the exact ray query alone — the same incoherent
//! rays through the CPU BVH and its GPU walk — as the mesh grows 16×.
//!
//! Without a hardware GPU the adapter is Mesa's lavapipe, which runs the shaders on the CPU's
//! cores: its figures say what the shaders cost there, not what a GPU does.

use super::{BenchError, Figure};
use glam::{Mat4, Vec3};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::{Duration, Instant};
use trompe::geom::{Mesh, Ray};
use trompe::methods::{MethodKind, MethodSettings};
use trompe::scene::Scene;
use trompe::trace::{Bvh, RayQuery};
use trompe_gpu::{DeviceRenderer, Gpu, GpuBvh};

/// Frames each device renders of a scene after its first.
const FRAMES: u32 = 3;

/// The mean frame time of `kind` after its first frame on the CPU and on the GPU, each keeping
/// what it keeps while nothing moves (the CPU its BVH, the GPU its uploaded scene), at the
/// scene's time through its camera.
fn method_pair(
    gpu: &Gpu,
    scene: &Scene,
    kind: MethodKind,
) -> Result<(Duration, Duration), BenchError> {
    let t = scene.render.time;
    let time = |device: Option<&Gpu>| -> Result<Duration, BenchError> {
        let mut renderer = DeviceRenderer::new(scene, kind, MethodSettings::default(), device)?;
        renderer.frame(t, None, &())?;
        let start = Instant::now();
        for _ in 0..FRAMES {
            renderer.frame(t, None, &())?;
        }
        Ok(start.elapsed() / FRAMES)
    };
    Ok((time(None)?, time(Some(gpu))?))
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// `n` incoherent rays from the box `(lo, hi)` grown by a quarter on each side toward points
/// inside it.
fn incoherent_rays(n: usize, lo: Vec3, hi: Vec3) -> Vec<Ray> {
    let mut rng = trompe::geom::SplitMix64::new(17);
    let size = hi - lo;
    let mut point = |grow: f32| {
        let s = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        lo - size * grow + size * (1.0 + 2.0 * grow) * s
    };
    (0..n)
        .map(|_| {
            let (from, to) = (point(0.25), point(0.0));
            Ray::new(from, (to - from).normalize_or(Vec3::Y))
        })
        .collect()
}

/// The GPU figures (see the module's text); `quick` keeps every size small.
pub fn gpu(
    inputs: &trompe::eval::fixtures::Shipped,
    quick: bool,
) -> Result<(String, Vec<Figure>), BenchError> {
    let gpu = trompe_gpu::GpuRequest::new().open()?;
    let adapter = gpu.report();
    let heading = format!(
        "trompe bench gpu on {} ({}, {}{}), beside {} CPU threads",
        adapter.name,
        adapter.backend,
        adapter.kind,
        if adapter.software { ", software" } else { "" },
        rayon::current_num_threads()
    );
    let versus = |gpu: Duration, cpu: Duration| {
        Some((
            gpu.as_secs_f64() / cpu.as_secs_f64().max(1e-12),
            "CPU".to_string(),
        ))
    };
    let mut out = Vec::new();

    // The trace method on every reflection scene.
    let (w, h) = if quick { (160, 120) } else { (320, 240) };
    for name in [
        "teapot-in-bunny",
        "intersecting",
        "reflections",
        "room",
        "teapots",
    ] {
        let mut scene =
            Scene::load(&inputs.scenes.join(format!("{name}.toml"))).map_err(Box::new)?;
        scene.camera.width = w;
        scene.camera.height = h;
        for kind in [MethodKind::Trace, MethodKind::Raster] {
            let (cpu, on_gpu) = method_pair(&gpu, &scene, kind)?;
            out.push(Figure {
                name: format!("{kind}, {name}, {w} × {h}: GPU frame"),
                value: ms(on_gpu),
                unit: "ms",
                versus: versus(on_gpu, cpu),
            });
        }
    }

    // Frame time against output resolution (paper 1's Table 1), teapot in the bunny.
    let sizes: &[(u32, u32)] = if quick {
        &[(160, 120), (320, 240)]
    } else {
        &[(320, 240), (640, 480), (1280, 720), (1920, 1080)]
    };
    let base = Scene::load(&inputs.scenes.join("teapot-in-bunny.toml")).map_err(Box::new)?;
    for &(w, h) in sizes {
        let mut scene = base.clone();
        scene.camera.width = w;
        scene.camera.height = h;
        let (cpu, on_gpu) = method_pair(&gpu, &scene, MethodKind::Trace)?;
        out.push(Figure {
            name: format!("trace, teapot-in-bunny, {w} × {h}: GPU frame"),
            value: ms(on_gpu),
            unit: "ms",
            versus: versus(on_gpu, cpu),
        });
    }

    // The exact ray query alone: the same rays through the CPU BVH and its GPU walk, the bunny
    // then 16 of them.
    let bunny = trompe::geom::io::load(&inputs.assets.join("meshes/bunny.obj"))?.mesh;
    let rays_n = if quick { 1 << 15 } else { 1 << 18 };
    for copies in [1u32, 16] {
        let meshes: Vec<Arc<Mesh>> = (0..copies)
            .map(|i| {
                let at = Vec3::new((i % 4) as f32, 0.0, (i / 4) as f32) * 0.8;
                Arc::new(bunny.transformed(&Mat4::from_translation(at)))
            })
            .collect();
        let triangles: usize = meshes.iter().map(|m| m.triangle_count()).sum();
        let (lo, hi) = meshes.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), m| {
            let b = m.bounds();
            (lo.min(b.min), hi.max(b.max))
        });
        let bvh = Bvh::build(meshes);
        let rays = incoherent_rays(rays_n, lo, hi);
        let start = Instant::now();
        let hits: Vec<_> = rays
            .par_iter()
            .map(|r| bvh.closest_hit(r, f32::INFINITY))
            .collect();
        let cpu = start.elapsed();
        drop(hits);
        let on_gpu = GpuBvh::upload(&gpu, &bvh)?;
        on_gpu.leaf_hits(&rays[..1024.min(rays.len())], f32::INFINITY, false)?;
        let start = Instant::now();
        on_gpu.leaf_hits(&rays, f32::INFINITY, false)?;
        let gpu_time = start.elapsed();
        let mrays = |d: Duration| rays.len() as f64 / d.as_secs_f64().max(1e-12) / 1e6;
        out.push(Figure {
            name: format!(
                "BVH, {} incoherent rays, {}k triangles: GPU",
                rays.len(),
                triangles / 1000
            ),
            value: mrays(gpu_time),
            unit: "Mrays/s",
            versus: Some((mrays(gpu_time) / mrays(cpu), "CPU".to_string())),
        });
    }
    Ok((heading, out))
}
