//! The saves the editor has asked for and what they left to do: saves waiting for the edits
//! queued before them (Ctrl+Z then Ctrl+S saves the undone scene), finished saves whose
//! bookkeeping (file, clean flag) is not yet on the document (its lock may be taken by
//! another save: the UI never waits), and the autosave clock.

use super::files::SharedDocument;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Saves waiting, saves finished, the last autosave.
pub(super) struct Saves {
    waiting: Vec<(PathBuf, bool)>,
    finished: Vec<(PathBuf, u64)>,
    last_autosave: Instant,
}

impl Saves {
    /// Nothing asked; the autosave clock starts now.
    pub(super) fn new() -> Self {
        Self {
            waiting: Vec::new(),
            finished: Vec::new(),
            last_autosave: Instant::now(),
        }
    }

    /// A save (to `path`; `autosave`: the recovery file) that must wait for queued edits.
    pub(super) fn defer(&mut self, path: PathBuf, autosave: bool) {
        self.waiting.push((path, autosave));
    }

    /// The waiting saves, to start now that the edits before them are applied.
    pub(super) fn take_waiting(&mut self) -> Vec<(PathBuf, bool)> {
        std::mem::take(&mut self.waiting)
    }

    /// A save finished: `path` holds the document's `revision`.
    pub(super) fn finished(&mut self, path: PathBuf, revision: u64) {
        self.finished.push((path, revision));
    }

    /// Puts the finished saves' bookkeeping on the document, unless another save is reading
    /// it right now (then the next frame does).
    pub(super) fn mark_saved(&mut self, doc: &SharedDocument) {
        if self.finished.is_empty() {
            return;
        }
        let mut d = match doc.try_write() {
            Ok(d) => d,
            Err(std::sync::TryLockError::Poisoned(p)) => p.into_inner(),
            Err(std::sync::TryLockError::WouldBlock) => return,
        };
        for (path, revision) in self.finished.drain(..) {
            d.mark_saved(&path, revision);
        }
    }

    /// Nothing waiting and nothing left to record.
    pub(super) fn settled(&self) -> bool {
        self.waiting.is_empty() && self.finished.is_empty()
    }

    /// Whether an autosave every `secs` seconds (0: never) is due; if so its clock restarts.
    pub(super) fn autosave_due(&mut self, secs: u64) -> bool {
        if secs == 0 || self.last_autosave.elapsed() < Duration::from_secs(secs) {
            return false;
        }
        self.last_autosave = Instant::now();
        true
    }

    /// When the next autosave every `secs` seconds falls due (None: never).
    pub(super) fn next_autosave(&self, secs: u64) -> Option<Instant> {
        (secs > 0).then(|| self.last_autosave + Duration::from_secs(secs))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Scene;
    use crate::editor::Document;
    use crate::editor::history::History;
    use brickmap::GridDims;
    use std::sync::{Arc, RwLock};

    #[test]
    fn finished_saves_wait_for_the_documents_lock_and_autosave_keeps_its_clock() {
        let scene = Scene::empty(GridDims::new(1, 1, 1).unwrap(), 1).unwrap();
        let doc: SharedDocument = Arc::new(RwLock::new(Document::new(scene, History::default())));
        let mut s = Saves::new();
        assert!(s.settled());
        s.defer("a.ron".into(), false);
        assert!(!s.settled());
        assert_eq!(s.take_waiting(), vec![(PathBuf::from("a.ron"), false)]);
        s.finished("a.ron".into(), 0);
        {
            let _reading = doc.read().unwrap();
            s.mark_saved(&doc);
            assert!(!s.settled(), "the lock was taken: kept for the next frame");
        }
        s.mark_saved(&doc);
        assert!(s.settled());
        assert!(!s.autosave_due(0), "0: never");
        assert!(!s.autosave_due(3600), "not yet");
        assert!(s.next_autosave(0).is_none());
        assert!(s.next_autosave(60).unwrap() > Instant::now());
    }
}
