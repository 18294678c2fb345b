//! The memory budget from the command line: what a command holds together is refused by its
//! sum, before the work, naming what was asked, what is held and the flag.

use crate::common;
use common::{fails_cleanly, scratch, trompe};

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

/// An instanced glTF of 2²⁰ triangles loads under 250 MiB (176 MiB of flattened mesh), but
/// what building its impostor needs does not fit beside it: the rasterizer's set-up at 250 MiB;
/// at 400 MiB the set-up fits and the tessellation the curved camera asks for, held beside it,
/// does not. Each refused with what it is and the triangles, no panic.
#[test]
fn what_an_impostor_build_holds_is_refused_step_by_step() {
    let d = scratch("memory_instanced");
    let gltf = common::instanced_triangle(&d, "instanced.gltf", 20);
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
