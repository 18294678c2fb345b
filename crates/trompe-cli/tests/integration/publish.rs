//! Nothing lost: every command that fills a folder refuses a user's folder and another command's
//! result, changing nothing; a result of several files killed while it is written, or raced by
//! a second writer, leaves the old result or the new one, whole and loadable.

use crate::common;
use common::{scratch, stderr, trompe};
use std::path::{Path, PathBuf};
use std::process::{Child, Command};
use std::time::{Duration, Instant};

/// Every file under `dir` with its bytes, sorted.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let bytes = std::fs::read(&p).unwrap();
                out.push((p, bytes));
            }
        }
    }
    out.sort();
    out
}

fn s(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

fn capture(count: u32, out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_trompe"));
    c.args(["views", "capture", &s(&common::asset("meshes/teapot.obj"))])
        .args(["--count", &count.to_string(), "--size", "48x36", "-o"])
        .arg(out)
        .current_dir(common::root())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped());
    c
}

fn encode(model: &Path, out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_trompe"));
    c.args(["master", "encode", &s(model), "--mesh"])
        .arg(common::asset("meshes/teapot.obj"))
        .args(["--scale", "0.5", "-o"])
        .arg(out)
        .current_dir(common::root())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped());
    c
}

/// How many kills and races each writer gets: a few in CI; `TROMPE_SWEEP_KILLS` and
/// `TROMPE_SWEEP_RACES` make the same tests the full sweep.
fn sweep(var: &str, default: u32) -> u32 {
    std::env::var(var)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
        .max(2)
}

fn bake(args: &[&str], out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_trompe"));
    c.args(["impostor", "bake", &s(&common::asset("meshes/teapot.obj"))])
        .args(args)
        .arg("-o")
        .arg(out)
        .current_dir(common::root())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped());
    c
}

fn run(mut c: Command) {
    let o = c.output().expect("runs");
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Hidden names beside `target` (staged results a killed writer left).
fn litter(target: &Path) -> Vec<String> {
    let name = target.file_name().unwrap().to_string_lossy().into_owned();
    std::fs::read_dir(target.parent().unwrap())
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(&format!(".{name}.")))
        .collect()
}

#[test]
fn folder_writers_refuse_a_users_folder_and_another_commands_result_changing_nothing() {
    let d = scratch("publish_refusals");
    let cap = d.join("capture");
    run(capture(2, &cap));
    let mine = d.join("mine");
    std::fs::create_dir_all(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), "mine").unwrap();
    let teapot = s(&common::asset("meshes/teapot.obj"));
    let scene = "scenes/relief-walk.toml";
    let mut attempts = 0;
    for (target, found) in [
        (&cap, "is a capture (trompe views capture)"),
        (&mine, "trompe did not write (notes.txt among them)"),
    ] {
        let before = snapshot(target);
        let t = s(target);
        for args in [
            vec!["master", "encode", &s(&cap), "--mesh", &teapot, "-o", &t],
            vec![
                "layers",
                "build",
                "scenes/diffuse.toml",
                "--views",
                "2",
                "-o",
                &t,
            ],
            vec!["relief", scene, "--frames", "2", "-o", &t],
            vec!["view", scene, "--frames", "1", "-o", &t],
            vec!["demo", "-o", &t],
        ] {
            let o = trompe(&args);
            let e = stderr(&o);
            assert!(!o.status.success(), "{args:?} wrote into {t}");
            assert!(
                e.contains(found) && !e.contains("panicked"),
                "{args:?}: {e}"
            );
            attempts += 1;
        }
        if target == &mine {
            let o = trompe(&["views", "capture", &teapot, "--count", "2", "-o", &t]);
            assert!(stderr(&o).contains(found), "{}", stderr(&o));
            attempts += 1;
        }
        assert_eq!(snapshot(target), before, "{t} changed");
    }
    // A render over a file the encoding or the capture is made of.
    let first_image = std::fs::read_dir(cap.join("images"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .min()
        .unwrap();
    let encoding = d.join("encoding");
    run(encode(&cap, &encoding));
    for args in [
        vec![
            "master",
            "render",
            &s(&encoding),
            "--mesh",
            &teapot,
            "--scene",
            "scenes/diffuse.toml",
            "-o",
            &s(&encoding.join("master_0000.png")),
        ],
        vec![
            "views",
            "render",
            &s(&cap),
            "--mesh",
            &teapot,
            "--scene",
            "scenes/diffuse.toml",
            "-o",
            &s(&first_image),
        ],
    ] {
        let before = snapshot(&d);
        let o = trompe(&args);
        assert!(
            !o.status.success() && stderr(&o).contains("refusing to overwrite"),
            "{args:?}: {}",
            stderr(&o)
        );
        assert_eq!(snapshot(&d), before);
        attempts += 1;
    }
    // An octahedral batch whose sibling's atlas would land on a mesh's texture.
    let batch = d.join("batch");
    std::fs::create_dir_all(&batch).unwrap();
    let src = common::shared("meshes/bunny10k_textured");
    let mut texture = None;
    for e in std::fs::read_dir(&src).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), batch.join(e.file_name())).unwrap();
        if e.path().extension().is_some_and(|x| x == "png") {
            texture = Some(e.file_name());
        }
    }
    let texture = PathBuf::from(texture.expect("the textured bunny has a PNG texture"));
    let obj = std::fs::read_dir(&batch)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "obj"))
        .unwrap();
    let sibling = batch.join(texture.with_extension("obj"));
    std::fs::copy(common::asset("meshes/teapot.obj"), &sibling).unwrap();
    let before = snapshot(&batch);
    let o = trompe(&[
        "impostor",
        "bake",
        &s(&obj),
        &s(&sibling),
        "--octahedral",
        "4",
        "--resolution",
        "64",
        "-o",
        &s(&batch),
    ]);
    assert!(
        !o.status.success() && stderr(&o).contains("a file of the user's is where the atlas"),
        "{}",
        stderr(&o)
    );
    assert_eq!(snapshot(&batch), before);
    attempts += 1;
    eprintln!("{attempts} overwrite attempts, {attempts} refused");
}

/// What kills left: the old result, the new one, and (files side by side only) a torn pair the
/// loader refused by name.
#[derive(Debug, Default)]
struct Kills {
    old: u32,
    new: u32,
    refused: u32,
}

/// Kills a writer of the result `new_n` (`spawn`) at `k` moments spread over its run, over the
/// result `old_n` (`reset` writes it): after each kill `whole(target)` must load one of the two,
/// or — where `torn` names what a loader says of a torn pair — refuse it with those words.
fn kill_during_publish(
    target: &Path,
    k: u32,
    (spawn, reset): (impl Fn() -> Child, impl Fn()),
    whole: impl Fn(&Path) -> Result<usize, String>,
    (old_n, new_n): (usize, usize),
    torn: Option<&str>,
) -> Kills {
    let t = Instant::now();
    assert!(spawn().wait().unwrap().success());
    let span = t.elapsed().as_millis() as u64;
    assert_eq!(whole(target), Ok(new_n));
    reset();
    let mut kills = Kills::default();
    for i in 0..k {
        let at = span * u64::from(i) / u64::from(k - 1);
        let mut child = spawn();
        std::thread::sleep(Duration::from_millis(at));
        let _ = child.kill();
        let _ = child.wait();
        match whole(target) {
            Ok(n) if n == old_n => kills.old += 1,
            Ok(n) if n == new_n => {
                kills.new += 1;
                reset();
            }
            Ok(n) => panic!("kill {i} at {at} ms: {n}, neither result"),
            Err(e) if torn.is_some_and(|t| e.contains(t)) => {
                kills.refused += 1;
                reset();
            }
            Err(e) => panic!("kill {i} at {at} ms: {e}"),
        }
    }
    assert!(litter(target).len() <= 1, "{:?}", litter(target));
    kills
}

#[test]
fn a_killed_or_raced_capture_or_encoding_leaves_a_whole_one() {
    let d = scratch("publish_kills");
    let cap = d.join("capture");
    run(capture(2, &cap));
    let views = |dir: &Path| -> Result<usize, String> {
        let mut set = trompe::views::ViewSet::load(dir, None).map_err(|e| e.to_string())?;
        set.load_images().map_err(|e| e.to_string())?;
        Ok(set.views.len())
    };
    assert_eq!(views(&cap), Ok(2));
    let kills = sweep("TROMPE_SWEEP_KILLS", 8);
    let left = kill_during_publish(
        &cap,
        kills,
        (
            || {
                let mut c = capture(3, &cap);
                c.env("TROMPE_TEST_PAUSE_IN_PUBLISH_MS", "300");
                c.spawn().unwrap()
            },
            || run(capture(2, &cap)),
        ),
        views,
        (2, 3),
        None,
    );
    eprintln!("capture: {kills} kills, {left:?}");
    // Two writers at once: one waits for the other; the folder holds one of them, whole.
    let races = sweep("TROMPE_SWEEP_RACES", 3);
    for trial in 0..races {
        let mut a = capture(2, &cap);
        a.env("TROMPE_TEST_PAUSE_IN_PUBLISH_MS", "200");
        let a = a.spawn().unwrap();
        let b = capture(3, &cap).spawn().unwrap();
        for c in [a, b] {
            let o = c.wait_with_output().unwrap();
            assert!(o.status.success(), "trial {trial}: {}", stderr(&o));
        }
        let n = views(&cap).unwrap_or_else(|e| panic!("trial {trial}: {e}"));
        assert!(n == 2 || n == 3);
        let images = std::fs::read_dir(cap.join("images")).unwrap().count();
        assert_eq!(images, n, "trial {trial}: one capture's images, not a mix");
    }
    // An encoding, killed while it encodes and while it publishes.
    let small = d.join("small");
    run(capture(2, &small));
    let enc = d.join("encoding");
    run(encode(&small, &enc));
    let masters = |dir: &Path| -> Result<usize, String> {
        let (manifest, images) = trompe::master::file::load(dir).map_err(|e| e.to_string())?;
        Ok(manifest.views.len().min(images.len()))
    };
    assert_eq!(masters(&enc), Ok(2));
    run(capture(3, &cap));
    let left = kill_during_publish(
        &enc,
        kills,
        (
            || {
                let mut c = encode(&cap, &enc);
                c.env("TROMPE_TEST_PAUSE_IN_PUBLISH_MS", "300");
                c.spawn().unwrap()
            },
            || run(encode(&small, &enc)),
        ),
        masters,
        (2, 3),
        None,
    );
    eprintln!("master encode: {kills} kills, {left:?}");
    // Two encodings at once: one waits for the other; the folder holds one of them, whole.
    for trial in 0..races {
        let mut a = encode(&small, &enc);
        a.env("TROMPE_TEST_PAUSE_IN_PUBLISH_MS", "200");
        let a = a.spawn().unwrap();
        let b = encode(&cap, &enc).spawn().unwrap();
        for c in [a, b] {
            let o = c.wait_with_output().unwrap();
            assert!(o.status.success(), "trial {trial}: {}", stderr(&o));
        }
        let n = masters(&enc).unwrap_or_else(|e| panic!("trial {trial}: {e}"));
        assert!(n == 2 || n == 3, "trial {trial}: {n}");
    }
    eprintln!("master encode: {races} races, each left one whole encoding");
    eprintln!("capture: {races} races, each left one whole capture");
    run(capture(2, &cap));
    assert!(litter(&cap).is_empty(), "{:?}", litter(&cap));
}

/// Results of files side by side (a SPOC impostor's EXR and sidecar, an octahedral atlas's four
/// maps and sidecar): killed at any moment, the sidecar loads with its own maps, or — killed
/// within the few renames that make them current — is refused by its checksums, never read with
/// another bake's maps; two writers at once leave one bake, whole.
#[test]
fn a_killed_or_raced_bake_leaves_one_whole_bake() {
    let d = scratch("publish_bakes");
    let kills = sweep("TROMPE_SWEEP_KILLS", 6);
    let races = sweep("TROMPE_SWEEP_RACES", 3);
    let spoc = d.join("t.json");
    let loads = |p: &Path| -> Result<usize, String> {
        let i = trompe::impostor::file::load(p).map_err(|e| e.to_string())?;
        Ok(i.gd().size().0 as usize)
    };
    let left = kill_during_publish(
        &spoc,
        kills,
        (
            || bake(&["--resolution", "96"], &spoc).spawn().unwrap(),
            || run(bake(&["--resolution", "64"], &spoc)),
        ),
        loads,
        (64, 96),
        Some("is not the EXR this sidecar was saved with"),
    );
    eprintln!("SPOC bake: {kills} kills, {left:?}");
    for trial in 0..races {
        let slow = bake(&["--resolution", "64"], &spoc).spawn().unwrap();
        let fast = bake(&["--resolution", "96"], &spoc).spawn().unwrap();
        for c in [slow, fast] {
            let o = c.wait_with_output().unwrap();
            assert!(o.status.success(), "trial {trial}: {}", stderr(&o));
        }
        let n = loads(&spoc).unwrap_or_else(|e| panic!("trial {trial}: {e}"));
        assert!(n == 64 || n == 96, "trial {trial}: {n}");
    }
    eprintln!("SPOC bake: {races} races, each left one whole bake");
    let atlas = d.join("o.json");
    let maps = |p: &Path| -> Result<usize, String> {
        let sidecar = trompe::octahedral::file::read_sidecar(p).map_err(|e| e.to_string())?;
        trompe::octahedral::file::verify_maps(p, &sidecar).map_err(|e| e.to_string())?;
        Ok(sidecar.grid.n as usize)
    };
    let octahedral = |n: &str| bake(&["--octahedral", n, "--resolution", "128"], &atlas);
    let left = kill_during_publish(
        &atlas,
        kills,
        (|| octahedral("8").spawn().unwrap(), || run(octahedral("4"))),
        maps,
        (4, 8),
        Some("is not the file its index was written with"),
    );
    eprintln!("octahedral bake: {kills} kills, {left:?}");
    for trial in 0..races {
        let mut slow = octahedral("4");
        slow.env("TROMPE_TEST_PAUSE_BEFORE_SIDECAR_MS", "300");
        let slow = slow.spawn().unwrap();
        std::thread::sleep(Duration::from_millis(100));
        let fast = octahedral("8").spawn().unwrap();
        for c in [slow, fast] {
            let o = c.wait_with_output().unwrap();
            assert!(o.status.success(), "trial {trial}: {}", stderr(&o));
        }
        let n = maps(&atlas).unwrap_or_else(|e| panic!("trial {trial}: {e}"));
        assert!(n == 4 || n == 8);
    }
    eprintln!("octahedral bake: {races} races, each left one whole atlas");
}

fn layers_build(views: u32, out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_trompe"));
    c.args(["layers", "build", "scenes/street.toml", "--views"])
        .arg(views.to_string())
        .args(["--size", "64x48", "-o"])
        .arg(out)
        .current_dir(common::root())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped());
    c
}

/// A layer set (a project file, one OpenRaster file a view and the cameras): killed while it
/// is built or published, the folder loads as the old set or the new one; two builds at once
/// leave one set, its views' files all of that build.
#[test]
fn a_killed_or_raced_layer_set_leaves_a_whole_one() {
    let d = scratch("publish_layers");
    let kills = sweep("TROMPE_SWEEP_KILLS", 6);
    let races = sweep("TROMPE_SWEEP_RACES", 3);
    let scene = trompe::Scene::load(&common::root().join("scenes/street.toml")).unwrap();
    let set = d.join("street");
    let views = |dir: &Path| -> Result<usize, String> {
        let (meshes, names) = trompe::layers::scene_objects(&scene).map_err(|e| e.to_string())?;
        let set = trompe::layers::file::load(dir, meshes, names).map_err(|e| e.to_string())?;
        Ok(set.views.len())
    };
    run(layers_build(2, &set));
    let left = kill_during_publish(
        &set,
        kills,
        (
            || {
                let mut c = layers_build(3, &set);
                c.env("TROMPE_TEST_PAUSE_IN_PUBLISH_MS", "300");
                c.spawn().unwrap()
            },
            || run(layers_build(2, &set)),
        ),
        views,
        (2, 3),
        None,
    );
    eprintln!("layers build: {kills} kills, {left:?}");
    for trial in 0..races {
        let mut a = layers_build(2, &set);
        a.env("TROMPE_TEST_PAUSE_IN_PUBLISH_MS", "200");
        let a = a.spawn().unwrap();
        let b = layers_build(3, &set).spawn().unwrap();
        for c in [a, b] {
            let o = c.wait_with_output().unwrap();
            assert!(o.status.success(), "trial {trial}: {}", stderr(&o));
        }
        let n = views(&set).unwrap_or_else(|e| panic!("trial {trial}: {e}"));
        assert!(n == 2 || n == 3);
        let ora = std::fs::read_dir(&set)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.path().extension().is_some_and(|x| x == "ora"))
            .count();
        assert_eq!(ora, n, "trial {trial}: one build's views, not a mix");
    }
    eprintln!("layers build: {races} races, each left one whole set");
}
