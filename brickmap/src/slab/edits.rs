//! A slab's part of an edit, applied: shapes (with the region each brick's coverage gives),
//! restores of prior state, generated columns and voxel batches (radix-sorted by cell), each
//! recording the `BrickUndo` that puts it back. Every brick change goes through
//! [`Slab::store`]; on an error the slab is rolled back to its state before the edit.

use super::*;

impl Slab {
    /// Applies this slab's part of an edit. On error the slab is rolled back to its state
    /// before the call and the error returned.
    /// `compact`: whole-brick writes into empty cells are recorded as positions (see
    /// [`Undo`]).
    pub(crate) fn run(&mut self, item: WorkItem, compact: bool) -> Result<(Undo, u64)> {
        let mut undo = Undo::new(compact);
        let result = match item {
            WorkItem::Shape(job) => self.run_shape(&job.0, job.1, &mut undo),
            WorkItem::Voxels(list) => self.run_voxels(&list, &mut undo),
            WorkItem::Restore(list) => self.run_restore(&list, &mut undo),
            WorkItem::RestoreRun(list, run) => self.run_restore(&list[run], &mut undo),
            WorkItem::Generate(source) => self.run_generate(source.as_ref(), &mut undo),
            #[cfg(feature = "test-hooks")]
            WorkItem::Panic => panic!("injected worker panic"),
        };
        match result {
            Ok(changed) => Ok((undo, changed)),
            Err(e) => {
                // Restoring only returns to states that fitted before.
                let mut ignored = Undo::new(true);
                for u in &undo.into_inverse() {
                    let _ = self.restore_brick(u, &mut ignored);
                }
                Err(e)
            }
        }
    }

    fn run_shape(&mut self, shape: &Shape, mode: Mode, undo: &mut Undo) -> Result<u64> {
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
        undo: &mut Undo,
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

    fn run_restore(&mut self, list: &[BrickUndo], undo: &mut Undo) -> Result<u64> {
        let mut changed = 0;
        for u in list {
            changed += self.restore_brick(u, undo)?;
        }
        Ok(changed)
    }

    /// Every column of the slab from the generator; cells it leaves out become empty.
    fn run_generate(&mut self, source: &dyn ColumnSource, undo: &mut Undo) -> Result<u64> {
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
    fn restore_brick(&mut self, u: &BrickUndo, undo: &mut Undo) -> Result<u64> {
        let cell = self.dims.cell_index(u.brick);
        let (old_mask, old) = self.read(cell);
        if u.touched.is_full() && old_mask.is_empty() {
            // A whole-brick write into an empty cell (loading, generating): no merging.
            let new = match &u.prior {
                PriorMaterials::Uniform(m) => NewMats::Uniform(*m),
                PriorMaterials::PerVoxel(v) => NewMats::Bytes(v),
            };
            self.store(cell, u.prior_mask, new)?;
            undo.was_empty(u.brick);
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
    fn run_voxels(&mut self, list: &[VoxelEdit], undo: &mut Undo) -> Result<u64> {
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
