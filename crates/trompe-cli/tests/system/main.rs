//! The command-line tests that need a system package: the viewer's real window under a virtual
//! X server (Xvfb), `--device gpu` on a GPU adapter (Mesa's lavapipe where there is no GPU),
//! the three.js runtime in headless Chromium, and real photographs (Debian's opencv-doc, read
//! by OpenCV's Python). A missing package makes its test *ignored* — counted in the summary, the
//! reason printed above it — or failed where `TROMPE_REQUIRE_SYSTEM` is set, as `.ci/run` sets
//! it.

#[path = "../integration/common/mod.rs"]
mod common;
mod stereo;
mod web;

use common::{fails_cleanly, needs, scratch, stderr, trompe};
use libtest_mimic::{Arguments, Trial};
use std::path::{Path, PathBuf};
use trompe::frame::metrics;

/// A test function as a trial that needs `what` (present or not): a panic fails it.
fn trial(name: &str, test: fn(), present: bool, what: &'static str) -> Trial {
    let run = move || {
        test();
        Ok(())
    };
    needs(Trial::test(name, run), present, what)
}

fn main() {
    let args = Arguments::from_args();
    let adapter = !trompe_gpu::adapters(trompe_gpu::Backends::All).is_empty();
    const ADAPTER: &str = "a GPU adapter (without a GPU: lavapipe, package mesa-vulkan-drivers)";
    let trials = vec![
        trial(
            "viewer::the_window_under_a_virtual_x_server_shows_the_headless_frame",
            the_window_under_a_virtual_x_server_shows_the_headless_frame,
            common::has_command("xvfb-run"),
            "xvfb-run (package xvfb)",
        ),
        trial(
            "viewer::the_gpu_window_shows_the_frame_through_a_wgpu_surface",
            the_gpu_window_shows_the_frame_through_a_wgpu_surface,
            common::has_command("xvfb-run") && adapter,
            "xvfb-run (package xvfb) and a GPU adapter (without a GPU: lavapipe, package \
             mesa-vulkan-drivers)",
        ),
        trial(
            "gpu::render_on_the_gpu_is_the_cpu_frame",
            render_on_the_gpu_is_the_cpu_frame,
            adapter,
            ADAPTER,
        ),
        trial(
            "gpu::projective_renders_on_the_gpu_are_the_cpu_frames",
            projective_renders_on_the_gpu_are_the_cpu_frames,
            adapter,
            ADAPTER,
        ),
        trial(
            "gpu::the_headless_viewer_draws_trace_and_raster_on_the_gpu",
            the_headless_viewer_draws_trace_and_raster_on_the_gpu,
            adapter,
            ADAPTER,
        ),
        trial(
            "gpu::the_headless_viewer_blends_views_and_masters_on_the_gpu",
            the_headless_viewer_blends_views_and_masters_on_the_gpu,
            adapter,
            ADAPTER,
        ),
        trial(
            "stereo::at_the_photographs_resolution_the_novel_view_beats_a_forward_warp_on_psnr_and_ssim",
            stereo::at_the_photographs_resolution_the_novel_view_beats_a_forward_warp_on_psnr_and_ssim,
            stereo::ready(),
            stereo::NEEDS,
        ),
        trial(
            "stereo::at_half_the_photographs_resolution_the_prefiltered_novel_view_beats_a_forward_warp",
            stereo::at_half_the_photographs_resolution_the_prefiltered_novel_view_beats_a_forward_warp,
            stereo::ready(),
            stereo::NEEDS,
        ),
        trial(
            "stereo::a_real_capture_with_an_exposure_change_bakes_with_its_seam_step_at_least_halved",
            stereo::a_real_capture_with_an_exposure_change_bakes_with_its_seam_step_at_least_halved,
            stereo::ready(),
            stereo::NEEDS,
        ),
        trial(
            "web::the_threejs_runtime_draws_the_ducks_bake_as_trompe_does",
            web::the_threejs_runtime_draws_the_ducks_bake_as_trompe_does,
            web::ready(),
            web::NEEDS,
        ),
        trial(
            "web::distant_impostors_sample_their_mip_levels",
            web::distant_impostors_sample_their_mip_levels,
            web::ready(),
            web::NEEDS,
        ),
        trial(
            "web::the_threejs_cross_fade_shares_the_pixels_by_the_layouts_rule",
            web::the_threejs_cross_fade_shares_the_pixels_by_the_layouts_rule,
            web::ready(),
            web::NEEDS,
        ),
        trial(
            "web::a_compressed_surface_reads_in_threejs_as_trompe_reads_it",
            web::a_compressed_surface_reads_in_threejs_as_trompe_reads_it,
            web::ready(),
            web::NEEDS,
        ),
        trial(
            "gpu::info_names_the_adapter_it_opens",
            info_names_the_adapter_it_opens,
            adapter,
            ADAPTER,
        ),
    ];
    libtest_mimic::run(&args, trials).exit();
}

/// `trompe view scenes/teapot-in-bunny.toml` with `args`, in a window under Xvfb, fed the
/// script `keys`, writing into `out`.
fn in_a_window(args: &[&str], keys: &Path, out: &Path) -> std::process::Output {
    std::process::Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24"])
        .arg(env!("CARGO_BIN_EXE_trompe"))
        .args(["view", "scenes/teapot-in-bunny.toml"])
        .args(args)
        .arg("--script")
        .arg(keys)
        .arg("-o")
        .arg(out)
        .current_dir(common::root())
        .output()
        .expect("xvfb-run runs")
}

/// The viewer's window, driven by a script under Xvfb, shows what the headless viewer renders.
pub fn the_window_under_a_virtual_x_server_shows_the_headless_frame() {
    let dir = scratch("viewer-window");
    let keys = dir.join("keys.txt");
    std::fs::write(&keys, "0.0 tap 4\n1.0 tap F12\n").unwrap();
    let (window, headless) = (dir.join("window"), dir.join("headless"));
    let o = in_a_window(&["--size", "160x120", "--quit-after", "2"], &keys, &window);
    assert!(o.status.success(), "{}", stderr(&o));
    let shot = std::fs::read_dir(&window)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("screenshot"))
        })
        .unwrap_or_else(|| panic!("no screenshot: {}", stderr(&o)));
    let o = trompe(&[
        "view",
        "scenes/teapot-in-bunny.toml",
        "--size",
        "160x120",
        "--frames",
        "1",
        "--script",
        keys.to_str().unwrap(),
        "-o",
        headless.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let read = |p: &Path| trompe::frame::io::read_color(p).unwrap();
    let score =
        metrics::compare(&read(&headless.join("frame_0000.png")), &read(&shot), None).unwrap();
    assert!(
        score.flip < 0.01,
        "window against headless: FLIP {}",
        score.flip
    );
}

/// `view --device gpu` under Xvfb shows its window through a wgpu surface on the GPU: what the
/// surface was given, read back from the device, is the frame the viewer rendered, byte for
/// byte below the overlay.
pub fn the_gpu_window_shows_the_frame_through_a_wgpu_surface() {
    let dir = scratch("viewer-gpu-window");
    let keys = dir.join("keys.txt");
    // F12 at 0.5 s; the window stays 8 s, time enough for a loaded machine to draw past it.
    std::fs::write(&keys, "0.5 tap F12\n").unwrap();
    let window = dir.join("window");
    let o = in_a_window(
        &["--device", "gpu", "--size", "240x320", "--quit-after", "8"],
        &keys,
        &window,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("the window shows through a wgpu surface on"),
        "{}",
        stderr(&o)
    );
    let named = |prefix: &str| {
        std::fs::read_dir(&window)
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| {
                p.file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with(prefix))
            })
            .unwrap_or_else(|| panic!("no {prefix}: {}", stderr(&o)))
    };
    let read = |p: &Path| trompe::frame::io::read_color(p).unwrap();
    let (frame, shown) = (read(&named("screenshot")), read(&named("shown")));
    assert_eq!(frame.size(), (240, 320));
    assert_eq!(shown.size(), frame.size());
    let level = |v: f32| (trompe::frame::linear_to_srgb(v) * 255.0).round() as i32;
    // The overlay covers at most the top thirteen lines (18 pixels each, from 4).
    let mut worst = 0;
    for y in 240..320 {
        for x in 0..240 {
            let (a, b) = (frame.get(x, y), shown.get(x, y));
            for c in 0..3 {
                worst = worst.max((level(a[c]) - level(b[c])).abs());
            }
        }
    }
    assert!(worst <= 1, "shown differs from the frame by {worst} levels");
    // And the overlay is drawn over the top: its first line's band darkens the frame.
    let darker = (4..22)
        .flat_map(|y| (0..240).map(move |x| (x, y)))
        .filter(|&(x, y)| level(shown.get(x, y)[1]) < level(frame.get(x, y)[1]))
        .count();
    assert!(darker > 240, "{darker} pixels of the overlay's first line");
}

/// `render --device gpu` writes the frame `--device cpu` writes (the trace method), one frame
/// and a sequence.
pub fn render_on_the_gpu_is_the_cpu_frame() {
    let dir = scratch("render-gpu");
    let (cpu, gpu) = (dir.join("cpu.png"), dir.join("gpu.png"));
    for (device, out) in [("cpu", &cpu), ("gpu", &gpu)] {
        let o = trompe(&[
            "render",
            "scenes/diffuse.toml",
            "--device",
            device,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let read = |p: &Path| trompe::frame::io::read_color(p).unwrap();
    let score = metrics::compare(&read(&cpu), &read(&gpu), None).unwrap();
    assert!(score.flip < 0.01, "GPU against CPU: FLIP {}", score.flip);
    // Paper 2's hybrid reflections: the splats projected and resolved on the GPU.
    for (device, out) in [("cpu", &cpu), ("gpu", &gpu)] {
        let o = trompe(&[
            "render",
            "scenes/c3rc-bunny.toml",
            "--method",
            "c3rc",
            "--device",
            device,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        // The report, on the terminal beside the progress.
        let printed = stderr(&o);
        assert!(printed.contains("valid projections"), "{printed}");
    }
    let score = metrics::compare(&read(&cpu), &read(&gpu), None).unwrap();
    println!("c3rc: GPU against CPU FLIP {:.5}", score.flip);
    assert!(
        score.flip < 0.02,
        "c3rc, GPU against CPU: FLIP {}",
        score.flip
    );
    // A time that is not a number is refused on the GPU as on the CPU.
    fails_cleanly(
        &trompe(&[
            "render",
            "scenes/diffuse.toml",
            "--device",
            "gpu",
            "--time",
            "nan",
            "-o",
            gpu.to_str().unwrap(),
        ]),
        "must be a finite number of seconds",
    );
    // A camera with a lens (a real camera's distortion) is the CPU tracer's alone: the GPU
    // refuses it by name rather than draw its pinhole.
    let lens = dir.join("lens.toml");
    let duck = common::asset("gltf/Duck.glb");
    std::fs::write(
        &lens,
        format!(
            "[camera]\nposition = [1.2, 1.9, 3.2]\nlook_at = [0.1, 0.85, 0.0]\nfx = 300\nfy = \
             300\ncx = 160\ncy = 120\nmodel = \"RADIAL\"\ndistortion = [-0.2, 0.05]\n\
             resolution = [320, 240]\n\n[[object]]\nmesh = {:?}\n",
            duck.to_str().unwrap()
        ),
    )
    .unwrap();
    fails_cleanly(
        &trompe(&[
            "render",
            lens.to_str().unwrap(),
            "--device",
            "gpu",
            "-o",
            gpu.to_str().unwrap(),
        ]),
        "RADIAL lens distortion, which only the trace method renders",
    );
    let pattern = dir.join("frame_%02d.png");
    let o = trompe(&[
        "render",
        "scenes/turntable.toml",
        "--device",
        "gpu",
        "--frames",
        "3",
        "-o",
        pattern.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("3 frames by trace"), "{out}");
    for i in 0..3 {
        assert!(dir.join(format!("frame_{i:02}.png")).is_file());
    }
}

/// `count` views of `duck` of `size` captured into `dir`/cap, and their master encoding in
/// `dir`/enc.
fn duck_capture_and_encoding(dir: &Path, count: u32, size: &str) -> (PathBuf, PathBuf) {
    let duck = common::asset("gltf/Duck.glb");
    let (cap, enc) = (dir.join("cap"), dir.join("enc"));
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let count = count.to_string();
    for args in [
        &[
            "views",
            "capture",
            &s(&duck),
            "-o",
            &s(&cap),
            "--count",
            &count,
            "--size",
            size,
        ][..],
        &[
            "master",
            "encode",
            &s(&cap),
            "--mesh",
            &s(&duck),
            "-o",
            &s(&enc),
        ],
    ] {
        let o = trompe(args);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    (cap, enc)
}

/// `master render --device gpu` (every master a layer of one texture array, blended by a
/// compute shader) and `views render --device gpu` (the views' images and depth maps in texture
/// arrays) and `layers render --device gpu` (every image layer, or every whole photograph, in
/// texture arrays) write the
/// frames `--device cpu` writes; what they do not blend is refused by name, pointing at the
/// CPU.
pub fn projective_renders_on_the_gpu_are_the_cpu_frames() {
    let dir = scratch("master-gpu");
    let duck = common::asset("gltf/Duck.glb");
    let duck = duck.to_str().unwrap();
    let (cap, enc) = duck_capture_and_encoding(&dir, 8, "160x120");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let render = |(command, input): (&str, &Path), device: &str, weights: &str, out: &Path| {
        let (input, out) = (s(input), s(out));
        let mut args = vec![command, "render", &input, "--mesh", duck];
        args.extend(["--scene", "scenes/duck-mirror.toml", "--device", device]);
        // "--weights W", or "--weights W --seamless".
        args.push("--weights");
        args.extend(weights.split(' '));
        args.extend(["-o", &out]);
        trompe(&args)
    };
    let read = |p: &Path| trompe::frame::io::read_color(p).unwrap();
    for source in [("master", enc.as_path()), ("views", cap.as_path())] {
        for weights in ["ulr", "ulr --prefilter", "view-map", "best-face"] {
            let (cpu, gpu) = (dir.join("cpu.png"), dir.join("gpu.png"));
            for (device, out) in [("cpu", &cpu), ("gpu", &gpu)] {
                let o = render(source, device, weights, out);
                assert!(o.status.success(), "{}", stderr(&o));
                let printed = String::from_utf8_lossy(&o.stdout);
                assert!(printed.contains("pixels show the mesh"), "{printed}");
            }
            let score = metrics::compare(&read(&cpu), &read(&gpu), None).unwrap();
            let name = source.0;
            println!(
                "{name} render, {weights}: GPU against CPU FLIP {:.5}",
                score.flip
            );
            assert!(score.flip < 0.01, "{name}, {weights}: FLIP {}", score.flip);
        }
        fails_cleanly(
            &render(source, "gpu", "best-face --seamless", &dir.join("map.png")),
            "a seamless best-face bake is not on the GPU yet (render it with --device cpu)",
        );
    }
    // Image layers of a street of objects that hide each other, from its own camera.
    let layers = dir.join("layers");
    let built = trompe(&[
        "layers",
        "build",
        "scenes/street.toml",
        "--views",
        "3",
        "--size",
        "160x120",
        "-o",
        &s(&layers),
    ]);
    assert!(built.status.success(), "{}", stderr(&built));
    let layered = |device: &str, method: &str, out: &Path| {
        trompe(&[
            "layers",
            "render",
            "scenes/street.toml",
            "--layers",
            &s(&layers),
            "--method",
            method,
            "--device",
            device,
            "-o",
            &s(out),
        ])
    };
    for method in ["layered", "projective"] {
        let (cpu, gpu) = (dir.join("layers-cpu.png"), dir.join("layers-gpu.png"));
        for (device, out) in [("cpu", &cpu), ("gpu", &gpu)] {
            let o = layered(device, method, out);
            assert!(o.status.success(), "{}", stderr(&o));
        }
        let score = metrics::compare(&read(&cpu), &read(&gpu), None).unwrap();
        println!(
            "layers render --method {method}: GPU against CPU FLIP {:.5}",
            score.flip
        );
        assert!(score.flip < 0.01, "{method}: FLIP {}", score.flip);
    }
}

/// `info --gpu` lists the adapters and the one it opens, with its limits.
pub fn info_names_the_adapter_it_opens() {
    let o = trompe(&["info", "--gpu"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let first = &trompe_gpu::adapters(trompe_gpu::Backends::All)[0];
    assert!(out.contains(&first.name), "{out}");
    assert!(out.contains("opens:") && out.contains("limits"), "{out}");
    // As JSON: every adapter, and the one opened with its limits.
    let o = trompe(&["--json", "info", "--gpu"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let doc: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON document");
    let result = &doc["result"];
    assert_eq!(result["adapters"][0]["name"], first.name.as_str());
    let opened = result["opens"]["name"]
        .as_str()
        .expect("the adapter opened");
    assert!(out.contains(opened), "{opened}\n{out}");
    assert!(result["opens"]["limits"]["max_texture_dimension_2d"].as_u64() > Some(0));
}

/// The headless viewer with `--device gpu` replays a script whose frames, trace then raster,
/// are the CPU viewer's.
pub fn the_headless_viewer_draws_trace_and_raster_on_the_gpu() {
    let dir = scratch("view-gpu");
    let keys = dir.join("keys.txt");
    // Key 1 is trace, key 5 raster (the viewer's order, `trompe::methods::MethodKind::ALL`).
    std::fs::write(&keys, "0.0 tap 1\n0.05 tap 5\n").unwrap();
    for device in ["cpu", "gpu"] {
        let o = trompe(&[
            "view",
            "scenes/teapot-in-bunny.toml",
            "--size",
            "160x120",
            "--frames",
            "3",
            "--script",
            keys.to_str().unwrap(),
            "--device",
            device,
            "-o",
            dir.join(device).to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let read = |p: &Path| trompe::frame::io::read_color(p).unwrap();
    for frame in ["frame_0000.png", "frame_0002.png"] {
        let (cpu, gpu) = (dir.join("cpu").join(frame), dir.join("gpu").join(frame));
        let score = metrics::compare(&read(&cpu), &read(&gpu), None).unwrap();
        assert!(
            score.flip < 0.01,
            "{frame}: GPU against CPU, FLIP {}",
            score.flip
        );
    }
}

/// The headless viewer flying around the duck textured from its photographs (`--views`) and
/// from their master encoding (`--master`), on the GPU: every weighting, and the next
/// photograph's camera, is the CPU viewer's frame.
pub fn the_headless_viewer_blends_views_and_masters_on_the_gpu() {
    let dir = scratch("view-photographs-gpu");
    let duck = common::asset("gltf/Duck.glb");
    let duck = duck.to_str().unwrap();
    let (cap, enc) = duck_capture_and_encoding(&dir, 6, "128x96");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    // Away from the photographs, a frame a weighting; then the next photograph's camera, and a
    // step forward (20 steps a second, one input a step).
    let keys = dir.join("keys.txt");
    std::fs::write(
        &keys,
        "0.025 look 60 20\n0.025 tap 1\n0.075 tap 2\n0.125 tap 3\n0.175 tap 4\n\
         0.225 tap O\n0.225 tap 1\n0.275 down W\n0.375 up W\n",
    )
    .unwrap();
    let read = |p: &Path| trompe::frame::io::read_color(p).unwrap();
    for (flag, input) in [("--views", &cap), ("--master", &enc)] {
        for device in ["cpu", "gpu"] {
            let o = trompe(&[
                "view",
                flag,
                &s(input),
                "--mesh",
                duck,
                "--frames",
                "8",
                "--fps",
                "20",
                "--script",
                &s(&keys),
                "--device",
                device,
                "-o",
                &s(&dir.join(format!("{}-{device}", &flag[2..]))),
            ]);
            assert!(o.status.success(), "{}", stderr(&o));
            let printed = String::from_utf8_lossy(&o.stdout);
            for name in ["ulr", "vdtm", "view-map", "best-face"] {
                assert!(printed.contains(name), "{name} not shown:\n{printed}");
            }
        }
        for i in 0..8 {
            let frame = format!("frame_{i:04}.png");
            let at =
                |device: &str| read(&dir.join(format!("{}-{device}", &flag[2..])).join(&frame));
            let score = metrics::compare(&at("cpu"), &at("gpu"), None).unwrap();
            println!(
                "view {flag}, {frame}: GPU against CPU FLIP {:.5}",
                score.flip
            );
            assert!(score.flip < 0.01, "{flag} {frame}: FLIP {}", score.flip);
        }
    }
}
