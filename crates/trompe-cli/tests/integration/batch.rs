//! Batches of any size (`impostor bake --octahedral` over folders and lists): the input tree
//! mirrored under -o, shards a job scheduler names, and a shard killed midway finished by a
//! re-run with --skip-existing exactly as an uninterrupted run.

use crate::common;
use common::{fails_cleanly, scratch, stderr, trompe};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};
use trompe::octahedral::batch::Manifest;

/// A library of `2n` small meshes, `n` in each of two folders; one name is in both.
fn library(dir: &Path, n: usize) -> PathBuf {
    let lib = dir.join("lib");
    for sub in ["trees", "rocks"] {
        std::fs::create_dir_all(lib.join(sub)).unwrap();
        // The same name in both folders.
        std::fs::copy(
            common::asset("gltf/Duck.glb"),
            lib.join(sub).join("same.glb"),
        )
        .unwrap();
        for k in 0..n - 1 {
            std::fs::copy(
                common::asset("meshes/teapot.obj"),
                lib.join(sub).join(format!("m{k}.obj")),
            )
            .unwrap();
        }
    }
    lib
}

fn bake(args: &[&str], out: &Path) -> std::process::Output {
    let mut all = vec!["impostor", "bake"];
    all.extend(args);
    all.extend(["--octahedral", "4", "--resolution", "64", "-o"]);
    all.push(out.to_str().unwrap());
    trompe(&all)
}

fn manifest(path: &Path) -> Manifest {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Every output file under `out` (manifests and journals aside) with its bytes, by its path
/// below `out`.
fn outputs(out: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut found = Vec::new();
    let mut stack = vec![out.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if !p
                .file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("manifest")
            {
                let bytes = std::fs::read(&p).unwrap();
                found.push((p.strip_prefix(out).unwrap().to_path_buf(), bytes));
            }
        }
    }
    found.sort();
    found
}

#[test]
fn a_folder_tree_is_walked_and_mirrored_and_a_list_adds_to_it() {
    let d = scratch("cli_batch_tree");
    let lib = library(&d, 2);
    // What the walk leaves alone: a hidden folder, a file of another kind.
    std::fs::create_dir_all(lib.join(".cache")).unwrap();
    std::fs::copy(common::asset("meshes/teapot.obj"), lib.join(".cache/x.obj")).unwrap();
    std::fs::write(lib.join("notes.txt"), "not a mesh").unwrap();
    let out = d.join("out");
    let o = bake(&[lib.to_str().unwrap()], &out);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "trees/same.json",
        "rocks/same.json",
        "trees/m0.png",
        "rocks/m0.json",
    ] {
        assert!(out.join(f).is_file(), "{f}: {}", stderr(&o));
    }
    assert!(!out.join(".cache").exists() && !out.join("x.json").exists());
    let m = manifest(&out.join("manifest-1-of-1.json"));
    assert_eq!(m.entries.len(), 4);
    for e in &m.entries {
        // Each input and output by its SHA-256, with the settings and the version.
        assert_eq!(e.input_sha256.as_ref().map(String::len), Some(64), "{e:?}");
        // The sidecar and its three maps.
        assert_eq!(e.outputs.len(), 4, "{e:?}");
        for f in &e.outputs {
            assert_eq!(
                trompe::octahedral::batch::sha256_of(&f.path).unwrap(),
                f.sha256
            );
        }
        assert_eq!(e.settings.map(|s| s.grid.n), Some(4));
        assert_eq!(e.trompe.as_deref(), Some(env!("CARGO_PKG_VERSION")));
    }
    // A list of paths (one a line, comments and blank lines skipped) bakes as the same files
    // named one by one.
    let list = d.join("list.txt");
    let named: Vec<String> = m
        .entries
        .iter()
        .map(|e| e.input.to_str().unwrap().to_string())
        .collect();
    std::fs::write(&list, format!("# the library\n\n{}\n", named.join("\n"))).unwrap();
    let listed = d.join("listed");
    let o = bake(&["--inputs-from", list.to_str().unwrap()], &listed);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(outputs(&listed), outputs(&out));
    // Two files that would write the same outputs are refused before any work.
    std::fs::copy(
        common::asset("meshes/teapot.obj"),
        lib.join("trees/same.obj"),
    )
    .unwrap();
    let o = bake(&[lib.to_str().unwrap()], &d.join("clash"));
    fails_cleanly(&o, "same outputs");
    assert!(!d.join("clash").join("trees").exists());
    // A folder with no meshes says so.
    std::fs::create_dir_all(d.join("empty")).unwrap();
    fails_cleanly(
        &bake(&[d.join("empty").to_str().unwrap()], &d.join("none")),
        "no meshes",
    );
}

/// `impostor bake LIB --shard SHARD` into `out` with a scheduler's variables `vars` and no
/// other scheduler's.
fn bake_as_scheduled(
    lib: &Path,
    (shard, vars): (&str, &[(&str, &str)]),
    out: &Path,
) -> std::process::Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_trompe"));
    command.args(["impostor", "bake"]).arg(lib).args([
        "--octahedral",
        "4",
        "--resolution",
        "64",
        "--shard",
        shard,
        "-o",
    ]);
    for name in [
        "SLURM_ARRAY_TASK_ID",
        "SLURM_ARRAY_TASK_MIN",
        "SLURM_ARRAY_TASK_STEP",
        "SLURM_ARRAY_TASK_COUNT",
        "JOB_COMPLETION_INDEX",
    ] {
        command.env_remove(name);
    }
    command
        .arg(out)
        .envs(vars.iter().copied())
        .current_dir(common::root())
        .output()
        .unwrap()
}

#[test]
fn shards_from_a_schedulers_variables_merge_into_the_whole_batch() {
    let d = scratch("cli_batch_scheduler");
    let lib = library(&d, 3);
    let whole = d.join("whole");
    assert!(bake(&[lib.to_str().unwrap()], &whole).status.success());
    let sharded = d.join("sharded");
    let mut manifests = Vec::new();
    // A Slurm array --array=0-2 and a Kubernetes Indexed Job of 3 completions (0-based).
    for (vars, shard) in [
        (
            vec![
                ("SLURM_ARRAY_TASK_ID", "0"),
                ("SLURM_ARRAY_TASK_MIN", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "3"),
            ],
            "auto",
        ),
        (vec![("JOB_COMPLETION_INDEX", "1")], "auto/3"),
        (
            vec![
                ("SLURM_ARRAY_TASK_ID", "2"),
                ("SLURM_ARRAY_TASK_MIN", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "3"),
            ],
            "auto",
        ),
    ] {
        let o = bake_as_scheduled(&lib, (shard, &vars), &sharded);
        assert!(o.status.success(), "{}", stderr(&o));
        manifests.push(sharded.join(format!("manifest-{}-of-3.json", manifests.len() + 1)));
    }
    let merged = d.join("merged.json");
    let mut args = vec!["impostor", "merge-manifests"];
    args.extend(manifests.iter().map(|p| p.to_str().unwrap()));
    args.extend(["-o", merged.to_str().unwrap()]);
    assert!(trompe(&args).status.success());
    assert_eq!(outputs(&sharded), outputs(&whole));
    let untimed = |m: Manifest| -> Vec<_> {
        m.entries
            .iter()
            .map(|e| {
                let e = e.untimed();
                (
                    e.input,
                    e.input_sha256,
                    e.outputs
                        .iter()
                        .map(|o| o.sha256.clone())
                        .collect::<Vec<_>>(),
                )
            })
            .collect()
    };
    assert_eq!(
        untimed(manifest(&merged)),
        untimed(manifest(&whole.join("manifest-1-of-1.json")))
    );
    // Without a scheduler, auto says what it looked for.
    let o = bake_as_scheduled(&lib, ("auto", &[]), &d.join("nowhere"));
    fails_cleanly(&o, "SLURM_ARRAY_TASK_ID");
}

#[test]
fn a_shard_killed_midway_is_finished_by_skip_existing_as_an_uninterrupted_run() {
    let d = scratch("cli_batch_killed");
    let lib = library(&d, 4);
    let args = |out: &Path| -> Vec<String> {
        [
            "impostor",
            "bake",
            lib.to_str().unwrap(),
            "--octahedral",
            "8",
            "--resolution",
            "256",
            "--glb",
            "-o",
            out.to_str().unwrap(),
        ]
        .map(String::from)
        .to_vec()
    };
    let uninterrupted = d.join("uninterrupted");
    let refs = |a: &[String]| a.iter().map(String::as_str).collect::<Vec<_>>().join(" ");
    let o = Command::new(env!("CARGO_BIN_EXE_trompe"))
        .args(args(&uninterrupted))
        .current_dir(common::root())
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{}: {}",
        refs(&args(&uninterrupted)),
        stderr(&o)
    );
    // Killed (SIGKILL) once the journal holds three finished inputs.
    let out = d.join("killed");
    let journal = out.join("manifest-1-of-1.partial.jsonl");
    let mut child = Command::new(env!("CARGO_BIN_EXE_trompe"))
        .args(args(&out))
        .current_dir(common::root())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        // Whole lines only: one being written does not parse yet.
        let done = std::fs::read_to_string(&journal)
            .map(|t| {
                t.lines()
                    .filter(|l| serde_json::from_str::<trompe::octahedral::batch::Entry>(l).is_ok())
                    .count()
            })
            .unwrap_or(0);
        if done >= 3 || start.elapsed() > Duration::from_secs(120) {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(
        !out.join("manifest-1-of-1.json").exists(),
        "the shard finished before it was killed"
    );
    // An output a finished input wrote, damaged since (as a half-written file would be): its
    // input is baked again, not taken for done.
    let finished: Vec<trompe::octahedral::batch::Entry> = std::fs::read_to_string(&journal)
        .unwrap()
        .lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect();
    assert!(finished.len() >= 3, "{} finished", finished.len());
    let damaged = &finished[0].outputs[1].path;
    let bytes = std::fs::read(damaged).unwrap();
    std::fs::write(damaged, &bytes[..bytes.len() / 2]).unwrap();
    let mut again = args(&out);
    again.push("--skip-existing".into());
    let o = Command::new(env!("CARGO_BIN_EXE_trompe"))
        .args(&again)
        .current_dir(common::root())
        .output()
        .unwrap();
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    let up_to_date = e.matches("up to date ").count();
    assert!(up_to_date >= 2, "{e}");
    assert!(
        e.contains(&format!("baked {}", finished[0].input.display())),
        "{e}"
    );
    // Every output complete and byte-identical to the uninterrupted run's; the journal gone.
    assert_eq!(outputs(&out), outputs(&uninterrupted));
    assert!(!journal.exists());
    assert_eq!(
        manifest(&out.join("manifest-1-of-1.json")).entries.len(),
        manifest(&uninterrupted.join("manifest-1-of-1.json"))
            .entries
            .len()
    );
}

#[test]
fn an_asset_whose_texture_changed_is_baked_again_by_skip_existing() {
    let d = scratch("cli_batch_texture");
    let lib = d.join("lib");
    let truck = lib.join("truck");
    std::fs::create_dir_all(&truck).unwrap();
    for f in [
        "CesiumMilkTruck.gltf",
        "CesiumMilkTruck.bin",
        "CesiumMilkTruck.png",
    ] {
        std::fs::copy(
            common::asset(&format!("gltf/CesiumMilkTruck/{f}")),
            truck.join(f),
        )
        .unwrap();
    }
    let out = d.join("out");
    let again = |out: &Path| bake(&[lib.to_str().unwrap(), "--skip-existing"], out);
    let o = again(&out);
    assert!(o.status.success(), "{}", stderr(&o));
    let m = manifest(&out.join("manifest-1-of-1.json"));
    // The buffer and the texture the glTF names are recorded with their hashes.
    let named: Vec<String> = m.entries[0]
        .input_files
        .iter()
        .map(|f| f.path.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert!(
        named.contains(&"CesiumMilkTruck.bin".to_string())
            && named.contains(&"CesiumMilkTruck.png".to_string()),
        "{named:?}"
    );
    let o = again(&out);
    assert!(stderr(&o).contains("up to date"), "{}", stderr(&o));
    // Asked for a .glb the earlier run did not write: baked again.
    let with_glb = bake(&[lib.to_str().unwrap(), "--skip-existing", "--glb"], &out);
    assert!(with_glb.status.success(), "{}", stderr(&with_glb));
    assert!(
        !stderr(&with_glb).contains("up to date"),
        "{}",
        stderr(&with_glb)
    );
    assert!(out.join("truck/CesiumMilkTruck.glb").is_file());
    // Another texture, the .gltf untouched: baked again, not taken for done.
    std::fs::copy(
        out.join("truck/CesiumMilkTruck.png"),
        truck.join("CesiumMilkTruck.png"),
    )
    .unwrap();
    let o = again(&out);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("up to date"), "{}", stderr(&o));
    assert!(stderr(&o).contains("baked "), "{}", stderr(&o));
}
