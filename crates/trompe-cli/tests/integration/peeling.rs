//! `trompe impostor bake --layers`: depth layers baked, shown by `info`, a bad count refused.

use crate::common;

#[test]
fn the_command_line_bakes_layers_shows_them_and_refuses_a_bad_count() {
    let dir = common::scratch("layers_cli");
    let out = dir.join("dragon.json");
    let (mesh, out_s) = (
        common::asset("meshes/dragon_res4.obj"),
        out.to_string_lossy().to_string(),
    );
    let mesh = mesh.to_string_lossy().to_string();
    let o = common::trompe(&[
        "impostor",
        "bake",
        &mesh,
        "--resolution",
        "128",
        "--layers",
        "auto",
        "-o",
        &out_s,
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(text.contains("depth layers"), "{text}");
    let info = common::trompe(&["info", &out_s]);
    let text = String::from_utf8_lossy(&info.stdout).to_string();
    assert!(
        info.status.success() && text.contains("  layers "),
        "{text}"
    );
    for bad in ["0", "9", "many"] {
        let o = common::trompe(&["impostor", "bake", &mesh, "--layers", bad, "-o", &out_s]);
        common::fails_cleanly(&o, "--layers");
    }
    let o = common::trompe(&[
        "impostor",
        "bake",
        "scenes/maze.maze",
        "--camera",
        "graph",
        "--layers",
        "2",
        "-o",
        &dir.join("maze.json").to_string_lossy(),
    ]);
    common::fails_cleanly(&o, "graph-camera impostor holds one layer");
    assert!(!dir.join("maze.json").exists());
}
