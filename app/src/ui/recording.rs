//! `--record OUT`: the session as a replay script. The recording starts from the file the
//! editor opened, as it was (copied beside OUT first: a save may overwrite it); each file
//! opened later is copied beside it too and becomes an `Open` step; a built scene (New, the
//! default scene) has no step that replays it, so the recording ends there and what it held
//! is what is written at exit. The recorder itself lives in the document (every edit records
//! there); this part owns the copies, the count of opens and the ended recording.

use crate::editor::script::{self, Recorder};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// The recording's files and the part that outlived its document.
#[derive(Debug, Default)]
pub(super) struct Recording {
    /// Where the script goes (`--record`); None: nothing is recorded.
    out: Option<PathBuf>,
    /// The file the session started from (the script's start).
    start: Option<PathBuf>,
    /// Files opened since the recording started (each copied beside it).
    opens: u32,
    /// The recording, once a built scene ended it (written at exit).
    ended: Option<Recorder>,
}

impl Recording {
    /// For `--record out`, starting from `file`: copies the file beside `out` now.
    pub(super) fn start(out: Option<&Path>, file: Option<&Path>) -> Result<Self> {
        if let (Some(out), Some(file)) = (out, file) {
            let copy = copy_path(out, file, "start");
            std::fs::copy(file, &copy).with_context(|| {
                format!("--record: copying {} to {}", file.display(), copy.display())
            })?;
        }
        Ok(Self {
            out: out.map(Path::to_path_buf),
            start: file.map(Path::to_path_buf),
            ..Self::default()
        })
    }

    /// Whether the session is recorded.
    pub(super) fn on(&self) -> bool {
        self.out.is_some()
    }

    /// The recorder for the next document. `previous`: the replaced document's recorder
    /// (None for the session's first document, which starts a new one); `path`: the file the
    /// next document comes from (None: a built scene). An `Err` is the message for the user
    /// when the opened file could not be copied (the recording ends there).
    pub(super) fn carry(
        &mut self,
        previous: Option<Option<Recorder>>,
        path: Option<&Path>,
    ) -> Result<Option<Recorder>, String> {
        let Some(previous) = previous else {
            return Ok(Some(Recorder::default()));
        };
        let Some(mut recorder) = previous else {
            return Ok(None);
        };
        let (Some(path), Some(out)) = (path, self.out.as_deref()) else {
            self.ended = Some(recorder);
            return Ok(None);
        };
        self.opens += 1;
        let copy = copy_path(out, path, &format!("open-{}", self.opens));
        if let Err(e) = std::fs::copy(path, &copy) {
            self.ended = Some(recorder);
            return Err(format!(
                "--record: copying {} to {}: {e}; the recording ends here",
                path.display(),
                copy.display()
            ));
        }
        let name = copy.file_name().map(|n| n.to_string_lossy().into_owned());
        recorder.record(script::Step::Open(name.unwrap_or_default()));
        Ok(Some(recorder))
    }

    /// The session's script so far: the document's recorder, or the one a built scene ended.
    pub(super) fn text(&self, current: Option<&Recorder>) -> Option<String> {
        let (out, file) = (self.out.as_deref()?, self.start.as_deref()?);
        let recorder = current.or(self.ended.as_ref())?;
        let start = copy_path(out, file, "start");
        let name = start.file_name().map(|n| n.to_string_lossy().into_owned());
        Some(recorder.to_ron(script::Start::File(name.unwrap_or_default()), None))
    }

    /// Writes the script (atomically); nothing without `--record` or without a start file.
    pub(super) fn write(&self, current: Option<&Recorder>) -> Result<()> {
        let (Some(out), Some(_)) = (&self.out, &self.start) else {
            return Ok(());
        };
        let Some(text) = self.text(current) else {
            anyhow::bail!("--record: the file was not opened, so nothing was recorded");
        };
        crate::atomic::write_atomic(out, |w| std::io::Write::write_all(w, text.as_bytes()))
            .with_context(|| format!("writing the recording {}", out.display()))
    }
}

/// Where `--record OUT` keeps a file the session opened, as it was: beside OUT, named after
/// it and `what` (`start`, `open-2`, …).
fn copy_path(record: &Path, file: &Path, what: &str) -> PathBuf {
    let ext = file.extension().and_then(|e| e.to_str()).unwrap_or("ron");
    let stem = record
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("session");
    record.with_file_name(format!("{stem}-{what}.{ext}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn copies_go_beside_the_recording_named_after_it() {
        let out = Path::new("/tmp/x/session.ron");
        assert_eq!(
            copy_path(out, Path::new("/a/castle.vox"), "open-2"),
            Path::new("/tmp/x/session-open-2.vox")
        );
        assert_eq!(
            copy_path(Path::new("/tmp/x/rec"), Path::new("/a/b"), "start"),
            Path::new("/tmp/x/rec-start.ron")
        );
    }

    #[test]
    fn a_built_scene_ends_the_recording_and_an_open_goes_on_with_a_copy() {
        let dir = crate::scratch::Scratch::new("recording");
        let file = dir.path().join("a.ron");
        std::fs::write(&file, "x").unwrap();
        let out = dir.path().join("rec.ron");
        let mut r = Recording::start(Some(&out), Some(&file)).unwrap();
        assert!(dir.path().join("rec-start.ron").exists());
        // The first document starts a new recorder.
        let first = r.carry(None, Some(&file)).unwrap().unwrap();
        // Opening a file goes on with an Open step of a copy.
        let second = r.carry(Some(Some(first)), Some(&file)).unwrap().unwrap();
        assert!(dir.path().join("rec-open-1.ron").exists());
        assert!(r.text(Some(&second)).unwrap().contains("rec-open-1.ron"));
        // A built scene ends it; the ended recording is what is written.
        assert!(r.carry(Some(Some(second)), None).unwrap().is_none());
        let text = r.text(None).unwrap();
        assert!(text.contains("rec-start.ron") && text.contains("rec-open-1.ron"));
        r.write(None).unwrap();
        assert_eq!(std::fs::read_to_string(&out).unwrap(), text);
        // A file that cannot be copied ends the recording with a message.
        let mut r = Recording::start(Some(&out), Some(&file)).unwrap();
        let gone = dir.path().join("gone.ron");
        let e = r.carry(Some(Some(Recorder::default())), Some(&gone));
        assert!(e.unwrap_err().contains("the recording ends here"));
        assert!(r.text(None).is_some());
    }

    #[test]
    fn without_record_nothing_is_written() {
        let r = Recording::start(None, None).unwrap();
        assert!(!r.on());
        assert!(r.text(Some(&Recorder::default())).is_none());
        r.write(Some(&Recorder::default())).unwrap();
    }
}
