//! The `trompe` binary: parse, run, print the error chain (as JSON under `--json`), exit
//! non-zero on failure.

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    quiet_on_closed_pipe();
    let cli = trompe_cli::cli::Cli::parse();
    let json = cli.json;
    match trompe_cli::cli::run(cli) {
        Ok(code) => code,
        Err(err) if json => {
            let causes = err.chain().map(|c| c.to_string()).collect();
            println!(
                "{}",
                trompe_cli::output::error_document(&error_chain(&err), causes)
            );
            ExitCode::from(1)
        }
        Err(err) => {
            eprintln!("error: {}", error_chain(&err));
            ExitCode::from(1)
        }
    }
}

/// A closed output pipe (`trompe info FILE | head`) ends the program quietly, as it ends any
/// Unix tool, instead of a panic at the next print.
fn quiet_on_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: sets the default action of one signal, before any other thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// The error and its causes joined by ": ", each cause said once: the library's errors already
/// print their cause ("{path}: {source}"), and repeating it would double the message.
fn error_chain(err: &anyhow::Error) -> String {
    let mut message = String::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if message.contains(&text) {
            continue;
        }
        if !message.is_empty() {
            message.push_str(": ");
        }
        message.push_str(&text);
    }
    message
}
