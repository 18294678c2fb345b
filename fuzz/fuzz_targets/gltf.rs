//! A glTF document: binary (`.glb`) when it starts with the GLB magic, else JSON (`.gltf`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    trompe_fuzz::small_budget();
    let name = if data.starts_with(b"glTF") {
        "m.glb"
    } else {
        "m.gltf"
    };
    let _ = trompe::geom::io::load(&trompe_fuzz::file(name, data));
});
