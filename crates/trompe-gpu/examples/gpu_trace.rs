//! Traces a scene on the GPU and on the CPU and compares the two frames.
//!
//! `cargo run --release -p trompe-gpu --example gpu_trace -- [SCENE.toml] [OUTPUT_DIR]`
//! (default: the teapot in the bunny, into `target/gpu-trace`).

use std::path::PathBuf;
use trompe::methods::{MethodKind, MethodSettings, Renderer};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let scene_path = PathBuf::from(
        args.next()
            .unwrap_or_else(|| "scenes/teapot-in-bunny.toml".into()),
    );
    let out = PathBuf::from(args.next().unwrap_or_else(|| "target/gpu-trace".into()));
    let mut scene = trompe::Scene::load(&scene_path)?;
    scene.camera.width = 320;
    scene.camera.height = 240;
    let gpu = trompe_gpu::GpuRequest::new().open()?;
    println!("{}", gpu.report());
    let t = scene.render.time;
    let cpu = Renderer::new(&scene, MethodKind::Trace, MethodSettings::default())?
        .frame(t, None, &())?
        .frame;
    let view = scene.view(t)?;
    let started = std::time::Instant::now();
    let on_gpu = trompe_gpu::trace::render(&gpu, &view, &scene.lighting, &scene.render)?;
    println!(
        "GPU frame in {:.1} ms",
        started.elapsed().as_secs_f64() * 1e3
    );
    std::fs::create_dir_all(&out)?;
    trompe::frame::io::write_png(&out.join("cpu.png"), &cpu.color)?;
    trompe::frame::io::write_png(&out.join("gpu.png"), &on_gpu.color)?;
    let scores = trompe::frame::metrics::compare(&cpu.color, &on_gpu.color, None)?;
    println!(
        "GPU against CPU: PSNR {:.2} dB, mean FLIP {:.5}",
        scores.psnr, scores.flip
    );
    println!("wrote {}/cpu.png and gpu.png", out.display());
    Ok(())
}
