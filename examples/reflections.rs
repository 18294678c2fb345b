//! Render a scene with its reflections answered three ways — the exact BVH, impostors, the
//! environment alone — through the one tracer, and score each against the exact frame.
//!
//! ```sh
//! cargo run --release --example reflections -- [SCENE.toml] [IMPOSTOR_RESOLUTION]
//! ```
//! Default: `scenes/reflections.toml`, 256² impostors. Images go to `target/examples/`.

use std::error::Error;
use std::path::PathBuf;
use trompe::frame::{io, metrics};
use trompe::render::shading::Shadows;
use trompe::render::{ImpostorInputs, ReflectorImpostors};
use trompe::{Bvh, EnvironmentOnly, Exact, Scene, SecondaryQuery, Timings, Tracer, render_trace};

fn main() -> Result<(), Box<dyn Error>> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .map_or_else(|| root.join("scenes/reflections.toml"), PathBuf::from);
    let resolution: u32 = args.next().map_or(Ok(256), |a| a.parse())?;
    let scene = Scene::load(&path)?;
    let view = scene.view(scene.render.time)?;
    let primary = Bvh::build(view.meshes.clone())?;

    // What answers the rays mirrors and glass send out: one renderer, three answers.
    let mut timings = Timings::default();
    let inputs = ImpostorInputs {
        // The impostors' texels shadowed as the tracer shadows what it hits.
        shadows: Some(Shadows {
            occluders: &primary,
            epsilon: scene.render.ray_epsilon,
        }),
        ..ImpostorInputs::new(resolution)
    };
    let impostors = ReflectorImpostors::build(&view, &scene.lighting, inputs, &mut timings)?;
    let exact = Exact(&primary);
    let answers: [(&str, &dyn SecondaryQuery); 3] = [
        ("exact", &exact),
        ("impostor", &impostors),
        ("environment", &EnvironmentOnly),
    ];

    let out = root.join("target/examples");
    std::fs::create_dir_all(&out)?;
    let mut reference = None;
    for (name, secondary) in answers {
        let tracer = Tracer {
            view: &view,
            primary: &primary,
            secondary,
            lighting: &scene.lighting,
            settings: &scene.render,
        };
        let frame = render_trace(&tracer, &())?;
        let file = out.join(format!("reflections-{name}.png"));
        io::write_png(&file, &frame.color)?;
        match &reference {
            None => {
                println!("{name:<12} wrote {}", file.display());
                reference = Some(frame.color);
            }
            Some(r) => {
                let s = metrics::compare(r, &frame.color, None)?;
                println!(
                    "{name:<12} PSNR {:.2} dB, FLIP {:.4} against exact; wrote {}",
                    s.psnr,
                    s.flip,
                    file.display()
                );
            }
        }
    }
    for (step, d) in &timings.0 {
        println!("  {step:<28} {:>8.1} ms", d.as_secs_f64() * 1e3);
    }
    Ok(())
}
