//! Scratch directories for the unit tests: under `target/test-scratch/`, emptied when a test
//! asks for one, so tests leave nothing in the system's temporary directory (the integration
//! tests' `common::scratch`, in `tests/integration/common/mod.rs`, does the same for them).

use std::path::PathBuf;

/// A fresh, empty directory `target/test-scratch/unit-<name>` for one test.
pub(crate) fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("target/test-scratch")
        .join(format!("unit-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}
