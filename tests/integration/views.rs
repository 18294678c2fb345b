//! Calibrated views against COLMAP's own files (written by pycolmap: tests/fixtures/colmap/),
//! capture rigs and view-dependent texturing.

use crate::common;
use glam::{DVec2, DVec3};
use std::path::{Path, PathBuf};
use trompe::views::{BlendSettings, ViewSet, Weighting, blend, visibility::DepthMap};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/colmap")
}

#[test]
fn text_and_binary_models_of_one_reconstruction_load_to_identical_views() {
    let text = ViewSet::load(&fixtures().join("text"), None).unwrap();
    let binary = ViewSet::load(&fixtures().join("binary"), None).unwrap();
    assert_eq!(text.views.len(), 6);
    for (a, b) in text.views.iter().zip(&binary.views) {
        assert_eq!(
            (a.name.as_str(), a.image_id, a.camera_id),
            (b.name.as_str(), b.image_id, b.camera_id)
        );
        assert_eq!(a.intrinsics, b.intrinsics);
        assert!((a.pose.rotation.dot(b.pose.rotation).abs() - 1.0).abs() < 1e-12);
        assert!((a.pose.translation - b.pose.translation).length() < 1e-12);
    }
}

#[test]
fn every_camera_model_reprojects_to_colmaps_pixels_and_undistorts_back() {
    let expected: serde_json::Value =
        serde_json::from_slice(&std::fs::read(fixtures().join("projections.json")).unwrap())
            .unwrap();
    let set = ViewSet::load(&fixtures().join("text"), None).unwrap();
    let mut checked = 0;
    for point in expected["points"].as_array().unwrap() {
        let p: Vec<f64> = serde_json::from_value(point["point"].clone()).unwrap();
        let p = DVec3::new(p[0], p[1], p[2]);
        for v in &set.views {
            let want = &point["pixels"][v.image_id.to_string()];
            let want: Vec<f64> = serde_json::from_value(want.clone()).unwrap();
            let (got, _) = v.project(p).unwrap();
            let err = (got - DVec2::new(want[0], want[1])).length();
            assert!(err < 1e-6, "{:?}: {err} px", v.intrinsics.model());
            checked += 1;
        }
    }
    assert_eq!(checked, 12 * 6);
    for v in &set.views {
        let rows = &expected["undistorted"][v.image_id.to_string()];
        let (fx, _) = v.intrinsics.focal();
        for row in rows.as_array().unwrap() {
            let r: Vec<f64> = serde_json::from_value(row.clone()).unwrap();
            let n = v.intrinsics.normalized_of(DVec2::new(r[0], r[1])).unwrap();
            let err_px = (n - DVec2::new(r[2], r[3])).length() * fx;
            assert!(err_px < 1e-3, "{:?}: {err_px} px", v.intrinsics.model());
            // And distortion is its inverse.
            let back = v.intrinsics.pixel_of(n);
            assert!((back - DVec2::new(r[0], r[1])).length() < 1e-6);
        }
    }
}

#[test]
fn a_written_text_model_reads_back_identically() {
    let d = common::scratch("views_write");
    let set = ViewSet::load(&fixtures().join("text"), None).unwrap();
    trompe::views::colmap::write_text(&d, &set.views).unwrap();
    let again = ViewSet::load(&d, None).unwrap();
    for (a, b) in set.views.iter().zip(&again.views) {
        assert_eq!(a.intrinsics, b.intrinsics);
        assert_eq!(a.pose, b.pose);
        assert_eq!(a.name, b.name);
    }
}

#[test]
fn malformed_models_are_named_errors() {
    let d = common::scratch("views_bad");
    let cameras = std::fs::read_to_string(fixtures().join("text/cameras.txt")).unwrap();
    let images = std::fs::read_to_string(fixtures().join("text/images.txt")).unwrap();
    let case = |name: &str, cameras: &str, images: &str, expect: &str| {
        let dir = d.join(name);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("cameras.txt"), cameras).unwrap();
        std::fs::write(dir.join("images.txt"), images).unwrap();
        let mut set = match ViewSet::load(&dir, None) {
            Err(e) => {
                let e = e.to_string();
                assert!(e.contains(expect), "{name}: {e}");
                return;
            }
            Ok(set) => set,
        };
        let e = set.load_images().unwrap_err().to_string();
        assert!(e.contains(expect), "{name}: {e}");
    };
    case(
        "fisheye",
        &cameras.replace("1 SIMPLE_PINHOLE", "1 THIN_PRISM_FISHEYE"),
        &images,
        "THIN_PRISM_FISHEYE is not one trompe reads",
    );
    case(
        "no_camera",
        &cameras.replace("\n6 FULL_OPENCV", "\n9 FULL_OPENCV"),
        &images,
        "camera 6 is not in the cameras file",
    );
    case(
        "nan_pose",
        &cameras,
        &images.replacen(" 0.10000000000000001 ", " nan ", 1),
        "not finite",
    );
    case(
        "not_unit",
        &cameras,
        &images.replacen("1 0.9785148789279039", "1 0.5", 1),
        "not 1",
    );
    case(
        "params",
        &cameras.replace(" 158.5 121.25\n", "\n"),
        &images,
        "takes 4 parameters",
    );
    // Images that are not there, or not the camera's size.
    case("missing_image", &cameras, &images, "view01.png");
    let dir = d.join("small_image");
    std::fs::create_dir_all(&dir).unwrap();
    for v in 1..=6 {
        let img = trompe::Image::new(32, 24, glam::Vec4::ONE).unwrap();
        trompe::frame::io::write_png(&dir.join(format!("view{v:02}.png")), &img).unwrap();
    }
    std::fs::write(dir.join("cameras.txt"), &cameras).unwrap();
    std::fs::write(dir.join("images.txt"), &images).unwrap();
    let mut set = ViewSet::load(&dir, None).unwrap();
    let e = set.load_images().unwrap_err().to_string();
    assert!(
        e.contains("32 × 24 pixels, but camera 1 is 320 × 240"),
        "{e}"
    );
    // A camera no image uses is a warning, not an error.
    let extra = cameras.clone() + "7 PINHOLE 320 240 400 400 160 120\n";
    std::fs::write(dir.join("cameras.txt"), extra).unwrap();
    let set = ViewSet::load(&dir, None).unwrap();
    assert_eq!(
        set.warnings,
        vec!["camera 7: no image uses it (skipped)".to_string()]
    );
}

/// `points3D.txt`, when present, is a sanity check: an observation behind its camera is a
/// warning naming the file.
#[test]
fn points_behind_their_cameras_are_a_warning() {
    let d = common::scratch("views_points");
    for f in ["cameras.txt", "images.txt", "points3D.txt"] {
        std::fs::copy(fixtures().join("text").join(f), d.join(f)).unwrap();
    }
    let set = ViewSet::load(&d, None).unwrap();
    assert!(set.warnings.is_empty(), "{:?}", set.warnings);
    let v = &set.views[0];
    let forward = v.pose.rotation.inverse() * DVec3::Z;
    let (front, back) = (v.pose.centre() + forward, v.pose.centre() - forward);
    let line =
        |p: DVec3, id: u32| format!("{id} {} {} {} 0 0 0 0 {} 0\n", p.x, p.y, p.z, v.image_id);
    std::fs::write(d.join("points3D.txt"), line(front, 1) + &line(back, 2)).unwrap();
    let set = ViewSet::load(&d, None).unwrap();
    assert_eq!(set.warnings.len(), 1, "{:?}", set.warnings);
    assert!(set.warnings[0].contains("1 of 2 observations see their point behind the camera"));
}

/// A ring capture of the teapot: at an input viewpoint the blend reproduces the view; left out,
/// the view is rebuilt from its neighbours.
#[test]
fn a_capture_is_reproduced_at_its_views_and_rebuilt_when_one_is_left_out() {
    let teapot = common::asset("meshes/teapot.obj");
    let settings = trompe::views::capture::CaptureSettings {
        count: 24,
        size: (128, 96),
        ..Default::default()
    };
    let set = trompe::views::capture::capture(&teapot, &settings, &()).unwrap();
    let mesh = trompe::geom::io::load(&teapot).unwrap().mesh;
    let depth = DepthMap::of_all(&set.views, &mesh).unwrap();
    let blend_settings = BlendSettings::default();
    let v = 5;
    let camera = set.views[v].pinhole();
    let truth = set.views[v].image.as_ref().unwrap();
    let score = |exclude: Option<usize>, weighting: Weighting| {
        let settings = BlendSettings {
            weighting,
            ..blend_settings
        };
        let b = blend::render(&camera, &mesh, &set.views, &depth, &settings, exclude).unwrap();
        let mask = b.image.map(|c| c.w > 0.0);
        let psnr = trompe::frame::metrics::psnr(truth, &b.image, Some(&mask)).unwrap();
        (psnr, b.holes as f64 / b.covered as f64)
    };
    let (same, holes) = score(None, Weighting::Ulr { beta: 0.1 });
    assert!(
        same > 40.0 && holes < 0.01,
        "at its own view: {same} dB, {holes} holes"
    );
    for w in [
        Weighting::Ulr { beta: 0.1 },
        Weighting::Vdtm,
        Weighting::ViewMap,
    ] {
        let (left_out, holes) = score(Some(v), w);
        eprintln!("{w:?}: left out {left_out:.2} dB, holes {holes:.4}");
        assert!(
            left_out > 22.0 && holes < 0.05,
            "{w:?}: {left_out} dB, {holes} holes"
        );
    }
}

#[test]
fn a_render_on_a_finer_grid_than_its_only_view_leaves_no_boundary_holes() {
    // One view of the teapot, rendered back from its own viewpoint on a pixel grid 1.375 times
    // finer: every surface point the render shows is one the view saw, but most of the render's
    // pixel centres fall between the view's, and along every silhouette a texel centre under
    // such a point may have missed the mesh or hit an occluder's edge.
    let teapot = common::asset("meshes/teapot.obj");
    let settings = trompe::views::capture::CaptureSettings {
        count: 24,
        size: (256, 192),
        ..Default::default()
    };
    let set = trompe::views::capture::capture(&teapot, &settings, &()).unwrap();
    let mesh = trompe::geom::io::load(&teapot).unwrap().mesh;
    let only = &set.views[5..6];
    let depth = DepthMap::of_all(only, &mesh).unwrap();
    let (a, b, c) = only[0].pinhole().mcmillan();
    let s = 1.375;
    let camera =
        trompe::camera::Pinhole::from_mcmillan(only[0].pose.centre(), a / s, b / s, c, 352, 264);
    let blend = blend::render(
        &camera,
        &mesh,
        only,
        &depth,
        &BlendSettings::default(),
        None,
    )
    .unwrap();
    let unseen = blend.unseen_share();
    eprintln!(
        "{} pixels show the teapot, {} unseen ({:.3} %)",
        blend.covered,
        blend.holes,
        100.0 * unseen
    );
    assert!(blend.covered > 5_000, "{} pixels", blend.covered);
    assert_eq!(blend.holes, 0, "{:.3} % unseen", 100.0 * unseen);
    // The same view encoded as a master texture: its texels carry the same visibility.
    let enc = trompe::master::encode_views(&mesh, only, 2.0, &()).unwrap();
    let masters = trompe::master::render::render(
        &camera,
        &mesh,
        &enc.atlas.layout,
        &enc.pinholes(),
        &enc.masters,
        &BlendSettings::default(),
    )
    .unwrap();
    eprintln!("master texture: {} unseen", masters.holes);
    assert_eq!(masters.covered, blend.covered);
    assert_eq!(masters.holes, 0, "{} unseen", masters.holes);
}

/// Copies the rig fixture's text model to a scratch folder, for a test to change one file.
fn rig_copy(name: &str) -> PathBuf {
    let dir = common::scratch(name);
    for f in [
        "cameras.txt",
        "images.txt",
        "points3D.txt",
        "rigs.txt",
        "frames.txt",
    ] {
        std::fs::copy(fixtures().join("rig/text").join(f), dir.join(f)).unwrap();
    }
    dir
}

#[test]
fn rig_and_frame_poses_equal_pycolmaps_image_poses() {
    let expected: serde_json::Value =
        serde_json::from_slice(&std::fs::read(fixtures().join("rig/poses.json")).unwrap()).unwrap();
    let points: Vec<DVec3> = expected["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let p: Vec<f64> = serde_json::from_value(p.clone()).unwrap();
            DVec3::new(p[0], p[1], p[2])
        })
        .collect();
    // The images file's own poses replaced by the identity: a reader that took them would be
    // wrong, and the frames' must win.
    let blanked = rig_copy("rig-blanked-images");
    let images = std::fs::read_to_string(blanked.join("images.txt")).unwrap();
    let mut lines = Vec::new();
    let mut pose_line = true;
    for l in images.lines() {
        if l.starts_with('#') {
            lines.push(l.to_string());
            continue;
        }
        if pose_line {
            let f: Vec<&str> = l.split_whitespace().collect();
            lines.push(format!("{} 1 0 0 0 0 0 0 {} {}", f[0], f[8], f[9]));
        } else {
            lines.push(l.to_string());
        }
        pose_line = !pose_line;
    }
    std::fs::write(blanked.join("images.txt"), lines.join("\n") + "\n").unwrap();

    for (dir, disagree) in [
        (fixtures().join("rig/text"), false),
        (fixtures().join("rig/binary"), false),
        (blanked, true),
    ] {
        let set = ViewSet::load(&dir, None).unwrap();
        assert_eq!(set.views.len(), 9, "{}", dir.display());
        let s = &set.summary;
        assert_eq!(
            (s.rigs, s.frames, s.posed_by_frame, s.posed_by_offset),
            (1, 3, 9, 6),
            "{}: {s}",
            dir.display()
        );
        assert_eq!(
            set.warnings.iter().any(|w| w.contains("disagree")),
            disagree,
            "{}: {:?}",
            dir.display(),
            set.warnings
        );
        for v in &set.views {
            let want = &expected["images"][v.image_id.to_string()];
            assert_eq!(want["name"], v.name.as_str());
            let q: Vec<f64> = serde_json::from_value(want["q_wxyz"].clone()).unwrap();
            let t: Vec<f64> = serde_json::from_value(want["t"].clone()).unwrap();
            let r = v.pose.rotation;
            let dq = (r.w - q[0])
                .abs()
                .max((r.x - q[1]).abs())
                .max((r.y - q[2]).abs())
                .max((r.z - q[3]).abs());
            let dq_flipped = (r.w + q[0])
                .abs()
                .max((r.x + q[1]).abs())
                .max((r.y + q[2]).abs())
                .max((r.z + q[3]).abs());
            let dt = (v.pose.translation - DVec3::new(t[0], t[1], t[2])).length();
            assert!(
                dq.min(dq_flipped) < 1e-6 && dt < 1e-6,
                "{}: image {}: rotation off by {dq}, translation by {dt}",
                dir.display(),
                v.image_id
            );
            for (p, px) in points.iter().zip(want["pixels"].as_array().unwrap()) {
                let (Some(ours), Some(theirs)) = (v.project(*p), px.as_array()) else {
                    continue;
                };
                let theirs = DVec2::new(theirs[0].as_f64().unwrap(), theirs[1].as_f64().unwrap());
                assert!(
                    (ours.0 - theirs).length() < 1e-6,
                    "image {}: {:?} against COLMAP's {theirs:?}",
                    v.image_id,
                    ours.0
                );
            }
        }
    }
}

#[test]
fn a_rig_or_frame_that_cannot_pose_its_images_is_an_error_naming_it() {
    let replace = |dir: &Path, file: &str, from: &str, to: &str| {
        let p = dir.join(file);
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.contains(from), "{file} lacks {from:?}");
        std::fs::write(&p, text.replacen(from, to, 1)).unwrap();
    };
    let cases: [(&str, &str, &str, &str, &[&str]); 4] = [
        // The third camera's offset in the rig not calibrated.
        (
            "rig-uncalibrated",
            "rigs.txt",
            "CAMERA 3 1 1 0 0 0 -0.29999999999999999 0.050000000000000003 0",
            "CAMERA 3 0",
            &["rigs.txt", "rig 1", "CAMERA 3", "no calibrated pose"],
        ),
        // A frame of a rig the model does not hold.
        (
            "rig-unknown",
            "frames.txt",
            "\n2 1 ",
            "\n2 7 ",
            &["frames.txt", "frame 2", "rig 7"],
        ),
        // A frame holding an image through a camera its rig does not have.
        (
            "rig-foreign-sensor",
            "frames.txt",
            "CAMERA 3 3",
            "CAMERA 4 3",
            &[
                "frames.txt",
                "frame 1",
                "CAMERA 4",
                "not a sensor of its rig 1",
            ],
        ),
        // A garbled pose.
        (
            "rig-garbled",
            "rigs.txt",
            "CAMERA 2 1 ",
            "CAMERA 2 1 x",
            &["rigs.txt", "line 4", "is not a number"],
        ),
    ];
    for (name, file, from, to, expect) in cases {
        let dir = rig_copy(name);
        replace(&dir, file, from, to);
        let err = ViewSet::load(&dir, None).unwrap_err().to_string();
        for e in expect {
            assert!(err.contains(e), "{name}: {err:?} lacks {e:?}");
        }
    }
    // Frames without their rigs.
    let dir = rig_copy("rig-no-rigs");
    std::fs::remove_file(dir.join("rigs.txt")).unwrap();
    let err = ViewSet::load(&dir, None).unwrap_err().to_string();
    assert!(err.contains("rigs.txt") && err.contains("missing"), "{err}");
}

#[test]
fn a_seamless_best_face_bake_levels_exposure_and_leaves_out_what_passed_in_front() {
    // The Duck from eight views, each view's exposure falling off from its left edge to its
    // right by a different amount (no one gain a view takes it out), and a red square in
    // front of view 3 (a person walking through the capture).
    let duck = common::asset("gltf/Duck.glb");
    let settings = trompe::views::capture::CaptureSettings {
        count: 8,
        size: (160, 120),
        ..Default::default()
    };
    let mut set = trompe::views::capture::capture(&duck, &settings, &()).unwrap();
    let red = glam::Vec3::new(0.9, 0.02, 0.02);
    for (v, view) in set.views.iter_mut().enumerate() {
        let img = view.image.as_mut().expect("captured");
        let w = img.width() as usize;
        for (i, p) in img.pixels_mut().iter_mut().enumerate() {
            let (x, y) = (i % w, i / w);
            let fall = 1.3 - (0.1 + 0.08 * v as f32) * x as f32 / 160.0;
            let c = if v == 3 && (50..110).contains(&x) && (30..90).contains(&y) {
                red
            } else {
                p.truncate() * fall
            };
            *p = c.extend(p.w);
        }
    }
    let mesh = trompe::geom::io::load(&duck).unwrap().mesh;
    let depth = DepthMap::of_all(&set.views, &mesh).unwrap();
    let camera = set.views[3].pinhole();
    let render = |seamless: bool| {
        let s = BlendSettings {
            weighting: Weighting::BestFace,
            seamless,
            ..BlendSettings::default()
        };
        blend::render(&camera, &mesh, &set.views, &depth, &s, None).unwrap()
    };
    let (plain, seamless) = (render(false), render(true));
    let reds = |b: &trompe::texturing::Blend| {
        (b.image.pixels().iter())
            .filter(|p| p.w > 0.0 && (p.truncate() - red).length() < 0.1)
            .count()
    };
    let report = seamless.seams.expect("a seamless bake reports");
    println!(
        "as it is: {} red pixels; seamless: {} red pixels, {report}",
        reds(&plain),
        reds(&seamless)
    );
    assert!(plain.seams.is_none());
    assert!(reds(&plain) > 500, "{} red pixels", reds(&plain));
    assert!(reds(&seamless) * 20 < reds(&plain), "{}", reds(&seamless));
    assert!(report.outliers > 0 && report.edges > 100, "{report:?}");
    assert!(report.step_levelled < 0.5 * report.step_gains, "{report:?}");
    assert_eq!(seamless.covered, plain.covered);
}
