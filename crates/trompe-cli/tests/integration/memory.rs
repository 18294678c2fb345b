//! The memory budget from the command line: what a command holds together is refused by its
//! sum, before the work, naming what was asked, what is held and the flag.

use crate::common;
use common::{fails_cleanly, scratch, trompe};
use std::path::{Path, PathBuf};

/// The atlases of a scene are refused by their sum: at 100 MiB the first fits and the second,
/// on top of it, does not; the error names the object and what is held.
#[test]
fn a_scenes_atlases_are_refused_by_their_sum() {
    let out = scratch("octahedral_sum").join("o.png");
    let o = trompe(&[
        "--memory-limit",
        "100M",
        "render",
        "scenes/teapots.toml",
        "--method",
        "octahedral",
        "--octahedral",
        "8",
        "-o",
        out.to_str().unwrap(),
    ]);
    fails_cleanly(
        &o,
        "object 1: an octahedral atlas of 1024 × 1024 (on top of",
    );
    assert!(!out.exists());
}

/// A glTF whose `levels` levels of two nodes each point at both nodes of the next level: one
/// triangle instanced 2^`levels` times, in a few kilobytes.
fn instanced_triangle(dir: &Path, levels: usize) -> PathBuf {
    let mut nodes = Vec::new();
    for level in 0..levels {
        for _ in 0..2 {
            if level + 1 == levels {
                nodes.push(r#"{"mesh":0}"#.to_string());
            } else {
                let (a, b) = (2 * (level + 1), 2 * (level + 1) + 1);
                nodes.push(format!(r#"{{"children":[{a},{b}]}}"#));
            }
        }
    }
    // One triangle: nine little-endian floats, base64.
    let positions = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";
    let doc = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],"nodes":[{}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{positions}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}]}}"#,
        nodes.join(",")
    );
    let path = dir.join("instanced.gltf");
    std::fs::write(&path, doc).unwrap();
    path
}

/// An instanced glTF of 2²⁰ triangles loads under 250 MiB (176 MiB of flattened mesh), but
/// what building its impostor needs does not fit beside it: the rasterizer's set-up at 250 MiB;
/// at 400 MiB the set-up fits and the tessellation the curved camera asks for, held beside it,
/// does not. Each refused with what it is and the triangles, no panic.
#[test]
fn what_an_impostor_build_holds_is_refused_step_by_step() {
    let d = scratch("memory_instanced");
    let gltf = instanced_triangle(&d, 20);
    let check = |limit: &str| {
        trompe(&[
            "--memory-limit",
            limit,
            "impostor",
            "check",
            gltf.to_str().unwrap(),
            "--resolution",
            "64",
        ])
    };
    let o = check("250M");
    fails_cleanly(&o, "rasterizing 1048576 triangles");
    fails_cleanly(&o, "--memory-limit");
    let o = check("400M");
    fails_cleanly(
        &o,
        "tessellating 1048576 triangles for a curved camera (on top of",
    );
}
