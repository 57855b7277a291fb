//! The editor's handshake log: with `VOXBRICK_REPORT=FILE` the editor appends one line per
//! thing it finished — an input event handled (`input …`), a stroke point taken (`stroke …`),
//! an edit applied (`edited …`), a save written (`saved …` / `autosaved …`) and a frame shown
//! (`frame …`) — and flushes each at once. Tests and input drivers wait for the line that
//! answers what they sent instead of sleeping, so they are fast on an idle machine and still
//! right on a loaded one. Without the variable nothing is written.

use std::fs::File;
use std::io::Write;

/// Environment variable naming the report file.
pub const REPORT_ENV: &str = "VOXBRICK_REPORT";

/// The log (None: off).
#[derive(Default)]
pub struct Report(Option<File>);

impl Report {
    /// The log named by [`REPORT_ENV`], created afresh; off when unset or when the file cannot
    /// be created (said once on stderr).
    pub fn from_env() -> Self {
        let Some(path) = std::env::var_os(REPORT_ENV) else {
            return Self(None);
        };
        match File::create(&path) {
            Ok(f) => Self(Some(f)),
            Err(e) => {
                eprintln!(
                    "voxbrick: {REPORT_ENV}={}: {e}; no report is written",
                    std::path::Path::new(&path).display()
                );
                Self(None)
            }
        }
    }

    /// Whether lines are written.
    pub fn on(&self) -> bool {
        self.0.is_some()
    }

    /// Appends a line (a failed write turns the log off rather than stopping the editor).
    pub fn line(&mut self, text: std::fmt::Arguments<'_>) {
        if let Some(f) = &mut self.0
            && writeln!(f, "{text}").and_then(|()| f.flush()).is_err()
        {
            self.0 = None;
        }
    }
}
