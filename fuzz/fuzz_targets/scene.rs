//! A scene file (TOML), loaded beside the repository's `assets/` (so its seeds' meshes and
//! panoramas resolve) and, when it loads, evaluated at its time.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    trompe_fuzz::small_budget();
    let dir = trompe_fuzz::scratch();
    let assets = dir.join("assets");
    if !assets.exists() {
        let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets");
        std::os::unix::fs::symlink(repo, &assets).expect("a link to assets/");
        std::fs::create_dir_all(dir.join("scenes")).expect("a scenes folder");
    }
    let p = dir.join("scenes/s.toml");
    std::fs::write(&p, data).expect("the scratch folder is writable");
    if let Ok(scene) = trompe::Scene::load(&p) {
        let _ = scene.view(scene.render.time);
    }
});
