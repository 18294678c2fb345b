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
    let scene = field();
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

/// The engines' shader places each copy by its own similarity: the field of ducks moved, turned
/// (about the sun's direction, so the light falls alike) and scaled, seen from the camera moved
/// with it, is the same frame; and the depth-only entry (`fs_depth`, a shadow map's) keeps
/// exactly the pixels the G-buffer entry keeps, at the same depth.
pub fn instances_moved_turned_and_scaled_and_the_depth_only_entry_draw_what_the_scene_draws(
    gpu: &Gpu,
) {
    use glam::{Quat, Vec3};
    use trompe::camera::Pinhole;
    use trompe::frame::NO_OBJECT;
    use trompe::scene::{Light, Lighting};
    use trompe_gpu::octahedral::{Entry, GpuAtlases, Similarity};
    let scene = field();
    let t = scene.render.time;
    let baked =
        trompe::octahedral::scene::SceneAtlases::bake(&scene, t, small().octahedral_bake(), &())
            .unwrap();
    let sun = Vec3::new(0.3, 1.0, 0.4).normalize();
    let lighting = Lighting {
        environment: trompe::frame::envmap::EnvMap::constant(Vec3::splat(0.3)),
        light: Some(Light {
            direction: sun,
            irradiance: Vec3::splat(2.5),
        }),
    };
    let mut atlases = GpuAtlases::new(gpu, &baked, &lighting, &scene.render).unwrap();
    let c = &scene.camera;
    let camera = |m: Similarity| {
        Pinhole::look_at(
            m.apply(c.position),
            m.apply(c.look_at),
            m.rotation * c.up,
            c.fov_y,
            320,
            240,
        )
        .unwrap()
        .with_near(c.near * f64::from(m.scale))
    };
    let here = atlases.frame(&camera(Similarity::IDENTITY)).unwrap();
    let depth = atlases
        .depth(&camera(Similarity::IDENTITY), Entry::GBuffer)
        .unwrap();
    let depth_only = atlases
        .depth(&camera(Similarity::IDENTITY), Entry::DepthOnly)
        .unwrap();
    // The depth-only entry: the same pixels, the same depths, bit for bit.
    assert!(
        depth_only == depth,
        "the depth-only entry drew another depth"
    );
    let kept = depth.pixels().iter().filter(|&&d| d > 0.0).count();
    let ids = (here.object_id.pixels().iter())
        .filter(|&&id| id != NO_OBJECT)
        .count();
    assert_eq!(kept, ids, "depth kept where no object was drawn");
    assert!(kept > 10_000, "{kept} pixels drawn");
    // Moved, turned and scaled.
    let m = Similarity {
        rotation: Quat::from_axis_angle(sun, 1.3),
        scale: 1.6,
        translation: Vec3::new(2.0, -1.0, 3.0),
    };
    atlases.place(m);
    let moved = atlases.frame(&camera(m)).unwrap();
    let same = (here.object_id.pixels().iter())
        .zip(moved.object_id.pixels())
        .filter(|(a, b)| a == b)
        .count();
    let share = same as f64 / here.object_id.pixels().len() as f64;
    let flip = trompe::frame::metrics::flip(&here.color, &moved.color, None).unwrap();
    println!(
        "moved, turned and scaled: {:.3} % of ids the same, FLIP {flip:.5}",
        100.0 * share
    );
    assert!(share >= 0.999, "{share}");
    assert!(flip <= 0.005, "{flip}");
    // Not a tautology: the copies moved without the camera are elsewhere.
    let elsewhere = atlases.frame(&camera(Similarity::IDENTITY)).unwrap();
    assert!(elsewhere.object_id != here.object_id);
}

/// The WGSL runtime's dithered cross-fade (`lod_impostor_draws`) on `scenes/field.toml`, its
/// copies spread over the fade band: a pixel shows a copy only where the 4 × 4 Bayer rule gives
/// it to the impostor at that copy's distance, and every pixel the rule gives to the copy that
/// is in front without the fade still shows it.
pub fn the_cross_fade_draws_each_copys_share_of_the_bayer_pattern(gpu: &Gpu) {
    use trompe::frame::NO_OBJECT;
    use trompe::octahedral::CrossFade;
    use trompe::octahedral::lod::Dither;
    use trompe_gpu::octahedral::GpuAtlases;
    let scene = field();
    let t = scene.render.time;
    let baked =
        trompe::octahedral::scene::SceneAtlases::bake(&scene, t, small().octahedral_bake(), &())
            .unwrap();
    let lighting = trompe::scene::Lighting {
        environment: trompe::frame::envmap::EnvMap::constant(glam::Vec3::splat(0.3)),
        light: None,
    };
    let mut atlases = GpuAtlases::new(gpu, &baked, &lighting, &scene.render).unwrap();
    let c = &scene.camera;
    let camera =
        trompe::camera::Pinhole::look_at(c.position, c.look_at, c.up, c.fov_y, 320, 240).unwrap();
    let eye = camera.position().as_vec3();
    let centres: Vec<_> = baked.atlases().map(|a| a.centre).collect();
    let distance: Vec<f32> = (baked.placed().iter())
        .map(|p| eye.distance(centres[p.atlas] + p.offset))
        .collect();
    let near = distance.iter().copied().fold(f32::MAX, f32::min);
    let far = distance.iter().copied().fold(0.0, f32::max);
    let fade = CrossFade {
        start: near,
        end: far,
        dither: Dither::Bayer4,
    };
    let whole = atlases.frame(&camera).unwrap();
    atlases.cross_fade(Some(fade));
    let faded = atlases.frame(&camera).unwrap();
    let w = whole.object_id.width();
    let (mut shown, mut kept) = (0usize, 0usize);
    for (k, (&before, &after)) in (whole.object_id.pixels().iter())
        .zip(faded.object_id.pixels())
        .enumerate()
    {
        let pixel = ((k % w as usize) as u32, (k / w as usize) as u32);
        if after != NO_OBJECT {
            shown += 1;
            let d = distance[after as usize];
            assert!(
                fade.impostor_draws(pixel, d),
                "object {after} drawn at {pixel:?}"
            );
        }
        if before != NO_OBJECT && fade.impostor_draws(pixel, distance[before as usize]) {
            kept += 1;
            assert_eq!(after, before, "at {pixel:?}");
        }
    }
    let all = whole
        .object_id
        .pixels()
        .iter()
        .filter(|&&id| id != NO_OBJECT)
        .count();
    println!(
        "cross-fade over {near:.2}..{far:.2}: {shown} of {all} pixels drawn, {kept} kept by the rule"
    );
    assert!(shown < all && kept > all / 10, "{shown}, {kept}, {all}");
}

/// `scenes/field.toml`: twelve ducks, a mirror ball, a ground.
fn field() -> trompe::scene::Scene {
    let (_, scene) = shipped_scenes()
        .into_iter()
        .find(|(p, _)| p.ends_with("field.toml"))
        .expect("scenes/field.toml");
    scene
}
