//! Every bad input gives an error naming the file and the element, never a panic.

use crate::common;
use common::{scratch, shared};
use std::path::{Path, PathBuf};
use trompe::geom::io::load;

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Loads `bytes` as `name` and returns the error text, which must name the file and `expect`.
#[track_caller]
fn error_of(dir: &Path, name: &str, bytes: &[u8], expect: &str) -> String {
    let p = write(dir, name, bytes);
    let e = load(&p).expect_err(name).to_string();
    assert!(
        e.contains(name),
        "{name}: error does not name the file: {e}"
    );
    assert!(e.contains(expect), "{name}: expected {expect:?} in: {e}");
    e
}

#[test]
fn bad_obj_files() {
    let d = scratch("bad_obj");
    error_of(&d, "truncated.obj", b"v 0 0 0\nv 1 0 0\nv 0 1", "line 3");
    error_of(
        &d,
        "word.obj",
        b"v 0 0 0\nv one 0 0\n",
        "\"one\" is not a number",
    );
    error_of(
        &d,
        "range.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
        "vertex index 9 out of range",
    );
    error_of(
        &d,
        "zero.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
        "line 4",
    );
    error_of(
        &d,
        "nan.obj",
        b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
        "not finite",
    );
    error_of(
        &d,
        "inf.obj",
        b"v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n",
        "not finite",
    );
    error_of(&d, "empty.obj", b"# nothing\n", "no triangles");
    error_of(&d, "short.obj", b"v 0 0 0\nv 1 0 0\nf 1 2\n", "at least 3");
    // A material library that names a missing texture.
    write(&d, "tex.mtl", b"newmtl m\nmap_Kd missing.png\n");
    let p = write(
        &d,
        "tex.obj",
        b"mtllib tex.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n",
    );
    let e = load(&p).unwrap_err().to_string();
    assert!(e.contains("tex.mtl: texture missing.png"), "{e}");
}

#[test]
fn degenerate_triangles_are_dropped_with_a_warning() {
    let d = scratch("degenerate");
    let p = write(
        &d,
        "deg.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 2 2 3\n",
    );
    let l = load(&p).unwrap();
    assert_eq!(l.mesh.triangle_count(), 1);
    assert_eq!(l.source.triangles, 3);
    assert!(
        l.warnings
            .iter()
            .any(|w| w.to_string().contains("dropped 2 degenerate")),
        "{:?}",
        l.warnings
    );
}

fn ply_header(format: &str, vertices: u64, faces: u64) -> String {
    format!(
        "ply\nformat {format} 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\nproperty float z\nelement face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
    )
}

#[test]
fn bad_ply_files() {
    let d = scratch("bad_ply");
    // Good files first, so the errors below are about the defects.
    let ascii = ply_header("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    assert_eq!(
        load(&write(&d, "ok.ply", ascii.as_bytes()))
            .unwrap()
            .mesh
            .triangle_count(),
        1
    );
    let mut bin = ply_header("binary_little_endian", 3, 1).into_bytes();
    for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for c in v {
            bin.extend(c.to_le_bytes());
        }
    }
    bin.push(3);
    for i in [0i32, 1, 2] {
        bin.extend(i.to_le_bytes());
    }
    assert_eq!(
        load(&write(&d, "ok_bin.ply", &bin))
            .unwrap()
            .mesh
            .triangle_count(),
        1
    );
    let mut be = ply_header("binary_big_endian", 3, 1).into_bytes();
    for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for c in v {
            be.extend(c.to_be_bytes());
        }
    }
    be.push(3);
    for i in [0i32, 1, 2] {
        be.extend(i.to_be_bytes());
    }
    assert_eq!(
        load(&write(&d, "ok_be.ply", &be))
            .unwrap()
            .mesh
            .bounds()
            .max
            .x,
        1.0
    );

    error_of(&d, "truncated.ply", &bin[..bin.len() - 5], "truncated");
    error_of(&d, "magic.ply", b"plx\n", "not a PLY");
    error_of(
        &d,
        "noend.ply",
        b"ply\nformat ascii 1.0\nelement vertex 3\n",
        "end_header",
    );
    // A count no file could hold: refused before anything is reserved.
    let huge = ply_header("binary_little_endian", 1_000_000_000_000_000, 1) + "xx";
    error_of(&d, "huge.ply", huge.as_bytes(), "declares");
    let range = ply_header("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n";
    error_of(
        &d,
        "range.ply",
        range.as_bytes(),
        "face 0: vertex index 7 out of range",
    );
    let nan = ply_header("ascii", 3, 1) + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n";
    error_of(&d, "nan.ply", nan.as_bytes(), "vertex 1");
    let half = ply_header("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n";
    error_of(
        &d,
        "half.ply",
        half.as_bytes(),
        "vertex index 1.5 is not a whole number",
    );
    let word = ply_header("ascii", 3, 1) + "0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n";
    error_of(&d, "word.ply", word.as_bytes(), "vertex 1");
}

#[test]
fn bad_gltf_files() {
    let d = scratch("bad_gltf");
    error_of(&d, "junk.gltf", b"{ this is not json", "document");
    let duck = std::fs::read(shared("gltf/Duck.glb")).unwrap();
    error_of(&d, "half.glb", &duck[..duck.len() / 2], "half.glb");
    // A .gltf whose buffer file is missing.
    let gltf =
        std::fs::read_to_string(shared("gltf/CesiumMilkTruck/CesiumMilkTruck.gltf")).unwrap();
    error_of(&d, "nobuffer.gltf", gltf.as_bytes(), "buffer 0");
    // The buffer exists but is shorter than its views need.
    std::fs::copy(
        shared("gltf/CesiumMilkTruck/CesiumMilkTruck.png"),
        d.join("CesiumMilkTruck.png"),
    )
    .unwrap();
    let bin = std::fs::read(shared("gltf/CesiumMilkTruck/CesiumMilkTruck.bin")).unwrap();
    write(&d, "CesiumMilkTruck.bin", &bin[..1000]);
    let e = load(&d.join("nobuffer.gltf"))
        .expect_err("short buffer")
        .to_string();
    assert!(e.contains("nobuffer.gltf"), "{e}");
    // A missing image.
    std::fs::write(d.join("CesiumMilkTruck.bin"), &bin).unwrap();
    std::fs::remove_file(d.join("CesiumMilkTruck.png")).unwrap();
    let e = load(&d.join("nobuffer.gltf"))
        .expect_err("missing image")
        .to_string();
    assert!(
        e.contains("image 0") && e.contains("CesiumMilkTruck.png"),
        "{e}"
    );
}

#[test]
fn unknown_extensions_and_missing_files() {
    let d = scratch("bad_misc");
    error_of(&d, "model.stl", b"solid", "unknown extension");
    let e = load(&d.join("absent.obj")).unwrap_err().to_string();
    assert!(e.contains("absent.obj"), "{e}");
}

#[test]
fn bad_images_are_errors() {
    let d = scratch("bad_images");
    let p = write(
        &d,
        "env.hdr",
        b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1000000 +X 1000000\n",
    );
    assert!(trompe::frame::envmap::EnvMap::load(&p, 0.0, 1.0).is_err());
    let p = write(&d, "env.exr", b"v/1\x01garbage");
    assert!(trompe::frame::envmap::EnvMap::load(&p, 0.0, 1.0).is_err());
}

/// The glTF files the `gltf` crate's readers panic on give a named error instead: indices of a
/// signed or float type, an attribute accessor that does not exist, a stride smaller than an
/// element, a bufferView image with no mimeType, UVs of a type the specification forbids.
#[test]
fn malformed_gltf_documents_are_named_errors_not_panics() {
    let d = common::scratch("bad_gltf_rules");
    // A triangle: 36 bytes of positions, then 3 index bytes (and a pad byte), in a data URI.
    let mut buf: Vec<u8> = [0.0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    buf.extend([0u8, 1, 2, 0]);
    let b64 = {
        const T: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut s = String::new();
        for c in buf.chunks(3) {
            let n = (u32::from(c[0]) << 16)
                | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
                | u32::from(*c.get(2).unwrap_or(&0));
            for k in 0..4 {
                if k <= c.len() {
                    s.push(T[(n >> (18 - 6 * k) & 63) as usize] as char);
                } else {
                    s.push('=');
                }
            }
        }
        s
    };
    let doc = |index_type: u32, position: u32, stride: &str, extra: &str, attrs: &str| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":{position}{attrs}}},"indices":1}}]}}],
"buffers":[{{"byteLength":40,"uri":"data:application/octet-stream;base64,{b64}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36{stride}}},{{"buffer":0,"byteOffset":36,"byteLength":3}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":{index_type},"count":3,"type":"SCALAR"}},
{{"bufferView":1,"componentType":5125,"count":1,"type":"VEC2"}}]{extra}}}"#
        )
    };
    let good = d.join("good.gltf");
    std::fs::write(&good, doc(5121, 0, "", "", "")).unwrap();
    assert!(
        trompe::geom::io::load(&good).is_ok(),
        "the well-formed triangle loads"
    );
    let image = r#","images":[{"bufferView":1}],"textures":[{"source":0}]"#;
    for (name, text, expect) in [
        (
            "byte_indices",
            doc(5120, 0, "", "", ""),
            "indices are unsigned",
        ),
        (
            "short_indices",
            doc(5122, 0, "", "", ""),
            "indices are unsigned",
        ),
        (
            "float_indices",
            doc(5126, 0, "", "", ""),
            "indices are unsigned",
        ),
        (
            "missing_accessor",
            doc(5121, 7, "", "", ""),
            "accessor 7 does not exist",
        ),
        (
            "stride",
            doc(5121, 0, r#","byteStride":4"#, "", ""),
            "smaller than one element",
        ),
        (
            "image_mime",
            doc(5121, 0, "", image, ""),
            "needs a mimeType",
        ),
        (
            "uint_uvs",
            doc(5121, 0, "", "", r#","TEXCOORD_0":2"#),
            "does not allow",
        ),
        (
            "count_overflow",
            doc(5121, 0, "", "", "").replacen(
                r#""count":3,"type":"SCALAR""#,
                r#""count":18446744073709551615,"type":"SCALAR""#,
                1,
            ),
            "accessor 1",
        ),
    ] {
        let p = d.join(format!("{name}.gltf"));
        std::fs::write(&p, text).unwrap();
        let e = trompe::geom::io::load(&p)
            .err()
            .unwrap_or_else(|| panic!("{name} loaded"));
        let e = e.to_string();
        assert!(e.contains(expect) && e.contains(name), "{name}: {e}");
    }
}

/// A texture is decoded once however many materials name it, and a glTF image no used material
/// references is never decoded (a garbage one does not stop the load).
#[test]
fn textures_are_decoded_once_and_only_when_used() {
    let d = common::scratch("textures_once");
    let png = common::shared("meshes/bunny10k_textured/TextureDouble_A.png");
    std::fs::copy(&png, d.join("t.png")).unwrap();
    let mut mtl = String::new();
    for m in 0..4 {
        mtl.push_str(&format!("newmtl m{m}\nmap_Kd t.png\n"));
    }
    std::fs::write(d.join("m.mtl"), mtl).unwrap();
    let mut obj = String::from("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n");
    for m in 0..4 {
        obj.push_str(&format!("usemtl m{m}\nf 1/1 2/2 3/3\n"));
    }
    std::fs::write(d.join("m.obj"), obj).unwrap();
    let loaded = trompe::geom::io::load(&d.join("m.obj")).unwrap();
    let textures: Vec<_> = loaded
        .mesh
        .materials
        .iter()
        .filter_map(|m| m.texture.clone())
        .collect();
    assert_eq!(textures.len(), 4);
    assert!(
        textures
            .iter()
            .all(|t| std::sync::Arc::ptr_eq(t, &textures[0])),
        "decoded once"
    );
    assert_eq!(
        loaded.files.iter().filter(|f| f.ends_with("t.png")).count(),
        1
    );
    // A glTF with an unused image of garbage bytes.
    let gltf = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
"buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36}],
"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
"images":[{"uri":"garbage.png"}]}"#;
    std::fs::write(d.join("garbage.png"), b"not a png at all").unwrap();
    std::fs::write(d.join("unused.gltf"), gltf).unwrap();
    let loaded = trompe::geom::io::load(&d.join("unused.gltf")).unwrap();
    assert_eq!(loaded.mesh.triangle_count(), 1);
}

/// Messages that named the wrong thing: an OBJ texture-coordinate or normal index out of
/// range, a glTF buffer that is a folder, and a sidecar that is a device with no length.
/// An EXR with more channels than any trompe file has is refused from its header, before its
/// pixels are read.
#[test]
fn an_exr_with_too_many_channels_is_refused_from_its_header() {
    use exr::prelude::*;
    let d = scratch("exr_channels");
    let size = (4, 4);
    let wide = trompe::frame::io::MAX_EXR_CHANNELS + 20;
    let channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = (0..wide)
        .map(|c| {
            AnyChannel::new(
                Text::from(format!("c{c}").as_str()),
                FlatSamples::F32(vec![0.0; 16]),
            )
        })
        .collect();
    let layer = Layer::new(
        size,
        LayerAttributes::default(),
        Encoding::UNCOMPRESSED,
        AnyChannels::sort(channels),
    );
    let p = d.join("wide.exr");
    Image::from_layer(layer).write().to_file(&p).unwrap();
    let e = trompe::frame::io::read_exr_channels(&p)
        .unwrap_err()
        .to_string();
    let count = format!("{wide} channels");
    assert!(e.contains("wide.exr") && e.contains(&count), "{e}");
}

#[test]
fn messages_name_what_is_wrong() {
    let d = common::scratch("bad_messages");
    let obj = d.join("vt.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/5 3/1\n").unwrap();
    let e = trompe::geom::io::load(&obj).unwrap_err().to_string();
    assert!(e.contains("texture coordinate index 5 out of range"), "{e}");
    let obj = d.join("vn.obj");
    std::fs::write(
        &obj,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n",
    )
    .unwrap();
    let e = trompe::geom::io::load(&obj).unwrap_err().to_string();
    assert!(e.contains("normal index 2 out of range"), "{e}");
    std::fs::create_dir_all(d.join("buffer.bin")).unwrap();
    let gltf = d.join("folder.gltf");
    std::fs::write(
        &gltf,
        r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":4,"uri":"buffer.bin"}]}"#,
    )
    .unwrap();
    let e = trompe::geom::io::load(&gltf).unwrap_err().to_string();
    assert!(e.contains("is a folder"), "{e}");
    #[cfg(unix)]
    {
        let link = d.join("zero.json");
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
        let e = trompe::impostor::file::load(&link).unwrap_err().to_string();
        assert!(e.contains("longer than 1 MiB"), "{e}");
    }
}

/// Every number of a scene — camera, light, render settings, placements, animation,
/// deformation, materials — set in turn to 3e38, −3e38, 1e20, NaN and ∞, and the scene rendered
/// by every method: each variant is refused by the loader or the method with an error, or
/// renders; none panics.
#[test]
fn every_number_at_the_edge_of_f32_is_an_error_or_a_frame_never_a_panic() {
    const SCENE: &str = r#"
[camera]
position = [0.0, 0.8, 1.9]
look_at = [0.0, 0.25, 0.0]
fov_y = 40.0
resolution = [12, 8]

[light]
direction = [0.4, 1.0, 0.6]
intensity = 1.5

[render]
max_depth = 4
time = 0.5
background = [0.2, 0.3, 0.4]

[[object]]
shape = "plane"
scale = 2.0
material = { type = "diffuse", color = [0.4, 0.4, 0.4] }

[[object]]
shape = "cube"
fit = 0.4
translate = [-0.3, 0.2, 0.0]
rotate = [0.0, 30.0, 0.0]
material = { type = "diffuse", color = [0.8, 0.5, 0.3] }

[object.deform]
kind = "twist"
amount = 0.5
hz = 1.0

[[object]]
shape = "sphere"
fit = 0.3
translate = [0.3, 0.2, 0.0]
material = { type = "mirror", tint = [0.9, 0.9, 0.9] }

[object.animate]
velocity = [0.1, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
degrees_per_second = 20.0

[[object]]
shape = "sphere"
fit = 0.2
translate = [0.0, 0.5, 0.3]
material = { type = "glass", ior = 1.5 }
"#;
    let path = common::root().join("scenes/edge-sweep.toml");
    // Number tokens outside comments and strings.
    let mut numbers = Vec::new();
    let bytes = SCENE.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        let starts = (c.is_ascii_digit() || c == b'-')
            && !(i > 0 && (bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_'));
        if c == b'"' {
            i += 1 + SCENE[i + 1..].find('"').unwrap() + 1;
        } else if starts {
            let end = i
                + 1
                + SCENE[i + 1..]
                    .find(|c: char| !(c.is_ascii_digit() || c == '.'))
                    .unwrap_or(SCENE.len() - i - 1);
            numbers.push((i, end));
            i = end;
        } else {
            i += 1;
        }
    }
    assert!(numbers.len() > 50, "{} numbers", numbers.len());
    let settings = trompe::methods::MethodSettings {
        impostor_resolution: 16,
        octahedral_frames: 2,
        octahedral_frame_size: 8,
        capture: trompe::views::capture::CaptureSettings {
            count: 2,
            size: (16, 12),
            ..Default::default()
        },
        ..Default::default()
    };
    let (mut variants, mut refused, mut frames, mut errors) = (0, 0, 0, 0);
    for &(start, end) in &numbers {
        for value in ["3e38", "-3e38", "1e20", "nan", "inf"] {
            let text = format!("{}{value}{}", &SCENE[..start], &SCENE[end..]);
            let what = format!("{} = {value}", &SCENE[start.saturating_sub(24)..start]);
            variants += 1;
            let loaded = std::panic::catch_unwind(|| trompe::Scene::from_toml(&text, &path));
            let scene = match loaded {
                Err(_) => panic!("loading panicked: {what}"),
                Ok(Err(_)) => {
                    refused += 1;
                    continue;
                }
                Ok(Ok(scene)) => scene,
            };
            for kind in trompe::methods::MethodKind::for_scenes() {
                let rendered = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    let mut r = trompe::methods::Renderer::new(&scene, kind, settings.clone())?;
                    r.frame(scene.render.time, None, &()).map(|_| ())
                }));
                match rendered {
                    Err(_) => panic!("{} panicked: {what}", kind.name()),
                    Ok(Err(_)) => errors += 1,
                    Ok(Ok(())) => frames += 1,
                }
            }
        }
    }
    println!(
        "{variants} variants of {} numbers: {refused} refused by the loader; {frames} frames and \
         {errors} errors from the methods; no panic",
        numbers.len()
    );
    assert!(refused > 0 && frames > 0 && errors > 0);
}
