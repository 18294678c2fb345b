//! Rendering from master textures on the GPU (one texture array, one atlas point a pixel)
//! against the library's CPU render of the same masters: at an exemplar's camera and between
//! two, for every weighting the GPU blends; the same frame on repeated runs; what the GPU does
//! not blend refused before any work.

use glam::{DVec3, Vec3};
use std::path::PathBuf;
use trompe::camera::Pinhole;
use trompe::geom::Mesh;
use trompe::master::{DEFAULT_SCALE, Encoding, encode_views};
use trompe::texturing::{BlendSettings, Weighting};
use trompe::views::capture::{CaptureSettings, capture};
use trompe_gpu::Gpu;
use trompe_gpu::master::GpuMasters;

/// The Duck captured from a ring of 12 views at 160 × 120 and encoded, and three cameras: view
/// 3's own, one between views 0 and 1, a little higher, and the same at 48 × 36.
fn duck_encoding() -> (Mesh, Encoding, [Pinhole; 3]) {
    let model = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/gltf/Duck.glb");
    let settings = CaptureSettings {
        count: 12,
        size: (160, 120),
        ..Default::default()
    };
    let set = capture(&model, &settings, &()).unwrap();
    let mesh = trompe::geom::io::load(&model).unwrap().mesh;
    let enc = encode_views(&mesh, &set.views, DEFAULT_SCALE, &()).unwrap();
    let (a, b) = (set.views[0].pose.centre(), set.views[1].pose.centre());
    let eye = (a + b) * 0.5 + DVec3::Y * 0.05 * a.length();
    let between = Pinhole::look_at(
        eye.as_vec3(),
        mesh.bounds().center(),
        Vec3::Y,
        40.0,
        320,
        240,
    )
    .unwrap();
    // The same, far smaller: a pixel spans several texels of the masters.
    let small =
        Pinhole::look_at(eye.as_vec3(), mesh.bounds().center(), Vec3::Y, 40.0, 48, 36).unwrap();
    (mesh, enc, [set.views[3].pinhole(), between, small])
}

pub fn master_textures_render_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    let (mesh, enc, cameras) = duck_encoding();
    let pinholes = enc.pinholes();
    let masters = (
        &enc.atlas.layout,
        pinholes.as_slice(),
        enc.masters.as_slice(),
    );
    for (settings, weighting) in crate::every_blend() {
        let uploaded = GpuMasters::new(gpu, &mesh, masters, &settings).unwrap();
        let names = ["view 3", "between views 0 and 1", "between, 48 × 36"];
        for (name, camera) in names.iter().zip(&cameras) {
            let cpu = trompe::master::render::render(
                camera, &mesh, masters.0, masters.1, masters.2, &settings,
            )
            .unwrap();
            let on_gpu = uploaded.render(camera).unwrap();
            crate::blends_agree(&format!("{weighting} at {name}"), &cpu, &on_gpu);
        }
    }
}

pub fn the_same_masters_render_the_same_bits_on_repeated_runs(gpu: &Gpu) {
    let (mesh, enc, cameras) = duck_encoding();
    let pinholes = enc.pinholes();
    let masters = (
        &enc.atlas.layout,
        pinholes.as_slice(),
        enc.masters.as_slice(),
    );
    let settings = BlendSettings::default();
    let uploaded = GpuMasters::new(gpu, &mesh, masters, &settings).unwrap();
    let first = uploaded.render(&cameras[1]).unwrap();
    let again = uploaded.render(&cameras[1]).unwrap();
    let fresh = GpuMasters::new(gpu, &mesh, masters, &settings)
        .unwrap()
        .render(&cameras[1])
        .unwrap();
    assert!(first.covered > 10_000, "{} pixels covered", first.covered);
    for other in [&again, &fresh] {
        assert!(
            other.image == first.image,
            "a repeated run changed the frame"
        );
    }
}

pub fn what_the_gpu_does_not_blend_is_refused_before_any_work(gpu: &Gpu) {
    let (mesh, enc, _) = duck_encoding();
    let pinholes = enc.pinholes();
    let masters = (
        &enc.atlas.layout,
        pinholes.as_slice(),
        enc.masters.as_slice(),
    );
    let refused = |settings: BlendSettings, says: &str| {
        let error = match GpuMasters::new(gpu, &mesh, masters, &settings) {
            Ok(_) => panic!("{settings:?} was accepted"),
            Err(e) => e.to_string(),
        };
        assert!(
            error.contains(says) && error.contains("--device cpu"),
            "{error}"
        );
    };
    let base = BlendSettings::default();
    refused(
        BlendSettings {
            weighting: Weighting::BestFace,
            seamless: true,
            ..base
        },
        "seamless",
    );
    refused(BlendSettings { k: 65, ..base }, "at most 64");
    // Masters of another mesh: the library's own refusal.
    let other = trompe::geom::cube();
    let error = match GpuMasters::new(gpu, &other, masters, &base) {
        Ok(_) => panic!("a layout of another mesh was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(error.contains("packing map"), "{error}");
}
