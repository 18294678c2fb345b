//! The octahedral impostor's WGSL shader (shaders/octahedral_impostor.wgsl): it parses and
//! validates with naga, and its constants are the Rust code's.

use std::path::Path;

fn source() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders/octahedral_impostor.wgsl"),
    )
    .unwrap()
}

#[test]
fn the_shader_parses_and_validates() {
    let module = naga::front::wgsl::parse_str(&source()).unwrap_or_else(|e| {
        panic!("{}", e.emit_to_string(&source()));
    });
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap();
    let entries: Vec<&str> = module
        .entry_points
        .iter()
        .map(|e| e.name.as_str())
        .collect();
    assert_eq!(entries, ["vs_main", "fs_main"]);
}

#[test]
fn the_shader_constants_are_the_rust_codes() {
    let src = source();
    assert!(
        src.contains(&format!(
            "const PARALLAX_STEPS: u32 = {}u;",
            trompe::octahedral::render::PARALLAX_STEPS
        )),
        "PARALLAX_STEPS"
    );
    // The coverage codes name the sidecar's values in order.
    let names = [
        trompe::octahedral::Coverage::Sphere,
        trompe::octahedral::Coverage::Hemisphere,
    ]
    .map(|c| serde_json::to_string(&c).unwrap());
    assert_eq!(names, ["\"sphere\"", "\"hemisphere\""]);
    assert!(src.contains("const COVERAGE_SPHERE: u32 = 0u;"));
    assert!(src.contains("const COVERAGE_HEMISPHERE: u32 = 1u;"));
}
