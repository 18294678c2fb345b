//! View-dependent projective texturing from calibrated views on the GPU (images and depth maps
//! in texture arrays) against the library's CPU render of the same views: a view left out and
//! seen from its own camera, and a camera between two, for every weighting the GPU blends; the
//! same frame on repeated runs.

use glam::{DVec3, Vec3};
use std::path::PathBuf;
use trompe::camera::Pinhole;
use trompe::geom::Mesh;
use trompe::texturing::BlendSettings;
use trompe::views::ViewSet;
use trompe::views::capture::{CaptureSettings, capture};
use trompe::views::visibility::DepthMap;
use trompe_gpu::Gpu;
use trompe_gpu::views::GpuViews;

/// The Duck captured from a ring of 12 views at 160 × 120, with its depth maps, and a camera
/// between views 0 and 1, a little higher, at 320 × 240 and at 48 × 36.
fn duck_views() -> (Mesh, ViewSet, Vec<DepthMap>, [Pinhole; 2]) {
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
    // The same, far smaller: a pixel spans several texels of the views.
    let small = Pinhole::look_at(eye.as_vec3(), target, Vec3::Y, 40.0, 48, 36).unwrap();
    (mesh, set, depth, [between, small])
}

pub fn calibrated_views_render_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    let (mesh, set, depth, [between, small]) = duck_views();
    let views = set.views.as_slice();
    for (settings, weighting) in crate::every_blend() {
        // View 3 left out and seen from its own camera (leave-one-out), then the new camera.
        for (name, camera, exclude) in [
            ("view 3 left out", views[3].pinhole(), Some(3)),
            ("between views 0 and 1", between.clone(), None),
            ("between, 48 × 36", small.clone(), None),
        ] {
            let cpu =
                trompe::views::blend::render(&camera, &mesh, views, &depth, &settings, exclude)
                    .unwrap();
            let on_gpu = GpuViews::new(gpu, &mesh, (views, &depth), &settings, exclude)
                .unwrap()
                .render(&camera)
                .unwrap();
            crate::blends_agree(&format!("{weighting} at {name}"), &cpu, &on_gpu);
        }
    }
}

/// The prefilter is at work where a pixel spans several texels: the far smaller camera's
/// prefiltered frame is not the plain one, and the GPU's is the CPU's prefiltered frame.
pub fn the_gpu_prefilters_as_the_cpu_where_a_pixel_spans_texels(gpu: &Gpu) {
    let (mesh, set, depth, [_, small]) = duck_views();
    let render = |prefilter: bool| {
        let settings = BlendSettings {
            prefilter,
            ..BlendSettings::default()
        };
        let cpu = trompe::views::blend::render(&small, &mesh, &set.views, &depth, &settings, None)
            .unwrap();
        let on_gpu = GpuViews::new(gpu, &mesh, (&set.views, &depth), &settings, None)
            .unwrap()
            .render(&small)
            .unwrap();
        (cpu.image, on_gpu.image)
    };
    let ((plain_cpu, plain_gpu), (filtered_cpu, filtered_gpu)) = (render(false), render(true));
    let mean_difference = |a: &trompe::frame::Image<glam::Vec4>,
                           b: &trompe::frame::Image<glam::Vec4>| {
        let sum: f32 = a
            .pixels()
            .iter()
            .zip(b.pixels())
            .map(|(p, q)| (*p - *q).abs().truncate().element_sum())
            .sum();
        sum / (3 * a.pixels().len()) as f32
    };
    let filtering = mean_difference(&plain_cpu, &filtered_cpu);
    let devices = mean_difference(&filtered_cpu, &filtered_gpu);
    println!(
        "48 × 36: the prefilter moves the CPU frame by {filtering:.5} a channel; the devices' \
         prefiltered frames differ by {devices:.6} (plain: {:.6})",
        mean_difference(&plain_cpu, &plain_gpu)
    );
    assert!(filtering > 20.0 * devices, "{filtering} against {devices}");
}

pub fn the_same_views_render_the_same_bits_on_repeated_runs(gpu: &Gpu) {
    let (mesh, set, depth, [between, _]) = duck_views();
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
