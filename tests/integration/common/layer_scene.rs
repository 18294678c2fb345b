//! The layer-test scene: a few objects on a ground plane, its captured views and its layers,
//! shared by the layers' tests and the Krita test.

use std::path::PathBuf;
use trompe::layers::{self, BuildSettings, LayerSet};
use trompe::scene::Scene;
use trompe::views::CalibratedView;
use trompe::views::capture::{CaptureSettings, capture_of};

/// A small scene of several objects on a ground plane.
pub fn scene() -> Scene {
    let text = r#"
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
mesh = "../assets/gltf/Duck.glb"
fit = 0.3
translate = [0.1, 0.0, 0.25]
[[object]]
name = "ball"
shape = "sphere"
fit = 0.2
translate = [-0.25, 0.0, 0.1]
material = { type = "diffuse", color = [0.8, 0.4, 0.3] }
"#;
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/layers-test.toml");
    Scene::from_toml(text, &path).expect("the test scene")
}

pub fn captured(count: usize) -> (Scene, Vec<CalibratedView>) {
    let scene = scene();
    let settings = CaptureSettings {
        count,
        size: (160, 120),
        distance: 1.4,
        fov_y: 50.0,
        ..CaptureSettings::default()
    };
    let views = capture_of(scene.clone(), &settings, &())
        .expect("captured")
        .views;
    (scene, views)
}

pub fn built(scene: &Scene, views: &[CalibratedView], settings: &BuildSettings) -> LayerSet {
    let (meshes, names) = layers::scene_objects(scene).expect("objects");
    layers::build(meshes, names, views, settings, &()).expect("built")
}
