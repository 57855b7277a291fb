//! The editor engine's one error type: what a command, an undo or a redo can fail with. The
//! UI tells them apart (a refused edit is shown and forgotten; a file error names the file);
//! whenever one is returned, the scene and the history are as they were.
//!
//! In detail:
//! `EditError`, the engine's one error enum (invalid command, world, parameter, file, nothing
//! to undo / redo, nothing to do: no selection, an empty clipboard, no unused material): the UI
//! tells them apart (`is_no_op`: a status-line notice, not the Error window). Commands, undo
//! and redo return it; a script step (`ScriptRun::step`) returns `anyhow::Result`, as it
//! also reports renders, files and expectations.

use crate::formats::FormatError;
use brickmap::BrickmapError;

/// Why a command, undo or redo did not happen.
#[derive(Debug, thiserror::Error)]
pub enum EditError {
    /// The command's own parameters are wrong (a stroke without points, a fill that starts
    /// in empty space).
    #[error("{0}")]
    Invalid(String),
    /// The world refused (outside the grid, no such material, over the memory budget).
    #[error(transparent)]
    World(#[from] BrickmapError),
    /// The objects refused (a locked object, no active object, an object that would leave
    /// the grid).
    #[error(transparent)]
    Objects(brickmap::objects::ObjectError),
    /// A scene setting outside its range.
    #[error(transparent)]
    Param(#[from] render::ParamError),
    /// A file the command reads (an import) could not be read or is not valid.
    #[error(transparent)]
    File(#[from] FormatError),
    /// Undo with an empty undo list.
    #[error("nothing to undo")]
    NothingToUndo,
    /// Redo with an empty redo list.
    #[error("nothing to redo")]
    NothingToRedo,
    /// Nothing for the command to act on (no selection, an empty clipboard, no unused
    /// material): harmless, said in passing rather than shown as a failure.
    #[error("{0}")]
    NothingToDo(&'static str),
}

impl From<brickmap::objects::ObjectError> for EditError {
    /// A model's or the world's refusal of an edit stays a world error.
    fn from(e: brickmap::objects::ObjectError) -> Self {
        match e {
            brickmap::objects::ObjectError::Edit(e) => Self::World(e),
            e => Self::Objects(e),
        }
    }
}

impl From<brickmap::objects::TreeError> for EditError {
    fn from(e: brickmap::objects::TreeError) -> Self {
        Self::Objects(e.into())
    }
}

impl EditError {
    /// Whether the edit had nothing to act on (an undo with nothing to undo, a copy without
    /// a selection): a no-op, not a failure.
    pub fn is_no_op(&self) -> bool {
        matches!(
            self,
            Self::NothingToUndo | Self::NothingToRedo | Self::NothingToDo(_)
        )
    }
}

/// The engine's result.
pub type Result<T, E = EditError> = std::result::Result<T, E>;

/// An [`EditError::Invalid`].
pub(crate) fn invalid(message: impl Into<String>) -> EditError {
    EditError::Invalid(message.into())
}
