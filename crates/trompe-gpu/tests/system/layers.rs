//! Layered projective rendering on the GPU (every image layer in texture arrays, each object
//! through its layer's sub-frustum) against the library's CPU render of the same layer set: a
//! scene of several objects that hide each other, from a captured view and between two, for
//! every weighting the GPU blends.

use glam::{DVec3, Vec3};
use std::path::PathBuf;
use trompe::camera::Pinhole;
use trompe::frame::metrics::flip;
use trompe::layers::{self, BuildSettings};
use trompe::scene::Scene;
use trompe::texturing::{BlendSettings, Holes, Weighting};
use trompe::views::capture::{CaptureSettings, capture_of};
use trompe_gpu::Gpu;
use trompe_gpu::layers::GpuLayers;

/// Every weighting the GPU blends, and the per-point ones again prefiltered to the pixel.
const WEIGHTINGS: [(Weighting, bool); 6] = [
    (Weighting::Ulr { beta: 0.1 }, false),
    (Weighting::Vdtm, false),
    (Weighting::ViewMap, false),
    (Weighting::BestFace, false),
    (Weighting::Ulr { beta: 0.1 }, true),
    (Weighting::ViewMap, true),
];

/// A box behind the Duck beside a ball on a ground plane: objects that hide each other, so a
/// view has several visibility layers.
const SCENE: &str = r#"
[camera]
position = [0.9, 0.7, 1.4]
look_at = [0.0, 0.15, 0.0]
fov_y = 45.0
resolution = [160, 120]
[light]
direction = [0.4, 1.0, 0.6]
intensity = 2.51
[render]
background = [0.3, 0.3, 0.35]
[[object]]
name = "ground"
shape = "plane"
scale = 1.6
material = { type = "diffuse", color = [0.5, 0.5, 0.45] }
[[object]]
name = "box"
shape = "cube"
fit = 0.4
translate = [0.0, 0.0, -0.3]
rotate = [0.0, 25.0, 0.0]
material = { type = "diffuse", color = [0.3, 0.5, 0.8] }
[[object]]
name = "duck"
mesh = "assets/gltf/Duck.glb"
fit = 0.3
translate = [0.1, 0.0, 0.25]
[[object]]
name = "ball"
shape = "sphere"
fit = 0.2
translate = [-0.25, 0.0, 0.1]
material = { type = "diffuse", color = [0.8, 0.4, 0.3] }
"#;

pub fn image_layers_render_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let scene = Scene::from_toml(SCENE, &root.join("layers-gpu-test.toml")).unwrap();
    let settings = CaptureSettings {
        count: 6,
        size: (160, 120),
        distance: 1.4,
        fov_y: 50.0,
        ..CaptureSettings::default()
    };
    let views = capture_of(scene.clone(), &settings, &()).unwrap().views;
    let (meshes, names) = layers::scene_objects(&scene).unwrap();
    let set = layers::build(meshes, names, &views, &BuildSettings::default(), &()).unwrap();
    let most = set.reports.iter().map(|r| r.visibility_layers).max();
    assert!(most >= Some(2), "visibility layers: {most:?}");
    let (a, b) = (views[0].pose.centre(), views[1].pose.centre());
    let eye = (a + b) * 0.5 + DVec3::Y * 0.1;
    let target = Vec3::new(0.0, 0.15, 0.0);
    let between = Pinhole::look_at(eye.as_vec3(), target, Vec3::Y, 45.0, 320, 240).unwrap();
    // The same, far smaller: a pixel spans several texels of the layers.
    let small = Pinhole::look_at(eye.as_vec3(), target, Vec3::Y, 45.0, 48, 36).unwrap();
    for (weighting, prefilter) in WEIGHTINGS {
        let settings = BlendSettings {
            weighting,
            prefilter,
            holes: Holes::Fill(glam::Vec4::new(1.0, 0.0, 1.0, 1.0)),
            ..BlendSettings::default()
        };
        let weighting = format!(
            "{}{}",
            weighting.name(),
            if prefilter { ", prefiltered" } else { "" }
        );
        let uploaded = GpuLayers::new(gpu, &set, &settings).unwrap();
        for (name, camera) in [
            ("view 2", views[2].pinhole()),
            ("between views 0 and 1", between.clone()),
            ("between, 48 × 36", small.clone()),
        ] {
            let cpu = layers::render::render(&camera, &set, &settings).unwrap();
            let on_gpu = uploaded.render(&camera).unwrap();
            let f = flip(&cpu.image, &on_gpu.image, None).unwrap();
            let worst = cpu
                .image
                .pixels()
                .iter()
                .zip(on_gpu.image.pixels())
                .map(|(a, b)| (*a - *b).abs().max_element())
                .fold(0.0f32, f32::max);

            println!(
                "{} at {name}: mean FLIP {f:.5}, largest channel difference {worst:.5}; \
                 covered {} / {}, holes {} / {}",
                weighting, on_gpu.covered, cpu.covered, on_gpu.holes, cpu.holes
            );
            // The goal: mean FLIP ≤ 0.01 against the CPU twin.
            assert!(f <= 0.01, "{weighting} at {name}: FLIP {f}");
            let covered_gap = on_gpu.covered.abs_diff(cpu.covered);
            assert!(
                covered_gap * 200 <= cpu.covered,
                "covered {covered_gap} apart"
            );
            let holes_gap = on_gpu.holes.abs_diff(cpu.holes);
            assert!(holes_gap * 200 <= cpu.covered, "holes {holes_gap} apart");
        }
    }
}

/// The `layered` method on the GPU (the library's layers of the scene photographed, blended on
/// the GPU, over the panorama) against the CPU's, on the shipped street (a truck, a bunny and a
/// duck that hide each other); its layers kept across frames.
pub fn the_layered_method_runs_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    use trompe::methods::{MethodKind, MethodSettings};
    let street = |scene: &Scene| scene.objects.len() == 4 && scene.objects[1].name == "truck";
    let compared = crate::trace::agrees_on_scenes(
        gpu,
        (MethodKind::Layered, &MethodSettings::default()),
        0.999,
        &street,
    );
    assert_eq!(compared, 1, "the street alone");
    let scene = crate::trace::shipped_scenes()
        .into_iter()
        .map(|(_, s)| s)
        .find(|s| street(s))
        .expect("scenes/street.toml");
    let mut renderer = trompe_gpu::DeviceRenderer::new(
        &scene,
        MethodKind::Layered,
        MethodSettings::default(),
        Some(gpu),
    )
    .unwrap();
    let t = scene.render.time;
    let first = renderer.frame(t, None, &()).unwrap();
    let again = renderer.frame(t, None, &()).unwrap();
    let built =
        |f: &trompe::methods::MethodFrame| f.timings.0.iter().any(|(s, _)| *s == "build layers");
    assert!(
        built(&first) && !built(&again),
        "the layers are built once, then kept"
    );
    assert!(
        again.frame.color == first.frame.color,
        "a kept frame changed"
    );
}

/// The `projective` method on the GPU (the library's photographs of the scene projected whole,
/// hidden or not, paper 4's baseline) against the CPU's, on the shipped street.
pub fn the_projective_method_runs_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    use trompe::methods::{MethodKind, MethodSettings};
    let street = |scene: &Scene| scene.objects.len() == 4 && scene.objects[1].name == "truck";
    let compared = crate::trace::agrees_on_scenes(
        gpu,
        (MethodKind::Projective, &MethodSettings::default()),
        0.999,
        &street,
    );
    assert_eq!(compared, 1, "the street alone");
}
