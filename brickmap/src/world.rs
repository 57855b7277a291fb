//! The world: the grid split into x-slabs, one worker thread per slab, fed by
//! crossbeam-channel queues. Any thread may submit an edit; it is validated first (bad input
//! never reaches a worker), split into per-slab parts, and queued to the workers it touches
//! in one global order, so every slab sees edits in the same order whatever the thread that
//! submitted them. A [`Ticket`] waits for the parts; if any part fails, the others are rolled
//! back, so an edit applies entirely or not at all. A worker panic is caught and reported.
//!
//! In detail:
//! `World` (workers, submit order, tickets, rollback, material table, light faces), `WorldView`
//! (queries, content hash, memory, GPU images, occupied bounds for framing, `lights()`),
//! `DirtySet`. A waited ticket recomputes the light faces of the bricks the edit changed and of
//! their face neighbours holding lit voxels (`Lights::apply`: an unchanged brick writes
//! nothing; a changed one rewrites its leaves and their ancestors), under a lock that orders
//! light updates, each from the voxels as they are when it runs, so the last update of a brick
//! is never older than its last edit; nothing is done while no material is a light. A material
//! change updates the weights (leaves rewritten, cost: the light faces); one that makes a
//! material a light or stops it being one rescans the bricks.

use crate::brick::Brick;
pub use crate::brick::BrickMaterials;
use crate::dirty::DirtyRanges;
use crate::edit::{EditInverse, EditOp, EditOutcome, VoxelEdit};
use crate::error::{BrickmapError, Result};
use crate::grid::{GridDims, SlabBounds};
use crate::lights::{self, Lights};
use crate::material::{Material, MaterialKind, MaterialTable, MaterialTablesGpu};
use crate::slab::{CellState, Slab, WorkItem};
use crate::storage::{BRICK_CHUNK, BucketSizes, ChunkCounters, MATERIAL_CHUNK};
use crossbeam_channel::{Receiver, Sender};
use glam::{IVec3, UVec3};
use std::ops::Range;
use std::sync::{Arc, Mutex, RwLock, RwLockReadGuard};
use std::thread::JoinHandle;

mod view;
mod workers;
pub use view::WorldView;
pub use workers::Ticket;
use workers::{Job, worker_loop};

/// How a world is built.
#[derive(Clone, Debug)]
pub struct WorldConfig {
    /// Worker threads (0: one per available core). Capped by the grid's coarse columns.
    pub workers: usize,
    /// Bucket sizes for per-voxel material bytes.
    pub bucket_sizes: BucketSizes,
    /// Budget for the brick buffer, in bricks (an edit that needs more fails cleanly).
    pub max_bricks: u64,
    /// Budget for the material-byte buffer, in bytes.
    pub max_material_bytes: u64,
}

impl WorldConfig {
    /// The default configuration with `workers` worker threads (0: one per core).
    pub fn with_workers(workers: usize) -> Self {
        Self {
            workers,
            ..Self::default()
        }
    }
}

impl Default for WorldConfig {
    fn default() -> Self {
        Self {
            workers: 0,
            bucket_sizes: BucketSizes::default(),
            max_bricks: u64::MAX,
            max_material_bytes: u64::MAX,
        }
    }
}

/// The buffers the GPU mirrors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GpuBuffer {
    /// One u32 per brick cell: global brick index or [`EMPTY_BRICK`].
    BrickIndex,
    /// [`Brick`]s (68 bytes each).
    Bricks,
    /// Coarse occupancy bits (see [`GridDims::coarse_bit`]).
    Coarse,
    /// Per-voxel material bytes.
    MaterialBytes,
    /// [`MaterialTablesGpu`].
    MaterialTables,
    /// The light faces' sum tree ([`crate::lights`]).
    Lights,
}

impl GpuBuffer {
    /// Every buffer.
    pub const ALL: [GpuBuffer; 6] = [
        GpuBuffer::BrickIndex,
        GpuBuffer::Bricks,
        GpuBuffer::Coarse,
        GpuBuffer::MaterialBytes,
        GpuBuffer::MaterialTables,
        GpuBuffer::Lights,
    ];
}

/// Changed byte ranges of every GPU buffer since the last drain, sorted and merged.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DirtySet {
    /// Per buffer, in [`GpuBuffer::ALL`] order.
    pub ranges: [Vec<Range<u64>>; 6],
}

impl DirtySet {
    /// The ranges of one buffer.
    pub fn of(&self, b: GpuBuffer) -> &[Range<u64>] {
        &self.ranges[b as usize]
    }
    /// Total bytes covered.
    pub fn bytes(&self) -> u64 {
        self.ranges.iter().flatten().map(|r| r.end - r.start).sum()
    }
}

/// Bytes by buffer.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MemoryStats {
    /// Brick-index grid (dense).
    pub brick_index: u64,
    /// Bricks in use × 68.
    pub bricks_used: u64,
    /// Brick chunks claimed × 68.
    pub bricks_reserved: u64,
    /// Coarse occupancy grid.
    pub coarse: u64,
    /// Material pages dedicated to a bucket size.
    pub material_used: u64,
    /// Material chunks claimed.
    pub material_reserved: u64,
    /// Material bytes the bricks actually hold (the rest of `material_used` is bucket slack).
    pub material_payload: u64,
    /// Stored bricks whose solid voxels share one material (no material bytes).
    pub uniform_bricks: u64,
    /// Full uniform cells, stored in the brick index alone.
    pub full_cells: u64,
    /// Material, colour and parameter tables.
    pub tables: u64,
    /// The light faces' tree and records.
    pub lights: u64,
    /// CPU-only bookkeeping (slot metadata, free-list links).
    pub cpu_only: u64,
}

impl MemoryStats {
    /// Everything the GPU must hold to render the world as it is.
    pub fn gpu_used(&self) -> u64 {
        self.brick_index
            + self.bricks_used
            + self.coarse
            + self.material_used
            + self.tables
            + self.lights
    }
    /// Everything the GPU buffers occupy with whole chunks.
    pub fn gpu_reserved(&self) -> u64 {
        self.brick_index
            + self.bricks_reserved
            + self.coarse
            + self.material_reserved
            + self.tables
            + self.lights
    }
}

/// The voxel world.
pub struct World {
    dims: GridDims,
    slabs: Vec<Arc<RwLock<Slab>>>,
    slab_of_x: Vec<u16>,
    senders: Vec<Sender<Job>>,
    threads: Vec<JoinHandle<()>>,
    submit_order: Mutex<()>,
    materials: RwLock<MaterialTable>,
    counters: Arc<ChunkCounters>,
    lights: RwLock<Lights>,
    /// Serialises light updates (each recomputes from the voxels as they are when it runs,
    /// so the last update of a brick is never older than its last edit).
    light_updates: Mutex<()>,
}

impl std::fmt::Debug for World {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("World")
            .field("dims", &self.dims)
            .field("workers", &self.slabs.len())
            .finish()
    }
}

impl World {
    /// An empty world with the default material table.
    pub fn new(dims: GridDims, config: WorldConfig) -> Result<Self> {
        let workers = if config.workers == 0 {
            std::thread::available_parallelism().map_or(1, |n| n.get())
        } else {
            config.workers
        };
        if workers > 1024 {
            return Err(BrickmapError::Config(format!(
                "{workers} workers is too many"
            )));
        }
        let counters = Arc::new(ChunkCounters::with_budget(
            config.max_bricks,
            config.max_material_bytes,
        ));
        let bounds = SlabBounds::split(&dims, workers);
        let mut slab_of_x = vec![0u16; dims.bricks().x as usize];
        let mut slabs = Vec::new();
        let mut senders = Vec::new();
        let mut threads = Vec::new();
        for (w, b) in bounds.into_iter().enumerate() {
            slab_of_x[b.bricks_x.start as usize..b.bricks_x.end as usize].fill(w as u16);
            let slab = Arc::new(RwLock::new(Slab::new(
                dims,
                b,
                config.bucket_sizes.clone(),
                counters.clone(),
            )));
            let (tx, rx) = crossbeam_channel::unbounded();
            let mine = slab.clone();
            let thread = std::thread::Builder::new()
                .name(format!("brickmap-worker-{w}"))
                .spawn(move || worker_loop(w, mine, rx))
                .map_err(|e| BrickmapError::Config(format!("cannot start worker: {e}")))?;
            slabs.push(slab);
            senders.push(tx);
            threads.push(thread);
        }
        Ok(Self {
            dims,
            slabs,
            slab_of_x,
            senders,
            threads,
            submit_order: Mutex::new(()),
            materials: RwLock::new(MaterialTable::default()),
            counters,
            lights: RwLock::new(Lights::default()),
            light_updates: Mutex::new(()),
        })
    }

    /// Grid size.
    pub fn dims(&self) -> GridDims {
        self.dims
    }
    /// Worker threads running.
    pub fn workers(&self) -> usize {
        self.slabs.len()
    }

    /// Validates and queues an edit; the ticket waits for it.
    pub fn submit(&self, op: EditOp) -> Result<Ticket<'_>> {
        self.submit_as(op, false)
    }

    /// Queues an edit; `compact`: its parts record whole-brick writes into empty cells as
    /// positions (see `slab::Undo`).
    fn submit_as(&self, op: EditOp, compact: bool) -> Result<Ticket<'_>> {
        self.validate(&op)?;
        let parts = self.split(op);
        let (reply, rx) = crossbeam_channel::unbounded();
        let expected = parts.len();
        {
            let _order = self.submit_order.lock().unwrap_or_else(|p| p.into_inner());
            for (w, item) in parts {
                self.senders[w]
                    .send(Job::Work {
                        item,
                        compact,
                        reply: reply.clone(),
                    })
                    .map_err(|_| BrickmapError::WorkerGone(w))?;
            }
        }
        Ok(Ticket {
            world: self,
            rx,
            expected,
        })
    }

    /// Submits an edit and waits for it.
    pub fn apply(&self, op: EditOp) -> Result<EditOutcome> {
        self.submit(op)?.wait()
    }

    /// Applies an edit nobody will undo (building a new scene, loading a file) and returns
    /// the voxels it changed. The same edit as [`World::apply`], and a failure still leaves
    /// the world as before it, but no inverse is kept: a whole-brick write into an empty
    /// cell is remembered by its position alone, for the rollback, and dropped after.
    pub fn apply_unrecorded(&self, op: EditOp) -> Result<u64> {
        self.submit_as(op, true)?.wait_unrecorded()
    }

    fn validate(&self, op: &EditOp) -> Result<()> {
        crate::edit::validate(op, &self.materials(), self.dims.voxels())
    }

    fn split(&self, op: EditOp) -> Vec<(usize, WorkItem)> {
        match op {
            EditOp::Shape { shape, mode } => {
                let (lo, hi) = shape.voxel_bounds();
                let max = self.dims.voxels() - 1;
                if hi.cmplt(IVec3::ZERO).any() || lo.cmpgt(max).any() {
                    return Vec::new();
                }
                let x0 = self.slab_of_x[(lo.x.clamp(0, max.x) / 8) as usize] as usize;
                let x1 = self.slab_of_x[(hi.x.clamp(0, max.x) / 8) as usize] as usize;
                let job = Arc::new((shape, mode));
                (x0..=x1)
                    .map(|w| (w, WorkItem::Shape(job.clone())))
                    .collect()
            }
            EditOp::Voxels(list) => {
                let mut per: Vec<Vec<VoxelEdit>> = vec![Vec::new(); self.slabs.len()];
                for e in list {
                    per[self.slab_of_x[(e.pos.x / 8) as usize] as usize].push(e);
                }
                per.into_iter()
                    .enumerate()
                    .filter(|(_, v)| !v.is_empty())
                    .map(|(w, v)| (w, WorkItem::Voxels(v)))
                    .collect()
            }
            EditOp::Generate(g) => (0..self.slabs.len())
                .map(|w| (w, WorkItem::Generate(g.0.clone())))
                .collect(),
            EditOp::Restore(inv) => {
                let slab = |u: &crate::edit::BrickUndo| self.slab_of_x[u.brick.x as usize];
                if inv.bricks.is_sorted_by_key(slab) {
                    // In slab order (a file's bricks, a generated grid's, most inverses): each
                    // worker reads its run of one shared list, nothing is copied.
                    let mut runs = Vec::new();
                    let mut start = 0;
                    while start < inv.bricks.len() {
                        let w = slab(&inv.bricks[start]);
                        let len = inv.bricks[start..].partition_point(|u| slab(u) == w);
                        runs.push((w as usize, start..start + len));
                        start += len;
                    }
                    let list = Arc::new(inv.bricks);
                    return runs
                        .into_iter()
                        .map(|(w, r)| (w, WorkItem::RestoreRun(list.clone(), r)))
                        .collect();
                }
                let mut per = vec![Vec::new(); self.slabs.len()];
                for u in inv.bricks {
                    per[self.slab_of_x[u.brick.x as usize] as usize].push(u);
                }
                per.into_iter()
                    .enumerate()
                    .filter(|(_, v)| !v.is_empty())
                    .map(|(w, v)| (w, WorkItem::Restore(v)))
                    .collect()
            }
        }
    }

    /// Makes worker `w` panic inside its next job (for testing that a panic surfaces as an
    /// error); its slab is marked poisoned and every later edit touching it fails.
    #[doc(hidden)]
    #[cfg(feature = "test-hooks")]
    pub fn inject_worker_panic(&self, w: usize) -> Result<Ticket<'_>> {
        let (reply, rx) = crossbeam_channel::unbounded();
        self.senders
            .get(w)
            .ok_or(BrickmapError::WorkerGone(w))?
            .send(Job::Work {
                item: WorkItem::Panic,
                compact: false,
                reply,
            })
            .map_err(|_| BrickmapError::WorkerGone(w))?;
        Ok(Ticket {
            world: self,
            rx,
            expected: 1,
        })
    }

    /// Waits until every edit queued so far has been applied: each worker answers an
    /// empty job, which it reaches only after every job queued before it.
    pub fn flush(&self) -> Result<()> {
        let (reply, rx) = crossbeam_channel::unbounded();
        {
            let _order = self.submit_order.lock().unwrap_or_else(|p| p.into_inner());
            for (w, s) in self.senders.iter().enumerate() {
                s.send(Job::Work {
                    item: WorkItem::Restore(Vec::new()),
                    compact: false,
                    reply: reply.clone(),
                })
                .map_err(|_| BrickmapError::WorkerGone(w))?;
            }
        }
        for _ in 0..self.senders.len() {
            rx.recv()
                .map_err(|_| BrickmapError::WorkerGone(usize::MAX))?
                .1?;
        }
        Ok(())
    }

    // ---- materials -------------------------------------------------------------------

    /// The material table (read-locked).
    pub fn materials(&self) -> RwLockReadGuard<'_, MaterialTable> {
        self.materials.read().unwrap_or_else(|p| p.into_inner())
    }
    fn materials_mut(&self) -> std::sync::RwLockWriteGuard<'_, MaterialTable> {
        self.materials.write().unwrap_or_else(|p| p.into_inner())
    }
    /// Appends a material, returning its index.
    pub fn push_material(&self, m: Material) -> Result<u8> {
        let i = self.materials_mut().push(m)?;
        self.refresh_light_weights();
        Ok(i)
    }
    /// Replaces a material, returning the previous one.
    pub fn set_material(&self, index: u8, m: Material) -> Result<Material> {
        let old = self.materials_mut().set(index, m)?;
        self.refresh_light_weights();
        Ok(old)
    }
    /// Replaces a colour, returning the previous one.
    pub fn set_colour(&self, index: u8, rgb: [u8; 3]) -> [u8; 3] {
        let old = self.materials_mut().set_colour(index, rgb);
        self.refresh_light_weights();
        old
    }
    /// Replaces the whole material table (loading a scene), returning the previous one.
    /// Refused when a voxel uses a material the new table lacks.
    pub fn replace_materials(&self, table: MaterialTable) -> Result<MaterialTable> {
        let mut highest = None::<u8>;
        self.read().for_each_brick(|_, mask, mats| {
            let top = match mats {
                BrickMaterials::Uniform(m) => m,
                BrickMaterials::PerVoxel(v) => v[..mask.count() as usize]
                    .iter()
                    .copied()
                    .max()
                    .unwrap_or(0),
            };
            highest = highest.max(Some(top));
        });
        if let Some(m) = highest {
            table.check(m as u32)?;
        }
        let mut table = table;
        table.mark_all_dirty();
        let old = std::mem::replace(&mut *self.materials_mut(), table);
        self.refresh_light_weights();
        Ok(old)
    }

    /// Sets a material parameter, returning the previous value.
    pub fn set_param(&self, kind: MaterialKind, index: u8, value: f32) -> Result<f32> {
        let old = self.materials_mut().set_param(kind, index, value)?;
        self.refresh_light_weights();
        Ok(old)
    }

    // ---- lights ----------------------------------------------------------------------

    /// Brings the light weights up to a changed material table: leaves rewritten when only
    /// weights changed (cost: the light faces), every brick rescanned when a material became
    /// a light or stopped being one (cost: the bricks).
    fn refresh_light_weights(&self) {
        let _one = self.light_updates.lock().unwrap_or_else(|p| p.into_inner());
        let weights = lights::material_weights(&self.materials());
        let rescan = self.lights_mut().set_weights(weights);
        if rescan {
            let view = self.read();
            let bricks = lights::rescan(&view, &weights);
            drop(view);
            let mut l = self.lights_mut();
            l.clear();
            l.apply(bricks);
        }
    }

    /// Recomputes the lights of the bricks an edit changed and of their neighbours (nothing
    /// when no material is a light).
    /// Whether an edit's bricks can change the lights (some material emits).
    fn lights_matter(&self) -> bool {
        self.lights
            .read()
            .unwrap_or_else(|p| p.into_inner())
            .any_lit_material()
    }

    fn refresh_lights(&self, changed: &[UVec3]) {
        if changed.is_empty() || !self.lights_matter() {
            return;
        }
        let _one = self.light_updates.lock().unwrap_or_else(|p| p.into_inner());
        let view = self.read();
        let bricks = lights::recompute(&view, &view.lights, changed);
        drop(view);
        self.lights_mut().apply(bricks);
    }

    fn lights_mut(&self) -> std::sync::RwLockWriteGuard<'_, Lights> {
        self.lights.write().unwrap_or_else(|p| p.into_inner())
    }

    // ---- reads -----------------------------------------------------------------------

    /// Read access to the whole world. Waits for the jobs workers are running now; edits
    /// queued later wait for the view to be dropped, so do not wait on an edit (`apply`,
    /// `Ticket::wait`, `flush`) while this thread holds a view: that waits forever.
    pub fn read(&self) -> WorldView<'_> {
        let slabs = self
            .slabs
            .iter()
            .map(|s| s.read().unwrap_or_else(|p| p.into_inner()))
            .collect();
        WorldView {
            world: self,
            slabs,
            materials: self.materials(),
            lights: self.lights.read().unwrap_or_else(|p| p.into_inner()),
        }
    }

    /// Takes the byte ranges changed since the last call, per GPU buffer.
    pub fn take_dirty(&self) -> DirtySet {
        let mut merged: [DirtyRanges; 4] = Default::default();
        for s in &self.slabs {
            let mut s = s.write().unwrap_or_else(|p| p.into_inner());
            let d = &mut s.dirty;
            for (m, part) in
                merged
                    .iter_mut()
                    .zip([&mut d.index, &mut d.bricks, &mut d.coarse, &mut d.material])
            {
                for r in part.take() {
                    m.record(r);
                }
            }
        }
        let [index, bricks, coarse, material] = merged.map(|mut m| m.take());
        DirtySet {
            ranges: [
                index,
                bricks,
                coarse,
                material,
                self.materials_mut().take_dirty(),
                self.lights_mut().take_dirty(),
            ],
        }
    }

    /// Size in bytes a GPU buffer must have now.
    pub fn gpu_buffer_size(&self, b: GpuBuffer) -> u64 {
        match b {
            GpuBuffer::BrickIndex => self.dims.brick_cells() as u64 * 4,
            GpuBuffer::Bricks => {
                self.counters.brick_chunks() as u64
                    * BRICK_CHUNK as u64
                    * std::mem::size_of::<Brick>() as u64
            }
            GpuBuffer::Coarse => self.dims.coarse_words() as u64 * 4,
            GpuBuffer::MaterialBytes => {
                self.counters.material_chunks() as u64 * MATERIAL_CHUNK as u64
            }
            GpuBuffer::MaterialTables => std::mem::size_of::<MaterialTablesGpu>() as u64,
            GpuBuffer::Lights => self
                .lights
                .read()
                .unwrap_or_else(|p| p.into_inner())
                .gpu_size(),
        }
    }
}

impl Drop for World {
    fn drop(&mut self) {
        for s in &self.senders {
            let _ = s.send(Job::Stop);
        }
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

/// Copies the part of `src` (which starts at buffer offset `at`) that falls inside `range`
/// into `dst` (which holds `range`).
fn copy_overlap(src: &[u8], at: u64, range: &Range<u64>, dst: &mut [u8]) {
    let lo = at.max(range.start);
    let hi = (at + src.len() as u64).min(range.end);
    if lo < hi {
        dst[(lo - range.start) as usize..(hi - range.start) as usize]
            .copy_from_slice(&src[(lo - at) as usize..(hi - at) as usize]);
    }
}

/// Brick coordinate and bit of a voxel inside the grid.
#[inline]
fn split_voxel(v: IVec3) -> (UVec3, usize) {
    let b = v / 8;
    let l = v - b * 8;
    (b.as_uvec3(), crate::brick::voxel_bit(l.x, l.y, l.z))
}
