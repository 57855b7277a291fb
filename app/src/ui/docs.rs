//! The editor's document-and-files part: the document (shared with the edit thread and the
//! file worker) and how far its long edit has come, the generation that tells the GPU session
//! a new document arrived, the edit queue, the file worker, saves waiting and finished, the
//! questions and builds pending, the `--record` bookkeeping and the long file jobs (a
//! rendered picture, a mesh export). Every edit and every save reaches the document through
//! here, so none can name the wrong one.

use super::files::{FileWorker, SharedDocument};
use super::jobs::{Edit, EditQueue};
use super::pending::Waits;
use super::progress::TaskProgress;
use super::recording::Recording;
use super::render_image::RenderTask;
use super::saves::Saves;
use crate::editor::Document;
use crate::editor::progress::Progress;
use std::path::PathBuf;
use std::sync::{Arc, RwLock, RwLockReadGuard, RwLockWriteGuard};

/// The document and the work on it.
pub(super) struct Docs {
    doc: SharedDocument,
    /// The document's long-edit progress (read without the document's lock).
    progress: Arc<Progress>,
    /// Bumped whenever the document is replaced (the GPU world is then rebuilt).
    generation: u64,
    pub(super) files: FileWorker,
    pub(super) edits: EditQueue,
    /// Saves waiting for queued edits, finished saves to record, the autosave clock.
    pub(super) saves: Saves,
    /// The unsaved-changes question, a save before an open or a quit, a built scene on its
    /// way, a recovery being loaded.
    pub(super) waits: Waits,
    /// `--record`: the copies of opened files and a recording a built scene ended.
    pub(super) recording: Recording,
    /// File → Render image…'s job, while it runs.
    pub(super) render_task: Option<RenderTask>,
    /// File → Export mesh's file and progress, while it runs.
    pub(super) mesh_task: Option<(PathBuf, Arc<TaskProgress>)>,
}

impl Docs {
    /// The first document (generation 0: no real scene has arrived yet).
    pub(super) fn new(
        doc: Document,
        files: FileWorker,
        edits: EditQueue,
        recording: Recording,
    ) -> Self {
        Self {
            progress: doc.progress.clone(),
            doc: Arc::new(RwLock::new(doc)),
            generation: 0,
            files,
            edits,
            saves: Saves::new(),
            waits: Waits::default(),
            recording,
            render_task: None,
            mesh_task: None,
        }
    }

    /// The document, read (a poisoned lock still reads: an edit's panic is reported).
    pub(super) fn read(&self) -> RwLockReadGuard<'_, Document> {
        self.doc.read().unwrap_or_else(|p| p.into_inner())
    }

    /// The document, written.
    pub(super) fn write(&self) -> RwLockWriteGuard<'_, Document> {
        self.doc.write().unwrap_or_else(|p| p.into_inner())
    }

    /// The document as the edit thread and the file worker share it.
    pub(super) fn shared(&self) -> SharedDocument {
        self.doc.clone()
    }

    /// Bumped whenever the document is replaced.
    pub(super) fn generation(&self) -> u64 {
        self.generation
    }

    /// A new document replaces the current one (open, new, recovery). Jobs that hold the
    /// old one finish on it; nothing later reaches it.
    pub(super) fn replace(&mut self, doc: Document) {
        self.progress = doc.progress.clone();
        self.doc = Arc::new(RwLock::new(doc));
        self.generation += 1;
    }

    /// Queues an edit of the document on the edit thread.
    pub(super) fn submit(&mut self, edit: Edit) {
        self.edits.submit(&self.doc, edit);
    }

    /// Saves on the file worker once the edits asked for before are applied (Ctrl+Z then
    /// Ctrl+S saves the undone scene).
    pub(super) fn save_to(&mut self, path: PathBuf, autosave: bool) {
        if self.edits.busy() {
            self.saves.defer(path, autosave);
        } else {
            self.files.save(&self.doc, path, autosave);
        }
    }

    /// Starts the saves that waited for edits, when none is queued or running any more.
    pub(super) fn start_waiting_saves(&mut self) {
        if self.edits.busy() {
            return;
        }
        for (path, autosave) in self.saves.take_waiting() {
            self.files.save(&self.doc, path, autosave);
        }
    }

    /// Applies finished saves' bookkeeping (file, clean flag) to the document, unless
    /// another save is reading it right now (then next frame: the UI never waits).
    pub(super) fn mark_saved(&mut self) {
        self.saves.mark_saved(&self.doc);
    }

    /// Exports the document as a mesh on the file worker.
    pub(super) fn export_mesh(
        &mut self,
        path: PathBuf,
        options: crate::formats::mesh::MeshOptions,
        progress: Arc<TaskProgress>,
    ) {
        self.files.export_mesh(&self.doc, path, options, progress);
    }

    /// An edit is queued or running, or a long one reports progress.
    pub(super) fn busy(&self) -> bool {
        self.edits.busy() || self.progress.fraction().is_some()
    }

    /// How far a long edit has come, while one runs.
    pub(super) fn progress(&self) -> Option<f32> {
        self.progress.fraction()
    }

    /// No edit queued or running, no file job, no save waiting or unrecorded.
    pub(super) fn settled(&self) -> bool {
        !self.edits.busy() && self.files.running.is_empty() && self.saves.settled()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Scene;
    use crate::editor::history::History;

    fn document(bricks: u32) -> Document {
        let dims = brickmap::GridDims::new(bricks, 1, 1).unwrap();
        Document::new(
            Scene::empty(dims, 1).unwrap(),
            History::with_budget(1 << 20),
        )
    }

    fn docs() -> Docs {
        let wake: Arc<dyn Fn() + Send + Sync> = Arc::new(|| {});
        let mut files = FileWorker::new(wake.clone());
        files.dialogs = false;
        let recording = Recording::start(None, None).unwrap();
        Docs::new(document(1), files, EditQueue::new(wake), recording)
    }

    #[test]
    fn a_replaced_document_is_a_new_generation_and_the_old_one_is_left_alone() {
        let mut d = docs();
        assert_eq!(d.generation(), 0);
        let old = d.shared();
        d.replace(document(2));
        assert_eq!(d.generation(), 1);
        assert_eq!(d.read().scene.world.dims().bricks().x, 2);
        assert_eq!(old.read().unwrap().scene.world.dims().bricks().x, 1);
        assert!(!Arc::ptr_eq(&old, &d.shared()));
    }

    #[test]
    fn a_save_asked_while_an_edit_is_queued_waits_for_it() {
        let mut d = docs();
        assert!(d.settled());
        d.submit(Edit::Undo);
        assert!(d.busy() && !d.settled());
        let path = std::env::temp_dir().join(format!("docs-wait-{}.ron", std::process::id()));
        d.save_to(path.clone(), false);
        assert!(
            d.files.running.is_empty(),
            "the save started before the edit"
        );
        assert!(!d.saves.settled());
        // Still queued: nothing starts.
        d.start_waiting_saves();
        assert!(d.files.running.is_empty());
        let _ = std::fs::remove_file(path);
    }
}
