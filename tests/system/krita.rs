//! Krita, the painting program an artist edits the layers in, opens the OpenRaster files trompe
//! writes as written, and what it saves renders the same (paper 4 §4.2: the layers are edited in
//! an image editor).

use crate::common;
use common::layer_scene::{built, captured};
use common::scratch;
use std::path::Path;
use trompe::frame::io::to_srgb8;
use trompe::layers::{self, BuildSettings, ora};
use trompe::texturing::BlendSettings;

/// Whether Krita and `xvfb-run` are installed.
pub fn installed() -> bool {
    common::has_command("krita") && common::has_command("xvfb-run")
}

/// Runs Krita headless (under `xvfb-run`) on `input`, exporting `output`.
fn krita(input: &Path, output: &Path) {
    // Krita starting under a fresh virtual display can lose the race with the display's own
    // start on a loaded machine; a second and third start are made before giving up.
    let mut errors = String::new();
    for _ in 0..3 {
        let o = std::process::Command::new("xvfb-run")
            .args(["-a", "krita"])
            .arg(input)
            .args(["--export", "--export-filename"])
            .arg(output)
            .output()
            .expect("krita runs");
        if output.is_file() {
            return;
        }
        errors.push_str(&common::stderr(&o));
    }
    panic!("krita wrote nothing in three starts: {errors}");
}

pub fn krita_opens_the_layers_as_written_and_what_it_saves_renders_the_same() {
    let (scene, views) = captured(2);
    let set = built(&scene, &views, &BuildSettings::default());
    let dir = scratch("layers-krita");
    layers::file::save(&dir, &set).expect("saved");
    let file = dir.join(layers::file::ora_name(&set.views[0].name));
    // Krita's composite of the stack is the photograph's.
    let png = dir.join("krita.png");
    krita(&file, &png);
    let flat = trompe::frame::io::read_png(&png).expect("krita's png");
    let composite = ora::read(&file)
        .expect("read")
        .composite()
        .expect("composite");
    assert_eq!(to_srgb8(&flat), to_srgb8(&composite));
    // Krita's own OpenRaster file (nested stack, its own entry names) textures the same frame.
    let (meshes, names) = layers::scene_objects(&scene).expect("objects");
    let cam = scene.camera.at(0.0).expect("camera");
    let render = |dir: &Path| {
        let set = layers::file::load(dir, meshes.clone(), names.clone()).expect("loaded");
        layers::render::render(&cam, &set, &BlendSettings::default()).expect("rendered")
    };
    let before = render(&dir);
    let saved = dir.join("krita.ora");
    krita(&file, &saved);
    std::fs::copy(&saved, &file).expect("replaced");
    assert_eq!(before.image.pixels(), render(&dir).image.pixels());
}
