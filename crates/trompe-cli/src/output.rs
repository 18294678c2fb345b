//! What a command prints. Text by default; with `--json`, one JSON document on stdout — its
//! `schema_version`, the command, and every figure the text shows (`docs/json.md`) — and an
//! error as a document too, with the same exit code; with `-q`, nothing else: no progress bars,
//! no spinners, no notes of the files written.
//!
//! Invariant: under `--json`, stdout holds exactly one JSON document, whatever happens.

use serde::Serialize;
use std::fmt::Display;
use std::sync::atomic::{AtomicBool, Ordering};

/// The version of the JSON documents' layout: raised when a field changes meaning or goes.
pub const SCHEMA_VERSION: u32 = 1;

static JSON: AtomicBool = AtomicBool::new(false);
static QUIET: AtomicBool = AtomicBool::new(false);

/// Sets how this process prints: as JSON, quietly (set once, before any command runs).
pub fn set(json: bool, quiet: bool) {
    JSON.store(json, Ordering::Relaxed);
    QUIET.store(quiet, Ordering::Relaxed);
}

/// Whether results print as JSON.
pub fn json() -> bool {
    JSON.load(Ordering::Relaxed)
}

/// Whether progress and notes are silenced.
pub fn quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
}

/// Prints a command's result: `text` as it reads, or under `--json` the document of `command`
/// with `result`'s fields.
pub fn report(command: &str, text: impl Display, result: &impl Serialize) -> anyhow::Result<()> {
    if json() {
        println!("{}", document(command, result)?);
    } else {
        println!("{text}");
    }
    Ok(())
}

/// The JSON document of `command`'s `result`: `{"schema_version", "command", "result"}`.
pub fn document(command: &str, result: &impl Serialize) -> serde_json::Result<String> {
    #[derive(Serialize)]
    struct Document<'a, T> {
        schema_version: u32,
        command: &'a str,
        result: &'a T,
    }
    serde_json::to_string_pretty(&Document {
        schema_version: SCHEMA_VERSION,
        command,
        result,
    })
}

/// The JSON document of an error: `{"schema_version", "error": {"message", "causes"}}`, the
/// message as the text prints it, the causes one a line of the chain.
pub fn error_document(message: &str, causes: Vec<String>) -> String {
    let document = serde_json::json!({
        "schema_version": SCHEMA_VERSION,
        "error": { "message": message, "causes": causes },
    });
    serde_json::to_string_pretty(&document).unwrap_or_else(|_| {
        // A tree of strings always serializes; this is never reached.
        format!("{{\"schema_version\": {SCHEMA_VERSION}, \"error\": {{}}}}")
    })
}

/// Prints a note on stderr (a file written), unless `-q`. Warnings are not notes: they print
/// whatever the flags.
pub fn note(text: impl Display) {
    if !quiet() {
        eprintln!("{text}");
    }
}
