//! Changes to the document off the UI thread. One thread runs every edit — commands, undo,
//! redo, script steps — in the order they were asked for (undo then redo stays undo then
//! redo). Each edit first takes the frame `gate` (the UI holds it for a whole frame or input
//! event and takes it with `try_lock`, so it skips a frame rather than meet a held write lock
//! mid-frame), then the document's write lock (waiting out a save that reads it). Results
//! come back by channel, with a wake-up for the idle frame loop.

use super::files::SharedDocument;
use crate::editor::command::{Command, Stroke};
use crate::editor::script::{Script, ScriptRun};
use crate::editor::{Document, EditError, Executed};
use crossbeam_channel::{Receiver, Sender};
use glam::DVec3;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex, TryLockError};
use std::time::Duration;

/// An edit the UI asks for.
pub enum Edit {
    /// Execute a command (one undo step).
    Command(Command),
    /// Undo the latest step.
    Undo,
    /// Redo the latest undone step.
    Redo,
    /// Run a replay script's next step (the run travels with the job and comes back).
    ScriptStep(Arc<Script>, Box<ScriptRun>),
    /// Start drawing a stroke (its first points are applied).
    StrokeBegin(Stroke),
    /// The stroke's next segment.
    StrokeExtend(Vec<DVec3>),
    /// End the stroke: one undo step.
    StrokeEnd,
    /// Abandon the stroke, undoing it.
    StrokeAbort,
}

impl Edit {
    /// What the busy indicator shows.
    pub fn label(&self) -> String {
        match self {
            Edit::Command(c) => c.label(),
            Edit::Undo => "Undo".into(),
            Edit::Redo => "Redo".into(),
            Edit::ScriptStep(_, run) => format!("Script step {}", run.steps_run() + 1),
            Edit::StrokeBegin(_) | Edit::StrokeExtend(_) => "Stroke".into(),
            Edit::StrokeEnd => "Stroke (end)".into(),
            Edit::StrokeAbort => "Stroke (cancel)".into(),
        }
    }
}

/// What an edit did.
pub enum Edited {
    /// A command ran: its label, and for a selection operation that did something, what
    /// the status line says it did (how many voxels it selected, copied or changed).
    Command(String, Result<Executed, EditError>, Option<String>),
    /// An undo (the label of what was undone).
    Undo(Result<String, EditError>),
    /// A redo.
    Redo(Result<String, EditError>),
    /// A stroke's begin, segment or end (the end reports the step).
    Stroke(Result<Option<Executed>, EditError>),
    /// A script step: the run back, its report line (None: every step ran), and whether the
    /// scene camera changed (the view follows it).
    ScriptStep {
        /// The replay, one step further.
        run: Box<ScriptRun>,
        /// The step's report.
        result: anyhow::Result<Option<String>>,
        /// The step replaced the scene camera.
        camera_changed: bool,
    },
}

struct Job {
    doc: SharedDocument,
    edit: Edit,
}

/// The document's edit thread.
pub struct EditQueue {
    jobs: Option<Sender<Job>>,
    /// Results, polled by the frame loop.
    pub done: Receiver<Edited>,
    /// Labels of edits asked for and not yet reported, oldest first.
    pub pending: VecDeque<String>,
    /// The frame gate (see the module documentation).
    pub gate: Arc<Mutex<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl EditQueue {
    /// Starts the thread; `wake` is called after each edit (to redraw an idle editor).
    pub fn new(wake: Arc<dyn Fn() + Send + Sync>) -> Self {
        let (jobs, rx) = crossbeam_channel::unbounded::<Job>();
        let (tx, done) = crossbeam_channel::unbounded();
        let gate = Arc::new(Mutex::new(()));
        let g = gate.clone();
        let thread = std::thread::Builder::new()
            .name("voxbrick-edits".into())
            .spawn(move || {
                for job in rx {
                    let edited = {
                        let _between_frames = g.lock().unwrap_or_else(|p| p.into_inner());
                        run(&job.doc, job.edit)
                    };
                    if tx.send(edited).is_err() {
                        break;
                    }
                    wake();
                }
            })
            .expect("spawning the edit thread");
        Self {
            jobs: Some(jobs),
            done,
            pending: VecDeque::new(),
            gate,
            thread: Some(thread),
        }
    }

    /// Queues an edit of `doc`; never waits.
    pub fn submit(&mut self, doc: &SharedDocument, edit: Edit) {
        self.pending.push_back(edit.label());
        if let Some(jobs) = &self.jobs {
            let _ = jobs.send(Job {
                doc: doc.clone(),
                edit,
            });
        }
    }

    /// Whether the edit thread is running (it ends only when the queue is dropped, or by a
    /// panic).
    pub fn alive(&self) -> bool {
        self.thread.as_ref().is_some_and(|t| !t.is_finished())
    }

    /// Marks the oldest edit reported (the caller got its result).
    pub fn finished(&mut self) {
        self.pending.pop_front();
    }

    /// Whether edits are queued or running.
    pub fn busy(&self) -> bool {
        !self.pending.is_empty()
    }
}

impl Drop for EditQueue {
    /// Lets queued edits finish (the document must not be left half-edited), then joins.
    fn drop(&mut self) {
        self.jobs = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The document's write lock, waiting out readers (a save) in short sleeps: `try_write` in
/// a loop never queues as a writer that the UI's reads would then wait behind.
fn write(doc: &SharedDocument) -> std::sync::RwLockWriteGuard<'_, Document> {
    loop {
        match doc.try_write() {
            Ok(d) => return d,
            Err(TryLockError::Poisoned(p)) => return p.into_inner(),
            Err(TryLockError::WouldBlock) => std::thread::sleep(Duration::from_millis(2)),
        }
    }
}

fn run(doc: &SharedDocument, edit: Edit) -> Edited {
    let mut d = write(doc);
    match edit {
        Edit::Command(c) => {
            let label = c.label();
            let landing = Landing::of(&c);
            let result = d.execute(c);
            let said = landing
                .zip(result.as_ref().ok())
                .map(|(l, done)| l.say(&label, &d, done));
            Edited::Command(label, result, said)
        }
        Edit::Undo => Edited::Undo(d.undo()),
        Edit::Redo => Edited::Redo(d.redo()),
        Edit::StrokeBegin(stroke) => Edited::Stroke(d.begin_stroke(stroke).map(|()| None)),
        Edit::StrokeExtend(points) => Edited::Stroke(d.extend_stroke(&points).map(|()| None)),
        Edit::StrokeEnd => Edited::Stroke(d.end_stroke()),
        Edit::StrokeAbort => Edited::Stroke(d.abort_stroke().map(|()| None)),
        Edit::ScriptStep(script, mut run) => {
            let camera = d.scene.params.camera.clone();
            let result = run.step(&script, &mut d);
            Edited::ScriptStep {
                run,
                result,
                camera_changed: d.scene.params.camera != camera,
            }
        }
    }
}

/// What a selection operation is said to have done on the status line, so that each one
/// visibly lands (a select all, a copy or a fill shows nothing else happening).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Landing {
    /// The selection changed: how many voxels it holds.
    Selected,
    /// The clipboard took a copy: how many voxels.
    Copied,
    /// Voxels changed (a delete, fill, paint, cut, move or paste): how many.
    Changed,
}

impl Landing {
    /// The landing of a command that is a selection operation.
    pub fn of(c: &Command) -> Option<Self> {
        match c {
            Command::Select(_) => Some(Landing::Selected),
            Command::Copy => Some(Landing::Copied),
            Command::DeleteSelection
            | Command::FillSelection(_)
            | Command::PaintSelection(_)
            | Command::MoveSelection(_)
            | Command::TransformSelection(_)
            | Command::ScaleSelection(_)
            | Command::Cut
            | Command::Paste { .. } => Some(Landing::Changed),
            _ => None,
        }
    }

    /// The status line's text after the command `label` ran on `doc` and did `done`.
    pub fn say(self, label: &str, doc: &Document, done: &Executed) -> String {
        let voxels = |n: u64| {
            if n == 1 {
                "1 voxel".to_string()
            } else {
                format!("{n} voxels")
            }
        };
        match self {
            Landing::Selected => match &doc.scene.selection {
                Some(s) => format!("{label}: {} selected", voxels(s.voxels.count())),
                None => format!("{label}: nothing selected"),
            },
            Landing::Copied => match &doc.scene.clipboard {
                Some(c) => format!("Copied {} to the clipboard", voxels(c.voxels)),
                None => format!("{label}: nothing copied"),
            },
            Landing::Changed => format!("{label}: {} changed", voxels(done.changed_voxels)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::editor::history::History;
    use crate::scene::Scene;
    use brickmap::GridDims;
    use std::sync::RwLock;

    fn doc() -> SharedDocument {
        let scene = Scene::empty(GridDims::new(2, 2, 2).unwrap(), 2).unwrap();
        Arc::new(RwLock::new(Document::new(
            scene,
            History::with_budget(1 << 20),
        )))
    }

    fn next(q: &mut EditQueue) -> Edited {
        let e = q.done.recv_timeout(Duration::from_secs(20)).unwrap();
        q.finished();
        e
    }

    fn sphere(radius: f64) -> Command {
        Command::Stroke(crate::editor::command::Stroke {
            mode: crate::editor::command::BrushMode::Attach,
            shape: crate::editor::command::BrushShape::Sphere,
            size: radius,
            material: 0,
            mirror: Default::default(),
            points: vec![glam::DVec3::splat(8.0)],
            axis: Default::default(),
            in_selection: false,
            paint: Default::default(),
        })
    }

    #[test]
    fn edits_wait_for_the_frame_and_run_in_the_order_asked() {
        let d = doc();
        let hash = || d.read().unwrap().scene.world.read().content_hash();
        let empty = hash();
        let mut q = EditQueue::new(Arc::new(|| {}));
        // A frame holds the gate: nothing runs, and the UI was not made to wait.
        let gate = q.gate.clone();
        let frame = gate.lock().unwrap();
        let started = std::time::Instant::now();
        q.submit(&d, Edit::Command(sphere(5.0)));
        q.submit(&d, Edit::Undo);
        q.submit(&d, Edit::Redo);
        q.submit(&d, Edit::Undo);
        q.submit(&d, Edit::Undo);
        assert!(started.elapsed() < Duration::from_millis(100));
        assert_eq!(q.pending.len(), 5);
        assert!(q.done.recv_timeout(Duration::from_millis(300)).is_err());
        assert_eq!(hash(), empty);
        drop(frame);
        let Edited::Command(label, Ok(done), _) = next(&mut q) else {
            panic!("the stroke")
        };
        assert!(label.contains("Sphere"), "{label}");
        assert!(done.changed_voxels > 400);
        assert!(matches!(next(&mut q), Edited::Undo(Ok(_))));
        let Edited::Redo(Ok(_)) = next(&mut q) else {
            panic!("redo")
        };
        assert!(matches!(next(&mut q), Edited::Undo(Ok(_))));
        // One undo too many is refused by name, and changes nothing.
        assert!(matches!(
            next(&mut q),
            Edited::Undo(Err(EditError::NothingToUndo))
        ));
        assert!(!q.busy());
        assert_eq!(hash(), empty);
        assert_eq!(d.read().unwrap().history.redo_len(), 1);
    }

    #[test]
    fn a_failing_edit_changes_nothing_and_the_queue_goes_on() {
        let d = doc();
        let mut q = EditQueue::new(Arc::new(|| {}));
        q.submit(&d, Edit::Command(sphere(-1.0)));
        q.submit(&d, Edit::Command(sphere(3.0)));
        let Edited::Command(_, Err(EditError::Invalid(message)), _) = next(&mut q) else {
            panic!("a bad brush size is invalid")
        };
        assert!(message.contains("brush size"), "{message}");
        assert!(matches!(next(&mut q), Edited::Command(_, Ok(_), _)));
        assert_eq!(d.read().unwrap().history.undo_len(), 1);
    }

    #[test]
    fn a_failed_import_changes_nothing_and_one_that_works_is_one_step() {
        let d = doc();
        let hash = || d.read().unwrap().scene.world.read().content_hash();
        let before = hash();
        let mut q = EditQueue::new(Arc::new(|| {}));
        let import = |path: String| {
            Edit::Command(Command::ImportVox {
                path,
                offset: glam::IVec3::new(3, 3, 3),
            })
        };
        q.submit(&d, import("/no/such/file.vox".into()));
        let Edited::Command(label, Err(EditError::File(e)), _) = next(&mut q) else {
            panic!("a missing file is a file error")
        };
        assert!(label.contains("Import"), "{label}");
        assert!(e.to_string().contains("/no/such/file.vox"), "{e}");
        assert_eq!(hash(), before);
        assert_eq!(d.read().unwrap().history.undo_len(), 0);
        assert!(!d.read().unwrap().dirty);
        let dir = crate::scratch::Scratch::new("jobs");
        let vox = dir.join("one.vox");
        let mut scene = Scene::empty(GridDims::new(1, 1, 1).unwrap(), 1).unwrap();
        sphere(2.0).apply(&mut scene, &dir).unwrap();
        crate::formats::save(&scene, &vox).unwrap();
        q.submit(&d, import(vox.display().to_string()));
        let Edited::Command(_, Ok(done), _) = next(&mut q) else {
            panic!("the import works")
        };
        assert!(done.changed_voxels > 0);
        assert_ne!(hash(), before);
        assert_eq!(d.read().unwrap().history.undo_len(), 1);
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn dropping_the_queue_finishes_what_was_asked() {
        let d = doc();
        let mut q = EditQueue::new(Arc::new(|| {}));
        q.submit(&d, Edit::Command(sphere(6.0)));
        drop(q);
        assert_eq!(d.read().unwrap().history.undo_len(), 1);
    }
}
