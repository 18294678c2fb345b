//! The layer-test scene: a few objects on a ground plane, its captured views and its layers,
//! shared by the layers' tests and the Krita test.

use std::path::PathBuf;
use trompe::layers::{self, BuildSettings, LayerSet};
use trompe::scene::Scene;
use trompe::views::CalibratedView;
use trompe::views::capture::{CaptureSettings, capture_of};

/// A small scene of several objects on a ground plane (`tests/fixtures/layers/scene.toml`).
pub fn scene() -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/layers/scene.toml");
    Scene::load(&path).expect("the test scene")
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
