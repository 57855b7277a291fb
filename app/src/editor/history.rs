//! The undo history: a bounded list of steps, each with a label, the command (for redo
//! labels and the recorder) and its inverse. A new command after undo drops the redo
//! branch; consecutive edits of one property coalesce into one step; when the steps' bytes
//! exceed the budget the oldest are dropped, and the history counts them.

use super::command::Command;
use super::inverse::Inverse;
use std::collections::VecDeque;

/// Default memory budget: 512 MiB.
pub const DEFAULT_BUDGET: usize = 512 << 20;

/// One undoable step.
#[derive(Debug)]
pub struct Step {
    /// For the history list.
    pub label: String,
    /// The command as executed (the latest one, for coalesced steps).
    pub command: Command,
    /// How to undo (in the undo list) or redo (in the redo list).
    pub inverse: Inverse,
    /// Voxels the step changed (for the history list).
    pub changed_voxels: u64,
    bytes: usize,
}

impl Step {
    /// Label, command, inverse and voxels changed.
    pub fn into_parts(self) -> (String, Command, Inverse, u64) {
        (self.label, self.command, self.inverse, self.changed_voxels)
    }
}

/// Undo and redo lists within a memory budget.
#[derive(Debug)]
pub struct History {
    undo: VecDeque<Step>,
    redo: Vec<Step>,
    bytes: usize,
    budget: usize,
    dropped: u64,
}

impl Default for History {
    fn default() -> Self {
        Self::with_budget(DEFAULT_BUDGET)
    }
}

impl History {
    /// An empty history holding at most `budget` bytes of steps (always at least the latest).
    pub fn with_budget(budget: usize) -> Self {
        Self {
            undo: VecDeque::new(),
            redo: Vec::new(),
            bytes: 0,
            budget,
            dropped: 0,
        }
    }

    /// Records an executed command; returns how many old steps were dropped to fit the budget.
    pub fn push(&mut self, command: Command, inverse: Inverse, changed_voxels: u64) -> u64 {
        self.clear_redo();
        let key = command.coalesce_key();
        if let (Some(key), Some(last)) = (&key, self.undo.back_mut())
            && last.command.coalesce_key().as_ref() == Some(key)
        {
            // Keep the oldest inverse (the value before the drag), take the newest command.
            last.label = command.label();
            last.command = command;
            last.changed_voxels += changed_voxels;
            return 0;
        }
        let bytes = inverse.bytes() + std::mem::size_of::<Step>();
        self.bytes += bytes;
        self.undo.push_back(Step {
            label: command.label(),
            command,
            inverse,
            changed_voxels,
            bytes,
        });
        let mut dropped = 0;
        while self.bytes > self.budget && self.undo.len() > 1 {
            let old = self.undo.pop_front().expect("more than one step");
            self.bytes -= old.bytes;
            dropped += 1;
        }
        self.dropped += dropped;
        dropped
    }

    /// Takes the latest step to undo.
    pub fn take_undo(&mut self) -> Option<Step> {
        let step = self.undo.pop_back()?;
        self.bytes -= step.bytes;
        Some(step)
    }

    /// Puts an undone step on the redo list with the inverse that redoes it.
    pub fn push_redo(&mut self, label: String, command: Command, redo: Inverse, changed: u64) {
        let bytes = redo.bytes() + std::mem::size_of::<Step>();
        self.bytes += bytes;
        self.redo.push(Step {
            label,
            command,
            inverse: redo,
            changed_voxels: changed,
            bytes,
        });
    }

    /// Takes the latest undone step to redo.
    pub fn take_redo(&mut self) -> Option<Step> {
        let step = self.redo.pop()?;
        self.bytes -= step.bytes;
        Some(step)
    }

    /// Puts a redone step back on the undo list with the inverse that undoes it again.
    pub fn push_undone(&mut self, label: String, command: Command, undo: Inverse, changed: u64) {
        let bytes = undo.bytes() + std::mem::size_of::<Step>();
        self.bytes += bytes;
        self.undo.push_back(Step {
            label,
            command,
            inverse: undo,
            changed_voxels: changed,
            bytes,
        });
    }

    fn clear_redo(&mut self) {
        for s in self.redo.drain(..) {
            self.bytes -= s.bytes;
        }
    }

    /// Labels of the undoable steps, oldest first.
    pub fn labels(&self) -> Vec<&str> {
        self.undo.iter().map(|s| s.label.as_str()).collect()
    }
    /// The undoable steps, oldest first.
    pub fn undo_steps(&self) -> impl Iterator<Item = &Step> {
        self.undo.iter()
    }
    /// The redoable steps, the next to redo first.
    pub fn redo_steps(&self) -> impl Iterator<Item = &Step> {
        self.redo.iter().rev()
    }
    /// Steps that can be undone.
    pub fn undo_len(&self) -> usize {
        self.undo.len()
    }
    /// Steps that can be redone.
    pub fn redo_len(&self) -> usize {
        self.redo.len()
    }
    /// Bytes held by every step.
    pub fn bytes(&self) -> usize {
        self.bytes
    }
    /// Steps dropped to fit the budget since the history began.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }
}
