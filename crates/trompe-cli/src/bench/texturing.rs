//! The projective-texturing methods on each device (papers 4 and 5, and calibrated views): the
//! same frame rendered by the library on the CPU and by the GPU's compute blend from sources
//! uploaded once — calibrated views with depth maps and image layers of
//! `scenes/street-100k.toml` seen from a ring of views with gradient images, and master
//! textures of the teapot from a sphere of views ([`super::master::gpu_renders`]).

use super::layers::ring_views;
use super::{BenchError, Figure};
use std::time::{Duration, Instant};
use trompe::layers::{self, BuildSettings};
use trompe::scene::Scene;
use trompe::texturing::{Blend, BlendSettings};
use trompe::views::visibility::DepthMap;
use trompe_gpu::Gpu;

/// Frames each device renders after its first.
const FRAMES: u32 = 3;

/// The mean time of `FRAMES` frames of `frame` after one (which compiles the GPU's pipeline).
fn mean_frame(frame: &dyn Fn() -> Result<Blend, BenchError>) -> Result<Duration, BenchError> {
    frame()?;
    let start = Instant::now();
    for _ in 0..FRAMES {
        std::hint::black_box(frame()?);
    }
    Ok(start.elapsed() / FRAMES)
}

/// The views and layers figures: `scenes/street-100k.toml` from 4 views of 720 × 576 (2 when
/// `quick`), rendered through its camera at 1920 × 1080 (640 × 360 when `quick`), ULR.
pub fn gpu_renders(
    gpu: &Gpu,
    inputs: &trompe::eval::fixtures::Shipped,
    quick: bool,
) -> Result<Vec<Figure>, BenchError> {
    let mut scene = Scene::load(&inputs.scenes.join("street-100k.toml")).map_err(Box::new)?;
    (scene.camera.width, scene.camera.height) = if quick { (640, 360) } else { (1920, 1080) };
    let camera = scene.camera.at(scene.render.time)?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let count = if quick { 2 } else { 4 };
    let views = ring_views(&scene, count, (720, 576))?;
    let (meshes, names) = layers::scene_objects(&scene)?;
    let mut mesh = trompe::geom::Mesh::default();
    meshes.iter().for_each(|m| mesh.append(m));
    let triangles = mesh.triangle_count();
    let settings = BlendSettings::default();
    let mut out = Vec::new();

    let depth = DepthMap::of_all(&views, &mesh)?;
    let cpu = mean_frame(&|| {
        Ok(trompe::views::blend::render(
            &camera, &mesh, &views, &depth, &settings, None,
        )?)
    })?;
    let uploaded = trompe_gpu::views::GpuViews::new(gpu, &mesh, (&views, &depth), &settings, None)?;
    let on_gpu = mean_frame(&|| Ok(uploaded.render(&camera)?))?;
    out.push(
        Figure::millis(
            format!(
                "views render, ulr, street-100k ({triangles} triangles), {count} views 720×576, \
                 {w}×{h}: GPU frame (with read-back)"
            ),
            on_gpu,
        )
        .versus((on_gpu, cpu), "CPU"),
    );

    let set =
        layers::build(meshes, names, &views, &BuildSettings::default(), &()).map_err(Box::new)?;
    let cpu = mean_frame(&|| Ok(trompe::layers::render::render(&camera, &set, &settings)?))?;
    let uploaded = trompe_gpu::layers::GpuLayers::new(gpu, &set, &settings)?;
    let on_gpu = mean_frame(&|| Ok(uploaded.render(&camera)?))?;
    let image_layers: usize = set.reports.iter().map(|r| r.image_layers).sum();
    out.push(
        Figure::millis(
            format!(
                "layers render, ulr, street-100k, {count} views 720×576 ({image_layers} image \
                 layers), {w}×{h}: GPU frame (with read-back)"
            ),
            on_gpu,
        )
        .versus((on_gpu, cpu), "CPU"),
    );
    Ok(out)
}
