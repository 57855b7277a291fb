//! Process-wide counts of how bulk work ran: the threads the last copy of a world into a
//! model spread over, and the bricks computed one voxel at a time (a model brick rewritten
//! voxel by voxel, a world brick recomputed by the composite). The command line reports them
//! after a bulk job (`voxbrick new`), so a path that falls back to one thread or to
//! voxel-by-voxel work shows in its output, and the CLI test checks it. Also the undo
//! records world edits kept (a bulk write nobody undoes should keep none: a 4096 × 1024 ×
//! 4096 terrain's 16 M records once cost two thirds of its generation). Relaxed atomics,
//! one add per brick: no measurable cost.

use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

static SPREAD: AtomicUsize = AtomicUsize::new(0);
static VOXEL_BRICKS: AtomicU64 = AtomicU64::new(0);
static COMPOSITED: AtomicU64 = AtomicU64::new(0);
static UNDO_RECORDS: AtomicU64 = AtomicU64::new(0);

/// What the counters read.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Census {
    /// Threads the last world → model copy ran on (0: none ran).
    pub adopted_on: usize,
    /// Model bricks rewritten voxel by voxel.
    pub voxel_bricks: u64,
    /// World bricks the composite recomputed.
    pub composited: u64,
    /// Brick undo records world edits kept (one add per edit part).
    pub undo_records: u64,
}

/// The counts so far in this process.
pub fn read() -> Census {
    Census {
        adopted_on: SPREAD.load(Ordering::Relaxed),
        voxel_bricks: VOXEL_BRICKS.load(Ordering::Relaxed),
        composited: COMPOSITED.load(Ordering::Relaxed),
        undo_records: UNDO_RECORDS.load(Ordering::Relaxed),
    }
}

pub(crate) fn adopted_on(threads: usize) {
    SPREAD.store(threads, Ordering::Relaxed);
}

pub(crate) fn voxel_brick() {
    VOXEL_BRICKS.fetch_add(1, Ordering::Relaxed);
}

pub(crate) fn composited(bricks: u64) {
    COMPOSITED.fetch_add(bricks, Ordering::Relaxed);
}

pub(crate) fn undo_records(records: u64) {
    UNDO_RECORDS.fetch_add(records, Ordering::Relaxed);
}
