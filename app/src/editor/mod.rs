//! The editor's engine, without a window: a document (scene, file, dirty flag, history) and
//! the commands that change it. The interactive editor and script replay drive it alike.

mod brush;
pub mod canvas;
pub mod command;
mod error;
mod extrude;
mod fill;
pub mod history;
mod inverse;
pub mod live;
pub mod objects;
mod paint;
pub mod progress;
mod replace;
pub mod script;
mod specs;
pub mod stamp;

pub use error::{EditError, Result};

use crate::scene::Scene;
use command::Command;
use history::History;
use std::path::{Path, PathBuf};

/// What executing a command did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Executed {
    /// Old history steps dropped to stay within the budget.
    pub dropped: u64,
    /// Voxels the command changed.
    pub changed_voxels: u64,
}

/// An open scene and everything about it the editor tracks.
#[derive(Debug)]
pub struct Document {
    /// The scene.
    pub scene: Scene,
    /// Where it was loaded from or last saved to.
    pub path: Option<PathBuf>,
    /// Changed since it was loaded or saved.
    pub dirty: bool,
    /// Counts changes (commands, undos, redos): a save made off the UI thread records the
    /// revision it wrote, so a change made meanwhile keeps the document dirty.
    pub revision: u64,
    /// Undo and redo.
    pub history: History,
    /// Folder that relative paths in commands (imports) are resolved against.
    pub folder: PathBuf,
    /// When set, every successful command, undo, redo and save is recorded as a script step.
    pub recorder: Option<script::Recorder>,
    /// The stroke being drawn, if any (see [`live`]).
    live: Option<live::LiveStroke>,
    /// How far the running long edit (terrain generation) has got.
    pub progress: std::sync::Arc<progress::Progress>,
}

impl Document {
    /// A document for a scene.
    pub fn new(scene: Scene, history: History) -> Self {
        Self {
            scene,
            path: None,
            dirty: false,
            revision: 0,
            history,
            folder: PathBuf::from("."),
            recorder: None,
            live: None,
            progress: Default::default(),
        }
    }

    fn changed(&mut self) {
        self.dirty = true;
        self.revision += 1;
    }

    /// Starts drawing a stroke: its first points are applied now. A stroke already open is
    /// finished first (one step each). On error nothing changed.
    pub fn begin_stroke(&mut self, stroke: command::Stroke) -> Result<()> {
        self.end_stroke()?;
        self.live = Some(live::LiveStroke::begin(&self.scene, stroke)?);
        self.changed();
        Ok(())
    }

    /// Adds points to the open stroke (visible as soon as this returns). On error the whole
    /// stroke is undone and closed, and nothing reaches the history.
    pub fn extend_stroke(&mut self, points: &[glam::DVec3]) -> Result<()> {
        let Some(live) = &mut self.live else {
            return Err(error::invalid("no stroke is being drawn"));
        };
        let result = live.extend(&self.scene, points);
        if result.is_err() {
            self.live = None;
        }
        self.changed();
        result
    }

    /// Ends the open stroke as one history step (recorded as the whole stroke); Ok(None)
    /// when none was open. On error nothing of the stroke remains.
    pub fn end_stroke(&mut self) -> Result<Option<Executed>> {
        let Some(live) = self.live.take() else {
            return Ok(None);
        };
        let (stroke, inverse, changed_voxels) = live.finish(&self.scene)?;
        self.changed();
        let command = Command::Stroke(stroke);
        if let Some(r) = &mut self.recorder {
            r.record(script::Step::Do(command.clone()));
        }
        let dropped = self.history.push(command, inverse, changed_voxels);
        Ok(Some(Executed {
            dropped,
            changed_voxels,
        }))
    }

    /// Abandons the open stroke, undoing what it applied (nothing reaches the history).
    pub fn abort_stroke(&mut self) -> Result<()> {
        if let Some(live) = self.live.take() {
            live.abort(&self.scene)?;
            self.changed();
        }
        Ok(())
    }

    /// The stroke being drawn.
    pub fn live_stroke(&self) -> Option<&live::LiveStroke> {
        self.live.as_ref()
    }

    /// Executes a command and records it; on error nothing changed (world, tables, history).
    pub fn execute(&mut self, command: Command) -> Result<Executed> {
        self.end_stroke()?;
        let applied = command.apply_with(&mut self.scene, &self.folder, &self.progress)?;
        if !command.changes_document() {
            if let Some(r) = &mut self.recorder {
                r.record(script::Step::Do(command));
            }
            return Ok(Executed {
                dropped: 0,
                changed_voxels: 0,
            });
        }
        self.changed();
        if let Some(r) = &mut self.recorder {
            r.record(script::Step::Do(command.clone()));
        }
        let dropped = self
            .history
            .push(command, applied.inverse, applied.changed_voxels);
        Ok(Executed {
            dropped,
            changed_voxels: applied.changed_voxels,
        })
    }

    /// Undoes the latest step; the label of what was undone.
    pub fn undo(&mut self) -> Result<String> {
        self.end_stroke()?;
        let Some(step) = self.history.take_undo() else {
            return Err(EditError::NothingToUndo);
        };
        let (label, command, inverse, changed) = step.into_parts();
        let redo = inverse.apply(&mut self.scene)?;
        self.history
            .push_redo(label.clone(), command, redo, changed);
        self.changed();
        if let Some(r) = &mut self.recorder {
            r.record(script::Step::Undo);
        }
        Ok(label)
    }

    /// Redoes the latest undone step; its label.
    pub fn redo(&mut self) -> Result<String> {
        self.end_stroke()?;
        let Some(step) = self.history.take_redo() else {
            return Err(EditError::NothingToRedo);
        };
        let (label, command, inverse, changed) = step.into_parts();
        let undo = inverse.apply(&mut self.scene)?;
        self.history
            .push_undone(label.clone(), command, undo, changed);
        self.changed();
        if let Some(r) = &mut self.recorder {
            r.record(script::Step::Redo);
        }
        Ok(label)
    }

    /// Saves (project or .vox by extension) atomically; a project save clears the dirty flag.
    pub fn save(&mut self, path: &Path) -> Result<(), crate::formats::FormatError> {
        crate::formats::save(&self.scene, path)?;
        self.mark_saved(path, self.revision);
        Ok(())
    }

    /// The bookkeeping of a save of `revision` that succeeded (the editor writes off the UI
    /// thread, then calls this): recorded, and a project save becomes the document's file,
    /// clean unless it changed since that revision.
    pub fn mark_saved(&mut self, path: &Path, revision: u64) {
        if let Some(r) = &mut self.recorder {
            // By file name: a replay writes it into its output folder, never over the file
            // the session saved.
            let name = path.file_name().unwrap_or(path.as_os_str());
            r.record(script::Step::Save(name.to_string_lossy().into_owned()));
        }
        if crate::formats::Format::of(path).ok() == Some(crate::formats::Format::Project) {
            self.path = Some(path.to_path_buf());
            self.dirty = self.revision != revision;
        }
    }
}
