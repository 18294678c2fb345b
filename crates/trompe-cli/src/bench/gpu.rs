//! The GPU beside the CPU in one run, on the adapter `--device gpu` opens (named in the
//! heading): every method with a GPU path on every reflection scene, what it keeps kept on each
//! device (the BVH, the uploaded scene, the impostors); the `trace` and `impostor` frames
//! against output resolution (paper 1's Table 1 axis) and the impostor frame against impostor
//! resolution (Table 2's); the impostor secondary pass — paper 1's walk of reflected rays —
//! beside the exact BVH pass on the same rays, on each device, as the reflected mesh grows 16×
//! to over a million triangles; the projective-texturing methods (calibrated views, image
//! layers, master textures) blended by the GPU beside the CPU's render of the same frame; paper
//! 2's reflection frames (its Table 2's scenes) by the `c3rc` method on each device and by the
//! GPU's exact tracer; paper 3's walk frame, its relief impostors mapped by each device; and the
//! exact ray query alone on incoherent rays.
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

/// The GPU suite's workloads, to run some alone (`trompe bench gpu --only`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum GpuWorkload {
    /// Every method with a GPU path on every reflection scene.
    Methods,
    /// The `trace` and `impostor` frames against output resolution.
    Resolution,
    /// The impostor frame against impostor resolution.
    ImpostorResolution,
    /// The impostor walk of reflected rays beside the exact BVH pass.
    Secondary,
    /// Impostors drawn by the GPU rasterizer beside the library's build.
    Builds,
    /// Calibrated views and image layers blended on each device.
    Texturing,
    /// Master textures rendered on each device.
    Master,
    /// Paper 2's reflection frames by the `c3rc` method on each device and the GPU's tracer.
    C3rc,
    /// Paper 3's walk frame: pre-warped relief impostors mapped by the GPU and by the CPU.
    Relief,
    /// The exact ray query alone on incoherent rays.
    Query,
}

/// Frames each device renders of a scene after its first.
const FRAMES: u32 = 3;

/// The mean frame time of `kind` after its first frame on the CPU and on the GPU, each keeping
/// what it keeps while nothing moves (the CPU its BVH and impostors, the GPU its uploaded scene),
/// at the scene's time through its camera.
fn method_pair(
    gpu: &Gpu,
    scene: &Scene,
    kind: MethodKind,
    settings: MethodSettings,
) -> Result<(Duration, Duration), BenchError> {
    Ok((
        frame_time(None, scene, kind, &settings)?,
        frame_time(Some(gpu), scene, kind, &settings)?,
    ))
}

/// The mean frame time of the GPU's exact tracer on `scene` after its first frame: the peer of
/// the GPU methods' frames.
pub(super) fn exact_frame_time(gpu: &Gpu, scene: &Scene) -> Result<Duration, BenchError> {
    frame_time(
        Some(gpu),
        scene,
        MethodKind::Trace,
        &MethodSettings::default(),
    )
}

/// The mean frame time of `kind` on `device` (the CPU without one) after its first frame, at
/// the scene's time through its camera.
pub(super) fn frame_time(
    device: Option<&Gpu>,
    scene: &Scene,
    kind: MethodKind,
    settings: &MethodSettings,
) -> Result<Duration, BenchError> {
    let t = scene.render.time;
    let mut renderer = DeviceRenderer::new(scene, kind, settings.clone(), device)?;
    renderer.frame(t, None, &())?;
    let start = Instant::now();
    for _ in 0..FRAMES {
        renderer.frame(t, None, &())?;
    }
    Ok(start.elapsed() / FRAMES)
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
    only: &[GpuWorkload],
) -> Result<(String, Vec<Figure>), BenchError> {
    let wants = |w: GpuWorkload| only.is_empty() || only.contains(&w);
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

    if wants(GpuWorkload::Methods) {
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
            for kind in MethodKind::ALL
                .into_iter()
                .filter(|k| trompe_gpu::has_gpu_path(*k))
            {
                let (cpu, on_gpu) = method_pair(&gpu, &scene, kind, MethodSettings::default())?;
                out.push(Figure {
                    name: format!("{kind}, {name}, {w} × {h}: GPU frame"),
                    value: ms(on_gpu),
                    unit: "ms",
                    versus: versus(on_gpu, cpu),
                });
            }
        }
    }

    let base = Scene::load(&inputs.scenes.join("teapot-in-bunny.toml")).map_err(Box::new)?;
    if wants(GpuWorkload::Resolution) {
        // Frame time against output resolution (paper 1's Table 1), teapot in the bunny.
        let sizes: &[(u32, u32)] = if quick {
            &[(160, 120), (320, 240)]
        } else {
            &[(320, 240), (640, 480), (1280, 720), (1920, 1080)]
        };
        for &(w, h) in sizes {
            let mut scene = base.clone();
            scene.camera.width = w;
            scene.camera.height = h;
            for kind in [MethodKind::Trace, MethodKind::Impostor] {
                let (cpu, on_gpu) = method_pair(&gpu, &scene, kind, MethodSettings::default())?;
                out.push(Figure {
                    name: format!("{kind}, teapot-in-bunny, {w} × {h}: GPU frame"),
                    value: ms(on_gpu),
                    unit: "ms",
                    versus: versus(on_gpu, cpu),
                });
            }
        }
    }

    if wants(GpuWorkload::ImpostorResolution) {
        // Frame time against impostor resolution (paper 1's Table 2), teapot in the bunny at
        // 640 × 480, impostors kept.
        let resolutions: &[u32] = if quick {
            &[64, 128]
        } else {
            &[128, 256, 512, 1024]
        };
        for &r in resolutions {
            let mut scene = base.clone();
            (scene.camera.width, scene.camera.height) = if quick { (160, 120) } else { (640, 480) };
            let settings = MethodSettings {
                impostor_resolution: r,
                ..MethodSettings::default()
            };
            let (cpu, on_gpu) = method_pair(&gpu, &scene, MethodKind::Impostor, settings)?;
            out.push(Figure {
                name: format!(
                    "impostor, teapot-in-bunny, {} × {}, impostors {r}²: GPU frame",
                    scene.camera.width, scene.camera.height
                ),
                value: ms(on_gpu),
                unit: "ms",
                versus: versus(on_gpu, cpu),
            });
        }
    }

    if wants(GpuWorkload::Secondary) {
        out.extend(secondary_pass(&gpu, inputs, quick)?);
    }
    if wants(GpuWorkload::Builds) {
        out.extend(impostor_builds(&gpu, inputs, quick)?);
    }
    if wants(GpuWorkload::Texturing) {
        out.extend(super::texturing::gpu_renders(&gpu, inputs, quick)?);
    }
    if wants(GpuWorkload::Master) {
        out.extend(super::master::gpu_renders(&gpu, inputs, quick)?);
    }
    if wants(GpuWorkload::C3rc) {
        out.extend(super::hybrid::gpu_frames(&gpu, inputs, quick)?);
    }
    if wants(GpuWorkload::Relief) {
        out.extend(super::relief::gpu_walk(&gpu, inputs, quick)?);
    }

    if wants(GpuWorkload::Query) {
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
            let bvh = Bvh::build(meshes)?;
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
    }

    Ok((heading, out))
}

/// Paper 1's claim on one device: the rays a mirror reflects toward an object, answered by a
/// SPOC impostor of it (the walk) and by the exact BVH (the query), on the same rays — the
/// bunny, then the bunny subdivided twice (16× the triangles); on the GPU, each beside the GPU
/// BVH pass, and on the CPU, each beside the CPU BVH pass.
fn secondary_pass(
    gpu: &Gpu,
    inputs: &trompe::eval::fixtures::Shipped,
    quick: bool,
) -> Result<Vec<Figure>, BenchError> {
    use trompe::impostor::{ImpostorCamera, ViewCamera};
    let bunny = trompe::geom::io::load(&inputs.assets.join("meshes/bunny.obj"))?.mesh;
    let rays_n = if quick { 1 << 15 } else { 1 << 18 };
    let resolution = if quick { 128 } else { 512 };
    let mut out = Vec::new();
    let mut mesh = bunny;
    for grown in [1u32, 16] {
        if grown == 16 {
            mesh = mesh.subdivided().subdivided();
        }
        let triangles = mesh.triangle_count();
        let b = mesh.bounds();
        let (centre, radius) = (b.center(), b.radius());
        // A mirror ball of a third of the bunny's radius, two and a half radii away.
        let eye = centre + Vec3::new(0.7, 0.25, 0.6).normalize() * (2.5 * radius);
        let region = radius / 3.0;
        let camera = ImpostorCamera::fitted(
            ViewCamera::Spoc(None),
            eye,
            centre,
            radius,
            f64::from(region),
            resolution,
            &mesh.positions,
        )?;
        let impostor = trompe::impostor::build(camera, &mesh, 0, &|_| Vec3::ONE)?;
        impostor.prepare_walks();
        let mut rng = trompe::geom::SplitMix64::new(23);
        let rays: Vec<Ray> = (0..rays_n)
            .map(|_| {
                let origin = eye + rng.unit_vector() * region;
                let target = centre + rng.unit_vector() * (radius * rng.next_f32().cbrt());
                Ray::new(origin, (target - origin).normalize_or(Vec3::Y))
            })
            .collect();
        let bvh = Bvh::build(vec![Arc::new(mesh.clone())])?;
        let timed = |f: &dyn Fn()| {
            let start = Instant::now();
            f();
            start.elapsed()
        };
        let cpu_bvh = timed(&|| {
            let _: Vec<_> = rays
                .par_iter()
                .map(|r| bvh.closest_hit(r, f32::INFINITY))
                .collect();
        });
        let cpu_walk = timed(&|| {
            let _: Vec<_> = rays
                .par_iter()
                .map(|r| impostor.closest_hit(r, f32::INFINITY))
                .collect();
        });
        let on_gpu = GpuBvh::upload(gpu, &bvh)?;
        let mut set = trompe_gpu::walk::WalkSet::new();
        set.push(&impostor, Mat4::IDENTITY, true)?;
        let walks = set.upload(gpu)?;
        // First passes compile the pipelines.
        on_gpu.leaf_hits(&rays[..1024], f32::INFINITY, false)?;
        walks.walk(gpu, 0, &rays[..1024], f32::INFINITY)?;
        let start = Instant::now();
        on_gpu.leaf_hits(&rays, f32::INFINITY, false)?;
        let gpu_bvh = start.elapsed();
        let start = Instant::now();
        walks.walk(gpu, 0, &rays, f32::INFINITY)?;
        let gpu_walk = start.elapsed();
        let mrays = |d: Duration| rays.len() as f64 / d.as_secs_f64().max(1e-12) / 1e6;
        let k = triangles / 1000;
        for (device, walk, exact) in [("GPU", gpu_walk, gpu_bvh), ("CPU", cpu_walk, cpu_bvh)] {
            out.push(Figure {
                name: format!(
                    "secondary pass, {} reflected rays, {k}k triangles, SPOC {resolution}²: \
                     {device} impostor walk",
                    rays.len()
                ),
                value: mrays(walk),
                unit: "Mrays/s",
                versus: Some((
                    walk.as_secs_f64() / exact.as_secs_f64().max(1e-12),
                    format!("{device} BVH (time)"),
                )),
            });
        }
    }
    Ok(out)
}

/// Paper 1 §3.1's construction on each device: a pinhole impostor of the bunny, then of the
/// bunny subdivided twice, drawn by the GPU rasterizer and resolved by the library, beside the
/// library's own build (its rasterizer and the same resolve).
fn impostor_builds(
    gpu: &Gpu,
    inputs: &trompe::eval::fixtures::Shipped,
    quick: bool,
) -> Result<Vec<Figure>, BenchError> {
    use trompe::impostor::{ImpostorCamera, ViewCamera};
    let mut mesh = trompe::geom::io::load(&inputs.assets.join("meshes/bunny.obj"))?.mesh;
    let resolution = if quick { 256 } else { 1024 };
    let mut out = Vec::new();
    for grown in [1u32, 16] {
        if grown == 16 {
            mesh = mesh.subdivided().subdivided();
        }
        let b = mesh.bounds();
        let eye = b.center() + Vec3::new(0.7, 0.25, 0.6).normalize() * (2.5 * b.radius());
        let camera = ImpostorCamera::fitted(
            ViewCamera::Pinhole,
            eye,
            b.center(),
            b.radius(),
            0.1,
            resolution,
            &mesh.positions,
        )?;
        let color = |_: &trompe::impostor::SurfaceSample| Vec3::ONE;
        let mut builder = trompe::impostor::ImpostorBuilder::new();
        // Each once first: the GPU compiles its pipeline, the builder allocates its memory.
        builder.build(camera.clone(), &mesh, 0, &color)?;
        trompe_gpu::build::build_impostor(gpu, camera.clone(), (&mesh, 0), &color)?;
        let start = Instant::now();
        builder.build(camera.clone(), &mesh, 0, &color)?;
        let cpu = start.elapsed();
        let start = Instant::now();
        trompe_gpu::build::build_impostor(gpu, camera, (&mesh, 0), &color)?;
        let on_gpu = start.elapsed();
        out.push(Figure {
            name: format!(
                "impostor build, pinhole {resolution}², {}k triangles: GPU draw + library resolve",
                mesh.triangle_count() / 1000
            ),
            value: ms(on_gpu),
            unit: "ms",
            versus: Some((
                on_gpu.as_secs_f64() / cpu.as_secs_f64().max(1e-12),
                "CPU".to_string(),
            )),
        });
    }
    Ok(out)
}
