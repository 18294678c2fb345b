//! The `octahedral` method on the GPU (the engines' shader, instanced, then shaded) against its
//! CPU twin, on every shipped scene; a field of instances drawn from one atlas; the same frames
//! on repeated runs.

use crate::trace::{agrees_on_scenes, shipped_scenes};
use trompe::methods::{MethodKind, MethodSettings};
use trompe_gpu::{DeviceRenderer, Gpu};

/// Atlases small enough to bake every shipped scene's objects twice in a test.
fn small() -> MethodSettings {
    MethodSettings {
        octahedral_frames: 8,
        octahedral_frame_size: 64,
        ..MethodSettings::default()
    }
}

pub fn every_shipped_scene_draws_octahedral_impostors_on_the_gpu_as_on_the_cpu(gpu: &Gpu) {
    // The same alpha test and depth rule on both devices; half-float maps and the GPU's bilinear
    // filter move silhouettes by a fraction of a texel: ≥ 99.5 % of ids.
    let compared = agrees_on_scenes(gpu, (MethodKind::Octahedral, &small()), 0.995, &|_| true);
    assert!(compared >= 10, "{compared} scenes compared");
}

/// `scenes/field.toml`'s twelve ducks are one atlas drawn twelve times (one instanced draw),
/// each copy with its own id, and the frame is the same on repeated runs; kept across frames
/// while nothing moves.
pub fn a_field_of_instances_is_one_atlas_drawn_once_a_copy_on_the_gpu(gpu: &Gpu) {
    let (_, scene) = shipped_scenes()
        .into_iter()
        .find(|(p, _)| p.ends_with("field.toml"))
        .expect("scenes/field.toml");
    let t = scene.render.time;
    let mut renderer =
        DeviceRenderer::new(&scene, MethodKind::Octahedral, small(), Some(gpu)).unwrap();
    let first = renderer.frame(t, None, &()).unwrap();
    assert!(
        first.report.contains("baked 3 atlases") && first.report.contains("drawing 14 objects"),
        "{}",
        first.report
    );
    let ducks: std::collections::BTreeSet<u32> = (first.frame.object_id.pixels().iter())
        .copied()
        .filter(|&id| id < 12)
        .collect();
    assert_eq!(ducks.len(), 12, "ducks seen: {ducks:?}");
    let again = renderer.frame(t, None, &()).unwrap();
    assert!(again.report.contains("kept 3 atlases"), "{}", again.report);
    let fresh = DeviceRenderer::new(&scene, MethodKind::Octahedral, small(), Some(gpu))
        .and_then(|mut r| r.frame(t, None, &()))
        .unwrap();
    for other in [&again.frame, &fresh.frame] {
        assert!(
            other.color == first.frame.color && other.object_id == first.frame.object_id,
            "a repeated run changed the frame"
        );
    }
}
