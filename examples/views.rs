//! Calibrated views: capture a textured model on a ring of cameras, then texture it from those
//! views at a viewpoint where no camera stood, and score the result against the exact render.
//!
//! ```sh
//! cargo run --release --example views -- [MESH]
//! ```
//! With no argument, the shipped glTF duck.

use glam::Vec3;
use std::error::Error;
use std::path::PathBuf;
use trompe::frame::metrics;
use trompe::views::capture::{CaptureSettings, capture, capture_scene};
use trompe::views::visibility::DepthMap;
use trompe::views::{BlendSettings, Weighting, blend};

fn main() -> Result<(), Box<dyn Error>> {
    let mesh_path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/gltf/Duck.glb"));
    // 24 views on a ring 15° up, rendered by the exact tracer.
    let settings = CaptureSettings {
        count: 24,
        size: (256, 192),
        ..Default::default()
    };
    let views = capture(&mesh_path, &settings, &())?;
    let mesh = trompe::geom::io::load(&mesh_path)?.mesh;
    let depth = DepthMap::of_all(&views.views, &mesh)?;

    // A new viewpoint, 40° up, between two ring cameras; the exact render is the truth.
    let mut scene = capture_scene(&mesh_path)?;
    let b = mesh.bounds();
    let (centre, radius) = ((b.min + b.max) * 0.5, b.extent().length() * 0.5);
    let (a, e) = (7.5f32.to_radians(), 40f32.to_radians());
    scene.camera.position =
        centre + Vec3::new(a.sin() * e.cos(), e.sin(), a.cos() * e.cos()) * radius * 3.0;
    scene.camera.look_at = centre;
    (scene.camera.width, scene.camera.height) = settings.size;
    let (exact, _) = trompe::render(&scene, trompe::Method::Trace, &())?;
    let camera = scene.view(0.0)?.camera;

    for weighting in [
        Weighting::Ulr { beta: 0.1 },
        Weighting::Vdtm,
        Weighting::ViewMap,
        Weighting::BestFace,
    ] {
        let k: usize = std::env::var("K")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(4);
        let s = BlendSettings {
            weighting,
            k,
            ..Default::default()
        };
        let textured = blend::render(&camera, &mesh, &views.views, &depth, &s, None)?;
        let covered = textured.image.map(|c| c.w > 0.0);
        let psnr = metrics::psnr(&exact.color, &textured.image, Some(&covered))?;
        println!(
            "{:<20} PSNR {psnr:.2} dB on the {} pixels that show the mesh ({} seen by no view)",
            trompe::views::score::name(weighting),
            textured.covered,
            textured.holes
        );
    }
    Ok(())
}
