//! Hybrid reflections (paper 2): sample a scene's diffuse objects as points once, then render
//! frames of it moving — the bunny spinning beside the mirror teapot — from the same points and
//! kd-trees, each scored against the exact frame.
//!
//! ```sh
//! cargo run --release --example hybrid -- [SCENE.toml] [FRAMES]
//! ```
//! Default: `scenes/c3rc-bunny.toml`, 4 frames. Images go to `target/examples/`.

use std::error::Error;
use std::path::PathBuf;
use trompe::frame::{io, metrics};
use trompe::glam::Vec3;
use trompe::hybrid::{HybridReflections, HybridSettings};
use trompe::render::{Method, render_at};
use trompe::scene::{Animation, Scene, Surface};

fn main() -> Result<(), Box<dyn Error>> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .map_or_else(|| root.join("scenes/c3rc-bunny.toml"), PathBuf::from);
    let frames: u32 = args.next().map_or(Ok(4), |a| a.parse())?;
    let mut scene = Scene::load(&path)?;
    // Spin every diffuse object about its vertical axis: a rigid motion, which the points and
    // trees survive.
    for o in &mut scene.objects {
        if matches!(o.surface, Surface::Diffuse(_)) {
            o.animation = Some(Animation {
                axis: Vec3::Y,
                angular_speed: 1.0,
                velocity: Vec3::ZERO,
            });
        }
    }
    let clouds = HybridReflections::prepare(&scene, HybridSettings::default())?;
    println!("{} points, sampled once", clouds.point_count());
    let out = root.join("target/examples");
    std::fs::create_dir_all(&out)?;
    for i in 0..frames {
        let t = i as f32 * 0.5;
        let hybrid = clouds.render_at(&scene, t, &())?;
        let (exact, _) = render_at(&scene, t, Method::Trace, &())?;
        let flip = metrics::flip(&exact.color, &hybrid.frame.color, None)?;
        let file = out.join(format!("hybrid-{i}.png"));
        io::write_png(&file, &hybrid.frame.color)?;
        let s = hybrid.stats;
        println!(
            "t = {t:.1} s: culling {:.1} ms, projection {:.1} ms, {} pixels reflect a point, FLIP {flip:.4} against exact; wrote {}",
            s.cull.as_secs_f64() * 1e3,
            s.project.as_secs_f64() * 1e3,
            s.pixels_splatted,
            file.display()
        );
    }
    Ok(())
}
