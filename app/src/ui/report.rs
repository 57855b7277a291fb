//! The editor's handshake log: with `VOXBRICK_REPORT=FILE` the editor appends one line per
//! thing it finished — an input event handled (`input …`), a stroke point taken (`stroke …`),
//! an edit applied (`edited …`), a save written (`saved …` / `autosaved …`) and a frame shown
//! (`frame …`), and where a labelled widget appeared or moved (`widget X Y LABEL`) — and
//! flushes each at once. Tests and input drivers wait for the line that
//! answers what they sent instead of sleeping, so they are fast on an idle machine and still
//! right on a loaded one. Without the variable nothing is written.

use std::fs::File;
use std::io::Write;

/// Environment variable naming the report file.
pub const REPORT_ENV: &str = "VOXBRICK_REPORT";

/// The log.
#[derive(Default)]
pub enum Report {
    /// Nothing written.
    #[default]
    Off,
    /// Lines appended to a file, each flushed; with where each labelled widget was last
    /// said to be.
    File(File, std::collections::HashMap<String, (i32, i32)>),
    /// Lines kept for a driver in the same process (a headless editor), taken with `take`.
    Memory(Vec<String>),
}

impl Report {
    /// The log named by [`REPORT_ENV`], created afresh; off when unset or when the file cannot
    /// be created (said once on stderr).
    pub fn from_env() -> Self {
        let Some(path) = std::env::var_os(REPORT_ENV) else {
            return Self::Off;
        };
        match File::create(&path) {
            Ok(f) => Self::File(f, Default::default()),
            Err(e) => {
                eprintln!(
                    "voxbrick: {REPORT_ENV}={}: {e}; no report is written",
                    std::path::Path::new(&path).display()
                );
                Self::Off
            }
        }
    }

    /// Whether lines are written.
    pub fn on(&self) -> bool {
        !matches!(self, Self::Off)
    }

    /// Appends a line (a failed write turns the log off rather than stopping the editor).
    pub fn line(&mut self, text: std::fmt::Arguments<'_>) {
        match self {
            Self::Off => {}
            Self::File(f, _) => {
                if writeln!(f, "{text}").and_then(|()| f.flush()).is_err() {
                    *self = Self::Off;
                }
            }
            Self::Memory(lines) => lines.push(text.to_string()),
        }
    }

    /// Whether lines go to a file (a driver outside the process, which cannot ask where a
    /// widget is: [`Report::widgets`] tells it).
    pub fn to_file(&self) -> bool {
        matches!(self, Self::File(..))
    }

    /// Says where each labelled widget drawn (the first of a label) shows, in window pixels,
    /// when it appeared or moved: `widget X Y LABEL`, X and Y its centre.
    pub fn widgets(&mut self, widgets: &[(String, egui::Rect)], pixels_per_point: f32) {
        let Self::File(_, seen) = self else {
            return;
        };
        let mut lines = Vec::new();
        let mut now = std::collections::HashMap::new();
        for (label, rect) in widgets {
            let c = rect.center() * pixels_per_point;
            let at = (c.x.round() as i32, c.y.round() as i32);
            if now.contains_key(label) {
                continue;
            }
            now.insert(label.clone(), at);
            if seen.get(label) != Some(&at) {
                lines.push(format!("widget {} {} {label}", at.0, at.1));
            }
        }
        *seen = now;
        for l in lines {
            self.line(format_args!("{l}"));
        }
    }

    /// The lines kept since the last call (a memory log's; none otherwise).
    pub fn take(&mut self) -> Vec<String> {
        match self {
            Self::Memory(lines) => std::mem::take(lines),
            _ => Vec::new(),
        }
    }
}
