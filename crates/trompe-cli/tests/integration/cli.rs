//! The `trompe` binary end to end: outputs, exit codes and error messages.

use crate::common;
use common::{fails_cleanly, scratch, stderr, trompe};
use std::path::Path;
use std::process::Command;

#[test]
fn render_then_compare() {
    let d = scratch("cli_render");
    let png = d.join("t.png");
    let depth = d.join("t-depth.exr");
    let o = trompe(&[
        "render",
        "scenes/turntable.toml",
        "-o",
        png.to_str().unwrap(),
        "--method",
        "raster",
        "--time",
        "1",
        "--depth",
        depth.to_str().unwrap(),
        "-v",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(png.is_file() && depth.is_file());
    assert!(stderr(&o).contains("rasterize"), "timings with -v");
    let heat = d.join("heat.png");
    let o = trompe(&[
        "compare",
        png.to_str().unwrap(),
        png.to_str().unwrap(),
        "--heatmap",
        heat.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("PSNR inf") && out.contains("SSIM 1.00000") && out.contains("FLIP 0.00000"),
        "{out}"
    );
    assert!(heat.is_file());
    // Without --heatmap nothing is written: not even in the working directory.
    let o = Command::new(env!("CARGO_BIN_EXE_trompe"))
        .args(["compare", png.to_str().unwrap(), png.to_str().unwrap()])
        .current_dir(&d)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", stderr(&o));
    let mut files: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    files.sort();
    assert_eq!(
        files,
        ["heat.png", "t-depth.exr", "t.png"],
        "only what was asked for"
    );
}

#[test]
fn info_reports_counts() {
    let o = trompe(&["info", "assets/meshes/bunny.obj"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("28088 in the file") && out.contains("56172 in the file"),
        "{out}"
    );
}

#[test]
fn bad_inputs_exit_non_zero_with_a_clear_message() {
    let d = scratch("cli_bad");
    let scene = |name: &str, text: &str| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let cam = "[camera]\nposition = [0, 1, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\n";
    let out = d.join("o.png");
    let out = out.to_str().unwrap();
    let absurd = scene(
        "absurd.toml",
        &format!("{cam}resolution = [1000000, 1000000]\n"),
    );
    fails_cleanly(
        &trompe(&["render", &absurd, "-o", out]),
        "camera.resolution",
    );
    let unknown = scene(
        "unknown.toml",
        &format!("{cam}resolution = [8, 8]\nfocal = 3\n"),
    );
    fails_cleanly(&trompe(&["render", &unknown, "-o", out]), "focal");
    let background = scene(
        "background.toml",
        &format!("{cam}resolution = [8, 8]\n[render]\nbackground = [nan, 0, 0]\n"),
    );
    fails_cleanly(
        &trompe(&["render", &background, "-o", out]),
        "render.background",
    );
    // A NaN pixel is named, not scored as PSNR NaN.
    let nan = d.join("nan.exr");
    let mut img = trompe::frame::Image::new(4, 3, glam::Vec4::new(0.5, 0.5, 0.5, 1.0)).unwrap();
    img.set(2, 1, glam::Vec4::new(f32::NAN, 0.5, 0.5, 1.0));
    trompe::frame::io::write_color(&nan, &img).unwrap();
    let fine = d.join("fine.exr");
    img.set(2, 1, glam::Vec4::new(0.5, 0.5, 0.5, 1.0));
    trompe::frame::io::write_color(&fine, &img).unwrap();
    fails_cleanly(
        &trompe(&["compare", fine.to_str().unwrap(), nan.to_str().unwrap()]),
        "the test image's pixel (2, 1) is not a number",
    );
    // A method without a GPU path is refused on the GPU before the scene is read (this one
    // does not exist), whether or not a GPU is present.
    fails_cleanly(
        &trompe(&[
            "render",
            "nowhere.toml",
            "--device",
            "gpu",
            "--method",
            "envmap",
            "-o",
            out,
        ]),
        "--method envmap has no GPU path yet",
    );
    let missing = scene(
        "missing.toml",
        &format!("{cam}resolution = [8, 8]\n[[object]]\nmesh = \"nowhere.obj\"\n"),
    );
    fails_cleanly(&trompe(&["render", &missing, "-o", out]), "nowhere.obj");
    // The output may not be an input.
    fails_cleanly(
        &trompe(&["render", &missing, "-o", &missing]),
        "refusing to overwrite",
    );
    let text = std::fs::read_to_string(&missing).unwrap();
    assert!(text.contains("nowhere.obj"), "input untouched");
    fails_cleanly(&trompe(&["info", "Cargo.toml"]), "unknown extension");
    // A cause is said once, though the library's message already holds it.
    let gone = trompe(&["info", "nowhere.obj"]);
    fails_cleanly(&gone, "nowhere.obj");
    let e = stderr(&gone);
    let os = "No such file or directory";
    assert_eq!(e.matches(os).count(), 1, "cause repeated: {e}");
    for bad in ["0", "100000"] {
        fails_cleanly(
            &trompe(&[
                "render",
                "scenes/reflections.toml",
                "--method",
                "impostor",
                "--impostor-resolution",
                bad,
                "-o",
                out,
            ]),
            "--impostor-resolution",
        );
    }
    let short = d.join("short.obj");
    std::fs::write(&short, "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
    fails_cleanly(&trompe(&["info", short.to_str().unwrap()]), "line 3");
    let a = d.join("a.png");
    std::fs::write(&a, "not a png").unwrap();
    fails_cleanly(
        &trompe(&[
            "compare",
            a.to_str().unwrap(),
            a.to_str().unwrap(),
            "--heatmap",
            d.join("h.png").to_str().unwrap(),
        ]),
        "a.png",
    );
    fails_cleanly(
        &trompe(&["--threads", "0", "info", "assets/meshes/teapot.obj"]),
        "--threads",
    );
}

#[test]
fn demo_writes_a_report() {
    let d = scratch("cli_demo");
    let o = trompe(&["demo", "-o", d.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let html = std::fs::read_to_string(Path::new(&d).join("index.html")).unwrap();
    assert!(html.contains("diffuse-raster.png") && html.contains("FLIP"));
    assert!(d.join("reflections-trace.png").is_file());
    assert!(d.join("room-impostor.png").is_file());
}

#[test]
fn impostors_bake_to_files_that_load_back() {
    let d = scratch("cli_bake");
    let json = d.join("nested/teapot.json");
    let o = trompe(&[
        "impostor",
        "bake",
        "assets/meshes/teapot.obj",
        "--camera",
        "spoc",
        "--resolution",
        "64",
        "-o",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for ext in ["json", "exr", "png"] {
        assert!(json.with_extension(ext).is_file(), "{ext}");
    }
    let back = trompe::impostor::file::load(&json).unwrap();
    assert_eq!(back.camera().kind(), "spoc");
    assert!(back.coverage() > 0.01);
    // The maze's graph camera.
    let maze = d.join("maze.json");
    let o = trompe(&[
        "impostor",
        "bake",
        "scenes/maze.maze",
        "--camera",
        "graph",
        "--resolution",
        "96",
        "-o",
        maze.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let back = trompe::impostor::file::load(&maze).unwrap();
    assert_eq!(back.camera().kind(), "graph");
    // Wrong pairings and bad floor plans are clear errors.
    let out = d.join("x.json");
    let out = out.to_str().unwrap();
    fails_cleanly(
        &trompe(&["impostor", "bake", "scenes/maze.maze", "-o", out]),
        "needs --camera graph",
    );
    fails_cleanly(
        &trompe(&[
            "impostor",
            "bake",
            "assets/meshes/teapot.obj",
            "--camera",
            "graph",
            "-o",
            out,
        ]),
        "maze floor plan",
    );
    let bad = d.join("bad.maze");
    std::fs::write(&bad, "#####\n#.x.#\n#####\n").unwrap();
    fails_cleanly(
        &trompe(&[
            "impostor",
            "check",
            bad.to_str().unwrap(),
            "--camera",
            "graph",
        ]),
        "unknown cell",
    );
    fails_cleanly(
        &trompe(&[
            "impostor",
            "bake",
            "assets/meshes/teapot.obj",
            "--from",
            "1,2",
            "-o",
            out,
        ]),
        "three finite numbers",
    );
}

#[test]
fn a_baked_impostor_is_checked_against_the_mesh_it_was_baked_from() {
    let d = scratch("cli_check_baked");
    let json = d.join("teapot.json");
    let json = json.to_str().unwrap();
    let o = trompe(&[
        "impostor",
        "bake",
        "assets/meshes/teapot.obj",
        "--resolution",
        "128",
        "-o",
        json,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = trompe(&["info", json]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("spoc camera, 128×128 texels"), "{out}");
    let o = trompe(&[
        "impostor",
        "check",
        "assets/meshes/teapot.obj",
        "--impostor",
        json,
        "--rays",
        "2000",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("rays      2000 ("), "{out}");
    assert!(out.contains("beside it, the pinhole depth image"), "{out}");
    // The percentage of agreeing rays, read back: most rays from the baked-for region agree.
    let agreement: f64 = out
        .lines()
        .find_map(|l| l.strip_prefix("agreement "))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no agreement in {out}"));
    assert!(agreement > 95.0, "{out}");
    // Another mesh, a maze, options that only apply to a build or only to a baked impostor.
    fails_cleanly(
        &trompe(&[
            "impostor",
            "check",
            "assets/meshes/bunny.obj",
            "--impostor",
            json,
        ]),
        "was not baked from",
    );
    fails_cleanly(
        &trompe(&["impostor", "check", "scenes/maze.maze", "--impostor", json]),
        "goes with a graph-camera one",
    );
    fails_cleanly(
        &trompe(&[
            "impostor",
            "check",
            "assets/meshes/teapot.obj",
            "--impostor",
            json,
            "--camera",
            "pinhole",
        ]),
        "cannot be used with",
    );
    fails_cleanly(
        &trompe(&[
            "impostor",
            "check",
            "assets/meshes/teapot.obj",
            "--region",
            "2",
        ]),
        "--impostor",
    );
    fails_cleanly(
        &trompe(&[
            "impostor",
            "check",
            "assets/meshes/teapot.obj",
            "--impostor",
            json,
            "--region",
            "0",
        ]),
        "must be a positive number",
    );
    fails_cleanly(
        &trompe(&[
            "impostor",
            "check",
            "assets/meshes/teapot.obj",
            "--sphere-rays",
            "100000000000",
        ]),
        "100000000000",
    );
}

/// What the loader survived reaches the user of every command that reads a mesh, not only
/// `info`: baking a mesh with a degenerate triangle warns of it, and still bakes the rest.
#[test]
fn baking_a_mesh_with_a_degenerate_triangle_warns_of_it() {
    let d = scratch("cli_bake_warning");
    let obj = d.join("degenerate.obj");
    std::fs::write(
        &obj,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 1\nf 1 2 3\nf 1 1 2\nf 1 2 4\n",
    )
    .unwrap();
    let json = d.join("degenerate.json");
    let o = trompe(&[
        "impostor",
        "bake",
        obj.to_str().unwrap(),
        "--resolution",
        "32",
        "-o",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("degenerate.obj") && e.contains("dropped 1 degenerate triangle"),
        "{e}"
    );
    assert!(json.is_file());
}

#[test]
fn bench_goal_times_the_goal_pair_alone() {
    // The teapot keeps a debug build quick; one run is 3 s of alternated pairs.
    let o = trompe(&["bench", "--goal", "1", "--mesh", "assets/meshes/teapot.obj"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let run = out
        .lines()
        .find(|l| l.trim_start().starts_with("run 1:"))
        .unwrap_or_else(|| panic!("no run line in: {out}"));
    // "run 1: build B ms, peer P ms, R ×": R is B / P as printed (three decimals each).
    let numbers: Vec<f64> = run
        .split(|c: char| !(c.is_ascii_digit() || c == '.'))
        .filter_map(|w| w.parse().ok())
        .collect();
    let [_, build, peer, ratio] = numbers[..] else {
        panic!("unexpected run line: {run}");
    };
    assert!(build > 0.0 && peer > 0.0, "{run}");
    assert!((ratio - build / peer).abs() <= 2e-3 * ratio + 1e-3, "{run}");
    assert!(out.contains("1 runs:") && out.contains("median"), "{out}");
    fails_cleanly(&trompe(&["bench", "--goal", "0"]), "--goal");
}

/// `impostor check` looks nothing up relative to the build tree: a copy of the binary, run
/// from a directory outside the repository on a copy of the mesh, prints the same figures.
#[test]
fn impostor_check_gives_the_same_figures_from_a_moved_binary() {
    let away = std::env::temp_dir().join(format!("trompe-moved-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&away);
    std::fs::create_dir_all(&away).unwrap();
    let binary = away.join("trompe");
    std::fs::copy(env!("CARGO_BIN_EXE_trompe"), &binary).unwrap();
    let mesh = away.join("teapot.obj");
    std::fs::copy(common::asset("meshes/teapot.obj"), &mesh).unwrap();
    let args = [
        "impostor",
        "check",
        mesh.to_str().unwrap(),
        "--resolution",
        "96",
        "--view",
        "160",
    ];
    let here = trompe(&args);
    let moved = Command::new(&binary)
        .args(args)
        .current_dir(&away)
        .output()
        .expect("runs");
    let _ = std::fs::remove_dir_all(&away);
    assert!(here.status.success(), "{}", stderr(&here));
    assert!(moved.status.success(), "{}", stderr(&moved));
    let out = String::from_utf8_lossy(&here.stdout);
    assert!(
        out.contains("agreement ") && out.contains("beside it"),
        "{out}"
    );
    assert_eq!(here.stdout, moved.stdout);
}

/// Every file a command reads is safe from its outputs: an output that is an input — by any
/// spelling, a derived output included — is refused before any work, and the input is left
/// byte for byte as it was.
#[test]
fn no_command_overwrites_what_it_reads() {
    let d = scratch("cli_outputs");
    // A scene reading a textured OBJ (its MTL and texture), a panorama and a second texture.
    let src = common::shared("meshes/bunny10k_textured");
    let mut mesh = None;
    for e in std::fs::read_dir(&src).unwrap() {
        let e = e.unwrap();
        let to = d.join(e.file_name());
        std::fs::copy(e.path(), &to).unwrap();
        if to.extension().is_some_and(|x| x == "obj") {
            mesh = Some(to);
        }
    }
    let mesh = mesh.expect("the textured bunny has an OBJ");
    let texture = std::fs::read_dir(&d)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "png" || x == "jpg"))
        .expect("and a texture");
    std::fs::copy(common::asset("envmaps/studio.hdr"), d.join("studio.hdr")).unwrap();
    std::fs::copy(common::asset("meshes/teapot.obj"), d.join("teapot.obj")).unwrap();
    std::fs::write(d.join("wood.png"), std::fs::read(&texture).unwrap()).unwrap();
    let scene = d.join("s.toml");
    std::fs::write(
        &scene,
        format!(
            "[camera]\nposition = [0, 0.5, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\nresolution = [16, 16]\n\n[environment]\npath = \"studio.hdr\"\n\n[[object]]\nmesh = \"{}\"\n\n[[object]]\nmesh = \"teapot.obj\"\nmaterial = {{ type = \"diffuse\", texture = \"wood.png\" }}\n",
            mesh.file_name().unwrap().to_string_lossy()
        ),
    )
    .unwrap();
    let sum = |p: &Path| std::fs::read(p).unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let guarded = [
        &scene,
        &mesh,
        &texture,
        &d.join("studio.hdr"),
        &d.join("wood.png"),
    ];
    let before: Vec<Vec<u8>> = guarded.iter().map(|p| sum(p)).collect();
    let png_texture = if texture.extension().is_some_and(|x| x == "png") {
        s(&texture)
    } else {
        s(&d.join("wood.png"))
    };
    // render: the colour over a texture, the depth over the mesh (by another spelling), the
    // normals over the scene.
    let dotted = d.join(".").join(mesh.file_name().unwrap());
    let wood = s(&d.join("wood.png"));
    for args in [
        vec!["render", &s(&scene), "-o", &png_texture],
        vec!["render", &s(&scene), "-o", &wood],
        vec![
            "render",
            &s(&scene),
            "-o",
            &s(&d.join("o.png")),
            "--depth",
            &s(&dotted),
        ],
        vec![
            "render",
            &s(&scene),
            "-o",
            &s(&d.join("o.exr")),
            "--depth",
            &s(&d.join("o.exr")),
        ],
    ] {
        let o = trompe(&args);
        let e = stderr(&o);
        assert!(
            !o.status.success() && !e.contains("panicked"),
            "{args:?}: {e}"
        );
        assert!(
            e.contains("refusing to overwrite")
                || e.contains("same file")
                || e.contains("ending in"),
            "{args:?}: {e}"
        );
    }
    fails_cleanly(
        &trompe(&["render", &s(&scene), "-o", &s(&d.join("studio.hdr"))]),
        "refusing to overwrite",
    );
    // bake: the preview it derives from -o would land on the model's own texture.
    let stem = texture.with_extension("json");
    if texture.extension().is_some_and(|x| x == "png") {
        fails_cleanly(
            &trompe(&["impostor", "bake", &s(&mesh), "-o", &s(&stem)]),
            "refusing to overwrite",
        );
    }
    // compare: the heat map over the mask.
    let mask = d.join("wood.png");
    fails_cleanly(
        &trompe(&[
            "compare",
            &wood,
            &wood,
            "--heatmap",
            &s(&mask),
            "--mask",
            &s(&mask),
        ]),
        "refusing to overwrite",
    );
    // check: the saved impostor over the reflector's sidecar name.
    fails_cleanly(
        &trompe(&[
            "impostor",
            "check",
            &s(&d.join("teapot.obj")),
            "--reflector",
            &s(&mesh),
            "-o",
            &s(&d.join("teapot.obj")),
        ]),
        "refusing to overwrite",
    );
    for (p, b) in guarded.iter().zip(&before) {
        assert_eq!(&sum(p), b, "{} changed", p.display());
    }
    // An existing output with an extension render does not write is left alone.
    let jpg = d.join("x.jpg");
    std::fs::write(&jpg, b"a photo").unwrap();
    fails_cleanly(
        &trompe(&["render", &s(&scene), "-o", &s(&jpg)]),
        "ending in",
    );
    assert_eq!(sum(&jpg), b"a photo");
    // demo refuses a directory of the user's, and names what is in it.
    fails_cleanly(
        &trompe(&["demo", "-o", &s(&d)]),
        "holds files trompe did not write",
    );
    assert_eq!(sum(&scene), before[0]);
}

/// Two identical bakes write identical bytes, and a sidecar is never read with another EXR.
#[test]
fn bakes_are_byte_identical_and_a_sidecar_keeps_to_its_own_maps() {
    let d = scratch("cli_bake_bytes");
    let teapot = common::asset("meshes/teapot.obj");
    let bake = |name: &str, from: &str| {
        let o = trompe(&[
            "impostor",
            "bake",
            teapot.to_str().unwrap(),
            "--resolution",
            "64",
            "--from",
            from,
            "-o",
            d.join(name).to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    };
    bake("a.json", "0,0.3,1");
    bake("b.json", "0,0.3,1");
    for ext in ["json", "exr", "png"] {
        let (a, b) = (
            d.join("a").with_extension(ext),
            d.join("b").with_extension(ext),
        );
        let (a, b) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
        if ext == "json" {
            let strip = |t: Vec<u8>| String::from_utf8(t).unwrap().replace("b.exr", "a.exr");
            assert_eq!(strip(a), strip(b), "{ext}");
        } else {
            assert!(a == b, "{ext} differs");
        }
    }
    // Another bake's maps under a's name: a's sidecar refuses them.
    bake("c.json", "1,0.3,0");
    std::fs::copy(d.join("c.exr"), d.join("a.exr")).unwrap();
    let o = trompe(&["info", d.join("a.json").to_str().unwrap()]);
    fails_cleanly(&o, "is not the EXR this sidecar was saved with");
}

/// A capture written by `views capture` is read back by `views score` and `views render`; a
/// folder that holds other files is refused.
#[test]
fn views_capture_score_and_render() {
    let d = scratch("cli_views");
    let cap = d.join("cap");
    let teapot = common::asset("meshes/teapot.obj");
    let t = teapot.to_str().unwrap();
    let o = trompe(&[
        "views",
        "capture",
        t,
        "--count",
        "16",
        "--size",
        "96x72",
        "-o",
        cap.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(cap.join("cameras.txt").is_file() && cap.join("images/view0015.png").is_file());
    // Noise past the rig's own distance records no camera of the capture: refused.
    fails_cleanly(
        &trompe(&[
            "views",
            "capture",
            t,
            "--pose-noise",
            "1e308",
            "-o",
            d.join("noisy").to_str().unwrap(),
        ]),
        "--pose-noise 1e308: must be between 0 and the distance (3 radii)",
    );
    let o = trompe(&[
        "views",
        "score",
        cap.to_str().unwrap(),
        "--mesh",
        t,
        "--every",
        "5",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("16 views; each of 4 left out") && out.contains("ulr"),
        "{out}"
    );
    let png = d.join("novel.png");
    let o = trompe(&[
        "views",
        "render",
        cap.to_str().unwrap(),
        "--mesh",
        t,
        "--scene",
        "scenes/diffuse.toml",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(png.is_file());
    // Into a folder of someone else's files: refused, nothing written.
    let foreign = d.join("foreign");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
    let o = trompe(&[
        "views",
        "capture",
        t,
        "--count",
        "2",
        "-o",
        foreign.to_str().unwrap(),
    ]);
    fails_cleanly(
        &o,
        "holds files trompe did not write (notes.txt among them)",
    );
    assert_eq!(std::fs::read_dir(&foreign).unwrap().count(), 1);
    let o = trompe(&["views", "score", d.to_str().unwrap(), "--mesh", t]);
    fails_cleanly(&o, "no COLMAP model here");
}

/// Every input the fuzzers found a crash with (tests/fuzz-regressions/) is a named error now,
/// without a panic even caught.
#[test]
fn fuzz_regressions_are_named_errors_without_a_panic() {
    let dir = common::root().join("tests/fuzz-regressions");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let o = trompe(&["info", path.to_str().unwrap()]);
        let e = stderr(&o);
        assert!(!o.status.success(), "{}: loaded", path.display());
        assert!(!e.contains("panicked"), "{}: {e}", path.display());
        assert!(
            e.contains(path.file_name().unwrap().to_str().unwrap()),
            "{e}"
        );
        seen += 1;
    }
    assert!(seen > 0);
}

/// Two bakes to one name at once leave one complete, loadable impostor: the first is held
/// between its EXR and its sidecar (a test hook) while the second bakes and publishes.
#[test]
fn concurrent_bakes_to_one_name_leave_one_complete_impostor() {
    let d = scratch("cli_bake_concurrent");
    let teapot = common::asset("meshes/teapot.obj");
    let out = d.join("t.json");
    let bake = |from: &str, pause_ms: &str| {
        Command::new(env!("CARGO_BIN_EXE_trompe"))
            .args(["impostor", "bake", teapot.to_str().unwrap()])
            .args(["--resolution", "96", "--from", from, "-o"])
            .arg(&out)
            .env("TROMPE_TEST_PAUSE_BEFORE_SIDECAR_MS", pause_ms)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("runs")
    };
    for trial in 0..2 {
        let slow = bake("0,0.3,1", "800");
        std::thread::sleep(std::time::Duration::from_millis(200));
        let fast = bake("1,0.3,0", "0");
        for child in [slow, fast] {
            let o = child.wait_with_output().expect("waits");
            assert!(o.status.success(), "trial {trial}: {}", stderr(&o));
        }
        let loaded = trompe::impostor::file::load(&out);
        assert!(loaded.is_ok(), "trial {trial}: {:?}", loaded.err());
    }
}

/// Numbers past what trompe can place are named errors, not panics: a NaN time, an object
/// placed or animated beyond f32, NaN animation speeds.
#[test]
fn non_finite_times_and_placements_are_named_errors() {
    let d = scratch("cli_non_finite");
    let out = d.join("o.png");
    let out = out.to_str().unwrap();
    fails_cleanly(
        &trompe(&[
            "render",
            "scenes/turntable.toml",
            "--time",
            "nan",
            "-o",
            out,
        ]),
        "must be a finite number",
    );
    let cam =
        "[camera]\nposition = [0, 1, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\nresolution = [8, 8]\n";
    for (name, body, time, expect) in [
        (
            "far.toml",
            "[[object]]\nshape = \"cube\"\ntranslate = [3e38, 0, 0]\n[[object]]\nshape = \"cube\"\ntranslate = [-3e38, 0, 0]\n",
            "0",
            "span more than",
        ),
        (
            "runs.toml",
            "[[object]]\nshape = \"sphere\"\n[object.animate]\nvelocity = [3e38, 0, 0]\n",
            "10",
            "(or not a number)",
        ),
        (
            "one-far.toml",
            "[[object]]\nshape = \"cube\"\ntranslate = [3e38, 0, 0]\n",
            "0",
            "beyond ±1e18",
        ),
        (
            "nan.toml",
            "[[object]]\nshape = \"sphere\"\n[object.animate]\ndegrees_per_second = nan\n",
            "1",
            "object[0].animate",
        ),
    ] {
        let p = d.join(name);
        std::fs::write(&p, format!("{cam}{body}")).unwrap();
        // Every method that places the scene at the time asked, the octahedral one included,
        // refuses it before building anything.
        for method in ["trace", "raster", "octahedral", "c3rc", "relief"] {
            fails_cleanly(
                &trompe(&[
                    "render",
                    p.to_str().unwrap(),
                    "--time",
                    time,
                    "--method",
                    method,
                    "-o",
                    out,
                ]),
                expect,
            );
        }
    }
    // A mesh file with a vertex at 3e38: every command that loads it names the vertex.
    let far = d.join("far.obj");
    std::fs::write(&far, "v 0 0 0\nv 1 0 0\nv 3e38 1 0\nf 1 2 3\n").unwrap();
    let json = d.join("far.json");
    fails_cleanly(
        &trompe(&[
            "impostor",
            "bake",
            far.to_str().unwrap(),
            "-o",
            json.to_str().unwrap(),
        ]),
        "vertex 2: coordinate 3e38 is beyond ±1e18",
    );
}

/// What used to pass silently or be named wrongly: NaN colours, tints and light intensities; an
/// all-black mask; `--k nan`; an absurd `--threads`; a UTF-8 byte-order mark before an OBJ's
/// first vertex.
#[test]
fn silent_wrong_results_are_named_errors() {
    let d = scratch("cli_silent");
    let out = d.join("o.png");
    let out = out.to_str().unwrap();
    let cam =
        "[camera]\nposition = [0, 1, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\nresolution = [8, 8]\n";
    for (name, body, expect) in [
        (
            "colour.toml",
            "[[object]]\nshape = \"cube\"\nmaterial = { type = \"diffuse\", color = [nan, 0, 0] }\n",
            "object[0].material",
        ),
        (
            "tint.toml",
            "[[object]]\nshape = \"cube\"\nmaterial = { type = \"mirror\", tint = [1, inf, 1] }\n",
            "object[0].material",
        ),
        (
            "light.toml",
            "[light]\ndirection = [0, 1, 0]\nintensity = nan\n",
            "light.intensity",
        ),
        (
            "env.toml",
            "[environment]\npath = \"x.hdr\"\nintensity = nan\n",
            "environment.intensity",
        ),
    ] {
        let p = d.join(name);
        std::fs::write(&p, format!("{cam}{body}")).unwrap();
        fails_cleanly(&trompe(&["render", p.to_str().unwrap(), "-o", out]), expect);
    }
    // An all-black mask selects nothing: an error, not NaN scores.
    let img = d.join("img.png");
    let black = d.join("black.png");
    trompe::frame::io::write_png(&img, &trompe::Image::new(4, 4, trompe::Rgba::ONE).unwrap())
        .unwrap();
    trompe::frame::io::write_png(&black, &trompe::Image::new(4, 4, trompe::Rgba::W).unwrap())
        .unwrap();
    let (i, b) = (img.to_str().unwrap(), black.to_str().unwrap());
    fails_cleanly(&trompe(&["compare", i, i, "--mask", b]), "selects no pixel");
    fails_cleanly(
        &trompe(&[
            "impostor",
            "bake",
            "assets/meshes/teapot.obj",
            "--k",
            "nan",
            "-o",
            out,
        ]),
        "finite number",
    );
    fails_cleanly(
        &trompe(&["--threads", "100000", "info", "assets/meshes/teapot.obj"]),
        "between 1 and",
    );
    // A byte-order mark does not cost the first vertex.
    let obj = d.join("bom.obj");
    std::fs::write(&obj, b"\xEF\xBB\xBFv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let loaded = trompe::geom::io::load(&obj).unwrap();
    assert_eq!(loaded.mesh.triangle_count(), 1);
}

#[test]
fn render_frames_writes_the_sequence_and_scores_it() {
    let d = scratch("cli_frames");
    let pattern = d.join("seq/frame_%03d.png");
    let o = trompe(&[
        "render",
        "scenes/turntable.toml",
        "-o",
        pattern.to_str().unwrap(),
        "--method",
        "envmap",
        "--frames",
        "3",
        "--fps",
        "2",
        "--compare",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for i in 0..3 {
        assert!(d.join(format!("seq/frame_{i:03}.png")).is_file());
    }
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        out.lines().filter(|l| l.starts_with("frame")).count(),
        3,
        "{out}"
    );
    assert!(
        out.contains("t    1.000 s") && out.contains("FLIP"),
        "{out}"
    );
    // A file name with no frame number in it is refused before any work.
    let o = trompe(&[
        "render",
        "scenes/turntable.toml",
        "-o",
        d.join("one.png").to_str().unwrap(),
        "--frames",
        "2",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("%04d"), "{}", stderr(&o));
}
