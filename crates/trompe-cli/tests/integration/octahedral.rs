//! `trompe impostor bake --octahedral`: atlases and their layout, batches, shards and their manifests.

use crate::common;
use common::{fails_cleanly, scratch, stderr, trompe};

#[test]
fn octahedral_bakes_write_the_atlas_and_its_layout() {
    let d = scratch("cli_octahedral");
    let json = d.join("duck.json");
    let o = trompe(&[
        "impostor",
        "bake",
        "assets/gltf/Duck.glb",
        "--octahedral",
        "8",
        "--resolution",
        "256",
        "-o",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "duck.json",
        "duck.png",
        "duck-normal-depth.png",
        "duck-orm.png",
    ] {
        assert!(d.join(f).is_file(), "{f}");
    }
    assert!(!d.join("duck-normal.exr").exists() && !d.join("duck-depth.exr").exists());
    let sidecar: trompe::octahedral::file::Sidecar =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!((sidecar.grid.n, sidecar.frame_size), (8, 32));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("switch distance"), "{out}");
    let glb = d.join("duck.glb");
    let o = trompe(&[
        "impostor",
        "export",
        json.to_str().unwrap(),
        "-o",
        glb.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(gltf::Gltf::open(&glb).is_ok());
    // Any other kind of impostor exports as its surface, a textured mesh with its camera.
    let spoc = d.join("spoc.json");
    let o = trompe(&[
        "impostor",
        "bake",
        "assets/gltf/Duck.glb",
        "--resolution",
        "32",
        "-o",
        spoc.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let spoc_glb = d.join("spoc.glb");
    let o = trompe(&[
        "impostor",
        "export",
        spoc.to_str().unwrap(),
        "-o",
        spoc_glb.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Compressed by default (the `gltf` crate refuses its extensions; trompe's loader reads
    // it), plain glTF with --geometry float: the same triangles.
    let float_glb = d.join("spoc-float.glb");
    let o = trompe(&[
        "impostor",
        "export",
        spoc.to_str().unwrap(),
        "--geometry",
        "float",
        "-o",
        float_glb.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (doc, _, images) = gltf::import(&float_glb).unwrap();
    assert_eq!((images[0].width, images[0].height), (32, 32));
    assert!(doc.meshes().count() == 1);
    let triangles = |p: &std::path::Path| trompe::geom::io::load(p).unwrap().mesh.triangles.len();
    assert_eq!(triangles(&spoc_glb), triangles(&float_glb));
    // A JSON file that is no impostor's sidecar is refused, naming its format.
    let other = d.join("other.json");
    std::fs::write(&other, r#"{ "format": "something-else" }"#).unwrap();
    fails_cleanly(
        &trompe(&[
            "impostor",
            "export",
            other.to_str().unwrap(),
            "-o",
            d.join("other.glb").to_str().unwrap(),
        ]),
        "something-else",
    );
    // A sidecar whose bounding sphere has no size makes no atlas: refused on load, not
    // exported as an unloadable glTF.
    let flat = d.join("flat.json");
    let mut text: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    text["radius"] = serde_json::json!(0.0);
    std::fs::write(&flat, text.to_string()).unwrap();
    fails_cleanly(
        &trompe(&[
            "impostor",
            "export",
            flat.to_str().unwrap(),
            "-o",
            d.join("flat.glb").to_str().unwrap(),
        ]),
        "radius 0: the bounding sphere's radius must be a positive number",
    );
    fails_cleanly(
        &trompe(&[
            "impostor",
            "bake",
            "assets/gltf/Duck.glb",
            "--octahedral",
            "64",
            "--resolution",
            "256",
            "-o",
            json.to_str().unwrap(),
        ]),
        "texels a frame",
    );
}

#[test]
fn an_octahedral_batch_skips_a_broken_file_and_shards_merge() {
    let d = scratch("cli_octahedral_batch");
    let inputs = d.join("in");
    std::fs::create_dir_all(&inputs).unwrap();
    std::fs::copy(common::asset("gltf/Duck.glb"), inputs.join("Duck.glb")).unwrap();
    std::fs::copy(
        common::asset("meshes/teapot.obj"),
        inputs.join("teapot.obj"),
    )
    .unwrap();
    std::fs::write(inputs.join("broken.obj"), "v 1 2\nf 1 2 3\n").unwrap();
    let out = d.join("out");
    let files: Vec<String> = ["Duck.glb", "broken.obj", "teapot.obj"]
        .iter()
        .map(|f| inputs.join(f).to_str().unwrap().to_string())
        .collect();
    let mut manifests = Vec::new();
    for k in 1..=2 {
        let shard = format!("{k}/2");
        let mut args = vec!["impostor", "bake"];
        args.extend(files.iter().map(String::as_str));
        args.extend([
            "--octahedral",
            "4",
            "--resolution",
            "64",
            "--shard",
            &shard,
            "-o",
        ]);
        args.push(out.to_str().unwrap());
        let o = trompe(&args);
        let e = stderr(&o);
        assert!(!e.contains("panicked"), "{e}");
        // Sorted, shard 2 of 2 holds broken.obj alone: it fails, by name.
        if k == 2 {
            fails_cleanly(&o, "broken.obj");
        } else {
            assert!(o.status.success(), "{e}");
        }
        manifests.push(out.join(format!("manifest-{k}-of-2.json")));
    }
    assert!(out.join("Duck.json").is_file() && out.join("teapot.png").is_file());
    let merged = out.join("manifest.json");
    let mut args = vec!["impostor", "merge-manifests"];
    args.extend(manifests.iter().map(|p| p.to_str().unwrap()));
    args.extend(["-o", merged.to_str().unwrap()]);
    let o = trompe(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let m: trompe::octahedral::batch::Manifest =
        serde_json::from_str(&std::fs::read_to_string(&merged).unwrap()).unwrap();
    assert_eq!(m.entries.len(), 3);
    assert_eq!(m.entries.iter().filter(|e| e.error.is_some()).count(), 1);
    // A manifest missing a shard does not merge.
    let o = trompe(&[
        "impostor",
        "merge-manifests",
        manifests[0].to_str().unwrap(),
        "-o",
        d.join("partial.json").to_str().unwrap(),
    ]);
    fails_cleanly(&o, "shards");
}

#[test]
fn a_glb_output_or_an_atlas_checked_as_an_impostor_is_refused_by_name() {
    let d = scratch("cli_octahedral_refusals");
    // -o NAME.glb with --exr: the .glb is the whole bake; refused before anything is written.
    let glb = d.join("eng.glb");
    let o = trompe(&[
        "impostor",
        "bake",
        "assets/gltf/Duck.glb",
        "--octahedral",
        "4",
        "--resolution",
        "64",
        "--exr",
        "-o",
        glb.to_str().unwrap(),
    ]);
    fails_cleanly(&o, "a .glb output is the whole bake");
    assert!(!glb.exists());
    // A batch's -o is a folder, never a .glb.
    let o = trompe(&[
        "impostor",
        "bake",
        "assets/gltf/Duck.glb",
        "assets/meshes/teapot.obj",
        "--octahedral",
        "4",
        "--resolution",
        "64",
        "-o",
        glb.to_str().unwrap(),
    ]);
    fails_cleanly(&o, "give -o FOLDER/");
    assert!(!glb.exists());
    // An atlas's layout given to `impostor check --impostor` says what it is.
    let json = d.join("duck.json");
    let o = trompe(&[
        "impostor",
        "bake",
        "assets/gltf/Duck.glb",
        "--octahedral",
        "4",
        "--resolution",
        "64",
        "-o",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = trompe(&[
        "impostor",
        "check",
        "assets/gltf/Duck.glb",
        "--impostor",
        json.to_str().unwrap(),
    ]);
    fails_cleanly(&o, "octahedral atlas");
}

#[test]
fn a_glb_output_is_the_whole_bake_and_exr_adds_the_float_maps() {
    let d = scratch("cli_octahedral_glb_alone");
    let glb = d.join("duck.glb");
    let bake = |extra: &[&str], out: &std::path::Path| {
        let mut args = vec![
            "impostor",
            "bake",
            "assets/gltf/Duck.glb",
            "--octahedral",
            "4",
            "--resolution",
            "64",
        ];
        args.extend_from_slice(extra);
        args.extend(["-o", out.to_str().unwrap()]);
        trompe(&args)
    };
    let o = bake(&[], &glb);
    assert!(o.status.success(), "{}", stderr(&o));
    // One file, nothing beside it, holding the three maps.
    let names: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert_eq!(names, ["duck.glb"]);
    let atlas = trompe::octahedral::gltf::load(&glb).unwrap();
    assert_eq!((atlas.settings.grid.n, atlas.side()), (4, 64));
    // `info` reads its layout.
    let o = trompe(&["info", glb.to_str().unwrap()]);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success() && said.contains("4 × 4") && said.contains("Png"),
        "{said}{}",
        stderr(&o)
    );
    // --ktx2 sets the .glb's textures: refused where no .glb is written.
    fails_cleanly(
        &bake(&["--ktx2"], &d.join("k.json")),
        "--ktx2 sets the .glb's textures",
    );
    assert!(!d.join("k.json").exists());
    // --exr adds the float maps beside a sidecar; baked again without, they go.
    let json = d.join("duck.json");
    let o = bake(&["--exr"], &json);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(d.join("duck-normal.exr").is_file() && d.join("duck-depth.exr").is_file());
    let o = bake(&[], &json);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!d.join("duck-normal.exr").exists() && !d.join("duck-depth.exr").exists());
    // A user's file named like a float map is never removed, nor replaced by --exr.
    std::fs::write(d.join("duck-depth.exr"), b"mine").unwrap();
    let o = bake(&[], &json);
    assert!(o.status.success(), "{}", stderr(&o));
    fails_cleanly(&bake(&["--exr"], &json), "a file of the user's");
    assert_eq!(std::fs::read(d.join("duck-depth.exr")).unwrap(), b"mine");
}
