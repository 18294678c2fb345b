//! Relief workloads (paper 3 §5–6): the pre-warp of a 256² relief impostor on one core beside a
//! copy of the same texel buffers; ray-traced impostor generation for a ~1000-triangle object
//! (the paper's 1500-polygon character: 228 ms) and the 56k-triangle bunny beside rasterizing
//! the same object's image; and a walk's frame through relief impostors beside direct
//! rasterization and beside ray tracing the frame with the software shader.

use super::{BenchError, Figure, time_pair_median, try_time_pair_median};
use glam::DVec3;
use std::time::{Duration, Instant};
use trompe::camera::Pinhole;
use trompe::relief::prewarp::{Eye, prewarp};
use trompe::relief::raster::raster_subset;
use trompe::relief::shader::SoftwareShader;
use trompe::relief::walk::true_frame;
use trompe::relief::{DepthEncoding, Displacements, PipelineSettings, ReliefImpostor};
use trompe::render::Timings;
use trompe::scene::Scene;

/// The relief impostor side every workload here uses (the paper's).
pub const SIDE: u32 = 256;

/// An eye 10° round the object from the one `impostor` was made for.
pub fn turned_eye(impostor: &ReliefImpostor) -> DVec3 {
    let c = impostor.frame.centre();
    c + glam::DQuat::from_rotation_y(10f64.to_radians()) * (impostor.eye - c)
}

/// Copies `impostor`'s texel buffers (colour and depth) into `into` (the pre-warp's peer).
pub fn copy_texels(impostor: &ReliefImpostor, into: &mut (Vec<trompe::relief::Srgba8>, Vec<u8>)) {
    into.0.copy_from_slice(&impostor.color);
    if let Displacements::U8(d) = &impostor.depth {
        into.1.copy_from_slice(d);
    }
}

/// A shader over the object `mesh` alone, lit as the raster benches light it.
pub fn lone_shader(
    mesh: &trompe::geom::Mesh,
) -> Result<std::sync::Arc<SoftwareShader>, trompe::memory::OverBudget> {
    let camera = super::framing_camera(mesh, SIDE);
    let (view, lighting) = super::raster_view(&camera, mesh);
    let settings = trompe::scene::RenderSettings {
        max_depth: 4,
        time: 0.0,
        ray_epsilon: mesh.bounds().radius() * 1e-4,
    };
    SoftwareShader::new(&view, &lighting, &settings)
}

/// The relief figures on the shipped teapot, bunny and walk scene.
pub fn relief(
    inputs: &trompe::eval::fixtures::Shipped,
    quick: bool,
) -> Result<Vec<Figure>, BenchError> {
    let min = Duration::from_millis(if quick { 200 } else { 1500 });
    let mut out = Vec::new();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|_| BenchError::Threads)?;
    let scene = Scene::load(&inputs.scenes.join("relief-walk.toml")).map_err(Box::new)?;
    let view = scene.view(scene.render.time)?;
    let shader = SoftwareShader::new(&view, &scene.lighting, &scene.render)?;
    let eye = scene.camera.position.as_dvec3();

    // The pre-warp, one core, beside a copy of the texel buffers it reads.
    let imp = shader
        .impostor(0, eye, SIDE, DepthEncoding::U8, &|| false)?
        .ok_or(trompe::relief::ReliefError::Worker("cancelled"))?;
    let target = turned_eye(&imp);
    let mut copy = (imp.color.clone(), vec![0u8; imp.color.len()]);
    for (lut, name) in [(true, "lookup tables"), (false, "direct")] {
        // Warm the caches and the clock before timing.
        one.install(|| prewarp(&imp, Eye::Point(target), lut));
        let pair = one.install(|| {
            time_pair_median(
                min,
                || prewarp(&imp, Eye::Point(target), lut),
                || copy_texels(&imp, &mut copy),
            )
        });
        out.push(
            Figure::millis(format!("relief pre-warp {SIDE}², 1 core, {name}"), pair.0)
                .versus(pair, "× a copy of its texel buffers"),
        );
    }

    // Generation by the software shader, one thread, beside rasterizing the object's image.
    let assets = &inputs.assets;
    for (file, name) in [
        ("meshes/teapot.obj", "teapot"),
        ("meshes/bunny.obj", "bunny"),
    ] {
        let mesh = trompe::geom::io::load(&assets.join(file))?.mesh;
        let lone = lone_shader(&mesh)?;
        let (c, r) = lone.bounds(0)?;
        let from = c + DVec3::new(0.3, 0.4, 1.0).normalize() * r * 4.0;
        let camera = super::framing_camera(&mesh, SIDE);
        let raster = super::raster_view(&camera, &mesh);
        let pair = one.install(|| {
            try_time_pair_median(
                min,
                || lone.impostor(0, from, SIDE, DepthEncoding::U8, &|| false),
                || super::render_raster_once(&raster),
            )
        })?;
        out.push(
            Figure::millis(
                format!(
                    "relief impostor {SIDE}² ray traced, {name} ({} tris)",
                    mesh.triangle_count()
                ),
                pair.0,
            )
            .versus(pair, "× rasterizing its image, 1 thread"),
        );
    }

    // A walk's frame: the pipeline against direct rasterization and ray tracing, per frame.
    let frames = if quick { 24 } else { 120 };
    let cameras = trompe::relief::walk::path(&scene, frames)?;
    let relief: Vec<usize> = (0..view.meshes.len()).collect();
    let mut pipeline =
        trompe::relief::Pipeline::new(shader.clone(), &relief, PipelineSettings::default())?;
    let (mut walk, mut raster, mut traced) = (Vec::new(), Vec::new(), Vec::new());
    for (_, camera) in &cameras {
        let time = |f: &mut dyn FnMut() -> Result<(), BenchError>| {
            let t = Instant::now();
            f().map(|_| t.elapsed())
        };
        walk.push(time(&mut || {
            pipeline.frame(camera).map(drop).map_err(Into::into)
        })?);
        raster.push(time(&mut || frame_raster(&shader, camera, &relief))?);
        traced.push(time(&mut || {
            true_frame(&shader, camera, &relief, &[])
                .map(drop)
                .map_err(Into::into)
        })?);
        // An interactive loop's pace: the rendering thread works between frames.
        std::thread::sleep(Duration::from_millis(4));
    }
    let median = |v: &mut Vec<Duration>| {
        v.sort();
        v[v.len() / 2]
    };
    let (w, r, t) = (median(&mut walk), median(&mut raster), median(&mut traced));
    let (fw, fh) = (scene.camera.width, scene.camera.height);
    out.push(
        Figure::millis(format!("relief walk frame {fw}×{fh}, 2 objects"), w)
            .versus((w, r), "× direct rasterization of the frame"),
    );
    out.push(
        Figure::millis(
            format!("software shader frame {fw}×{fh} (ray traced, shadows)"),
            t,
        )
        .versus((t, w), "× the relief walk frame"),
    );
    Ok(out)
}

fn frame_raster(
    shader: &SoftwareShader,
    camera: &Pinhole,
    objects: &[usize],
) -> Result<(), BenchError> {
    raster_subset(
        shader.view(),
        shader.lighting(),
        camera,
        objects,
        &mut Timings::default(),
    )
    .map(drop)
    .map_err(Into::into)
}

/// Paper 3's walk frame on the GPU: the shipped relief walk (deterministic, each eye 4° round
/// the scene from the last) by the `relief` method on each device — the CPU's pipeline (the
/// software shader's thread, the pre-warps) feeding either the library's drawing or the GPU's
/// (the objects drawn directly by its rasterizer, the impostors texture-mapped over them) —
/// beside the GPU's exact tracer on the same scene, at 1920 × 1080 (`quick`: 320 × 240). The
/// first frames, drawn before any impostor arrives, are not timed.
pub fn gpu_walk(
    gpu: &trompe_gpu::Gpu,
    inputs: &trompe::eval::fixtures::Shipped,
    quick: bool,
) -> Result<Vec<Figure>, BenchError> {
    use trompe::methods::{MethodKind, MethodSettings};
    let (w, h) = if quick { (320, 240) } else { (1920, 1080) };
    let mut scene = Scene::load(&inputs.scenes.join("relief-walk.toml")).map_err(Box::new)?;
    (scene.camera.width, scene.camera.height) = (w, h);
    let settings = MethodSettings {
        relief: PipelineSettings {
            resolution: SIDE,
            deterministic: Some(1),
            ..PipelineSettings::default()
        },
        ..MethodSettings::default()
    };
    let spec = &scene.camera;
    let centre = spec.look_at;
    let (radius, height) = {
        let r = spec.position - centre;
        (glam::Vec2::new(r.x, r.z).length(), r.y)
    };
    let frames = if quick { 12 } else { 36 };
    let walk = |device: Option<&trompe_gpu::Gpu>| -> Result<(Duration, u32), BenchError> {
        let mut renderer =
            trompe_gpu::DeviceRenderer::new(&scene, MethodKind::Relief, settings.clone(), device)?;
        let (mut total, mut timed) = (Duration::ZERO, 0u32);
        for i in 0..frames {
            let a = (i as f32 * 4.0).to_radians();
            let eye = centre + glam::Vec3::new(radius * a.sin(), height, radius * a.cos());
            let camera = Pinhole::look_at(eye, centre, spec.up, spec.fov_y, w, h)?;
            let start = Instant::now();
            let frame = renderer.frame(0.0, Some(camera), &())?;
            let took = start.elapsed();
            // Timed once an impostor is drawn (the state lines name each object's state).
            if frame.state.iter().any(|l| !l.contains("fallback")) {
                total += took;
                timed += 1;
            }
        }
        Ok((total / timed.max(1), timed))
    };
    let (cpu, _) = walk(None)?;
    let (on_gpu, timed) = walk(Some(gpu))?;
    let exact = super::gpu::exact_frame_time(gpu, &scene)?;
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let name = format!(
        "relief walk (paper 3), {w} × {h}, {timed} frames, impostors of {SIDE}²: GPU frame"
    );
    let ratio = |peer: Duration| on_gpu.as_secs_f64() / peer.as_secs_f64().max(1e-12);
    Ok(vec![
        Figure {
            name: name.clone(),
            value: ms(on_gpu),
            unit: "ms",
            versus: Some((ratio(cpu), "CPU".into())),
        },
        Figure {
            name,
            value: ms(on_gpu),
            unit: "ms",
            versus: Some((ratio(exact), "the GPU's exact tracer".into())),
        },
    ])
}
