//! `trompe views`: what reading a COLMAP model reports.

use crate::common;

#[test]
fn verbose_reports_the_rigs_and_frames_a_model_holds() {
    // COLMAP 4's rig fixture (three cameras on one rig, three frames), without its photographs:
    // the model is read and reported, then the first missing photograph is named.
    let model = common::repo("tests/fixtures/colmap/rig/binary");
    let model = model.to_str().unwrap();
    let teapot = common::asset("meshes/teapot.obj");
    let out = common::trompe(&[
        "-v",
        "views",
        "score",
        model,
        "--mesh",
        teapot.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let e = common::stderr(&out);
    assert!(
        e.contains("binary model: 3 cameras, 9 images; 1 rigs, 3 frames: 9 images posed by their frame, 6 of them through a sensor's offset in its rig"),
        "{e}"
    );
    assert!(e.contains("frame1_cam1.png"), "{e}");
}

#[test]
fn a_photographs_own_camera_renders_it_back() {
    // A synthetic photograph taken by a camera whose principal point is 30 px right of and
    // 20 px above the image's centre, with unequal focal lengths; its COLMAP model says so.
    let dir = common::scratch("views-cli-camera");
    let duck = common::asset("gltf/Duck.glb");
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        format!(
            "[camera]\nposition = [1.2, 1.9, 3.2]\nlook_at = [0.1, 0.85, 0.0]\nfx = 300\nfy = \
             305\ncx = 190\ncy = 100\nresolution = [320, 240]\n\n[light]\ndirection = [0.4, \
             1.0, 0.6]\nintensity = 2.5\n\n[[object]]\nmesh = {:?}\n",
            duck.to_str().unwrap()
        ),
    )
    .unwrap();
    let model = dir.join("model");
    std::fs::create_dir_all(&model).unwrap();
    let photo = model.join("photo.png");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let run = |args: &[&str]| {
        let out = common::trompe(args);
        assert!(out.status.success(), "{}", common::stderr(&out));
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    run(&["render", &s(&scene), "-o", &s(&photo)]);
    let spec = trompe::scene::Scene::load(&scene).unwrap().camera;
    let pose = trompe::views::Pose::looking_at(
        spec.position.as_dvec3(),
        spec.look_at.as_dvec3(),
        spec.up.as_dvec3(),
    )
    .unwrap();
    let view = trompe::views::CalibratedView {
        name: "photo.png".into(),
        image_id: 7,
        camera_id: 1,
        intrinsics: trompe::views::Intrinsics::pinhole(320, 240, 300.0, 305.0, 190.0, 100.0),
        pose,
        image: None,
    };
    trompe::views::colmap::write_text(&model, &[view]).unwrap();
    let truth = trompe::frame::io::read_color(&photo).unwrap();
    let at = format!("{}:photo.png", s(&model));

    // The exact tracer from the photograph's camera, named by the image's name.
    let again = dir.join("again.png");
    run(&["render", &s(&scene), "--camera", &at, "-o", &s(&again)]);
    let again = trompe::frame::io::read_color(&again).unwrap();
    let db = trompe::frame::metrics::psnr(&truth, &again, None).unwrap();
    assert!(db >= 60.0, "render --camera: {db:.2} dB");

    // The photograph textured back onto the mesh from its own camera, named by the image's id.
    let by_id = format!("{}:7", s(&model));
    let novel = dir.join("novel.png");
    let said = run(&[
        "views",
        "render",
        &s(&model),
        "--mesh",
        duck.to_str().unwrap(),
        "--camera",
        &by_id,
        "-o",
        &s(&novel),
    ]);
    assert!(said.contains(" 0 of them seen by no view"), "{said}");
    let novel = trompe::frame::io::read_color(&novel).unwrap();
    let mask = novel.map(|c| c.w > 0.0);
    let covered = mask.pixels().iter().filter(|&&m| m).count();
    let db = trompe::frame::metrics::psnr(&truth, &novel, Some(&mask)).unwrap();
    eprintln!("views render --camera: {db:.2} dB over {covered} pixels");
    assert!(covered > 5_000, "{covered} pixels");
    assert!(db >= 60.0, "views render --camera: {db:.2} dB");

    // The photograph encoded as a master texture and rendered back from its camera: two
    // bilinear resamplings (photograph to atlas, atlas to frame) instead of none.
    let enc = dir.join("enc");
    run(&[
        "master",
        "encode",
        &s(&model),
        "--mesh",
        duck.to_str().unwrap(),
        "-o",
        &s(&enc),
    ]);
    let from_master = dir.join("master.png");
    let said = run(&[
        "master",
        "render",
        &s(&enc),
        "--mesh",
        duck.to_str().unwrap(),
        "--camera",
        &at,
        "-o",
        &s(&from_master),
    ]);
    assert!(said.contains(" 0 of them seen by no view"), "{said}");
    let from_master = trompe::frame::io::read_color(&from_master).unwrap();
    let db = trompe::frame::metrics::psnr(&truth, &from_master, Some(&mask)).unwrap();
    eprintln!("master render --camera: {db:.2} dB");
    assert!(db >= 30.0, "master render --camera: {db:.2} dB");

    // A name the model does not hold, and a malformed argument.
    let out = common::trompe(&[
        "render",
        &s(&scene),
        "--camera",
        &format!("{}:nope.png", s(&model)),
        "-o",
        &s(&dir.join("x.png")),
    ]);
    assert!(!out.status.success());
    assert!(
        common::stderr(&out).contains("no image named \"nope.png\""),
        "{}",
        common::stderr(&out)
    );
    let out = common::trompe(&[
        "render",
        &s(&scene),
        "--camera",
        "photo.png",
        "-o",
        &s(&dir.join("x.png")),
    ]);
    assert!(
        common::stderr(&out).contains("expected MODEL:IMAGE"),
        "{}",
        common::stderr(&out)
    );
}

#[test]
fn a_distorted_photographs_own_camera_renders_its_distorted_frame_back() {
    // For each COLMAP lens model, with the principal point off the centre: the exact tracer
    // renders a scene camera with that lens (the "photograph"); the photograph's COLMAP camera
    // with --distort then renders the same frame, traced and textured from the photograph.
    use trompe::views::CameraModel;
    let duck = common::asset("gltf/Duck.glb");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let run = |args: &[&str]| {
        let out = common::trompe(args);
        assert!(out.status.success(), "{}", common::stderr(&out));
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let lenses: [(CameraModel, &[f64]); 4] = [
        (CameraModel::SimpleRadial, &[-0.18]),
        (CameraModel::Radial, &[-0.2, 0.06]),
        (CameraModel::OpenCv, &[-0.16, 0.05, 0.002, -0.003]),
        (
            CameraModel::FullOpenCv,
            &[-0.16, 0.05, 0.002, -0.003, 0.01, 0.02, -0.01, 0.005],
        ),
    ];
    for (model, distortion) in lenses {
        let name = model.name();
        let dir = common::scratch(&format!("views-cli-lens-{name}"));
        let (fx, fy) = match model {
            CameraModel::OpenCv | CameraModel::FullOpenCv => (300.0, 306.0),
            _ => (300.0, 300.0),
        };
        let scene = dir.join("scene.toml");
        std::fs::write(
            &scene,
            format!(
                "[camera]\nposition = [1.2, 1.9, 3.2]\nlook_at = [0.1, 0.85, 0.0]\nfx = {fx}\nfy \
                 = {fy}\ncx = 184.5\ncy = 104\nmodel = {name:?}\ndistortion = {distortion:?}\n\
                 resolution = [320, 240]\n\n[light]\ndirection = [0.4, 1.0, 0.6]\nintensity = \
                 2.5\n\n[[object]]\nmesh = {:?}\n",
                duck.to_str().unwrap()
            ),
        )
        .unwrap();
        let folder = dir.join("model");
        std::fs::create_dir_all(&folder).unwrap();
        let photo = folder.join("photo.png");
        run(&["render", &s(&scene), "-o", &s(&photo)]);
        let spec = trompe::scene::Scene::load(&scene).unwrap().camera;
        let lens = spec.lens.clone().expect("a lens");
        let pose = trompe::views::Pose::looking_at(
            spec.position.as_dvec3(),
            spec.look_at.as_dvec3(),
            spec.up.as_dvec3(),
        )
        .unwrap();
        let view = trompe::views::CalibratedView {
            name: "photo.png".into(),
            image_id: 3,
            camera_id: 1,
            intrinsics: lens,
            pose,
            image: None,
        };
        trompe::views::colmap::write_text(&folder, &[view]).unwrap();
        let truth = trompe::frame::io::read_color(&photo).unwrap();
        let at = format!("{}:photo.png", s(&folder));

        // The exact tracer through the COLMAP camera's lens: the same frame.
        let again = dir.join("again.png");
        run(&[
            "render",
            &s(&scene),
            "--camera",
            &at,
            "--distort",
            "-o",
            &s(&again),
        ]);
        let again = trompe::frame::io::read_color(&again).unwrap();
        let db = trompe::frame::metrics::psnr(&truth, &again, None).unwrap();
        assert!(db >= 60.0, "{name}: render --camera --distort: {db:.2} dB");

        // The photograph textured back onto the mesh through its own lens.
        let novel = dir.join("novel.png");
        let said = run(&[
            "views",
            "render",
            &s(&folder),
            "--mesh",
            &s(&duck),
            "--camera",
            &at,
            "--distort",
            "-o",
            &s(&novel),
        ]);
        assert!(
            said.contains(" 0 of them seen by no view"),
            "{name}: {said}"
        );
        let novel = trompe::frame::io::read_color(&novel).unwrap();
        let mask = novel.map(|c| c.w > 0.0);
        let covered = mask.pixels().iter().filter(|&&m| m).count();
        let db = trompe::frame::metrics::psnr(&truth, &novel, Some(&mask)).unwrap();
        eprintln!("{name}: views render --camera --distort: {db:.2} dB over {covered} pixels");
        assert!(covered > 5_000, "{name}: {covered} pixels");
        assert!(
            db >= 60.0,
            "{name}: views render --camera --distort: {db:.2} dB"
        );

        // Without --distort, the undistorted frame: the photograph resampled to its pinhole.
        let flat = dir.join("flat.png");
        run(&[
            "views",
            "render",
            &s(&folder),
            "--mesh",
            &s(&duck),
            "--camera",
            &at,
            "-o",
            &s(&flat),
        ]);
        let flat = trompe::frame::io::read_color(&flat).unwrap();
        let mut set = trompe::views::ViewSet::load(&folder, None).unwrap();
        set.load_images().unwrap();
        let undistorted = trompe::views::blend::undistorted_image(&set.views[0]).unwrap();
        let mask = flat.map(|c| c.w > 0.0);
        let db = trompe::frame::metrics::psnr(&undistorted, &flat, Some(&mask)).unwrap();
        eprintln!("{name}: views render --camera (undistorted frame): {db:.2} dB");
        assert!(db >= 30.0, "{name}: the undistorted frame: {db:.2} dB");
        // The lens matters: far from the 60 dB of the same frame, the two are different pictures.
        let apart = trompe::frame::metrics::psnr(&truth, &flat, Some(&mask)).unwrap();
        eprintln!("{name}: distorted and undistorted frames {apart:.2} dB apart");
        assert!(
            apart < 35.0,
            "{name}: distorted and undistorted frames {apart:.2} dB apart"
        );

        // The photograph as a master texture, rendered back through the lens: two bilinear
        // resamplings (photograph to atlas, atlas to frame), as from a pinhole's.
        let enc = dir.join("enc");
        run(&[
            "master",
            "encode",
            &s(&folder),
            "--mesh",
            &s(&duck),
            "-o",
            &s(&enc),
        ]);
        let from_master = dir.join("master.png");
        run(&[
            "master",
            "render",
            &s(&enc),
            "--mesh",
            &s(&duck),
            "--camera",
            &at,
            "--distort",
            "-o",
            &s(&from_master),
        ]);
        let from_master = trompe::frame::io::read_color(&from_master).unwrap();
        let mask = from_master.map(|c| c.w > 0.0);
        let db = trompe::frame::metrics::psnr(&truth, &from_master, Some(&mask)).unwrap();
        eprintln!("{name}: master render --camera --distort: {db:.2} dB");
        assert!(
            db >= 30.0,
            "{name}: master render --camera --distort: {db:.2} dB"
        );

        // A rasterizing method cannot draw through a lens: a clear error.
        let out = common::trompe(&[
            "render",
            &s(&scene),
            "--method",
            "raster",
            "-o",
            &s(&dir.join("x.png")),
        ]);
        assert!(!out.status.success());
        assert!(
            common::stderr(&out).contains("only the trace method renders"),
            "{}",
            common::stderr(&out)
        );
    }
}

#[test]
fn seamless_asks_for_the_best_face_bake() {
    let model = common::repo("tests/fixtures/colmap/rig/binary");
    let teapot = common::asset("meshes/teapot.obj");
    let out = common::trompe(&[
        "views",
        "render",
        model.to_str().unwrap(),
        "--mesh",
        teapot.to_str().unwrap(),
        "--camera",
        &format!("{}:1", model.to_str().unwrap()),
        "--seamless",
        "-o",
        common::scratch("views-cli-seamless")
            .join("x.png")
            .to_str()
            .unwrap(),
    ]);
    assert!(!out.status.success());
    let e = common::stderr(&out);
    assert!(
        e.contains(
            "--seamless makes the best-face bake seamless: it needs --weights best-face, not ulr"
        ),
        "{e}"
    );
}
