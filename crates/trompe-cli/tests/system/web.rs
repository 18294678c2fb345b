//! The three.js runtime (`web/trompe-octahedral.js`) in a real browser: headless Chromium
//! (Debian's package, WebGL 2 through SwiftShader) draws the Duck's self-contained bake — with
//! PNG textures and with KTX2 ones (Basis Universal, transcoded by three's KTX2Loader) — from 8
//! directions, straight down included, and one instance moved, turned and scaled; each picture
//! is scored by FLIP against trompe's CPU reference of the same bake and camera
//! (`OctahedralAtlas::render_cutout` of the file loaded back) and against the exact render of
//! the mesh. A distant view checks that the mip levels help: nearer the supersampled reference
//! with them than without. An impostor's compressed surface (quantized, meshopt) reads in
//! three.js as trompe reads it.

use super::common::{root, scratch};
use glam::{Quat, Vec3};
use std::path::{Path, PathBuf};
use trompe::camera::Pinhole;
use trompe::frame::{Image, Rgba, io, metrics};
use trompe::octahedral::OctahedralAtlas;
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

/// A camera: eye, target, up.
type Eye = (Vec3, Vec3, Vec3);

const SIZE: u32 = 256;

fn lighting() -> Lighting {
    Lighting {
        environment: trompe::frame::envmap::EnvMap::constant(Vec3::splat(0.3)),
        light: Some(Light {
            direction: Vec3::new(0.4, 1.0, 0.6).normalize(),
            irradiance: Vec3::splat(2.5),
        }),
    }
}

/// One view as `web/test/render.html` reads it.
fn view_json((eye, target, up): Eye, lighting: &Lighting) -> serde_json::Value {
    let sun = lighting.light.expect("the test's lighting has a sun");
    serde_json::json!({
        "eye": eye.to_array(), "target": target.to_array(), "up": up.to_array(),
        "fov_y": 30.0, "width": SIZE, "height": SIZE, "near": 0.01,
        "ambient": [0.3, 0.3, 0.3],
        "sun_direction": sun.direction.to_array(),
        "sun_irradiance": sun.irradiance.to_array(),
    })
}

/// `trompe impostor bake` of the Duck to `glb`, 16 × 16 frames in a 2048² atlas, with `extra`.
fn bake(glb: &Path, extra: &[&str]) -> OctahedralAtlas {
    let mut args = vec![
        "impostor",
        "bake",
        "assets/gltf/Duck.glb",
        "--octahedral",
        "16",
        "--resolution",
        "2048",
    ];
    args.extend_from_slice(extra);
    args.extend(["-o", glb.to_str().unwrap()]);
    let out = super::common::trompe(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    trompe::octahedral::gltf::load(glb).unwrap()
}

/// The browser's pictures of `views` of the bake `glb`.
fn browser(glb: &Path, views: &[serde_json::Value], dir: &Path) -> Vec<Image<Rgba>> {
    std::fs::create_dir_all(dir).unwrap();
    let views_path = dir.join("views.json");
    std::fs::write(&views_path, serde_json::to_string(views).unwrap()).unwrap();
    let shots: PathBuf = dir.join("shots");
    let run = std::process::Command::new("node")
        .arg(root().join("web/test/render.mjs"))
        .arg("--glb")
        .arg(glb)
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
    (0..views.len())
        .map(|k| io::read_png(&shots.join(format!("view-{k}.png"))).unwrap())
        .collect()
}

/// The 8 directions (azimuth, elevation in degrees) round the duck, straight down last.
const DIRECTIONS: [(f32, f32); 8] = [
    (0.0, 0.0),
    (45.0, 20.0),
    (100.0, 35.0),
    (150.0, -25.0),
    (200.0, 50.0),
    (250.0, 10.0),
    (310.0, 65.0),
    (0.0, 90.0),
];

/// A camera `distance` radii from the sphere's centre along (azimuth, elevation).
fn around(atlas: &OctahedralAtlas, (a, e): (f32, f32), distance: f32) -> Eye {
    let (a, e) = (a.to_radians(), e.to_radians());
    let d = Vec3::new(e.cos() * a.cos(), e.sin(), e.cos() * a.sin());
    let up = if d.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    (
        atlas.centre + d * (distance * atlas.radius),
        atlas.centre,
        up,
    )
}

fn pinhole((eye, target, up): Eye, size: u32) -> Pinhole {
    Pinhole::look_at(eye, target, up, 30.0, size, size).unwrap()
}

/// Scores the 8 directions and the moved instance of `atlas` (baked to `glb`); returns the
/// mean FLIP against the CPU reference and against the exact render over the 8 directions,
/// and the moved instance's against the reference.
fn score(name: &str, glb: &Path, atlas: &OctahedralAtlas, dir: &Path) -> (f64, f64, f64) {
    let lighting = lighting();
    let mesh = trompe::geom::io::load(&root().join("assets/gltf/Duck.glb"))
        .unwrap()
        .mesh;
    let cameras: Vec<Eye> = DIRECTIONS.iter().map(|&d| around(atlas, d, 4.0)).collect();
    let mut views: Vec<serde_json::Value> = cameras
        .iter()
        .map(|&cam| view_json(cam, &lighting))
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
    let mut moved = view_json((place(eye), place(target), q * up), &lighting);
    let sun = lighting.light.unwrap();
    moved["sun_direction"] = serde_json::json!((q * sun.direction).to_array());
    moved["near"] = serde_json::json!(0.01 * s);
    moved["instance"] = serde_json::json!({
        "position": t.to_array(), "quaternion": q.to_array(), "scale": s,
    });
    views.push(moved);
    let pictures = browser(glb, &views, dir);
    let settings = RenderSettings {
        max_depth: 2,
        time: 0.0,
        ray_epsilon: atlas.radius * 1e-4,
    };
    let mut scores = Vec::new();
    for (k, &cam) in cameras.iter().chain([&cameras[1]]).enumerate() {
        let camera = pinhole(cam, SIZE);
        let reference = atlas.render_cutout(&camera, &lighting, 4);
        let view = View {
            lens: None,
            camera,
            meshes: vec![std::sync::Arc::new(mesh.clone())],
            surfaces: vec![Surface::Diffuse(None)],
        };
        let exact = trompe::octahedral::turntable::exact_unshadowed(&view, &lighting, &settings)
            .unwrap()
            .color;
        let to_reference = metrics::flip(&reference, &pictures[k], None).unwrap();
        let to_exact = metrics::flip(&exact, &pictures[k], None).unwrap();
        let what = match DIRECTIONS.get(k) {
            Some((a, e)) => format!("azimuth {a}°, elevation {e}°"),
            None => "instance moved, turned, scaled".to_string(),
        };
        println!(
            "{name} view {k}, {what}: FLIP {to_reference:.4} against trompe's CPU reference, \
             {to_exact:.4} against the exact render"
        );
        scores.push((to_reference, to_exact));
    }
    let eight = &scores[..8];
    let mean = |f: fn(&(f64, f64)) -> f64| eight.iter().map(f).sum::<f64>() / 8.0;
    let worst = eight.iter().map(|s| s.0).fold(0.0, f64::max);
    println!(
        "{name}: mean FLIP over 8 directions {:.4} against the CPU reference (worst {worst:.4}), \
         {:.4} against the exact render; the moved instance {:.4}",
        mean(|s| s.0),
        mean(|s| s.1),
        scores[8].0
    );
    (mean(|s| s.0), mean(|s| s.1), scores[8].0)
}

pub fn the_threejs_runtime_draws_the_ducks_bake_as_trompe_does() {
    // The runtime's constants are the Rust code's.
    let runtime = std::fs::read_to_string(root().join("web/trompe-octahedral.js")).unwrap();
    for (name, value) in [
        ("COVERED", f64::from(trompe::octahedral::render::ALPHA_TEST)),
        (
            "DEPTH_AGREEMENT",
            trompe::octahedral::render::DEPTH_AGREEMENT,
        ),
    ] {
        assert!(
            runtime.contains(&format!("const float {name} = {value:?};")),
            "{name}"
        );
    }
    let dir = scratch("web_threejs_runtime");
    for (name, extra) in [("PNG", &[][..]), ("KTX2", &["--ktx2"][..])] {
        let glb = dir.join(format!("duck-{name}.glb"));
        let atlas = bake(&glb, extra);
        let bytes = std::fs::metadata(&glb).unwrap().len();
        println!("{name} bake: {:.1} MB", bytes as f64 / 1e6);
        let (reference, exact, moved) = score(name, &glb, &atlas, &dir.join(name));
        assert!(
            reference <= 0.02,
            "{name}: mean FLIP {reference} against the CPU reference"
        );
        assert!(
            exact <= 0.05,
            "{name}: mean FLIP {exact} against the exact render"
        );
        // The moved instance draws what the instance at the bake's place drew.
        assert!(moved <= 0.02, "{name}: moved instance FLIP {moved}");
    }
}

/// Far away (40 radii: the duck some 25 pixels across), the KTX2 bake's mip levels bring the
/// browser's picture nearer the CPU reference supersampled 8 × 8 than level 0 alone does.
pub fn distant_impostors_sample_their_mip_levels() {
    let dir = scratch("web_threejs_mips");
    let glb = dir.join("duck.glb");
    let atlas = bake(&glb, &["--ktx2"]);
    let lighting = lighting();
    let cameras: Vec<Eye> = [(30.0, 25.0), (200.0, 50.0)]
        .iter()
        .map(|&d| around(&atlas, d, 40.0))
        .collect();
    let mut views = Vec::new();
    for &cam in &cameras {
        for mipmaps in [true, false] {
            let mut v = view_json(cam, &lighting);
            v["mipmaps"] = serde_json::json!(mipmaps);
            views.push(v);
        }
    }
    let pictures = browser(&glb, &views, &dir);
    for (k, &cam) in cameras.iter().enumerate() {
        let fine = atlas.render_cutout(&pinhole(cam, SIZE * 8), &lighting, 4);
        let sky = lighting.environment.radiance(Vec3::Y).extend(1.0);
        let samples = |i: u32| {
            let (x, y) = (i % SIZE, i / SIZE);
            (0..64).map(move |j| (8 * x + j % 8, 8 * y + j / 8))
        };
        let reference = Image::from_vec(
            SIZE,
            SIZE,
            (0..SIZE * SIZE)
                .map(|i| samples(i).map(|(x, y)| fine.get(x, y)).sum::<Rgba>() / 64.0)
                .collect(),
        )
        .unwrap();
        // Scored inside the duck (every sample of the pixel on it): where the atlas is
        // minified, not where the alpha test cuts the silhouette.
        let inside = Image::from_vec(
            SIZE,
            SIZE,
            (0..SIZE * SIZE)
                .map(|i| samples(i).all(|(x, y)| fine.get(x, y) != sky))
                .collect(),
        )
        .unwrap();
        let pixels = inside.pixels().iter().filter(|&&b| b).count();
        let with = metrics::flip(&reference, &pictures[2 * k], Some(&inside)).unwrap();
        let without = metrics::flip(&reference, &pictures[2 * k + 1], Some(&inside)).unwrap();
        println!(
            "distant view {k}: FLIP {with:.4} with mip levels, {without:.4} with level 0 alone, \
             against the CPU reference supersampled 8 × 8, over the {pixels} pixels inside the duck"
        );
        assert!(with < without, "view {k}: mips {with} vs level 0 {without}");
    }
}

/// The SPOC bunny's surface exported compressed (`KHR_mesh_quantization`,
/// `EXT_meshopt_compression`) and float: three.js's GLTFLoader with its meshopt decoder reads the
/// compressed file's vertices where trompe's loader puts them, and both files hold the same
/// triangles; the compressed one is at least 4 × smaller.
pub fn a_compressed_surface_reads_in_threejs_as_trompe_reads_it() {
    let dir = scratch("web_meshopt");
    let mut sizes = Vec::new();
    for geometry in ["float", "compressed"] {
        let json = dir.join(format!("bunny-{geometry}.json"));
        let out = super::common::trompe(&[
            "impostor",
            "bake",
            "assets/meshes/bunny.obj",
            "--resolution",
            "256",
            "--glb",
            "--geometry",
            geometry,
            "-o",
            json.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        sizes.push(std::fs::metadata(json.with_extension("glb")).unwrap().len());
    }
    println!(
        "bunny's SPOC surface at 256²: {} bytes float, {} bytes compressed ({:.1} × smaller)",
        sizes[0],
        sizes[1],
        sizes[0] as f64 / sizes[1] as f64
    );
    assert!(sizes[1] * 4 <= sizes[0], "{sizes:?}");
    let read = |name: &str| -> serde_json::Value {
        let glb = dir.join(format!("bunny-{name}.glb"));
        let out_json = dir.join(format!("three-{name}.json"));
        let run = std::process::Command::new("node")
            .arg(root().join("web/test/mesh.mjs"))
            .arg("--glb")
            .arg(&glb)
            .arg("--out")
            .arg(&out_json)
            .output()
            .expect("node runs");
        assert!(
            run.status.success(),
            "{}{}",
            String::from_utf8_lossy(&run.stdout),
            String::from_utf8_lossy(&run.stderr)
        );
        serde_json::from_str(&std::fs::read_to_string(out_json).unwrap()).unwrap()
    };
    let (float, compressed) = (read("float"), read("compressed"));
    assert_eq!(float["triangles"], compressed["triangles"]);
    let ours = trompe::geom::io::load(&dir.join("bunny-compressed.glb"))
        .unwrap()
        .mesh;
    let theirs: Vec<f32> = serde_json::from_value(compressed["positions"].clone()).unwrap();
    let uvs: Vec<f32> = serde_json::from_value(compressed["uvs"].clone()).unwrap();
    assert_eq!(theirs.len(), ours.positions.len() * 3);
    assert_eq!(compressed["triangles"], ours.triangles.len());
    let ours_uv = ours.uvs.as_ref().unwrap();
    let mut worst = (0.0f32, 0.0f32);
    for (i, p) in ours.positions.iter().enumerate() {
        let q = Vec3::from_slice(&theirs[3 * i..3 * i + 3]);
        worst.0 = worst.0.max(p.distance(q));
        // three.js keeps glTF's UV origin (top left) as trompe's loader does.
        let uv = glam::Vec2::from_slice(&uvs[2 * i..2 * i + 2]);
        worst.1 = worst.1.max((uv - ours_uv[i]).abs().max_element());
    }
    println!(
        "three.js against trompe: positions {:.2e} apart, UVs {:.2e}",
        worst.0, worst.1
    );
    assert!(worst.0 < 1e-5 && worst.1 < 1e-6, "{worst:?}");
}

/// The three.js runtime's dithered cross-fade: halfway through the layout's fade, the impostor
/// (`crossFade: true`) keeps exactly the pixels of its whole picture that the 4 × 4 Bayer rule
/// gives it, and a mesh under `crossFadeMaterial` (a sphere standing for the Duck) exactly the
/// others.
pub fn the_threejs_cross_fade_shares_the_pixels_by_the_layouts_rule() {
    let dir = scratch("web_threejs_fade");
    let glb = dir.join("duck.glb");
    let atlas = bake(&glb, &[]);
    let (layout, _) = trompe::octahedral::gltf::read_layout(&glb)
        .unwrap()
        .unwrap();
    let fade = layout.cross_fade.expect("the layout has a cross-fade");
    let halfway = (fade.start + fade.end) / 2.0;
    let lighting = lighting();
    let (eye, target, up) = around(&atlas, (45.0, 20.0), halfway / atlas.radius);
    let view = |impostor: bool, fade_impostor: bool, sphere: Option<bool>| {
        let mut v = view_json((eye, target, up), &lighting);
        v["fov_y"] = serde_json::json!(6.0);
        v["impostor"] = serde_json::json!(impostor);
        v["cross_fade"] = serde_json::json!(fade_impostor);
        if let Some(faded) = sphere {
            v["sphere"] = serde_json::json!({ "radius": 0.6 * atlas.radius, "cross_fade": faded });
        }
        v
    };
    let views = [
        view(true, true, None),
        view(true, false, None),
        view(false, false, Some(true)),
        view(false, false, Some(false)),
    ];
    let pictures = browser(&glb, &views, &dir);
    let backgrounds: Vec<Rgba> = pictures.iter().map(|p| p.get(0, 0)).collect();
    let drawn = |k: usize, x: u32, y: u32| pictures[k].get(x, y) != backgrounds[k];
    let impostor = |x, y| drawn(0, x, y);
    let whole = |x, y| drawn(1, x, y);
    let sphere = |x, y| drawn(2, x, y);
    let solid = |x, y| drawn(3, x, y);
    let (mut counts, distance) = ([0usize; 4], eye.distance(atlas.centre));
    for y in 0..SIZE {
        for x in 0..SIZE {
            // gl_FragCoord counts rows from the bottom.
            let rule = fade.impostor_draws((x, SIZE - 1 - y), distance);
            assert_eq!(
                impostor(x, y),
                whole(x, y) && rule,
                "impostor at ({x}, {y})"
            );
            assert_eq!(sphere(x, y), solid(x, y) && !rule, "mesh at ({x}, {y})");
            for (c, on) in
                counts
                    .iter_mut()
                    .zip([impostor(x, y), whole(x, y), sphere(x, y), solid(x, y)])
            {
                *c += usize::from(on);
            }
        }
    }
    println!(
        "cross-fade halfway ({distance:.2} units, fade {:.2}..{:.2}): the impostor keeps {} of {} pixels, the mesh {} of {}",
        fade.start, fade.end, counts[0], counts[1], counts[2], counts[3]
    );
    assert!(counts[1] > 1000 && counts[3] > 1000, "{counts:?}");
}
