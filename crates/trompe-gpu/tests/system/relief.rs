//! Paper 3's `relief` method on the GPU against its CPU twin: the library's pipeline prepares
//! each frame (pre-warps on the CPU), and the GPU's texture mapping must draw what the library's
//! draws; uploads are double-buffered and never show a stale or half-written pre-warp.

use glam::{DVec3, Vec3, Vec4};
use std::path::Path;
use std::sync::Arc;
use trompe::camera::Pinhole;
use trompe::frame::Frame;
use trompe::relief::prewarp::flag;
use trompe::relief::shader::SoftwareShader;
use trompe::relief::{Pipeline, PipelineSettings, Prewarped, ReliefDraw, ReliefFrame};
use trompe::scene::Scene;
use trompe_gpu::Gpu;
use trompe_gpu::relief::ReliefMapper;

fn walk_scene() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/relief-walk.toml");
    let mut scene = Scene::load(&path).expect("the shipped relief scene");
    scene.camera.width = 320;
    scene.camera.height = 240;
    scene
}

/// The library's texture mapping of `draws` over `background`, on the CPU.
fn mapped_on_the_cpu(background: &Frame, draws: &[ReliefDraw], camera: &Pinhole) -> Frame {
    let mut frame = background.clone();
    for d in draws {
        trompe::relief::texture::draw(&d.image, &d.frame, camera, &mut frame, d.object);
    }
    frame
}

/// A walk around the shipped relief scene (deterministic mode, impostors regenerated along the
/// way, each eye held two frames): every frame's impostors mapped by the GPU against the
/// library's mapping of the same prepared frame — object ids equal on ≥ 99.9 % of pixels, mean
/// FLIP ≤ 0.01 — and a pre-warp uploaded only when the frame loop made a new one.
pub fn relief_frames_on_the_gpu_are_the_cpus(gpu: &Gpu) {
    let scene = walk_scene();
    let view = scene.view(0.0).unwrap();
    let shader = SoftwareShader::new(&view, &scene.lighting, &scene.render).unwrap();
    let settings = PipelineSettings {
        resolution: 128,
        first_resolution: Some(32),
        deterministic: Some(1),
        ..Default::default()
    };
    let mut pipeline = Pipeline::new(shader, &[0, 1], settings).unwrap();
    let mut mapper = ReliefMapper::new(gpu);
    let spec = &scene.camera;
    let centre = Vec3::new(0.0, 0.3, 0.0);
    let (mut drawn, mut uploads, mut prewarps) = (0, 0, 0);
    let mut last: Vec<Arc<Prewarped>> = Vec::new();
    let mut stood = 0;
    for i in 0..20 {
        // Each eye held for two frames: the second keeps its pre-warps (Schaufler's test).
        let a = ((i / 2) as f32 * 4.0).to_radians();
        let eye = centre + Vec3::new(6.5 * a.sin(), 1.2, 6.5 * a.cos());
        let camera =
            Pinhole::look_at(eye, centre, spec.up, spec.fov_y, spec.width, spec.height).unwrap();
        let prepared = pipeline.prepare(&camera).unwrap();
        let cpu = mapped_on_the_cpu(&prepared.background, &prepared.draws, &camera);
        let on_gpu = mapper
            .map(&prepared.background, &prepared.draws, &camera)
            .unwrap();
        let (ids, flip) = crate::agreement(&cpu, &on_gpu.frame);
        let relief_pixels = (cpu.object_id.pixels().iter())
            .filter(|&&id| prepared.draws.iter().any(|d| d.object == id))
            .count();
        println!(
            "frame {i}: {} impostors, {} uploaded; ids {:.3} % equal, mean FLIP {flip:.5}, \
             {relief_pixels} pixels of relief",
            prepared.draws.len(),
            on_gpu.uploads,
            100.0 * ids
        );
        assert!(ids >= 0.999, "frame {i}: ids {ids}");
        assert!(flip <= 0.01, "frame {i}: FLIP {flip}");
        // An upload for every pre-warp the frame loop made anew, and none for one that stood.
        let fresh = prepared
            .draws
            .iter()
            .filter(|d| !last.iter().any(|l| Arc::ptr_eq(l, &d.image)))
            .count();
        assert_eq!(on_gpu.uploads, fresh, "frame {i}");
        last = prepared.draws.iter().map(|d| d.image.clone()).collect();
        stood += usize::from(!prepared.draws.is_empty() && on_gpu.uploads == 0);
        drawn += relief_pixels;
        uploads += on_gpu.uploads;
        prewarps += prepared.draws.len();
    }
    println!(
        "{drawn} relief pixels, {uploads} uploads for {prewarps} impostors drawn, {stood} frames \
         uploading nothing"
    );
    assert!(drawn > 16 * 500, "the impostors drew {drawn} pixels");
    assert!(stood >= 5, "{stood} frames kept every pre-warp");
}

/// A frame where no impostor changes draws identically twice, uploading nothing the second time.
pub fn a_relief_frame_where_no_impostor_changes_draws_identically_twice(gpu: &Gpu) {
    let (camera, background) = flat_scene();
    let draw = square(Vec3::new(0.8, 0.3, 0.1), 0.0);
    let mut mapper = ReliefMapper::new(gpu);
    let first = mapper
        .map(&background, std::slice::from_ref(&draw), &camera)
        .unwrap();
    let second = mapper
        .map(&background, std::slice::from_ref(&draw), &camera)
        .unwrap();
    assert_eq!((first.uploads, second.uploads), (1, 0));
    assert!(first.frame.color.pixels() == second.frame.color.pixels());
    assert!(first.frame.depth.pixels() == second.frame.depth.pixels());
    assert!(first.frame.object_id.pixels() == second.frame.object_id.pixels());
}

/// New pre-warps of one object, each a flat colour, uploaded frame after frame (and one of
/// another size): every frame shows the pre-warp it was given over every pixel the impostor
/// covers — none of the previous one, none of a texture being written. Reading the pair being
/// written, or the pair before the swap, fails it.
pub fn a_new_pre_warp_is_never_drawn_half_written(gpu: &Gpu) {
    let (camera, background) = flat_scene();
    let mut mapper = ReliefMapper::new(gpu);
    let colours = [
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
    ];
    let mut covered = None;
    for i in 0..24 {
        let colour = colours[i % 3];
        // Every fifth frame, a pre-warp of another size (a pair made anew).
        let margin = if i % 5 == 4 { 3 } else { 0 };
        let draw = square(colour, f64::from(margin));
        let mapped = mapper
            .map(&background, std::slice::from_ref(&draw), &camera)
            .unwrap();
        assert_eq!(mapped.uploads, 1, "frame {i}");
        let mut drawn = 0;
        for (c, id) in mapped
            .frame
            .color
            .pixels()
            .iter()
            .zip(mapped.frame.object_id.pixels())
        {
            if *id == draw.object {
                drawn += 1;
                let apart = (c.truncate() - colour).abs().max_element();
                assert!(apart < 1e-3, "frame {i}: {c} where {colour} was uploaded");
            }
        }
        assert!(drawn > 1000, "frame {i}: {drawn} pixels");
        if margin == 0 {
            assert_eq!(*covered.get_or_insert(drawn), drawn, "frame {i}");
        }
    }
}

/// A 160 × 120 camera looking down −z at the origin from z = 4, and an empty background.
fn flat_scene() -> (Pinhole, Frame) {
    let camera = Pinhole::look_at(
        Vec3::new(0.0, 0.0, 4.0),
        Vec3::ZERO,
        Vec3::Y,
        40.0,
        160,
        120,
    )
    .unwrap();
    let mut background = Frame::new(160, 120).unwrap();
    for y in 0..120 {
        for x in 0..160 {
            background.color.set(x, y, Vec4::new(0.2, 0.2, 0.2, 1.0));
        }
    }
    (camera, background)
}

/// A 32² relief impostor of a flat square at the origin facing +z, every texel of `colour`
/// (at displacement 0), its pre-warp enlarged by `margin` texels of the same colour.
fn square(colour: Vec3, margin: f64) -> ReliefDraw {
    let frame = ReliefFrame::facing(DVec3::ZERO, 1.0, DVec3::new(0.0, 0.0, 4.0), 32).unwrap();
    let m = margin as u32;
    let (w, h) = (32 + 2 * m, 32 + 2 * m);
    let n = (w * h) as usize;
    let image = Prewarped {
        width: w,
        height: h,
        margin: (m, m),
        color: vec![trompe::relief::encode(colour.extend(1.0)); n],
        displacement: vec![0.0; n],
        flags: vec![flag::DIRECT; n],
        direct: n,
        interpolated: 0,
        dropped: 0,
    };
    ReliefDraw {
        object: 7,
        image: Arc::new(image),
        frame,
    }
}

/// The `relief` method through the library's one interface, in deterministic mode so both
/// devices decide alike: a short orbit, each frame the GPU's against the CPU's (ids ≥ 99.9 %,
/// mean FLIP ≤ 0.01), the GPU's report counting what it uploaded.
pub fn the_relief_method_on_the_gpu_is_the_cpus(gpu: &Gpu) {
    use trompe::methods::{MethodKind, MethodSettings};
    let scene = walk_scene();
    let settings = MethodSettings {
        relief: PipelineSettings {
            resolution: 128,
            first_resolution: Some(32),
            deterministic: Some(1),
            ..Default::default()
        },
        ..MethodSettings::default()
    };
    let renderer = |device| {
        trompe_gpu::DeviceRenderer::new(&scene, MethodKind::Relief, settings.clone(), device)
            .unwrap()
    };
    let (mut cpu, mut on_gpu) = (renderer(None), renderer(Some(gpu)));
    let spec = &scene.camera;
    let centre = Vec3::new(0.0, 0.3, 0.0);
    for i in 0..6 {
        let a = (i as f32 * 5.0).to_radians();
        let eye = centre + Vec3::new(6.5 * a.sin(), 1.2, 6.5 * a.cos());
        let camera =
            Pinhole::look_at(eye, centre, spec.up, spec.fov_y, spec.width, spec.height).unwrap();
        let c = cpu.frame(0.0, Some(camera.clone()), &()).unwrap();
        let g = on_gpu.frame(0.0, Some(camera), &()).unwrap();
        let (ids, flip) = crate::agreement(&c.frame, &g.frame);
        println!(
            "frame {i}: {}; ids {:.3} %, FLIP {flip:.5}",
            g.report,
            100.0 * ids
        );
        assert!(g.report.contains("pre-warps uploaded"), "{}", g.report);
        assert_eq!(c.state, g.state, "frame {i}: the same decisions");
        assert!(
            ids >= 0.999 && flip <= 0.01,
            "frame {i}: ids {ids}, FLIP {flip}"
        );
    }
}
