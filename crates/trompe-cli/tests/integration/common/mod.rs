//! Helpers shared by the command-line tests: the library tests' helpers, and the `trompe`
//! binary run from the repository's root.
#![allow(dead_code, unused_imports)]

#[path = "../../../../../tests/integration/common/mod.rs"]
mod library;

pub use library::*;
use std::process::{Command, Output};

/// Runs the `trompe` binary from the repository's root.
pub fn trompe(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_trompe"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("runs")
}
