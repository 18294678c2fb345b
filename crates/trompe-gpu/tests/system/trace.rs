//! The `trace` and `raster` methods on the GPU against their CPU twins, on every shipped scene.

use std::path::{Path, PathBuf};
use trompe::methods::{MethodKind, MethodSettings};
use trompe::scene::Scene;
use trompe_gpu::{DeviceRenderer, Gpu};

/// Every shipped scene file, at 320 × 240.
pub fn shipped_scenes() -> Vec<(PathBuf, Scene)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    paths
        .into_iter()
        .map(|p| {
            let mut scene = Scene::load(&p).unwrap_or_else(|e| {
                panic!(
                    "{}: {e} (the scenes' meshes and panoramas live in ../shared)",
                    p.display()
                )
            });
            scene.camera.width = 320;
            scene.camera.height = 240;
            (p, scene)
        })
        .collect()
}

pub fn every_shipped_scene_traces_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    // The exact tracer: the same object on ≥ 99.9 % of pixels.
    agrees_on_every_scene(gpu, MethodKind::Trace, 0.999);
}

pub fn every_shipped_scene_rasterizes_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    // Two rasterizers' coverage rules may differ on silhouette pixels: ≥ 99.5 %.
    agrees_on_every_scene(gpu, MethodKind::Raster, 0.995);
}

pub fn every_shipped_scene_renders_through_impostors_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    // SPOCs, orthographic and cube-map impostors, graph cameras in mazes.
    agrees_on_every_scene(gpu, MethodKind::Impostor, 0.995);
}

pub fn every_shipped_scene_renders_through_pinhole_impostors_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    // The primary pass is the exact tracer's; impostor answers agree texel for texel.
    agrees_on_every_scene(gpu, MethodKind::PinholeImpostor, 0.995);
}

/// The `trace` and `impostor` methods with Wyman's refraction (its back faces drawn by the GPU
/// rasterizer, the second interface found in the shader) against the CPU's, on every shipped
/// scene with glass.
pub fn wymans_refraction_runs_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    let wyman = MethodSettings {
        refraction: trompe::render::Refraction::Wyman,
        ..MethodSettings::default()
    };
    let glass = |scene: &Scene| {
        scene
            .objects
            .iter()
            .any(|o| matches!(o.surface, trompe::scene::Surface::Glass { .. }))
    };
    let compared = agrees_on_scenes(gpu, (MethodKind::Trace, &wyman), 0.999, &glass);
    assert!(compared >= 2, "{compared} scenes with glass");
    agrees_on_scenes(gpu, (MethodKind::Impostor, &wyman), 0.995, &glass);
    // The approximation is what runs: on the GPU, Wyman's frame of the teapots differs from the
    // exact one by more than the two devices' Wyman frames differ.
    let (_, scene) = shipped_scenes()
        .into_iter()
        .find(|(p, _)| p.ends_with("teapots.toml"))
        .expect("scenes/teapots.toml");
    let frame = |settings: &MethodSettings, device: Option<&Gpu>| {
        DeviceRenderer::new(&scene, MethodKind::Trace, settings.clone(), device)
            .and_then(|mut r| r.frame(scene.render.time, None, &()))
            .unwrap()
            .frame
            .color
    };
    let on_gpu = frame(&wyman, Some(gpu));
    let flip = |a: &trompe::frame::Image<glam::Vec4>, b: &trompe::frame::Image<glam::Vec4>| {
        trompe::frame::metrics::compare(a, b, None).unwrap().flip
    };
    let from_exact = flip(&on_gpu, &frame(&MethodSettings::default(), Some(gpu)));
    let from_cpu = flip(&on_gpu, &frame(&wyman, None));
    eprintln!(
        "teapots, Wyman on the GPU: mean FLIP {from_exact:.5} from exact, {from_cpu:.5} from the CPU's Wyman"
    );
    assert!(
        from_exact > 2.0 * from_cpu,
        "{from_exact} from exact, {from_cpu} from the CPU's"
    );
}

/// `kind` on the GPU against its CPU twin through the same interface: object ids equal on at
/// least `ids` of the pixels, mean FLIP ≤ 0.01, on every shipped scene at 320 × 240.
fn agrees_on_every_scene(gpu: &Gpu, kind: MethodKind, ids: f64) {
    agrees_on_scenes(gpu, (kind, &MethodSettings::default()), ids, &|_| true);
}

/// [`agrees_on_every_scene`] with `settings`, on the shipped scenes `which` picks; how many
/// were compared.
pub fn agrees_on_scenes(
    gpu: &Gpu,
    (kind, settings): (MethodKind, &MethodSettings),
    ids: f64,
    which: &dyn Fn(&Scene) -> bool,
) -> usize {
    let mut compared = 0;
    let mut failures = Vec::new();
    let mut refused = Vec::new();
    // One device runs every method: a `trace` frame first, whose pipeline shares its entry
    // point's name with the impostor methods'.
    if let Some((_, scene)) = shipped_scenes().first() {
        DeviceRenderer::new(
            scene,
            MethodKind::Trace,
            MethodSettings::default(),
            Some(gpu),
        )
        .and_then(|mut r| r.frame(scene.render.time, None, &()))
        .unwrap_or_else(|e| panic!("trace first: {e}"));
    }
    for (path, scene) in shipped_scenes().into_iter().filter(|(_, s)| which(s)) {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let t = scene.render.time;
        let frame = |device: Option<&Gpu>| {
            DeviceRenderer::new(&scene, kind, settings.clone(), device)
                .and_then(|mut r| r.frame(t, None, &()))
                .map(|f| f.frame)
        };
        let cpu = match frame(None) {
            Ok(frame) => frame,
            // A scene the method refuses on the CPU (one naming a baked impostor the quick
            // start writes) must be refused on the GPU too.
            Err(e) => {
                let on_gpu = frame(Some(gpu));
                eprintln!("{kind} {name:>16}: refused on both devices: {e}");
                assert!(
                    on_gpu.is_err(),
                    "{name}: the CPU refused ({e}), the GPU did not"
                );
                continue;
            }
        };
        let started = std::time::Instant::now();
        let gpu_frame = match frame(Some(gpu)) {
            Ok(frame) => frame,
            // What the GPU does not run yet (a graph camera's walk) is refused by name, and
            // listed, never passed.
            Err(trompe_gpu::DeviceError::Gpu(e @ trompe_gpu::GpuError::Unsupported { .. })) => {
                eprintln!("{kind} {name:>16}: NOT COMPARED, the GPU refuses it: {e}");
                refused.push(name);
                continue;
            }
            Err(e) => panic!("{name}: {e}"),
        };
        let took = started.elapsed();
        let pixels = cpu.object_id.pixels().len();
        let same_id = cpu
            .object_id
            .pixels()
            .iter()
            .zip(gpu_frame.object_id.pixels())
            .filter(|(a, b)| a == b)
            .count();
        let equal = same_id as f64 / pixels as f64;
        let flip = trompe::frame::metrics::compare(&cpu.color, &gpu_frame.color, None)
            .unwrap()
            .flip;
        eprintln!(
            "{kind} {name:>16}: ids {:.3} % equal, mean FLIP {flip:.5} ({} ms on the GPU)",
            100.0 * equal,
            took.as_millis()
        );
        if equal < ids || flip > 0.01 {
            failures.push(format!("{name}: ids {equal:.4}, FLIP {flip:.4}"));
        }
        compared += 1;
    }
    assert!(failures.is_empty(), "{kind}: {failures:#?}");
    assert!(
        refused.is_empty(),
        "{kind}: refused on the GPU: {refused:?}"
    );
    compared
}

/// A bunny turning beside a mirror ball, the camera still: under the impostor method the GPU
/// keeps the bunny's impostor between frames (placed where the bunny has turned, lit again),
/// as the CPU does, and every frame agrees with the CPU's.
pub fn impostors_are_kept_across_frames_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let text = r#"
[camera]
position = [0.0, 0.6, 1.9]
look_at = [0.25, 0.25, 0.0]
fov_y = 40.0
resolution = [240, 180]

[environment]
path = "../assets/envmaps/studio.hdr"

[light]
direction = [0.3, 1.0, 0.4]

[[object]]
shape = "plane"
scale = 3.0
material = { type = "diffuse", color = [0.5, 0.5, 0.5] }

[[object]]
mesh = "../assets/meshes/bunny.obj"
fit = 0.6
material = { type = "diffuse", color = [0.75, 0.7, 0.6] }

[object.animate]
axis = [0.0, 1.0, 0.0]
degrees_per_second = 45.0

[[object]]
shape = "sphere"
scale = 0.2
translate = [0.6, 0.25, 0.2]
material = { type = "mirror", tint = [0.9, 0.9, 0.9] }
"#;
    let scene = Scene::from_toml(text, &scenes.join("turning-beside-a-mirror.toml"))
        .unwrap_or_else(|e| panic!("{e}"));
    let settings = MethodSettings {
        impostor_resolution: 256,
        ..MethodSettings::default()
    };
    let mut cpu =
        DeviceRenderer::new(&scene, MethodKind::Impostor, settings.clone(), None).unwrap();
    let mut on_gpu =
        DeviceRenderer::new(&scene, MethodKind::Impostor, settings, Some(gpu)).unwrap();
    // A degree a frame: the mirror stays within the region the impostors were built for.
    for (i, t) in [0.0f32, 0.02, 0.04].into_iter().enumerate() {
        let c = cpu.frame(t, None, &()).unwrap();
        let g = on_gpu.frame(t, None, &()).unwrap();
        eprintln!("t = {t}: CPU {} | GPU {}", c.report, g.report);
        if i == 0 {
            // The floor's orthographic impostor and the bunny's SPOC, drawn by the GPU
            // rasterizer.
            assert!(
                g.report.contains("2 built (2 drawn by the device)"),
                "{}",
                g.report
            );
        } else {
            // Kept, not rebuilt: the bunny turned rigidly; both lit again.
            assert!(
                g.report.contains("0 built, 2 reused (2 relit)"),
                "{}",
                g.report
            );
        }
        let (ids, flip) = crate::agreement(&c.frame, &g.frame);
        eprintln!("t = {t}: ids {:.3} % equal, FLIP {flip:.5}", ids * 100.0);
        assert!(
            ids >= 0.995 && flip <= 0.01,
            "t = {t}: ids {ids}, FLIP {flip}"
        );
    }
}

/// What the GPU does not run yet is refused when the method is prepared, with the reason, before
/// any frame: mirrors seen as impostors, Wyman's refraction.
pub fn what_the_gpu_does_not_run_is_refused_before_any_work(gpu: &Gpu) {
    let (_, scene) = shipped_scenes()
        .into_iter()
        .find(|(p, _)| p.ends_with("c3rc-bunny.toml"))
        .expect("scenes/c3rc-bunny.toml");
    match DeviceRenderer::new(
        &scene,
        MethodKind::EnvMap,
        MethodSettings::default(),
        Some(gpu),
    ) {
        Err(e) => assert!(e.to_string().contains("no GPU path"), "{e}"),
        Ok(_) => panic!("envmap: accepted on the GPU"),
    }
}

/// The impostor methods with `--mirrors impostor` (paper 1 §6's second-order reflections: a
/// mirror sees the other mirrors through impostors that store their surface, and reflects on
/// off it) against the CPU's, on every shipped scene with two or more mirror or glass objects;
/// and on the teapots, whose mirrors see one another, the pixels where it changes the GPU's frame
/// agree with the CPU's.
pub fn mirrors_seen_as_impostors_run_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    let mirrors = MethodSettings {
        mirrors: trompe::render::Mirrors::Impostor,
        ..MethodSettings::default()
    };
    let specular = |scene: &Scene| {
        scene
            .objects
            .iter()
            .filter(|o| !matches!(o.surface, trompe::scene::Surface::Diffuse(_)))
            .count()
            >= 2
    };
    let compared = agrees_on_scenes(gpu, (MethodKind::Impostor, &mirrors), 0.995, &specular);
    assert!(compared >= 2, "{compared} scenes with several mirrors");
    agrees_on_scenes(
        gpu,
        (MethodKind::PinholeImpostor, &mirrors),
        0.995,
        &specular,
    );
    let (_, scene) = shipped_scenes()
        .into_iter()
        .find(|(p, _)| p.ends_with("teapots.toml"))
        .expect("scenes/teapots.toml");
    let frame = |settings: &MethodSettings, device: Option<&Gpu>| {
        DeviceRenderer::new(&scene, MethodKind::Impostor, settings.clone(), device)
            .and_then(|mut r| r.frame(scene.render.time, None, &()))
            .unwrap()
            .frame
            .color
    };
    // Where the mirrors seen as impostors change the GPU's frame, it agrees with the CPU's.
    let on_gpu = frame(&mirrors, Some(gpu));
    let exact = frame(&MethodSettings::default(), Some(gpu));
    let on_cpu = frame(&mirrors, None);
    let (mut changed, mut from_exact, mut from_cpu) = (0, 0.0f32, 0.0f32);
    for ((g, e), c) in on_gpu
        .pixels()
        .iter()
        .zip(exact.pixels())
        .zip(on_cpu.pixels())
    {
        let off_exact = (*g - *e).truncate().abs().max_element();
        if off_exact > 0.01 {
            changed += 1;
            from_exact += off_exact;
            from_cpu += (*g - *c).truncate().abs().max_element();
        }
    }
    eprintln!(
        "teapots, mirrors as impostors on the GPU: {changed} pixels differ from mirrors seen \
         exactly, by {:.4} on average; from the CPU's, by {:.4}",
        from_exact / changed.max(1) as f32,
        from_cpu / changed.max(1) as f32
    );
    assert!(changed >= 50, "{changed} pixels changed");
    assert!(
        from_cpu < 0.25 * from_exact,
        "{from_cpu} from the CPU's, {from_exact} from exact"
    );
}
