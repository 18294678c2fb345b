//! The `trace` method on the GPU against its CPU twin, on every shipped scene.

use std::path::{Path, PathBuf};
use trompe::methods::{MethodKind, MethodSettings, Renderer};
use trompe::scene::Scene;
use trompe_gpu::Gpu;

/// Every shipped scene file, at 320 × 240.
fn shipped_scenes() -> Vec<(PathBuf, Scene)> {
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
    let mut failures = Vec::new();
    for (path, scene) in shipped_scenes() {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let t = scene.render.time;
        let cpu = Renderer::new(&scene, MethodKind::Trace, MethodSettings::default())
            .and_then(|mut r| r.frame(t, None, &()))
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .frame;
        let view = scene.view(t).unwrap();
        let started = std::time::Instant::now();
        let gpu_frame = trompe_gpu::trace::render(gpu, &view, &scene.lighting, &scene.render)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let took = started.elapsed();
        let pixels = cpu.object_id.pixels().len();
        let same_id = cpu
            .object_id
            .pixels()
            .iter()
            .zip(gpu_frame.object_id.pixels())
            .filter(|(a, b)| a == b)
            .count();
        let ids = same_id as f64 / pixels as f64;
        let flip = trompe::frame::metrics::compare(&cpu.color, &gpu_frame.color, None)
            .unwrap()
            .flip;
        eprintln!(
            "{name:>16}: ids {:.3} % equal, mean FLIP {flip:.5} ({} ms on the GPU)",
            100.0 * ids,
            took.as_millis()
        );
        if ids < 0.999 || flip > 0.01 {
            failures.push(format!("{name}: ids {ids:.4}, FLIP {flip:.4}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
