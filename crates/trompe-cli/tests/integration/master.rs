//! `trompe master`: encode a capture, render from the encoding, propagate an edit — and the
//! errors a user meets on the way.

use crate::common;

use std::path::Path;
use std::process::{Command, Output};

fn trompe(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_trompe"))
        .args(args)
        .output()
        .expect("trompe runs")
}

fn ok(out: &Output) -> String {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn err(out: &Output) -> String {
    assert!(!out.status.success());
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn encode_render_and_edit_through_the_command_line() {
    let dir = common::scratch("master-cli");
    let duck = common::asset("gltf/Duck.glb");
    let duck = duck.to_str().unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let cap = dir.join("cap");
    ok(&trompe(&[
        "views",
        "capture",
        duck,
        "-o",
        &s(&cap),
        "--count",
        "8",
        "--size",
        "160x120",
    ]));
    let enc = dir.join("enc");
    let printed = ok(&trompe(&[
        "master",
        "encode",
        &s(&cap),
        "--mesh",
        duck,
        "-o",
        &s(&enc),
    ]));
    assert!(printed.contains("8 views of 4212 faces"), "{printed}");
    for f in ["masters.json", "bake.png", "mesh.glb", "master_0007.png"] {
        assert!(enc.join(f).is_file(), "{f}");
    }
    // The glTF loads with the gltf crate: one primitive, one UV set of 3 a face.
    let (doc, buffers, _) = gltf::import(enc.join("mesh.glb")).expect("a valid glTF");
    let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
    let reader = prim.reader(|b| Some(&buffers[b.index()]));
    assert_eq!(
        reader.read_tex_coords(0).unwrap().into_f32().count(),
        4212 * 3
    );
    assert!(reader.read_tex_coords(1).is_none());

    // Render from the encoding through a scene's camera.
    let scene = common::root().join("scenes/duck-mirror.toml");
    let frame = dir.join("from-masters.png");
    let printed = ok(&trompe(&[
        "master",
        "render",
        &s(&enc),
        "--mesh",
        duck,
        "--scene",
        &s(&scene),
        "-o",
        &s(&frame),
    ]));
    assert!(
        frame.is_file() && printed.contains("pixels show the mesh"),
        "{printed}"
    );

    // An edit of view 0 (a blue square painted on its image) reaches other views.
    let mut img = trompe::frame::io::read_png(&cap.join("images/view0000.png")).unwrap();
    for y in 50..70 {
        for x in 70..90 {
            img.set(x, y, trompe::glam::Vec4::new(0.0, 0.1, 0.9, 1.0));
        }
    }
    let painted = dir.join("painted.png");
    trompe::frame::io::write_png(&painted, &img).unwrap();
    let edited = dir.join("edited");
    let printed = ok(&trompe(&[
        "master",
        "edit",
        &s(&enc),
        "--mesh",
        duck,
        "--view",
        "0",
        "--edited",
        &s(&painted),
        "-o",
        &s(&edited),
    ]));
    assert!(printed.contains("propagated to 8 views"), "{printed}");
    let before = trompe::frame::io::read_png(&enc.join("master_0001.png")).unwrap();
    let after = trompe::frame::io::read_png(&edited.join("master_0001.png")).unwrap();
    let bluer = before
        .pixels()
        .iter()
        .zip(after.pixels())
        .filter(|(b, a)| a.z > b.z + 0.3)
        .count();
    assert!(bluer > 100, "view 1 took {bluer} texels of the edit");

    // An effect seen from a new camera: the scene's camera, a render without and with it.
    let without = dir.join("without.png");
    let with = dir.join("with.png");
    let mut img = trompe::frame::io::read_png(&frame).unwrap();
    trompe::frame::io::write_png(&without, &img).unwrap();
    let (w, h) = img.size();
    for y in h / 3..h / 2 {
        for x in w / 5..w / 3 {
            if img.get(x, y).w > 0.0 {
                img.set(x, y, trompe::glam::Vec4::new(0.1, 0.1, 0.1, 1.0));
            }
        }
    }
    trompe::frame::io::write_png(&with, &img).unwrap();
    let printed = ok(&trompe(&[
        "master",
        "edit",
        &s(&enc),
        "--mesh",
        duck,
        "--scene",
        &s(&scene),
        "--without",
        &s(&without),
        "--edited",
        &s(&with),
        "-o",
        &s(&dir.join("shadowed")),
    ]));
    assert!(printed.contains("propagated to 8 views"), "{printed}");
    let changed: usize = printed
        .split("changed ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap();
    assert!(changed > 100, "{printed}");

    // Errors that name what is wrong.
    let teapot = common::asset("meshes/teapot.obj");
    let e = err(&trompe(&[
        "master",
        "render",
        &s(&enc),
        "--mesh",
        teapot.to_str().unwrap(),
        "--scene",
        &s(&scene),
        "-o",
        &s(&dir.join("x.png")),
    ]));
    assert!(e.contains("992 triangles") && e.contains("4212"), "{e}");
    // Every weighting the views take, master textures take: the per-face ones from the masters'
    // own texels at each triangle's centroid.
    for weights in ["view-map", "best-face"] {
        let out = dir.join(format!("{weights}.png"));
        let o = trompe(&[
            "master",
            "render",
            &s(&enc),
            "--mesh",
            duck,
            "--scene",
            &s(&scene),
            "--weights",
            weights,
            "-o",
            &s(&out),
        ]);
        assert!(o.status.success(), "{weights}: {}", common::stderr(&o));
        assert!(out.is_file(), "{weights}");
    }
    let e = err(&trompe(&[
        "master",
        "edit",
        &s(&enc),
        "--mesh",
        duck,
        "--view",
        "8",
        "--edited",
        &s(&painted),
        "-o",
        &s(&dir.join("e2")),
    ]));
    assert!(e.contains("view 8") && e.contains("8 views"), "{e}");
    let e = err(&trompe(&[
        "master",
        "edit",
        &s(&enc),
        "--mesh",
        duck,
        "--view",
        "0",
        "--edited",
        &s(&painted),
        "-o",
        &s(&enc),
    ]));
    assert!(e.contains("new folder"), "{e}");
    // `master render` of the encoding with `manifest` as its masters.json: its error.
    let render_with = |manifest: &[u8]| {
        std::fs::write(enc.join("masters.json"), manifest).unwrap();
        err(&trompe(&[
            "master",
            "render",
            &s(&enc),
            "--mesh",
            duck,
            "--scene",
            &s(&scene),
            "-o",
            &s(&dir.join("y.png")),
        ]))
    };
    // A face whose right angle is at a corner a triangle does not have.
    let manifest = std::fs::read(enc.join("masters.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_slice(&manifest).unwrap();
    json["layout"]["faces"][5]["corner"] = serde_json::json!(3);
    let e = render_with(json.to_string().as_bytes());
    assert!(
        e.contains("masters.json") && e.contains("face 5") && e.contains("corner 3"),
        "{e}"
    );
    let e = render_with(b"{\"version\": 1}");
    assert!(e.contains("masters.json"), "{e}");
}
