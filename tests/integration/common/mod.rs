//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod layer_scene;

use std::path::{Path, PathBuf};
use std::process::Output;

/// The repository's root: the workspace folder, which holds `Cargo.lock`, `assets/` and
/// `scenes/` (the tests of every crate of the workspace read from there).
pub fn root() -> PathBuf {
    let crate_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    crate_dir
        .ancestors()
        .find(|dir| dir.join("Cargo.lock").is_file() && dir.join("scenes").is_dir())
        .map(PathBuf::from)
        .unwrap_or(crate_dir)
}

/// A file under `../shared/data` (the test models, beside the repository). A test that needs
/// it fails here, saying so, when the folder is missing.
#[track_caller]
pub fn shared(rel: &str) -> PathBuf {
    let data = root().join("../shared/data");
    assert!(
        data.is_dir(),
        "this test reads the shared test models in {} (the `shared/data` folder beside the \
         checkout, see README.md), and that folder is missing",
        data.display()
    );
    data.join(rel)
}

/// A file under the repository's `assets/` (what the demo ships).
pub fn asset(rel: &str) -> PathBuf {
    root().join("assets").join(rel)
}

/// A file of the repository: `scenes/…`, `shaders/…`, `tests/fixtures/…`.
pub fn repo(rel: &str) -> PathBuf {
    root().join(rel)
}

/// A fresh scratch directory under `target/` for one test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = root().join("target/test-scratch").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// What a run wrote to standard error.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A run that failed without a panic and said `expect`.
#[track_caller]
pub fn fails_cleanly(o: &Output, expect: &str) {
    let e = stderr(o);
    assert!(!o.status.success(), "should fail: {e}");
    assert!(!e.contains("panicked"), "panicked: {e}");
    assert!(e.contains(expect), "expected {expect:?} in: {e}");
}

/// How the texel walk ([`trompe::impostor::WalkMode::Exact`]) answers rays against the linear
/// walk of paper 1 §3.2 ([`trompe::impostor::WalkMode::Linear`]), ray by ray. The two test the
/// ray against the stored planes at different points — the texel walk where the ray enters and
/// leaves every texel, the linear walk every half pixel of image path — so where the stored
/// surface is smooth both accept the crossing in the same texel, or in neighbouring texels of
/// one surface, and where it is not (a silhouette, a plane seen edge-on) their samples can meet
/// different texels there and decide differently. Every ray falls in one count.
#[derive(Debug, Default)]
pub struct WalkComparison {
    pub rays: usize,
    /// Rays the texel walk answers with a hit.
    pub hits: usize,
    /// Both miss, or both hit in the same texel.
    pub same: usize,
    /// Both hit, in different texels, within one texel footprint of each other.
    pub same_surface: usize,
    /// The texel walk hits where the linear walk misses, or more than a footprint nearer: a
    /// crossing the linear walk's samples stepped over.
    pub texel_nearer: usize,
    /// The linear walk hits where the texel walk misses, or more than a footprint nearer.
    pub linear_nearer: usize,
    /// The pyramid walk differs from the texel walk (it must not: it skips only stretches in
    /// front of every plane).
    pub pyramid_differs: usize,
    /// Rays each walk answers as the BVH does (within 1.5 footprints).
    pub texel_agrees: usize,
    pub linear_agrees: usize,
}

impl WalkComparison {
    /// What every comparison must show: the pyramid changes nothing; at least 95 % of rays get
    /// the same hit (texel, or point on one surface) from both walks (measured: 98.5 – 99.6 %
    /// on the teapot and the corridor, 96.6 % on the dragon's three layers, whose thin parts
    /// the linear walk steps over); at most 0.5 % have the linear walk hit nearer, or hit where
    /// the texel walk misses (measured: 0.06 – 0.3 %); and the texel walk agrees with the exact
    /// BVH at least as often as the linear walk.
    pub fn holds(&self) {
        assert_eq!(self.pyramid_differs, 0, "{self:?}");
        let share = |n: usize| n as f64 / self.rays as f64;
        assert!(share(self.same + self.same_surface) >= 0.95, "{self:?}");
        assert!(share(self.linear_nearer) <= 0.005, "{self:?}");
        assert!(self.texel_agrees >= self.linear_agrees, "{self:?}");
    }
}

pub fn compare_walks(
    imp: &trompe::impostor::Impostor,
    exact: &trompe::trace::Bvh,
    rays: &[trompe::geom::Ray],
) -> WalkComparison {
    use trompe::impostor::WalkMode;
    use trompe::trace::{Hit, RayQuery};
    let footprint = |h: &Hit| {
        imp.camera()
            .project(h.position.as_dvec3())
            .map_or(f64::INFINITY, |p| imp.footprint(p.uv, p.gd))
    };
    let near = |a: &Hit, b: &Hit| a.position.distance(b.position) as f64 <= footprint(a);
    let mut c = WalkComparison::default();
    for r in rays {
        let linear = imp.walk_mode(r, f32::INFINITY, WalkMode::Linear).0;
        let texel = imp.walk_mode(r, f32::INFINITY, WalkMode::Exact).0;
        let pyramid = imp.walk_mode(r, f32::INFINITY, WalkMode::Pyramid).0;
        let e = exact.closest_hit(r, f32::INFINITY);
        let agrees = |i: &Option<Hit>| match (&e, i) {
            (None, None) => true,
            (Some(e), Some(i)) => e.position.distance(i.position) as f64 <= 1.5 * footprint(e),
            _ => false,
        };
        c.rays += 1;
        c.hits += texel.is_some() as usize;
        c.pyramid_differs += (pyramid != texel) as usize;
        c.texel_agrees += agrees(&texel) as usize;
        c.linear_agrees += agrees(&linear) as usize;
        match (&texel, &linear) {
            (None, None) => c.same += 1,
            (Some(a), Some(b)) if a.uv == b.uv => c.same += 1,
            (Some(a), Some(b)) if near(a, b) => c.same_surface += 1,
            (Some(a), Some(b)) if a.t < b.t => c.texel_nearer += 1,
            (Some(_), None) => c.texel_nearer += 1,
            _ => c.linear_nearer += 1,
        }
    }
    c
}

/// Writes a ZIP file of `entries` (name, bytes), stored uncompressed: an OpenRaster file made
/// by hand, broken as a test wants it.
pub fn zip_of(path: &std::path::Path, entries: &[(&str, Vec<u8>)]) {
    use std::io::Write;
    let mut z = zip::ZipWriter::new(std::fs::File::create(path).expect("create"));
    let stored =
        zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    for (name, bytes) in entries {
        z.start_file(*name, stored).expect("entry");
        z.write_all(bytes).expect("write");
    }
    z.finish().expect("finished");
}

/// A test that needs a system package (`what`, which `present` says is installed): run as is
/// when it is; otherwise ignored — counted in the test summary, the reason printed — or, where
/// `TROMPE_REQUIRE_SYSTEM` is set (`.ci/run` sets it), failed.
pub fn needs(
    trial: libtest_mimic::Trial,
    present: bool,
    what: &'static str,
) -> libtest_mimic::Trial {
    if present {
        return trial;
    }
    let name = trial.name().to_string();
    if std::env::var_os("TROMPE_REQUIRE_SYSTEM").is_some() {
        return libtest_mimic::Trial::test(name, move || {
            Err(format!(
                "{what} is not installed, and TROMPE_REQUIRE_SYSTEM is set (.ci/run installs it)"
            )
            .into())
        });
    }
    println!("ignored {name}: {what} is not installed (.ci/run installs it)");
    trial.with_ignored_flag(true)
}

/// Whether `tool` is a command on the `PATH`.
pub fn has_command(tool: &str) -> bool {
    std::process::Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// A glTF whose `levels` levels of two nodes each point at both nodes of the next level: one
/// triangle instanced 2^`levels` times, in a few kilobytes (`name` in `dir`).
pub fn instanced_triangle(dir: &Path, name: &str, levels: usize) -> PathBuf {
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
    // One triangle: 36 bytes of positions, base64 of nine little-endian floats.
    let positions = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";
    let doc = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],"nodes":[{}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{positions}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}]}}"#,
        nodes.join(",")
    );
    let path = dir.join(name);
    std::fs::write(&path, doc).unwrap();
    path
}
