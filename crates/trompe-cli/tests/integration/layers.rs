//! `trompe layers build` and `layers render`: a project built, rendered, and a broken one refused.

use crate::common;
use common::{fails_cleanly, scratch, trompe};

#[test]
fn the_command_line_builds_renders_and_refuses_a_broken_project() {
    let dir = scratch("layers-cli");
    let out = dir.join("street");
    let o = trompe(&[
        "layers",
        "build",
        "scenes/street.toml",
        "--views",
        "3",
        "--size",
        "160x120",
        "-o",
        out.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let png = dir.join("street.png");
    for method in ["layered", "projective"] {
        let o = trompe(&[
            "layers",
            "render",
            "scenes/street.toml",
            "--layers",
            out.to_str().expect("utf-8"),
            "--method",
            method,
            "-o",
            png.to_str().expect("utf-8"),
        ]);
        assert!(o.status.success(), "{method}: {}", common::stderr(&o));
    }
    // A view's file without its stack.
    common::zip_of(
        &out.join("view0001.ora"),
        &[("mimetype", b"image/openraster".to_vec())],
    );
    let o = trompe(&[
        "layers",
        "render",
        "scenes/street.toml",
        "--layers",
        out.to_str().expect("utf-8"),
        "-o",
        png.to_str().expect("utf-8"),
    ]);
    fails_cleanly(&o, "view0001.ora: entry stack.xml is missing");
    // Built for another scene.
    let o = trompe(&[
        "layers",
        "render",
        "scenes/diffuse.toml",
        "--layers",
        out.to_str().expect("utf-8"),
        "-o",
        png.to_str().expect("utf-8"),
    ]);
    fails_cleanly(&o, "layers.json: object 1");
}
