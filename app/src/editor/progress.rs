//! How far a long edit (terrain generation) has got, for a progress bar: the edit's workers
//! count what they finished with atomics; the UI reads the fraction without any lock (the
//! document is locked by the edit meanwhile).
//!
//! In detail:
//! `Progress` (atomics: work done of work to do) and `Counted`, a column source wrapper that
//! counts generated columns; `Document::progress` is shared with the UI, which reads it without
//! the document's lock (a terrain generation holds it): while an edit runs the loop wakes ten
//! times a second and a long edit's percentage goes in the window title (no frame can be drawn
//! meanwhile).

use std::sync::atomic::{AtomicU64, Ordering};

/// Work done out of work to do; nothing running when `total` is 0.
#[derive(Debug, Default)]
pub struct Progress {
    done: AtomicU64,
    total: AtomicU64,
}

impl Progress {
    /// A new piece of work of `total` steps starts.
    pub fn start(&self, total: u64) {
        self.done.store(0, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
    }

    /// One more step done.
    pub fn step(&self) {
        self.done.fetch_add(1, Ordering::Relaxed);
    }

    /// The work ended (done or failed).
    pub fn finish(&self) {
        self.total.store(0, Ordering::Relaxed);
    }

    /// The fraction done of the work running, if any.
    pub fn fraction(&self) -> Option<f32> {
        let total = self.total.load(Ordering::Relaxed);
        (total > 0).then(|| (self.done.load(Ordering::Relaxed) as f64 / total as f64) as f32)
    }

    /// Steps done so far (of the latest work).
    pub fn done(&self) -> u64 {
        self.done.load(Ordering::Relaxed)
    }
}

/// A column source that counts the columns it produced, each once (a flat scene's model and
/// world are generated at the same time, from the same source).
pub(super) struct Counted {
    /// What produces the columns.
    inner: std::sync::Arc<dyn brickmap::edit::ColumnSource>,
    /// Where the count goes.
    progress: std::sync::Arc<Progress>,
    /// Columns produced so far, x fastest.
    seen: Vec<std::sync::atomic::AtomicBool>,
    /// Columns along x.
    width: u32,
}

impl Counted {
    /// Counts `inner`'s columns of a grid of `columns` (x, z) brick columns into `progress`,
    /// which starts now.
    pub fn new(
        inner: std::sync::Arc<dyn brickmap::edit::ColumnSource>,
        progress: std::sync::Arc<Progress>,
        columns: (u32, u32),
    ) -> Self {
        let n = columns.0 as usize * columns.1 as usize;
        progress.start(n as u64);
        Self {
            inner,
            progress,
            seen: (0..n).map(|_| Default::default()).collect(),
            width: columns.0,
        }
    }
}

impl brickmap::edit::ColumnSource for Counted {
    fn column(
        &self,
        bx: u32,
        bz: u32,
        emit: &mut dyn FnMut(u32, brickmap::Mask, brickmap::PriorMaterials),
    ) {
        self.inner.column(bx, bz, emit);
        let at = bz as usize * self.width as usize + bx as usize;
        if self
            .seen
            .get(at)
            .is_some_and(|s| !s.swap(true, Ordering::Relaxed))
        {
            self.progress.step();
        }
    }
    fn materials(&self) -> Vec<u8> {
        self.inner.materials()
    }
}
