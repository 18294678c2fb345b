//! What the fuzz targets share: trompe's loaders read files, so each input is written to a
//! scratch folder of this process (in `/dev/shm` where there is one) and loaded from there.
//! An input made of several files separates them by [`SEPARATOR`].

use std::path::{Path, PathBuf};

/// Separates the files of a multi-file input (an OBJ and its MTL, a sidecar and its EXR).
pub const SEPARATOR: &[u8] = b"\n--8<--\n";

/// This process's scratch folder, made once.
pub fn scratch() -> &'static Path {
    static DIR: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(|| {
        let base = Path::new("/dev/shm");
        let base = if base.is_dir() {
            base.to_path_buf()
        } else {
            std::env::temp_dir()
        };
        let dir = base.join(format!("trompe-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a scratch folder");
        dir
    })
}

/// Writes `bytes` as `name` in the scratch folder and returns its path.
pub fn file(name: &str, bytes: &[u8]) -> PathBuf {
    let path = scratch().join(name);
    std::fs::write(&path, bytes).expect("the scratch folder is writable");
    path
}

/// Splits `data` into at most `n` parts at [`SEPARATOR`]; missing parts are empty.
pub fn parts(data: &[u8], n: usize) -> Vec<&[u8]> {
    let mut out = Vec::with_capacity(n);
    let mut rest = data;
    while out.len() + 1 < n {
        match rest.windows(SEPARATOR.len()).position(|w| w == SEPARATOR) {
            Some(i) => {
                out.push(&rest[..i]);
                rest = &rest[i + SEPARATOR.len()..];
            }
            None => break,
        }
    }
    out.push(rest);
    out.resize(n, &[]);
    out
}

/// Fuzzing runs under a small memory budget, so a refusal is exercised, not a 2 GiB allocation.
pub fn small_budget() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| trompe::memory::set_limit(256 << 20));
}
