//! What one worker owns: an x-slab of the brick grid with its bricks, material buckets,
//! coarse-grid words and dirty ranges. Only its worker mutates it, so no lock is ever taken
//! between workers. Every brick change goes through [`Slab::store`], which keeps the brick
//! index, the coarse grid, the buckets and the dirty ranges consistent, and allocates before it
//! frees, so a failed allocation leaves the brick exactly as it was.

use crate::brick::{Brick, Mask, UNIFORM_FLAG};
use crate::dirty::DirtyRanges;
use crate::edit::{BrickUndo, ColumnSource, Mode, PriorMaterials, VoxelEdit, VoxelOp};
use crate::error::Result;
use crate::grid::{COARSE_BRICKS, EMPTY_BRICK, FULL_BRICK_BASE, GridDims, SlabBounds};
use crate::shape::{Coverage, Shape};
use crate::storage::{BrickPool, BucketSizes, ChunkCounters, MaterialBuckets};
use glam::{IVec3, UVec3};
use std::sync::Arc;

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
    /// Generated columns (every column of the slab).
    Generate(Arc<dyn ColumnSource>),
    /// Panics (see `World::inject_worker_panic`).
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
    pub(crate) fn visit(&self, f: &mut dyn FnMut(usize, &Mask, crate::world::BrickMaterials<'_>)) {
        use crate::world::BrickMaterials;
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

    // ---- edits ---------------------------------------------------------------------------

    /// Applies this slab's part of an edit. On error the slab is rolled back to its state
    /// before the call and the error returned.
    pub(crate) fn run(&mut self, item: WorkItem) -> Result<(Vec<BrickUndo>, u64)> {
        let mut undo = Vec::new();
        let result = match item {
            WorkItem::Shape(job) => self.run_shape(&job.0, job.1, &mut undo),
            WorkItem::Voxels(list) => self.run_voxels(&list, &mut undo),
            WorkItem::Restore(list) => self.run_restore(&list, &mut undo),
            WorkItem::Generate(source) => self.run_generate(source.as_ref(), &mut undo),
            WorkItem::Panic => panic!("injected worker panic"),
        };
        match result {
            Ok(changed) => Ok((undo, changed)),
            Err(e) => {
                // Undo in reverse; restoring only returns to states that fitted before.
                let mut ignored = Vec::new();
                for u in undo.iter().rev() {
                    let _ = self.restore_brick(u, &mut ignored);
                }
                Err(e)
            }
        }
    }

    fn run_shape(&mut self, shape: &Shape, mode: Mode, undo: &mut Vec<BrickUndo>) -> Result<u64> {
        let (lo, hi) = shape.voxel_bounds();
        let max = self.dims.voxels() - 1;
        let lo = lo.clamp(IVec3::ZERO, max);
        let hi = hi.clamp(IVec3::ZERO, max);
        let (blo, bhi) = (lo / 8, hi / 8);
        let x0 = blo.x.max(self.bounds.bricks_x.start as i32);
        let x1 = bhi.x.min(self.bounds.bricks_x.end as i32 - 1);
        let mut changed = 0;
        for bx in x0..=x1 {
            for bz in blo.z..=bhi.z {
                for by in blo.y..=bhi.y {
                    let b = IVec3::new(bx, by, bz);
                    let region = match shape.coverage(b * 8) {
                        Coverage::Outside => continue,
                        Coverage::Inside => Mask::FULL,
                        Coverage::Partial => shape.mask(b * 8),
                    };
                    if region.is_empty() {
                        continue;
                    }
                    changed += self.apply_region(b.as_uvec3(), &region, mode, undo)?;
                }
            }
        }
        Ok(changed)
    }

    /// Applies a mode to the voxels of `region` in one brick, whole-mask where possible.
    fn apply_region(
        &mut self,
        b: UVec3,
        region: &Mask,
        mode: Mode,
        undo: &mut Vec<BrickUndo>,
    ) -> Result<u64> {
        let cell = self.dims.cell_index(b);
        let (old_mask, old) = self.read(cell);
        let touched = match mode {
            Mode::Add(_) => *region,
            Mode::Remove | Mode::Paint(_) => region.and(&old_mask),
        };
        if touched.is_empty() {
            return Ok(0);
        }
        let count_equal = |m: u8| -> u64 {
            // Solid voxels of `touched` whose material already is m.
            match &old {
                Mats::Uniform(a) => {
                    if *a == m {
                        touched.and(&old_mask).count() as u64
                    } else {
                        0
                    }
                }
                Mats::Bytes { buf, .. } => old_mask
                    .ones()
                    .enumerate()
                    .filter(|&(k, bit)| touched.get(bit) && buf[k] == m)
                    .count() as u64,
            }
        };
        let (new_mask, changed) = match mode {
            Mode::Add(m) => (old_mask.or(region), touched.count() as u64 - count_equal(m)),
            Mode::Remove => (old_mask.and_not(region), touched.count() as u64),
            Mode::Paint(m) => (old_mask, touched.count() as u64 - count_equal(m)),
        };
        if changed == 0 {
            return Ok(0);
        }
        let mut scratch = [0u8; 512];
        let new = match (mode, &old) {
            (Mode::Add(m), _) if region.is_full() || old_mask.is_empty() => NewMats::Uniform(m),
            (Mode::Add(m), Mats::Uniform(a)) if *a == m => NewMats::Uniform(m),
            (Mode::Paint(m), _) if touched == old_mask => NewMats::Uniform(m),
            (Mode::Remove, Mats::Uniform(a)) => NewMats::Uniform(*a),
            (Mode::Remove, Mats::Bytes { buf, .. }) => {
                let mut n = 0;
                for (k, bit) in old_mask.ones().enumerate() {
                    if new_mask.get(bit) {
                        scratch[n] = buf[k];
                        n += 1;
                    }
                }
                NewMats::Bytes(&scratch[..n])
            }
            (Mode::Add(m) | Mode::Paint(m), _) => {
                let mut dense = [0u8; 512];
                for (k, bit) in old_mask.ones().enumerate() {
                    dense[bit] = old.at(k);
                }
                for bit in touched.ones() {
                    dense[bit] = m;
                }
                let n = compact(&new_mask, &dense, &mut scratch);
                NewMats::Bytes(&scratch[..n])
            }
        };
        let prior = prior_of(&old_mask, &old, &touched);
        self.store(cell, new_mask, new)?;
        undo.push(BrickUndo {
            brick: b,
            prior_mask: old_mask,
            touched,
            prior,
        });
        Ok(changed)
    }

    fn run_restore(&mut self, list: &[BrickUndo], undo: &mut Vec<BrickUndo>) -> Result<u64> {
        let mut changed = 0;
        for u in list {
            changed += self.restore_brick(u, undo)?;
        }
        Ok(changed)
    }

    /// Every column of the slab from the generator; cells it leaves out become empty.
    fn run_generate(
        &mut self,
        source: &dyn ColumnSource,
        undo: &mut Vec<BrickUndo>,
    ) -> Result<u64> {
        let height = self.dims.bricks().y;
        let mut column: Vec<(u32, Mask, PriorMaterials)> = Vec::new();
        let mut changed = 0;
        for bx in self.bounds.bricks_x.clone() {
            for bz in 0..self.dims.bricks().z {
                column.clear();
                source.column(bx, bz, &mut |by, mask, mats| column.push((by, mask, mats)));
                column.sort_by_key(|c| c.0);
                let mut next = column.drain(..).peekable();
                for by in 0..height {
                    let brick = UVec3::new(bx, by, bz);
                    let (mask, prior) = match next.next_if(|c| c.0 == by) {
                        Some((_, mask, PriorMaterials::PerVoxel(v)))
                            if v.len() != mask.count() as usize =>
                        {
                            return Err(crate::BrickmapError::BadInverse(
                                "generator emitted a brick whose materials do not match its mask",
                            ));
                        }
                        Some((_, mask, mats)) => (mask, mats),
                        None => {
                            if self.cell(self.dims.cell_index(brick)) == CellState::Empty {
                                continue;
                            }
                            (Mask::EMPTY, PriorMaterials::PerVoxel(Vec::new()))
                        }
                    };
                    let set = BrickUndo {
                        brick,
                        prior_mask: mask,
                        touched: Mask::FULL,
                        prior,
                    };
                    changed += self.restore_brick(&set, undo)?;
                }
            }
        }
        Ok(changed)
    }

    /// Puts back the touched voxels of one brick, recording what they were.
    fn restore_brick(&mut self, u: &BrickUndo, undo: &mut Vec<BrickUndo>) -> Result<u64> {
        let cell = self.dims.cell_index(u.brick);
        let (old_mask, old) = self.read(cell);
        if u.touched.is_full() && old_mask.is_empty() {
            // A whole-brick write into an empty cell (loading, generating): no merging.
            let new = match &u.prior {
                PriorMaterials::Uniform(m) => NewMats::Uniform(*m),
                PriorMaterials::PerVoxel(v) => NewMats::Bytes(v),
            };
            self.store(cell, u.prior_mask, new)?;
            undo.push(BrickUndo {
                brick: u.brick,
                prior_mask: Mask::EMPTY,
                touched: Mask::FULL,
                prior: PriorMaterials::PerVoxel(Vec::new()),
            });
            return Ok(u.prior_mask.count() as u64);
        }
        let back = u.prior_mask.and(&u.touched);
        let new_mask = old_mask.and_not(&u.touched).or(&back);
        let mut dense = [0u8; 512];
        for (k, bit) in old_mask.ones().enumerate() {
            dense[bit] = old.at(k);
        }
        let mut changed = 0u64;
        for bit in u.touched.ones() {
            if old_mask.get(bit) != back.get(bit) {
                changed += 1;
            }
        }
        for (k, bit) in back.ones().enumerate() {
            let m = u.prior_material(k);
            if old_mask.get(bit) && dense[bit] != m {
                changed += 1;
            }
            dense[bit] = m;
        }
        let mut scratch = [0u8; 512];
        let n = compact(&new_mask, &dense, &mut scratch);
        let prior = prior_of(&old_mask, &old, &u.touched);
        self.store(cell, new_mask, NewMats::Bytes(&scratch[..n]))?;
        undo.push(BrickUndo {
            brick: u.brick,
            prior_mask: old_mask,
            touched: u.touched,
            prior,
        });
        Ok(changed)
    }

    /// Single-voxel writes, each O(1) plus a move of at most one brick's bytes. The list is
    /// first grouped by brick (a stable radix sort on the cell, so a later write to a voxel
    /// still wins), so each brick is visited once and memory is walked in order: in arrival
    /// order, scattered writes spend most of their time waiting on cache misses.
    fn run_voxels(&mut self, list: &[VoxelEdit], undo: &mut Vec<BrickUndo>) -> Result<u64> {
        let packed: Vec<u64> = list
            .iter()
            .map(|e| {
                let local = self.dims.cell_index((e.pos / 8).as_uvec3()) - self.cell_base;
                let l = e.pos - (e.pos / 8) * 8;
                (local as u64) << 32
                    | pack_voxel(crate::brick::voxel_bit(l.x, l.y, l.z), e.op) as u64
            })
            .collect();
        let sorted = radix_sort_high(packed);
        let mut changed = 0;
        let mut i = 0;
        while i < sorted.len() {
            let local = sorted[i] >> 32;
            let cell = local as usize + self.cell_base;
            let (prior_mask, prior) = self.read(cell);
            let mut touched = Mask::EMPTY;
            let mut failure = None;
            while i < sorted.len() && sorted[i] >> 32 == local {
                let (bit, op) = unpack_voxel(sorted[i] as u32);
                i += 1;
                match self.voxel_op(cell, bit, op) {
                    Ok(true) => touched.set(bit),
                    Ok(false) => {}
                    Err(err) => {
                        failure = Some(err);
                        break;
                    }
                }
            }
            if !touched.is_empty() {
                // Net change: a voxel written twice (set, then cleared) may end as it began.
                let (now, now_mats) = self.read(cell);
                for (k, bit) in prior_mask.ones().enumerate() {
                    if touched.get(bit) {
                        let same = now.get(bit) && now_mats.at(now.rank(bit)) == prior.at(k);
                        changed += !same as u64;
                    }
                }
                changed += touched.and_not(&prior_mask).and(&now).count() as u64;
                undo.push(BrickUndo {
                    brick: self.dims.cell_coord(cell),
                    prior_mask,
                    touched,
                    prior: prior_of(&prior_mask, &prior, &touched),
                });
            }
            if let Some(err) = failure {
                return Err(err);
            }
        }
        Ok(changed)
    }

    /// One voxel write; returns whether anything changed.
    fn voxel_op(&mut self, cell: usize, bit: usize, op: VoxelOp) -> Result<bool> {
        let slot = match self.cell(cell) {
            CellState::Brick(slot) => slot,
            CellState::Empty => {
                if let VoxelOp::Set(m) = op {
                    let mut mask = Mask::EMPTY;
                    mask.set(bit);
                    self.store(cell, mask, NewMats::Uniform(m))?;
                    return Ok(true);
                }
                return Ok(false);
            }
            CellState::Full(a) => {
                // Leaving the full state stores a brick (rare: once per cell and edit).
                return match op {
                    VoxelOp::Set(m) | VoxelOp::Paint(m) if m == a => Ok(false),
                    VoxelOp::Set(m) | VoxelOp::Paint(m) => {
                        let mut bytes = [a; 512];
                        bytes[bit] = m;
                        self.store(cell, Mask::FULL, NewMats::Bytes(&bytes))
                            .map(|_| true)
                    }
                    VoxelOp::Clear => {
                        let mut mask = Mask::FULL;
                        mask.clear(bit);
                        self.store(cell, mask, NewMats::Uniform(a)).map(|_| true)
                    }
                };
            }
        };
        let brick = *self.pool.get(slot);
        let solid = brick.mask.get(bit);
        let n = brick.mask.count() as usize;
        let meta = self.meta[slot as usize];
        match op {
            VoxelOp::Set(m) | VoxelOp::Paint(m) => {
                if !solid && matches!(op, VoxelOp::Paint(_)) {
                    return Ok(false);
                }
                let mut mask = brick.mask;
                mask.set(bit);
                if brick.is_uniform() {
                    let a = brick.material as u8;
                    if a == m {
                        if solid {
                            return Ok(false);
                        }
                        if mask.is_full() {
                            // A uniform brick that fills up becomes a full cell.
                            return self.store(cell, mask, NewMats::Uniform(a)).map(|_| true);
                        }
                        self.set_mask_in_place(slot, mask, 1);
                        return Ok(true);
                    }
                    if solid && n == 1 {
                        return self.store(cell, mask, NewMats::Uniform(m)).map(|_| true);
                    }
                    let mut bytes = [a; 512];
                    bytes[mask.rank(bit)] = m;
                    return self
                        .store(cell, mask, NewMats::Bytes(&bytes[..mask.count() as usize]))
                        .map(|_| true);
                }
                let rank = brick.mask.rank(bit);
                let size = self.buckets.sizes().size(meta.class) as usize;
                if solid {
                    if self.buckets.slice(meta.bucket, n)[rank] == m {
                        return Ok(false);
                    }
                    self.buckets.slice_mut(meta.bucket, n)[rank] = m;
                    self.record_material(meta.bucket, rank, rank + 1);
                    return Ok(true);
                }
                if n < size {
                    let bytes = self.buckets.slice_mut(meta.bucket, n + 1);
                    bytes.copy_within(rank..n, rank + 1);
                    bytes[rank] = m;
                    self.record_material(meta.bucket, rank, n + 1);
                    self.set_mask_in_place(slot, mask, 1);
                    return Ok(true);
                }
                let mut bytes = [0u8; 512];
                let old = self.buckets.slice(meta.bucket, n);
                bytes[..rank].copy_from_slice(&old[..rank]);
                bytes[rank] = m;
                bytes[rank + 1..n + 1].copy_from_slice(&old[rank..]);
                self.store(cell, mask, NewMats::Bytes(&bytes[..n + 1]))
                    .map(|_| true)
            }
            VoxelOp::Clear => {
                if !solid {
                    return Ok(false);
                }
                let mut mask = brick.mask;
                mask.clear(bit);
                if n == 1 {
                    self.clear_cell(cell);
                    return Ok(true);
                }
                if brick.is_uniform() {
                    self.set_mask_in_place(slot, mask, -1);
                    return Ok(true);
                }
                let rank = brick.mask.rank(bit);
                if self.buckets.sizes().keeps(meta.class, n as u32 - 1) {
                    let bytes = self.buckets.slice_mut(meta.bucket, n);
                    bytes.copy_within(rank + 1..n, rank);
                    self.record_material(meta.bucket, rank, n - 1);
                    self.set_mask_in_place(slot, mask, -1);
                    return Ok(true);
                }
                let mut bytes = [0u8; 512];
                let old = self.buckets.slice(meta.bucket, n);
                bytes[..rank].copy_from_slice(&old[..rank]);
                bytes[rank..n - 1].copy_from_slice(&old[rank + 1..]);
                self.store(cell, mask, NewMats::Bytes(&bytes[..n - 1]))
                    .map(|_| true)
            }
        }
    }

    fn set_mask_in_place(&mut self, slot: u32, mask: Mask, delta: i64) {
        self.pool.get_mut(slot).mask = mask;
        self.solid = (self.solid as i64 + delta) as u64;
        self.record_brick(slot);
    }

    fn record_material(&mut self, bucket: u32, from: usize, to: usize) {
        if from < to {
            let g = self.buckets.global(bucket) as u64;
            self.dirty.material.record(g + from as u64..g + to as u64);
        }
    }

    // ---- checks --------------------------------------------------------------------------

    /// Checks every invariant this slab keeps (for tests): index ↔ slots, free list,
    /// coarse counts and bits, solid count, bucket accounting.
    pub(crate) fn validate(&self) -> std::result::Result<(), String> {
        let mut used = vec![false; self.pool.reserved()];
        for &f in self.pool.free_slots() {
            if std::mem::replace(&mut used[f as usize], true) {
                return Err(format!("slot {f} free twice"));
            }
        }
        let mut held = Vec::new();
        let mut solid = 0u64;
        let mut counts = vec![0u8; self.coarse_counts.len()];
        for (cell, state) in self.cells() {
            counts[self.coarse_count_index(cell).0] += 1;
            let slot = match state {
                CellState::Empty => return Err(format!("cell {cell} listed but empty")),
                CellState::Full(_) => {
                    solid += 512;
                    continue;
                }
                CellState::Brick(slot) => slot,
            };
            if std::mem::replace(&mut used[slot as usize], true) {
                return Err(format!("slot {slot} used twice or both used and free"));
            }
            let b = self.pool.get(slot);
            if b.mask.is_empty() {
                return Err(format!("cell {cell} holds an empty brick"));
            }
            solid += b.mask.count() as u64;
            let m = self.meta[slot as usize];
            if b.is_uniform() {
                if m.bucket != NO_BUCKET {
                    return Err(format!("uniform brick {cell} holds a bucket"));
                }
            } else {
                if m.bucket == NO_BUCKET || self.buckets.global(m.bucket) != b.material {
                    return Err(format!(
                        "brick {cell} material word does not match its bucket"
                    ));
                }
                if !self.buckets.sizes().keeps(m.class, b.mask.count()) {
                    return Err(format!(
                        "brick {cell}: {} voxels in a bucket of {} (overflow or missed shrink)",
                        b.mask.count(),
                        self.buckets.sizes().size(m.class)
                    ));
                }
                held.push((m.bucket, m.class));
            }
            if b.is_uniform() && b.mask.is_full() {
                return Err(format!(
                    "cell {cell}: a full uniform brick should be a full cell"
                ));
            }
        }
        if used.iter().any(|u| !u) {
            return Err("a brick slot is neither used nor free".into());
        }
        if solid != self.solid {
            return Err(format!(
                "solid count {} but bricks hold {solid}",
                self.solid
            ));
        }
        if counts != self.coarse_counts {
            return Err("coarse counts differ from bricks".into());
        }
        let cd = self.dims.coarse();
        for cx in self.bounds.coarse_x.clone() {
            for cz in 0..cd.z {
                for cy in 0..cd.y {
                    let c = UVec3::new(cx, cy, cz);
                    let local = ((cx - self.bounds.coarse_x.start) * cd.z + cz) * cd.y + cy;
                    if self.coarse_occupied(c) != (counts[local as usize] > 0) {
                        return Err(format!("coarse bit {c} is wrong"));
                    }
                }
            }
        }
        self.buckets.validate(&held)
    }
}

/// A voxel write in 32 bits: bit index (9 bits), op kind (2 bits), material (8 bits).
fn pack_voxel(bit: usize, op: VoxelOp) -> u32 {
    let (kind, m) = match op {
        VoxelOp::Set(m) => (0, m),
        VoxelOp::Clear => (1, 0),
        VoxelOp::Paint(m) => (2, m),
    };
    bit as u32 | kind << 9 | (m as u32) << 11
}

fn unpack_voxel(v: u32) -> (usize, VoxelOp) {
    let m = (v >> 11) as u8;
    let op = match v >> 9 & 3 {
        0 => VoxelOp::Set(m),
        1 => VoxelOp::Clear,
        _ => VoxelOp::Paint(m),
    };
    ((v & 511) as usize, op)
}

/// Sorts by the high 32 bits, stably (equal keys keep their order): LSD radix, 11 bits a
/// pass, only as many passes as the largest key needs.
fn radix_sort_high(mut items: Vec<u64>) -> Vec<u64> {
    if items.len() < 64 {
        items.sort_by_key(|v| v >> 32);
        return items;
    }
    let max = items.iter().map(|v| v >> 32).max().unwrap_or(0);
    let mut scratch = vec![0u64; items.len()];
    let mut shift = 32;
    while shift < 64 && (max >> (shift - 32)) > 0 {
        let mut count = [0usize; 2049];
        for v in &items {
            count[(v >> shift & 2047) as usize + 1] += 1;
        }
        for d in 1..2049 {
            count[d] += count[d - 1];
        }
        for &v in &items {
            let d = (v >> shift & 2047) as usize;
            scratch[count[d]] = v;
            count[d] += 1;
        }
        std::mem::swap(&mut items, &mut scratch);
        shift += 11;
    }
    items
}

/// Materials in popcount order of `mask`, from a dense 512-entry array.
fn compact(mask: &Mask, dense: &[u8; 512], out: &mut [u8; 512]) -> usize {
    let mut n = 0;
    for bit in mask.ones() {
        out[n] = dense[bit];
        n += 1;
    }
    n
}

/// Prior materials of the voxels of `touched ∩ mask`.
fn prior_of(mask: &Mask, mats: &Mats, touched: &Mask) -> PriorMaterials {
    match mats {
        Mats::Uniform(m) => PriorMaterials::Uniform(*m),
        Mats::Bytes { buf, len } => {
            if touched.and(mask) == *mask {
                PriorMaterials::PerVoxel(buf[..*len].to_vec())
            } else {
                PriorMaterials::PerVoxel(
                    mask.ones()
                        .enumerate()
                        .filter(|&(_, bit)| touched.get(bit))
                        .map(|(k, _)| buf[k])
                        .collect(),
                )
            }
        }
    }
}
