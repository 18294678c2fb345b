//! The `trompe` binary end to end: outputs, exit codes and error messages.

mod common;
use common::scratch;
use std::path::Path;
use std::process::{Command, Output};

fn trompe(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_trompe"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[track_caller]
fn fails_cleanly(o: &Output, expect: &str) {
    let e = stderr(o);
    assert!(!o.status.success(), "should fail: {e}");
    assert!(!e.contains("panicked"), "panicked: {e}");
    assert!(e.contains(expect), "expected {expect:?} in: {e}");
}

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
