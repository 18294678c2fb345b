//! `trompe render --method c3rc`: its statistics, and the settings it refuses.

use crate::common;
use common::{fails_cleanly, scratch, stderr, trompe};

#[test]
fn render_c3rc_prints_its_statistics_and_refuses_bad_settings() {
    let d = scratch("cli_c3rc");
    let png = d.join("c3rc.png");
    let o = trompe(&[
        "render",
        "scenes/c3rc-bunny.toml",
        "--method",
        "c3rc",
        "--splat",
        "1",
        "-o",
        png.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(png.is_file());
    for said in ["kd-tree", "C3RCs", "valid projections", "culling"] {
        assert!(e.contains(said), "{said:?} in {e}");
    }
    let out = png.to_str().unwrap();
    fails_cleanly(
        &trompe(&[
            "render",
            "scenes/c3rc-bunny.toml",
            "--method",
            "c3rc",
            "--spacing=-1",
            "-o",
            out,
        ]),
        "--spacing",
    );
    fails_cleanly(
        &trompe(&[
            "render",
            "scenes/c3rc-bunny.toml",
            "--method",
            "c3rc",
            "--splat",
            "3",
            "-o",
            out,
        ]),
        "splat",
    );
    let scene = d.join("subdivided.toml");
    std::fs::write(
        &scene,
        "[camera]\nposition = [0, 1, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\nresolution = [8, 8]\n\
         [[object]]\nshape = \"sphere\"\nsubdivide = 9\n",
    )
    .unwrap();
    fails_cleanly(
        &trompe(&["render", scene.to_str().unwrap(), "-o", out]),
        "subdivide",
    );
}
