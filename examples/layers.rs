//! Layered projective textures: capture a scene of several objects from a ring of views, sort
//! each view's objects into visibility layers, write the image layers as OpenRaster files, then
//! render the scene from its own camera through the layers and through plain projective
//! texturing, each scored against the exact render.
//!
//! ```sh
//! cargo run --release --example layers -- [SCENE]
//! ```
//! With no argument, the shipped street scene; the layers go to `target/example-layers/`.

use std::error::Error;
use std::path::PathBuf;
use trompe::frame::metrics;
use trompe::layers::{self, BuildSettings};
use trompe::texturing::BlendSettings;
use trompe::views::capture::{CaptureSettings, capture_of};

fn main() -> Result<(), Box<dyn Error>> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let scene_path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("scenes/street.toml"));
    let scene = trompe::Scene::load(&scene_path)?;

    // Four photographs, rendered by the exact tracer on a ring around the objects.
    let settings = CaptureSettings {
        count: 4,
        size: (320, 240),
        distance: 1.4,
        fov_y: 50.0,
        ..CaptureSettings::default()
    };
    let views = capture_of(scene.clone(), &settings, &())?.views;

    // Visibility layers, image layers, one OpenRaster file a view.
    let (meshes, names) = layers::scene_objects(&scene)?;
    let set = layers::build(meshes, names, &views, &BuildSettings::default(), &())?;
    println!("{}", layers::REPORT_HEADER);
    for r in &set.reports {
        println!("{r}");
    }
    let out = root.join("target/example-layers");
    layers::file::save(&out, &set)?;
    println!("OpenRaster files for GIMP or Krita in {}", out.display());

    // The scene's own camera, where no photograph was taken.
    let (exact, _) = trompe::render(&scene, trompe::Method::Trace, &())?;
    let camera = scene.view(0.0)?.camera;
    let rs = BlendSettings::default();
    for (name, blend) in [
        ("layered", layers::render::render(&camera, &set, &rs)?),
        (
            "plain projective",
            layers::render::render_projective(&camera, &set.mesh_refs(), &set.views, &rs)?,
        ),
    ] {
        let mask = blend.image.map(|p| p.w >= 0.5);
        let scores = metrics::compare(&exact.color, &blend.image, Some(&mask))?;
        println!(
            "{name:>16}: PSNR {:.1} dB, FLIP {:.4}, holes {:.2} %",
            scores.psnr,
            scores.flip,
            100.0 * blend.holes as f64 / blend.covered.max(1) as f64
        );
    }
    Ok(())
}
