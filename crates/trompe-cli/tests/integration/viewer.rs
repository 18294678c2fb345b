//! The interactive viewer's state, driven without a display: scripted input replays the same
//! frames, the controls move the camera as they say, a saved camera reproduces the view (the
//! real window under a virtual X server is tested in `tests/system/`).

use crate::common;
use common::{scratch, stderr, trompe};
use std::path::Path;
use trompe::frame::metrics;
use trompe::scene::Scene;
use trompe_cli::viewer::script::Script;
use trompe_cli::viewer::{Input, Key, Viewer};

fn scene(name: &str) -> Scene {
    let p = common::root().join("scenes").join(name);
    Scene::load(&p).unwrap_or_else(|e| panic!("{e}"))
}

const SIZE: (u32, u32) = (96, 72);

/// The frames a script gives, `frames` steps of 1/30 s.
fn replay(scene: &Scene, script: &Script, frames: u32) -> Vec<trompe::Image<trompe::Rgba>> {
    let mut viewer = Viewer::new(scene, 64, None).unwrap();
    let dt = 1.0 / 30.0;
    (0..frames)
        .map(|i| {
            for input in script.between(i as f32 * dt, (i + 1) as f32 * dt) {
                viewer.input(input);
            }
            let image = viewer.frame(SIZE, 1.0).unwrap().image;
            viewer.step(dt);
            image
        })
        .collect()
}

#[test]
fn a_script_replays_the_same_frames_on_one_and_two_threads_and_across_runs() {
    let s = scene("intersecting.toml");
    let script = Script::parse(
        "0 down W\n0.1 up W\n0.1 look 40 -10\n0.12 tap 3\n0.15 tap V\n0.2 tap 2\n",
        Path::new("keys"),
    )
    .unwrap();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| replay(&s, &script, 8))
    };
    let (one, two, again) = (run(1), run(2), run(2));
    assert!(one == two, "1 and 2 threads differ");
    assert!(two == again, "two runs differ");
    // The inputs show: the camera moved and the ball rolled.
    assert!(one[0] != one[7]);
}

#[test]
fn a_second_forward_at_speed_s_moves_the_eye_by_s() {
    let s = scene("teapot-in-bunny.toml");
    let mut viewer = Viewer::new(&s, 64, None).unwrap();
    let (start, speed) = (viewer.camera().eye, viewer.speed());
    viewer.input(Input::Down(Key::Forward));
    let dt = 1.0 / 30.0;
    for _ in 0..30 {
        viewer.step(dt);
    }
    let moved = viewer.camera().eye.distance(start);
    assert!(
        (moved - speed).abs() <= speed * dt,
        "moved {moved}, speed {speed}"
    );
    // Along the view direction.
    let along = (viewer.camera().eye - start)
        .normalize()
        .dot(viewer.camera().direction());
    assert!(along > 0.9999, "{along}");
}

#[test]
fn orbiting_keeps_the_distance_to_the_target() {
    let s = scene("teapot-in-bunny.toml");
    let mut viewer = Viewer::new(&s, 64, None).unwrap();
    viewer.input(Input::Down(Key::Orbit));
    let c = *viewer.camera();
    let distance = c.eye.distance(c.target);
    viewer.input(Input::Down(Key::Right));
    viewer.input(Input::Down(Key::Up));
    for _ in 0..45 {
        viewer.step(1.0 / 30.0);
    }
    viewer.input(Input::Look(120.0, 30.0));
    let c2 = *viewer.camera();
    assert!(c2.eye.distance(c.eye) > 0.1 * distance, "the eye moved");
    assert!((c2.eye.distance(c2.target) - distance).abs() < 1e-4 * distance);
    assert_eq!(c2.target, c.target);
}

#[test]
fn a_saved_camera_block_parses_as_a_scene_camera_and_reproduces_the_view() {
    let s = scene("teapot-in-bunny.toml");
    let mut viewer = Viewer::new(&s, 64, None).unwrap();
    viewer.input(Input::Look(200.0, 40.0));
    viewer.input(Input::Down(Key::Left));
    viewer.step(0.4);
    let block = viewer.camera_block(SIZE);
    let text = format!("{block}\n[[object]]\nshape = \"cube\"\n");
    let parsed = Scene::from_toml(&text, Path::new("saved.toml")).unwrap();
    let from_block = parsed.camera.at(0.0).unwrap();
    let live = viewer.camera().pinhole(SIZE).unwrap();
    for p in [(0.5, 0.5), (48.0, 36.0), (95.5, 71.5)] {
        let (a, b) = (
            from_block.ray(trompe::glam::DVec2::new(p.0, p.1)),
            live.ray(trompe::glam::DVec2::new(p.0, p.1)),
        );
        assert!(
            a.origin.distance(b.origin) < 1e-5 && a.dir.dot(b.dir) > 1.0 - 1e-6,
            "{a:?} {b:?}"
        );
    }
}

#[test]
fn a_bad_script_or_a_foreign_folder_is_refused_with_the_reason() {
    let dir = scratch("viewer-bad");
    let keys = dir.join("keys.txt");
    std::fs::write(&keys, "0 down W\n0.5 jump\n").unwrap();
    let out = dir.join("out");
    let run = |out: &Path| {
        trompe(&[
            "view",
            "scenes/teapot-in-bunny.toml",
            "--frames",
            "1",
            "--script",
            keys.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
    };
    let o = run(&out);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("line 2"), "{}", stderr(&o));
    // A folder of someone else's files is not written into.
    let foreign = dir.join("foreign");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("mine.png"), b"x").unwrap();
    std::fs::write(&keys, "0 down W\n").unwrap();
    let o = run(&foreign);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("trompe did not write (mine.png"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read(foreign.join("mine.png")).unwrap(), b"x");
}

#[test]
fn the_photographs_options_are_refused_with_a_scene_and_a_missing_encoding_is_named() {
    let dir = scratch("viewer-photographs-bad");
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    let o = trompe(&[
        "view",
        "scenes/teapot-in-bunny.toml",
        "--k",
        "8",
        "--frames",
        "1",
        "-o",
        out,
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("give them with --views or --master"),
        "{}",
        stderr(&o)
    );
    let o = trompe(&["view", "--views", "nowhere", "--frames", "1", "-o", out]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--mesh"), "{}", stderr(&o));
    let duck = common::asset("gltf/Duck.glb");
    let missing = dir.join("no-encoding");
    let o = trompe(&[
        "view",
        "--master",
        missing.to_str().unwrap(),
        "--mesh",
        duck.to_str().unwrap(),
        "--frames",
        "1",
        "-o",
        out,
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("no-encoding"), "{}", stderr(&o));
}

#[test]
fn a_fly_camera_looks_where_it_is_told_whatever_the_worlds_up() {
    use glam::Vec3;
    use trompe_cli::viewer::FlyCamera;
    for up in [
        Vec3::Y,
        Vec3::Z,
        Vec3::new(0.3, -0.8, 0.5).normalize(),
        -Vec3::Z,
    ] {
        for target in [Vec3::new(1.0, 2.0, -3.0), Vec3::new(-0.5, 0.2, 4.0)] {
            let eye = Vec3::new(0.5, -0.25, 1.0);
            let c = FlyCamera::looking_at(eye, target, up, 40.0, 0.01);
            let wanted = (target - eye).normalize();
            assert!(
                c.direction().distance(wanted) < 1e-5,
                "up {up}: {} for {wanted}",
                c.direction()
            );
            // Its frame is level: the image's right hand is square to the world's up.
            let pinhole = c.pinhole((64, 48)).unwrap();
            let right = pinhole.mcmillan().0.as_vec3().normalize();
            assert!(right.dot(up).abs() < 1e-5, "up {up}: right {right}");
        }
    }
}

#[test]
fn orbiting_an_object_turns_around_its_centre_and_the_hybrid_method_is_one_key_away() {
    let s = scene("c3rc-bunny.toml");
    let mut viewer = Viewer::new(&s, 64, None).unwrap();
    assert_eq!(viewer.methods().get(5), Some(&"c3rc"));
    // The second object, the bunny.
    viewer.input(Input::Down(Key::NextObject));
    viewer.input(Input::Down(Key::NextObject));
    let bunny = &s.objects[1];
    let centre = bunny
        .world_from_object_at(s.render.time)
        .transform_point3(bunny.mesh.bounds().center());
    let c = *viewer.camera();
    assert!(c.orbit && c.target.distance(centre) < 1e-5);
    assert!(c.direction().dot((centre - c.eye).normalize()) > 0.9999);
    viewer.input(Input::Down(Key::Right));
    viewer.step(0.5);
    let d = viewer.camera().eye.distance(centre);
    assert!((d - c.eye.distance(centre)).abs() < 1e-4 * d);
    // Key 6: paper 2's hybrid reflections, against trace (key 1) from the same camera.
    viewer.input(Input::Down(Key::Method(5)));
    let hybrid = viewer.frame(SIZE, 1.0).unwrap();
    assert!(hybrid.hud[0].starts_with("c3rc"), "{}", hybrid.hud[0]);
    viewer.input(Input::Down(Key::Method(0)));
    let traced = viewer.frame(SIZE, 1.0).unwrap();
    let score = metrics::compare(&traced.image, &hybrid.image, None).unwrap();
    assert!(score.flip < 0.05, "c3rc against trace: FLIP {}", score.flip);
}

#[test]
fn the_layered_method_is_built_on_first_use_and_comes_close_to_tracing() {
    let s = scene("street.toml");
    let mut viewer = Viewer::new(&s, 64, None).unwrap();
    assert_eq!(viewer.methods().get(6), Some(&"layered"));
    viewer.input(Input::Down(Key::Method(0)));
    let traced = viewer.frame(SIZE, 1.0).unwrap();
    viewer.input(Input::Down(Key::Method(6)));
    let layered = viewer.frame(SIZE, 1.0).unwrap();
    assert!(
        layered
            .timings
            .0
            .iter()
            .any(|(step, _)| *step == "build layers"),
        "built on first use"
    );
    let again = viewer.frame(SIZE, 1.0).unwrap();
    assert!(
        again
            .timings
            .0
            .iter()
            .all(|(step, _)| *step != "build layers")
    );
    assert!(again.image == layered.image);
    let score = metrics::compare(&traced.image, &layered.image, None).unwrap();
    assert!(
        score.flip < 0.1,
        "layered against trace: FLIP {}",
        score.flip
    );
}

#[test]
fn the_relief_method_warps_impostors_its_shader_thread_makes_and_shows_their_state() {
    let s = scene("teapot-in-bunny.toml");
    let script = Script::parse("0 tap 8\n0.1 down D\n0.5 up D\n", Path::new("keys")).unwrap();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut viewer = Viewer::new(&s, 64, None).unwrap();
                let dt = 1.0 / 30.0;
                let mut frames = Vec::new();
                for i in 0..20 {
                    for input in script.between(i as f32 * dt, (i + 1) as f32 * dt) {
                        viewer.input(input);
                    }
                    frames.push(viewer.frame(SIZE, 1.0).unwrap());
                    viewer.step(dt);
                }
                viewer.input(Input::Down(Key::Method(0)));
                (frames, viewer.frame(SIZE, 1.0).unwrap())
            })
    };
    assert_eq!(
        Viewer::new(&s, 64, None).unwrap().methods().get(7).copied(),
        Some("relief")
    );
    let (frames, traced) = run(2);
    let (one, _) = run(1);
    assert!(
        frames.iter().zip(&one).all(|(a, b)| a.image == b.image),
        "1 and 2 threads differ"
    );
    let state = |f: &trompe_cli::viewer::ViewFrame, object: &str| {
        f.hud
            .iter()
            .find(|l| l.trim_start().starts_with(&format!("{object}:")))
            .cloned()
            .unwrap_or_else(|| panic!("no {object} line in {:?}", f.hud))
    };
    // Started on first use: no impostor yet, so the objects are rasterized while the
    // shader thread makes them.
    let first = &frames[0];
    assert!(first.hud[0].starts_with("relief"), "{}", first.hud[0]);
    assert!(
        first
            .timings
            .0
            .iter()
            .any(|(s, _)| *s == "start the relief pipeline")
    );
    assert!(frames[1..].iter().all(|f| {
        f.timings
            .0
            .iter()
            .all(|(s, _)| *s != "start the relief pipeline")
    }));
    assert!(state(first, "bunny").contains("fallback + regenerating"));
    // Then low-resolution impostors, then full ones, warped as the camera moves, each with
    // the heuristic's predicted share against its limit.
    assert!(frames.iter().any(|f| state(f, "bunny").contains("64^2")));
    let last = frames.last().unwrap();
    for object in ["bunny", "teapot"] {
        let line = state(last, object);
        assert!(
            (line.contains("warping") || line.contains("valid")) && line.contains("256^2"),
            "{line}"
        );
        assert!(
            line.contains("predicted") && line.contains("of limit"),
            "{line}"
        );
    }
    let score = metrics::compare(&traced.image, &last.image, None).unwrap();
    assert!(
        score.flip < 0.12,
        "relief against trace: FLIP {}",
        score.flip
    );
}

#[test]
fn the_photographs_viewer_starts_at_the_first_photograph_and_goes_to_the_next() {
    use trompe::texturing::BlendSettings;
    use trompe::views::visibility::DepthMap;
    use trompe_gpu::{PhotoSource, TexturedMesh};
    // Six photographs of the duck on a ring, read back as a COLMAP model.
    let dir = scratch("viewer-photographs");
    let duck = common::asset("gltf/Duck.glb");
    let cap = dir.join("cap");
    let o = trompe(&[
        "views",
        "capture",
        duck.to_str().unwrap(),
        "--count",
        "6",
        "--size",
        "96x72",
        "-o",
        cap.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut set = trompe::views::ViewSet::load(&cap, None).unwrap();
    set.load_images().unwrap();
    let mesh = trompe::geom::io::load(&duck).unwrap().mesh;
    let depth = DepthMap::of_all(&set.views, &mesh).unwrap();
    let source = PhotoSource::Views {
        views: &set.views,
        depth: &depth,
    };
    let textured = TexturedMesh::new(None, &mesh, source, &BlendSettings::default()).unwrap();
    let mut viewer = Viewer::of_photographs(textured, &mesh).unwrap();
    assert_eq!(viewer.methods(), ["ulr", "vdtm", "view-map", "best-face"]);
    // Through a photograph's own camera, the blend gives the photograph back where it shows
    // the duck (the blend leaves the background out: the photograph fills it).
    let agreement = |viewer: &mut Viewer, i: usize| {
        let frame = viewer.frame(SIZE, 1.0).unwrap().image;
        let photo = set.views[i].image.as_ref().unwrap();
        let mut over = photo.clone();
        for (o, f) in over.pixels_mut().iter_mut().zip(frame.pixels()) {
            if f.w > 0.99 {
                *o = *f;
            }
        }
        let shown = frame.pixels().iter().filter(|f| f.w > 0.99).count();
        assert!(shown > 500, "the duck shows on {shown} pixels");
        metrics::compare(photo, &over, None).unwrap().flip
    };
    let first = agreement(&mut viewer, 0);
    assert!(first < 0.01, "at the first photograph: FLIP {first}");
    viewer.input(Input::Down(Key::NextObject));
    let second = agreement(&mut viewer, 1);
    assert!(second < 0.01, "at the second photograph: FLIP {second}");
    // Key 4 blends one view a face: another frame, still the duck.
    let ulr = viewer.frame(SIZE, 1.0).unwrap();
    viewer.input(Input::Down(Key::Method(3)));
    let best = viewer.frame(SIZE, 1.0).unwrap();
    assert!(best.hud[0].starts_with("views best-face"), "{:?}", best.hud);
    assert!(ulr.image != best.image);
}
