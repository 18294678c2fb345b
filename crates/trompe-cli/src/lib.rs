//! # trompe-cli — the `trompe` command-line tool
//!
//! The application around the [`trompe`] library: the command line ([`cli`]), the demo report
//! ([`report`]), the benchmark workloads of `trompe bench` and `cargo bench` ([`mod@bench`])
//! and the interactive viewer ([`viewer`], its window in `cli/view/window.rs`); how results
//! print, as text or JSON ([`output`]). Each command parses its arguments, calls the library
//! and prints what it returns; no rendering algorithm lives here.

#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod bench;
pub mod cli;
pub mod output;
pub mod report;
pub mod viewer;
