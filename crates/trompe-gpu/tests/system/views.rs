//! View-dependent projective texturing from calibrated views on the GPU (images and depth maps
//! in texture arrays) against the library's CPU render of the same views: a view left out and
//! seen from its own camera, and a camera between two, for every weighting the GPU blends; the
//! same frame on repeated runs.

use glam::{DVec3, Vec3};
use std::path::PathBuf;
use trompe::camera::Pinhole;
use trompe::frame::metrics::flip;
use trompe::geom::Mesh;
use trompe::texturing::{BlendSettings, Holes, Weighting};
use trompe::views::ViewSet;
use trompe::views::capture::{CaptureSettings, capture};
use trompe::views::visibility::DepthMap;
use trompe_gpu::Gpu;
use trompe_gpu::views::GpuViews;

/// The Duck captured from a ring of 12 views at 160 × 120, with its depth maps, and a camera
/// between views 0 and 1, a little higher, at 320 × 240.
fn duck_views() -> (Mesh, ViewSet, Vec<DepthMap>, Pinhole) {
    let model = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/gltf/Duck.glb");
    let settings = CaptureSettings {
        count: 12,
        size: (160, 120),
        ..Default::default()
    };
    let set = capture(&model, &settings, &()).unwrap();
    let mesh = trompe::geom::io::load(&model).unwrap().mesh;
    let depth = DepthMap::of_all(&set.views, &mesh).unwrap();
    let (a, b) = (set.views[0].pose.centre(), set.views[1].pose.centre());
    let eye = (a + b) * 0.5 + DVec3::Y * 0.05 * a.length();
    let target = mesh.bounds().center();
    let between = Pinhole::look_at(eye.as_vec3(), target, Vec3::Y, 40.0, 320, 240).unwrap();
    (mesh, set, depth, between)
}

pub fn calibrated_views_render_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    let (mesh, set, depth, between) = duck_views();
    let views = set.views.as_slice();
    for weighting in [
        Weighting::Ulr { beta: 0.1 },
        Weighting::Vdtm,
        Weighting::ViewMap,
        Weighting::BestFace,
    ] {
        let settings = BlendSettings {
            weighting,
            holes: Holes::Fill(glam::Vec4::new(1.0, 0.0, 1.0, 1.0)),
            ..BlendSettings::default()
        };
        // View 3 left out and seen from its own camera (leave-one-out), then the new camera.
        for (name, camera, exclude) in [
            ("view 3 left out", views[3].pinhole(), Some(3)),
            ("between views 0 and 1", between.clone(), None),
        ] {
            let cpu =
                trompe::views::blend::render(&camera, &mesh, views, &depth, &settings, exclude)
                    .unwrap();
            let on_gpu = GpuViews::new(gpu, &mesh, (views, &depth), &settings, exclude)
                .unwrap()
                .render(&camera)
                .unwrap();
            let f = flip(&cpu.image, &on_gpu.image, None).unwrap();
            println!(
                "{} at {name}: mean FLIP {f:.5}; covered {} / {}, holes {} / {}",
                weighting.name(),
                on_gpu.covered,
                cpu.covered,
                on_gpu.holes,
                cpu.holes
            );
            // The goal: mean FLIP ≤ 0.01 against the CPU twin.
            assert!(f <= 0.01, "{} at {name}: FLIP {f}", weighting.name());
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

pub fn the_same_views_render_the_same_bits_on_repeated_runs(gpu: &Gpu) {
    let (mesh, set, depth, between) = duck_views();
    let settings = BlendSettings::default();
    let uploaded = GpuViews::new(gpu, &mesh, (&set.views, &depth), &settings, None).unwrap();
    let first = uploaded.render(&between).unwrap();
    let again = uploaded.render(&between).unwrap();
    assert!(first.covered > 10_000, "{} pixels covered", first.covered);
    assert!(
        again.image == first.image,
        "a repeated run changed the frame"
    );
}
