//! The three.js runtime (`web/trompe-octahedral.js`) in a real browser: headless Chromium
//! (Debian's package, WebGL 2 through SwiftShader) draws the Duck's self-contained bake from 8
//! directions, straight down included, and one instance moved, turned and scaled; each picture
//! is scored by FLIP against trompe's CPU reference of the same bake and camera
//! (`OctahedralAtlas::render_cutout`) and against the exact render of the mesh.

use super::common::{root, scratch};
use glam::{Quat, Vec3};
use std::path::Path;
use trompe::camera::Pinhole;
use trompe::frame::{io, metrics};
use trompe::scene::{Light, Lighting, RenderSettings, Surface, View};

/// Whether the browser test can run here: Node.js, Chromium and the runtime's npm packages.
pub fn ready() -> bool {
    let modules = root().join("web/node_modules");
    super::common::has_command("node")
        && Path::new("/usr/bin/chromium").exists()
        && modules.join("three").is_dir()
        && modules.join("playwright-core").is_dir()
}

/// What [`ready`] needs, as the harness prints it.
pub const NEEDS: &str =
    "node, Chromium (package chromium) and the runtime's npm packages (npm ci in web/)";

/// One view as `web/test/render.html` reads it.
fn view_json(
    camera: (Vec3, Vec3, Vec3),
    size: u32,
    lighting: &Lighting,
    sky: Vec3,
) -> serde_json::Value {
    let sun = lighting.light.expect("the test's lighting has a sun");
    serde_json::json!({
        "eye": camera.0.to_array(), "target": camera.1.to_array(), "up": camera.2.to_array(),
        "fov_y": 30.0, "width": size, "height": size, "near": 0.01,
        "ambient": sky.to_array(),
        "sun_direction": sun.direction.to_array(),
        "sun_irradiance": sun.irradiance.to_array(),
    })
}

pub fn the_threejs_runtime_draws_the_ducks_bake_as_trompe_does() {
    let dir = scratch("web_threejs_runtime");
    let glb = dir.join("duck.glb");
    let out = super::common::trompe(&[
        "impostor",
        "bake",
        "assets/gltf/Duck.glb",
        "--octahedral",
        "16",
        "--resolution",
        "2048",
        "-o",
        glb.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let atlas = trompe::octahedral::gltf::load(&glb).unwrap();
    let mesh = trompe::geom::io::load(&root().join("assets/gltf/Duck.glb"))
        .unwrap()
        .mesh;
    let sky = Vec3::splat(0.3);
    let lighting = Lighting {
        environment: trompe::frame::envmap::EnvMap::constant(sky),
        light: Some(Light {
            direction: Vec3::new(0.4, 1.0, 0.6).normalize(),
            irradiance: Vec3::splat(2.5),
        }),
    };
    let size = 256;
    let (c, r) = (atlas.centre, atlas.radius);
    // 8 directions (azimuth, elevation in degrees) round the duck, straight down last.
    let directions = [
        (0.0f32, 0.0f32),
        (45.0, 20.0),
        (100.0, 35.0),
        (150.0, -25.0),
        (200.0, 50.0),
        (250.0, 10.0),
        (310.0, 65.0),
        (0.0, 90.0),
    ];
    let cameras: Vec<(Vec3, Vec3, Vec3)> = directions
        .iter()
        .map(|&(a, e)| {
            let (a, e) = (a.to_radians(), e.to_radians());
            let d = Vec3::new(e.cos() * a.cos(), e.sin(), e.cos() * a.sin());
            let up = if d.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
            (c + d * (4.0 * r), c, up)
        })
        .collect();
    let mut views: Vec<serde_json::Value> = cameras
        .iter()
        .map(|&cam| view_json(cam, size, &lighting, sky))
        .collect();
    // The second view again with the duck moved, turned and scaled as an instance, the camera
    // and the sun carried along: the same picture.
    let (q, s, t) = (
        Quat::from_axis_angle(Vec3::new(1.0, 2.0, -0.5).normalize(), 1.1),
        1.7f32,
        Vec3::new(3.0, -1.0, 2.0),
    );
    let place = |p: Vec3| q * (p * s) + t;
    let (eye, target, up) = cameras[1];
    let mut moved = view_json((place(eye), place(target), q * up), size, &lighting, sky);
    let sun = lighting.light.unwrap();
    moved["sun_direction"] = serde_json::json!((q * sun.direction).to_array());
    moved["near"] = serde_json::json!(0.01 * s);
    moved["instance"] = serde_json::json!({
        "position": t.to_array(), "quaternion": q.to_array(), "scale": s,
    });
    views.push(moved);
    let views_path = dir.join("views.json");
    std::fs::write(&views_path, serde_json::to_string(&views).unwrap()).unwrap();
    let shots = dir.join("shots");
    let run = std::process::Command::new("node")
        .arg(root().join("web/test/render.mjs"))
        .arg("--glb")
        .arg(&glb)
        .arg("--views")
        .arg(&views_path)
        .arg("--out")
        .arg(&shots)
        .output()
        .expect("node runs");
    let said = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{said}{}",
        String::from_utf8_lossy(&run.stderr)
    );
    print!("{said}");
    let settings = RenderSettings {
        max_depth: 2,
        time: 0.0,
        ray_epsilon: r * 1e-4,
    };
    let mut scores = Vec::new();
    for (k, &(eye, target, up)) in cameras.iter().chain([&cameras[1]]).enumerate() {
        let camera = Pinhole::look_at(eye, target, up, 30.0, size, size).unwrap();
        let browser = io::read_png(&shots.join(format!("view-{k}.png"))).unwrap();
        let reference = atlas.render_cutout(&camera, &lighting, 4);
        let view = View {
            camera,
            meshes: vec![std::sync::Arc::new(mesh.clone())],
            surfaces: vec![Surface::Diffuse(None)],
        };
        let exact = trompe::octahedral::turntable::exact_unshadowed(&view, &lighting, &settings)
            .unwrap()
            .color;
        let flip_reference = metrics::flip(&reference, &browser, None).unwrap();
        let flip_exact = metrics::flip(&exact, &browser, None).unwrap();
        println!(
            "view {k}, {}: FLIP {flip_reference:.4} against trompe's CPU reference, \
             {flip_exact:.4} against the exact render",
            directions
                .get(k)
                .map_or("instance moved, turned, scaled".to_string(), |d| format!(
                    "azimuth {}°, elevation {}°",
                    d.0, d.1
                ))
        );
        scores.push((flip_reference, flip_exact));
    }
    let eight = &scores[..8];
    let mean = |f: fn(&(f64, f64)) -> f64| eight.iter().map(f).sum::<f64>() / 8.0;
    let worst = eight.iter().map(|s| s.0).fold(0.0, f64::max);
    println!(
        "mean FLIP over 8 directions: {:.4} against the CPU reference (worst {worst:.4}), {:.4} \
         against the exact render",
        mean(|s| s.0),
        mean(|s| s.1)
    );
    assert!(
        mean(|s| s.0) <= 0.02,
        "mean FLIP {} against the CPU reference",
        mean(|s| s.0)
    );
    assert!(
        mean(|s| s.1) <= 0.05,
        "mean FLIP {} against the exact render",
        mean(|s| s.1)
    );
    // The moved instance draws what the instance at the bake's place drew.
    assert!(scores[8].0 <= 0.02, "moved instance: FLIP {}", scores[8].0);
}
