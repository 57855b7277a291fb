//! Subcommands of the `voxbrick` binary. Each owns its arguments (a `clap::Args` struct)
//! and its run; a file's own docs say what it measures or writes.
//!
//! - scene files: `scene_file.rs` (`new`, `convert`, `info`), `stats.rs` (`stats` and the
//!   statistics text), `render.rs`, `replay.rs`, `soak.rs`;
//! - benchmarks and suites: `harness/` (the thesis path, complexities, lights, the
//!   viewport, skips, error against time, the stress suite, their plots);
//! - `args.rs`: the value parsers they share; this file: the spinner and stdout helpers.

pub mod args;
pub mod harness;
pub mod picture;
pub mod render;
pub mod replay;
pub mod scene_file;
pub mod soak;
pub mod stats;
pub mod table;

use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
use std::time::Duration;

/// A spinner on stderr while `work` runs (hidden when stderr is not a terminal).
pub(crate) fn with_progress<T>(message: String, work: impl FnOnce() -> Result<T>) -> Result<T> {
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} {elapsed}").expect("valid template"),
    );
    bar.set_message(message);
    bar.enable_steady_tick(Duration::from_millis(100));
    let out = work();
    bar.finish_and_clear();
    out
}

/// Writes a report file (Markdown, CSV) atomically.
pub(crate) fn write_report(path: &std::path::Path, text: &str) -> Result<()> {
    Ok(app::atomic::write_atomic(path, |w| {
        w.write_all(text.as_bytes())
    })?)
}

/// Writes a report's JSON, pretty-printed, atomically.
pub(crate) fn write_json(path: &std::path::Path, value: &serde_json::Value) -> Result<()> {
    write_report(path, &serde_json::to_string_pretty(value)?)
}

/// Writes to stdout; a reader that went away (`voxbrick info f | head`) ends output quietly.
pub(crate) fn emit(text: &str) -> Result<()> {
    use std::io::Write;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}
