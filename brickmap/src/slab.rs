//! What one worker owns: an x-slab of the brick grid with its bricks, material buckets,
//! coarse-grid words and dirty ranges. Only its worker mutates it, so no lock is ever taken
//! between workers. Every brick change goes through [`Slab::store`], which keeps the brick
//! index, the coarse grid, the buckets and the dirty ranges consistent, and allocates before it
//! frees, so a failed allocation leaves the brick exactly as it was.

use crate::brick::{Brick, BrickMaterials, Mask, UNIFORM_FLAG};
use crate::dirty::DirtyRanges;
use crate::edit::{BrickUndo, ColumnSource, Mode, PriorMaterials, VoxelEdit, VoxelOp};
use crate::error::Result;
use crate::grid::{COARSE_BRICKS, EMPTY_BRICK, FULL_BRICK_BASE, GridDims, SlabBounds};
use crate::shape::{Coverage, Shape};
use crate::storage::{BrickPool, BucketSizes, ChunkCounters, MaterialBuckets};
use glam::{IVec3, UVec3};
use std::sync::Arc;

mod edits;
mod undo;
mod validate;

pub(crate) use undo::Undo;

const NO_BUCKET: u32 = u32::MAX;
const BRICK_BYTES: u64 = std::mem::size_of::<Brick>() as u64;

/// CPU-only facts about a brick slot.
#[derive(Clone, Copy, Debug)]
struct SlotMeta {
    bucket: u32,
    class: u8,
}

/// Byte ranges changed per GPU buffer, as recorded by one worker.
#[derive(Clone, Debug, Default)]
pub struct SlabDirty {
    /// Brick-index grid.
    pub index: DirtyRanges,
    /// Brick array.
    pub bricks: DirtyRanges,
    /// Coarse occupancy grid.
    pub coarse: DirtyRanges,
    /// Material bytes.
    pub material: DirtyRanges,
}

/// What one grid cell holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum CellState {
    /// Nothing.
    Empty,
    /// Every voxel solid with one material; no brick stored.
    Full(u8),
    /// A stored brick in this local slot.
    Brick(u32),
}

/// A brick's materials, copied out so the brick can be rewritten. A stack copy on purpose:
/// boxing it would allocate once per edited brick.
#[allow(clippy::large_enum_variant)]
#[derive(Clone)]
pub(crate) enum Mats {
    Uniform(u8),
    Bytes { buf: [u8; 512], len: usize },
}

impl Mats {
    pub(crate) fn at(&self, k: usize) -> u8 {
        match self {
            Mats::Uniform(m) => *m,
            Mats::Bytes { buf, .. } => buf[k],
        }
    }
    /// The copy as borrowed materials.
    pub(crate) fn borrowed(&self) -> BrickMaterials<'_> {
        match self {
            Mats::Uniform(m) => BrickMaterials::Uniform(*m),
            Mats::Bytes { buf, len } => BrickMaterials::PerVoxel(&buf[..*len]),
        }
    }
}

/// New materials for [`Slab::store`]: one for all, or one per solid voxel in popcount order.
pub(crate) enum NewMats<'a> {
    Uniform(u8),
    Bytes(&'a [u8]),
}

/// Part of an edit that falls into one slab.
pub(crate) enum WorkItem {
    Shape(Arc<(Shape, Mode)>),
    Voxels(Vec<VoxelEdit>),
    Restore(Vec<BrickUndo>),
    /// This slab's run of a restore's list (the list in slab order, shared by the workers).
    RestoreRun(Arc<Vec<BrickUndo>>, std::ops::Range<usize>),
    /// Generated columns (every column of the slab).
    Generate(Arc<dyn ColumnSource>),
    /// Panics (see `World::inject_worker_panic`; tests only).
    #[cfg(feature = "test-hooks")]
    Panic,
}

/// One worker's share of the world.
pub struct Slab {
    pub(crate) bounds: SlabBounds,
    dims: GridDims,
    cell_base: usize,
    coarse_base: usize,
    slots: Vec<u32>,
    pub(crate) pool: BrickPool,
    meta: Vec<SlotMeta>,
    pub(crate) buckets: MaterialBuckets,
    coarse: Vec<u32>,
    coarse_counts: Vec<u8>,
    pub(crate) dirty: SlabDirty,
    solid: u64,
    counters: Arc<ChunkCounters>,
}

impl Slab {
    pub(crate) fn new(
        dims: GridDims,
        bounds: SlabBounds,
        sizes: BucketSizes,
        counters: Arc<ChunkCounters>,
    ) -> Self {
        let cells = bounds.cells(&dims);
        let words = bounds.coarse_words(&dims);
        let c = dims.coarse();
        let coarse_cells = (bounds.coarse_x.end - bounds.coarse_x.start) * c.y * c.z;
        Self {
            dims,
            cell_base: cells.start,
            coarse_base: words.start,
            slots: vec![EMPTY_BRICK; cells.len()],
            pool: BrickPool::default(),
            meta: Vec::new(),
            buckets: MaterialBuckets::new(sizes),
            coarse: vec![0; words.len()],
            coarse_counts: vec![0; coarse_cells as usize],
            dirty: SlabDirty::default(),
            solid: 0,
            counters,
            bounds,
        }
    }

    // ---- reads -------------------------------------------------------------------------

    /// What a grid cell holds.
    #[inline]
    pub(crate) fn cell(&self, cell: usize) -> CellState {
        match self.slots[cell - self.cell_base] {
            EMPTY_BRICK => CellState::Empty,
            v if v >= FULL_BRICK_BASE => CellState::Full(v as u8),
            slot => CellState::Brick(slot),
        }
    }
    /// Occupancy and materials of a cell, copied out.
    pub(crate) fn read(&self, cell: usize) -> (Mask, Mats) {
        match self.cell(cell) {
            CellState::Empty => (Mask::EMPTY, Mats::Uniform(0)),
            CellState::Full(m) => (Mask::FULL, Mats::Uniform(m)),
            CellState::Brick(s) => (self.pool.get(s).mask, self.mats(s)),
        }
    }
    /// Material of voxel `bit` of a cell, `None` when empty.
    #[inline]
    pub(crate) fn voxel(&self, cell: usize, bit: usize) -> Option<u8> {
        match self.cell(cell) {
            CellState::Empty => None,
            CellState::Full(m) => Some(m),
            CellState::Brick(s) => self
                .pool
                .get(s)
                .mask
                .get(bit)
                .then(|| self.material(s, bit)),
        }
    }
    /// Whether voxel `bit` of a cell is solid.
    #[inline]
    pub(crate) fn solid_at(&self, cell: usize, bit: usize) -> bool {
        match self.cell(cell) {
            CellState::Empty => false,
            CellState::Full(_) => true,
            CellState::Brick(s) => self.pool.get(s).mask.get(bit),
        }
    }
    /// The brick in a slot.
    #[inline]
    pub(crate) fn brick(&self, slot: u32) -> &Brick {
        self.pool.get(slot)
    }
    /// Material of the solid voxel `bit` of the brick in `slot`.
    pub(crate) fn material(&self, slot: u32, bit: usize) -> u8 {
        let b = self.pool.get(slot);
        if b.is_uniform() {
            b.material as u8
        } else {
            let m = self.meta[slot as usize];
            self.buckets.slice(m.bucket, 512)[b.mask.rank(bit)]
        }
    }
    /// Materials of a brick, copied out.
    pub(crate) fn mats(&self, slot: u32) -> Mats {
        let b = self.pool.get(slot);
        if b.is_uniform() {
            return Mats::Uniform(b.material as u8);
        }
        let len = b.mask.count() as usize;
        let mut buf = [0u8; 512];
        buf[..len].copy_from_slice(self.buckets.slice(self.meta[slot as usize].bucket, len));
        Mats::Bytes { buf, len }
    }
    /// Whether the coarse cell `c` (global coarse coordinates, inside this slab) has a brick.
    #[inline]
    pub(crate) fn coarse_occupied(&self, c: UVec3) -> bool {
        let (w, bit) = self.dims.coarse_bit(c);
        self.coarse[w - self.coarse_base] >> bit & 1 != 0
    }
    /// Solid voxels in this slab.
    pub(crate) fn solid(&self) -> u64 {
        self.solid
    }
    /// Non-empty cells of this slab: (global cell, state).
    pub(crate) fn cells(&self) -> impl Iterator<Item = (usize, CellState)> + '_ {
        (0..self.slots.len())
            .filter(|&i| self.slots[i] != EMPTY_BRICK)
            .map(|i| (i + self.cell_base, self.cell(i + self.cell_base)))
    }
    /// Calls `f(cell, mask, materials)` for every non-empty cell, in cell order.
    pub(crate) fn visit(&self, f: &mut dyn FnMut(usize, &Mask, BrickMaterials<'_>)) {
        for (cell, state) in self.cells() {
            match state {
                CellState::Empty => {}
                CellState::Full(m) => f(cell, &Mask::FULL, BrickMaterials::Uniform(m)),
                CellState::Brick(slot) => {
                    let b = self.pool.get(slot);
                    let mats = if b.is_uniform() {
                        BrickMaterials::Uniform(b.material as u8)
                    } else {
                        let n = b.mask.count() as usize;
                        BrickMaterials::PerVoxel(
                            self.buckets.slice(self.meta[slot as usize].bucket, n),
                        )
                    };
                    f(cell, &b.mask, mats);
                }
            }
        }
    }
    /// The global cells this slab holds.
    pub(crate) fn cell_range(&self) -> std::ops::Range<usize> {
        self.cell_base..self.cell_base + self.slots.len()
    }
    /// The brick-index words of this slab's cells as the GPU reads them.
    pub(crate) fn gpu_index_words(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.slots.len()).map(|i| self.gpu_index_word(i + self.cell_base))
    }
    /// The brick-index word of a global cell of this slab, as the GPU reads it.
    pub(crate) fn gpu_index_word(&self, cell: usize) -> u32 {
        match self.slots[cell - self.cell_base] {
            v if v >= FULL_BRICK_BASE => v,
            slot => self.pool.global(slot),
        }
    }
    /// A coarse-grid word of this slab, by global word index.
    pub(crate) fn coarse_word(&self, word: usize) -> u32 {
        self.coarse[word - self.coarse_base]
    }
    /// Coarse words of this slab.
    pub(crate) fn coarse_words(&self) -> &[u32] {
        &self.coarse
    }

    // ---- the one place bricks change ---------------------------------------------------

    fn coarse_count_index(&self, cell: usize) -> (usize, UVec3) {
        let b = self.dims.cell_coord(cell);
        let c = b / COARSE_BRICKS;
        let cd = self.dims.coarse();
        let local_x = c.x - self.bounds.coarse_x.start;
        (((local_x * cd.z + c.z) * cd.y + c.y) as usize, c)
    }

    fn coarse_adjust(&mut self, cell: usize, up: bool) {
        let (i, c) = self.coarse_count_index(cell);
        let n = &mut self.coarse_counts[i];
        let flips = if up { *n == 0 } else { *n == 1 };
        if up {
            *n += 1
        } else {
            *n -= 1
        }
        if flips {
            let (w, bit) = self.dims.coarse_bit(c);
            self.coarse[w - self.coarse_base] ^= 1 << bit;
            self.dirty.coarse.record(4 * w as u64..4 * w as u64 + 4);
        }
    }

    fn record_brick(&mut self, slot: u32) {
        let g = self.pool.global(slot) as u64;
        self.dirty
            .bricks
            .record(g * BRICK_BYTES..(g + 1) * BRICK_BYTES);
    }

    fn record_index(&mut self, cell: usize) {
        self.dirty
            .index
            .record(4 * cell as u64..4 * cell as u64 + 4);
    }

    /// Empties a cell, returning its brick slot and bucket.
    fn clear_cell(&mut self, cell: usize) {
        let (count, slot) = match self.cell(cell) {
            CellState::Empty => return,
            CellState::Full(_) => (512, None),
            CellState::Brick(s) => (self.pool.get(s).mask.count(), Some(s)),
        };
        if let Some(slot) = slot {
            self.free_brick(slot);
        }
        self.solid -= count as u64;
        self.slots[cell - self.cell_base] = EMPTY_BRICK;
        self.record_index(cell);
        self.coarse_adjust(cell, false);
    }

    fn free_brick(&mut self, slot: u32) {
        let meta = self.meta[slot as usize];
        if meta.bucket != NO_BUCKET {
            self.buckets.free(meta.bucket, meta.class);
        }
        self.pool.free(slot);
    }

    /// Makes the cell hold `mask` with `new` materials: nothing, a full cell, or a stored
    /// brick. Allocates before it frees: on error the cell is exactly as before.
    pub(crate) fn store(&mut self, cell: usize, mask: Mask, new: NewMats<'_>) -> Result<()> {
        let old = self.cell(cell);
        if mask.is_empty() {
            self.clear_cell(cell);
            return Ok(());
        }
        let new = match new {
            NewMats::Bytes(b) if b.iter().all(|&m| m == b[0]) => NewMats::Uniform(b[0]),
            other => other,
        };
        let old_count = match old {
            CellState::Empty => 0,
            CellState::Full(_) => 512,
            CellState::Brick(s) => self.pool.get(s).mask.count(),
        };
        if let (true, NewMats::Uniform(m)) = (mask.is_full(), &new) {
            if let CellState::Brick(s) = old {
                self.free_brick(s);
            }
            self.slots[cell - self.cell_base] = FULL_BRICK_BASE | *m as u32;
            self.record_index(cell);
            if old == CellState::Empty {
                self.coarse_adjust(cell, true);
            }
            self.solid = self.solid + 512 - old_count as u64;
            return Ok(());
        }
        let old_slot = match old {
            CellState::Brick(s) => Some(s),
            _ => None,
        };
        let slot = match old_slot {
            Some(s) => s,
            None => self.pool.alloc(&self.counters)?,
        };
        if self.meta.len() < self.pool.reserved() {
            self.meta.resize(
                self.pool.reserved(),
                SlotMeta {
                    bucket: NO_BUCKET,
                    class: 0,
                },
            );
        }
        if old_slot.is_none() {
            self.meta[slot as usize] = SlotMeta {
                bucket: NO_BUCKET,
                class: 0,
            };
        }
        let old_meta = self.meta[slot as usize];
        let word = match new {
            NewMats::Uniform(m) => {
                if old_meta.bucket != NO_BUCKET {
                    self.buckets.free(old_meta.bucket, old_meta.class);
                }
                self.meta[slot as usize].bucket = NO_BUCKET;
                UNIFORM_FLAG | m as u32
            }
            NewMats::Bytes(bytes) => {
                let n = bytes.len() as u32;
                let keep =
                    old_meta.bucket != NO_BUCKET && self.buckets.sizes().keeps(old_meta.class, n);
                let (off, class) = if keep {
                    (old_meta.bucket, old_meta.class)
                } else {
                    let class = self.buckets.sizes().class_for(n);
                    match self.buckets.alloc(class, &self.counters) {
                        Ok(off) => (off, class),
                        Err(e) => {
                            if old_slot.is_none() {
                                self.pool.free(slot);
                            }
                            return Err(e);
                        }
                    }
                };
                if !keep && old_meta.bucket != NO_BUCKET {
                    self.buckets.free(old_meta.bucket, old_meta.class);
                }
                self.buckets
                    .slice_mut(off, bytes.len())
                    .copy_from_slice(bytes);
                self.meta[slot as usize] = SlotMeta { bucket: off, class };
                let g = self.buckets.global(off) as u64;
                self.dirty.material.record(g..g + n as u64);
                self.buckets.global(off)
            }
        };
        *self.pool.get_mut(slot) = Brick {
            mask,
            material: word,
        };
        self.solid = self.solid + mask.count() as u64 - old_count as u64;
        self.record_brick(slot);
        if old_slot.is_none() {
            self.slots[cell - self.cell_base] = slot;
            self.record_index(cell);
            if old == CellState::Empty {
                self.coarse_adjust(cell, true);
            }
        }
        Ok(())
    }
}
