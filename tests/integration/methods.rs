//! The one list of methods: every method that renders a scene makes a frame of a shipped scene
//! and a three-frame sequence of it through the same interface, the same on one and two
//! threads; the methods that cannot render a scene are refused with their reason.

use crate::common;

use trompe::frame::Frame;
use trompe::methods::{MethodError, MethodKind, MethodSettings, Renderer};
use trompe::scene::Scene;

/// Paper 1's Fig. 2 scene (a mirror ball moving through a teapot, over a ground plane), shrunk
/// to 64 × 48 pixels.
fn scene() -> Scene {
    let path = common::repo("scenes/intersecting.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let text = text.replace("resolution = [480, 360]", "resolution = [64, 48]");
    assert!(
        text.contains("[64, 48]"),
        "the scene's resolution line moved"
    );
    Scene::from_toml(&text, &path).unwrap_or_else(|e| panic!("{e}"))
}

/// Settings small enough for a test: small impostors, atlases, photographs and relief images.
fn settings() -> MethodSettings {
    let mut s = MethodSettings {
        impostor_resolution: 64,
        octahedral_frames: 8,
        octahedral_frame_size: 24,
        ..Default::default()
    };
    s.capture.size = (96, 72);
    s.relief.resolution = 48;
    s.relief.first_resolution = None;
    s
}

/// The frame's colour as bits, for exact comparison.
fn bits(frame: &Frame) -> Vec<u32> {
    frame
        .color
        .pixels()
        .iter()
        .flat_map(|c| c.to_array().map(f32::to_bits))
        .collect()
}

/// One frame at the scene's time, then three frames 1/30 s apart from a fresh renderer, on
/// `threads` threads.
fn frames(scene: &Scene, kind: MethodKind, threads: usize) -> (Vec<u32>, Vec<Vec<u32>>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let t0 = scene.render.time;
        let mut one = Renderer::new(scene, kind, settings()).unwrap();
        let single = one
            .frame(t0, None, &())
            .unwrap_or_else(|e| panic!("{kind}: {e}"));
        assert_eq!(single.frame.color.size(), (64, 48), "{kind}");
        let mut sequence = Renderer::new(scene, kind, settings()).unwrap();
        let three = (0..3)
            .map(|i| {
                let t = t0 + i as f32 / 30.0;
                let out = sequence
                    .frame(t, None, &())
                    .unwrap_or_else(|e| panic!("{kind} frame {i}: {e}"));
                bits(&out.frame)
            })
            .collect();
        (bits(&single.frame), three)
    })
}

#[test]
fn every_method_renders_a_frame_and_a_sequence_the_same_on_one_and_two_threads() {
    let scene = scene();
    let env = {
        // The panorama alone, along every pixel's ray: what a method that drew nothing shows.
        let camera = scene.camera.at(scene.render.time).unwrap();
        let mut f = Frame::new(64, 48).unwrap();
        for y in 0..48 {
            for x in 0..64 {
                let ray = camera.ray(glam::DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
                f.color.set(
                    x,
                    y,
                    scene.lighting.environment.radiance(ray.dir).extend(1.0),
                );
            }
        }
        bits(&f)
    };
    let mut tried = Vec::new();
    for kind in MethodKind::for_scenes() {
        let (single1, seq1) = frames(&scene, kind, 1);
        let (single2, seq2) = frames(&scene, kind, 2);
        assert!(
            single1 == single2,
            "{kind}: one frame differs between 1 and 2 threads"
        );
        assert!(
            seq1 == seq2,
            "{kind}: the sequence differs between 1 and 2 threads"
        );
        // The sequence's first frame is the single frame: preparing once changes nothing.
        assert!(
            seq1[0] == single1,
            "{kind}: a sequence's first frame is not the frame"
        );
        // The ball moves: the frames of the sequence are not all one — but for the methods
        // that photograph the scene on the first frame, which a still camera sees the same.
        // (Relief impostors are of the scene as it stood too, but its frames change as the
        // pipeline's impostors come into use: tests/integration/relief.rs follows them.)
        match kind {
            MethodKind::Layered | MethodKind::Projective => {
                assert!(seq1[0] == seq1[2], "{kind}: a still camera, another frame")
            }
            MethodKind::Relief => {}
            _ => assert!(seq1[0] != seq1[2], "{kind}: the sequence does not move"),
        }
        // Something of the scene is drawn over the panorama (4 floats a pixel).
        let drawn = single1
            .chunks(4)
            .zip(env.chunks(4))
            .filter(|(a, b)| a != b)
            .count();
        assert!(drawn > 64 * 48 / 4, "{kind}: only {drawn} pixels drawn");
        tried.push(kind.name());
    }
    assert_eq!(
        tried,
        [
            "trace",
            "impostor",
            "pinhole-impostor",
            "envmap",
            "raster",
            "c3rc",
            "layered",
            "relief",
            "octahedral",
            "projective"
        ]
    );
}

#[test]
fn methods_that_do_not_render_scenes_are_refused_with_their_reason() {
    let scene = scene();
    for kind in [MethodKind::Views, MethodKind::Master] {
        match Renderer::new(&scene, kind, MethodSettings::default()) {
            Err(MethodError::Refused { method, reason }) => {
                assert_eq!(method, kind);
                assert!(reason.contains("trompe"), "{reason}");
            }
            Err(e) => panic!("{kind}: {e}"),
            Ok(_) => panic!("{kind} renders a scene"),
        }
    }
}

#[test]
fn names_parse_back_and_bad_settings_are_refused_before_any_frame() {
    for kind in MethodKind::ALL {
        assert_eq!(kind.name().parse::<MethodKind>().unwrap(), kind);
        assert!(!kind.about().is_empty());
    }
    let e = "warp".parse::<MethodKind>().unwrap_err().to_string();
    assert!(e.contains("trace") && e.contains("relief"), "{e}");
    let scene = scene();
    let mut nan = settings();
    nan.relief.threshold = f64::NAN;
    let e = Renderer::new(&scene, MethodKind::Relief, nan)
        .err()
        .unwrap();
    assert!(e.to_string().contains("threshold"), "{e}");
    let mut spacing = settings();
    spacing.hybrid.spacing = Some(-1.0);
    let e = Renderer::new(&scene, MethodKind::C3rc, spacing)
        .err()
        .unwrap();
    assert!(e.to_string().contains("spacing"), "{e}");
}

#[test]
fn a_camera_given_to_a_frame_replaces_the_scenes_lens_too() {
    // The scene's camera with a real lens (barrel distortion), and the same camera without it.
    let intrinsics = "fx = 66.0\nfy = 66.0\ncx = 32.0\ncy = 24.0";
    let lensed = |lens: &str| {
        let path = common::repo("scenes/intersecting.toml");
        let text = std::fs::read_to_string(&path).unwrap();
        let text = text
            .replace("resolution = [480, 360]", "resolution = [64, 48]")
            .replace("fov_y = 40.0", &format!("{intrinsics}{lens}"));
        Scene::from_toml(&text, &path).unwrap_or_else(|e| panic!("{e}"))
    };
    let (with, without) = (
        lensed("\nmodel = \"SIMPLE_RADIAL\"\ndistortion = [-0.2]"),
        lensed(""),
    );
    let t = with.render.time;
    assert!(with.view(t).unwrap().lens.is_some());
    let pinhole = without.view(t).unwrap().camera;
    let frame = |scene: &Scene, camera| {
        let mut r = Renderer::new(scene, MethodKind::Trace, settings()).unwrap();
        bits(&r.frame(t, camera, &()).unwrap().frame)
    };
    let plain = frame(&without, None);
    assert_ne!(frame(&with, None), plain, "the lens bends the frame");
    assert_eq!(frame(&with, Some(pinhole)), plain);
}
