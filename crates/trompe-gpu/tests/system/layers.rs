//! Layered projective rendering on the GPU (every image layer in texture arrays, each object
//! through its layer's sub-frustum) against the library's CPU render of the same layer set: a
//! scene of several objects that hide each other, from a captured view and between two, for
//! every weighting the GPU blends.

use glam::{DVec3, Vec3};
use std::path::PathBuf;
use trompe::camera::Pinhole;
use trompe::layers::{self, BuildSettings};
use trompe::scene::Scene;
use trompe::views::capture::{CaptureSettings, capture_of};
use trompe_gpu::Gpu;
use trompe_gpu::layers::GpuLayers;

pub fn image_layers_render_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    // A box behind the Duck beside a ball on a ground plane: objects that hide each other, so
    // a view has several visibility layers.
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let scene = Scene::load(&root.join("tests/fixtures/layers/scene.toml")).unwrap();
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
    for (settings, weighting) in crate::every_blend() {
        let uploaded = GpuLayers::new(gpu, &set, &settings).unwrap();
        for (name, camera) in [
            ("view 2", views[2].pinhole()),
            ("between views 0 and 1", between.clone()),
            ("between, 48 × 36", small.clone()),
        ] {
            let cpu = layers::render::render(&camera, &set, &settings).unwrap();
            let on_gpu = uploaded.render(&camera).unwrap();
            crate::blends_agree(&format!("{weighting} at {name}"), &cpu, &on_gpu);
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
