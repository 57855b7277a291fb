//! The read side of the world: [`WorldView`], every slab and the material table read-locked
//! at once, so a reader sees whole edits. Queries (voxels, solid counts, occupied bounds),
//! the content hash, memory statistics, the exact GPU images the renderer uploads and
//! compares against, the light faces, and `validate` (every invariant, for tests).

use super::*;

/// Read access to every slab and the material table at once.
pub struct WorldView<'w> {
    pub(super) world: &'w World,
    pub(super) slabs: Vec<RwLockReadGuard<'w, Slab>>,
    pub(super) materials: RwLockReadGuard<'w, MaterialTable>,
    pub(super) lights: RwLockReadGuard<'w, Lights>,
}

impl WorldView<'_> {
    /// Grid size.
    pub fn dims(&self) -> GridDims {
        self.world.dims
    }
    /// The material table.
    pub fn materials(&self) -> &MaterialTable {
        &self.materials
    }
    /// The light faces ([`crate::lights`]).
    pub fn lights(&self) -> &Lights {
        &self.lights
    }

    #[inline]
    pub(crate) fn slab_for_brick_x(&self, bx: u32) -> &Slab {
        &self.slabs[self.world.slab_of_x[bx as usize] as usize]
    }

    /// Whether the brick cell at `b` (inside the grid) holds anything.
    #[inline]
    pub(crate) fn brick_occupied(&self, b: UVec3) -> bool {
        self.slab_for_brick_x(b.x)
            .cell(self.world.dims.cell_index(b))
            != CellState::Empty
    }

    /// Whether voxel `v` (inside the grid) is solid.
    #[inline]
    pub(crate) fn solid_at(&self, v: IVec3) -> bool {
        let (b, bit) = split_voxel(v);
        self.slab_for_brick_x(b.x)
            .solid_at(self.world.dims.cell_index(b), bit)
    }

    /// The material of a voxel, `None` when empty; an error outside the grid.
    pub fn voxel(&self, v: IVec3) -> Result<Option<u8>> {
        if !self.world.dims.contains_voxel(v) {
            return Err(BrickmapError::OutOfRange(v, self.world.dims.voxels()));
        }
        let (b, bit) = split_voxel(v);
        Ok(self
            .slab_for_brick_x(b.x)
            .voxel(self.world.dims.cell_index(b), bit))
    }

    /// The solid voxels of brick `b` (inside the grid) and their materials by voxel index
    /// (0 where empty): what a copy of a selection reads.
    pub fn brick_voxels(&self, b: UVec3) -> (crate::Mask, [u8; 512]) {
        let (mask, mats) = self
            .slab_for_brick_x(b.x)
            .read(self.world.dims.cell_index(b));
        let mut dense = [0u8; 512];
        for (k, bit) in mask.ones().enumerate() {
            dense[bit] = mats.at(k);
        }
        (mask, dense)
    }

    /// The box of brick cells that hold anything, in voxels (min inclusive, max exclusive;
    /// brick-granular), or None for an empty world. For framing the content in a view.
    pub fn occupied_bounds(&self) -> Option<(IVec3, IVec3)> {
        let b = self.world.dims.bricks();
        let mut bounds: Option<(UVec3, UVec3)> = None;
        for x in 0..b.x {
            for y in 0..b.y {
                for z in 0..b.z {
                    let c = UVec3::new(x, y, z);
                    if self.brick_occupied(c) {
                        bounds = Some(match bounds {
                            None => (c, c),
                            Some((lo, hi)) => (lo.min(c), hi.max(c)),
                        });
                    }
                }
            }
        }
        bounds.map(|(lo, hi)| ((lo * 8).as_ivec3(), ((hi + 1) * 8).as_ivec3()))
    }

    /// Solid voxels in the world.
    pub fn solid_count(&self) -> u64 {
        self.slabs.iter().map(|s| s.solid()).sum()
    }

    /// Bricks in the world.
    pub fn brick_count(&self) -> u64 {
        self.slabs.iter().map(|s| s.pool.used() as u64).sum()
    }

    /// Bytes by buffer.
    pub fn memory(&self) -> MemoryStats {
        let brick = std::mem::size_of::<Brick>() as u64;
        let mut m = MemoryStats {
            brick_index: self.world.dims.brick_cells() as u64 * 4,
            coarse: self.world.dims.coarse_words() as u64 * 4,
            tables: std::mem::size_of::<MaterialTablesGpu>() as u64,
            lights: self.lights.gpu_size(),
            ..Default::default()
        };
        for s in &self.slabs {
            m.bricks_used += s.pool.used() as u64 * brick;
            m.bricks_reserved += s.pool.reserved() as u64 * brick;
            m.material_used += s.buckets.bytes_in_use();
            m.material_reserved += s.buckets.bytes_reserved();
            for (_, state) in s.cells() {
                let CellState::Brick(slot) = state else {
                    m.full_cells += 1;
                    continue;
                };
                let b = s.brick(slot);
                if b.is_uniform() {
                    m.uniform_bricks += 1;
                } else {
                    m.material_payload += b.mask.count() as u64;
                }
            }
            m.cpu_only += s.pool.reserved() as u64 * 8 + s.buckets.bytes_reserved() / 8;
        }
        m
    }

    /// A hash of the logical content: grid size, every solid voxel with its material, and
    /// the material tables. Independent of bucket layout, brick slots, uniform-or-not storage
    /// and worker count.
    pub fn content_hash(&self) -> u64 {
        use xxhash_rust::xxh3::{Xxh3, xxh3_64};
        let mut sum = 0u64;
        let mut mats = Vec::with_capacity(512);
        for s in &self.slabs {
            for (cell, _) in s.cells() {
                let (mask, materials) = s.read(cell);
                let coord = self.world.dims.cell_coord(cell);
                let mut h = Xxh3::new();
                h.update(bytemuck::bytes_of(&coord.to_array()));
                h.update(bytemuck::bytes_of(&mask));
                mats.clear();
                mats.extend((0..mask.count() as usize).map(|k| materials.at(k)));
                h.update(&mats);
                // A commutative combination: the order slabs are visited in does not matter.
                sum = sum.wrapping_add(h.digest());
            }
        }
        let mut all = Vec::new();
        all.extend_from_slice(bytemuck::bytes_of(&self.world.dims.bricks().to_array()));
        all.extend_from_slice(&sum.to_le_bytes());
        all.extend_from_slice(&self.materials.logical_bytes());
        xxh3_64(&all)
    }

    /// Calls `f(brick, mask, materials)` for every non-empty brick cell in cell order
    /// (`(bx·Z + bz)·Y + by` ascending), materials borrowed, without copying the world.
    pub fn for_each_brick(&self, mut f: impl FnMut(UVec3, &crate::Mask, BrickMaterials<'_>)) {
        for s in &self.slabs {
            s.visit(&mut |cell, mask, mats| f(self.world.dims.cell_coord(cell), mask, mats));
        }
    }

    /// The cells each worker's slab holds, in slab order: consecutive runs covering the grid
    /// in cell order.
    pub fn slab_cells(&self) -> Vec<Range<usize>> {
        self.slabs.iter().map(|s| s.cell_range()).collect()
    }

    /// Every non-empty cell of slab `s` (cell index, mask, materials), in cell order: what
    /// [`WorldView::for_each_brick`] visits of that slab, for a reader with a thread per slab.
    pub fn visit_slab(&self, s: usize, f: &mut dyn FnMut(usize, &crate::Mask, BrickMaterials<'_>)) {
        self.slabs[s].visit(f);
    }

    /// Checks every invariant of every slab (tests use it after each step).
    pub fn validate(&self) -> std::result::Result<(), String> {
        for (w, s) in self.slabs.iter().enumerate() {
            s.validate().map_err(|e| format!("worker {w}: {e}"))?;
        }
        self.lights
            .validate(self)
            .map_err(|e| format!("lights: {e}"))
    }

    /// The bytes `range` of a GPU buffer, appended to `out`, built from only the cells,
    /// bricks, words and chunks the range covers: what an upload of drained dirty ranges
    /// copies, at a cost proportional to the range. Bytes beyond the buffer's size read 0.
    pub fn copy_gpu_range(&self, buffer: GpuBuffer, range: Range<u64>, out: &mut Vec<u8>) {
        let start = out.len();
        let len = (range.end.saturating_sub(range.start)) as usize;
        out.resize(start + len, 0);
        let dst = &mut out[start..];
        let dims = self.world.dims;
        match buffer {
            GpuBuffer::BrickIndex | GpuBuffer::Coarse => {
                let words = (range.start / 4)..range.end.div_ceil(4);
                let per_x = (dims.bricks().y * dims.bricks().z) as u64;
                let per_cx = dims.coarse_words_per_column() as u64;
                let total = self.world.gpu_buffer_size(buffer) / 4;
                for w in words.start..words.end.min(total) {
                    let word = if buffer == GpuBuffer::BrickIndex {
                        let slab = self.slab_for_brick_x((w / per_x) as u32);
                        slab.gpu_index_word(w as usize)
                    } else {
                        let cx = (w / per_cx) as u32;
                        let slab = self.slab_for_brick_x(cx * crate::grid::COARSE_BRICKS);
                        slab.coarse_word(w as usize)
                    };
                    copy_overlap(&word.to_le_bytes(), w * 4, &range, dst);
                }
            }
            GpuBuffer::Bricks | GpuBuffer::MaterialBytes => {
                let chunk = if buffer == GpuBuffer::Bricks {
                    (BRICK_CHUNK as usize * std::mem::size_of::<Brick>()) as u64
                } else {
                    MATERIAL_CHUNK as u64
                };
                for id in range.start / chunk..range.end.div_ceil(chunk) {
                    for s in &self.slabs {
                        let (ids, bytes): (&[u32], &[u8]) = if buffer == GpuBuffer::Bricks {
                            (s.pool.chunk_ids(), bytemuck::cast_slice(s.pool.bricks()))
                        } else {
                            (s.buckets.chunk_ids(), s.buckets.bytes())
                        };
                        if let Some(k) = ids.iter().position(|&c| c as u64 == id) {
                            let local = &bytes[k * chunk as usize..(k + 1) * chunk as usize];
                            copy_overlap(local, id * chunk, &range, dst);
                        }
                    }
                }
            }
            GpuBuffer::MaterialTables => {
                copy_overlap(bytemuck::bytes_of(self.materials.gpu()), 0, &range, dst)
            }
            GpuBuffer::Lights => self.lights.copy_range(&range, dst),
        }
    }

    /// Current size in bytes of a GPU buffer ([`World::gpu_buffer_size`]).
    pub fn gpu_buffer_size(&self, buffer: GpuBuffer) -> u64 {
        match buffer {
            // The view holds the lights' read lock already.
            GpuBuffer::Lights => self.lights.gpu_size(),
            _ => self.world.gpu_buffer_size(buffer),
        }
    }

    /// The whole of a GPU buffer, as the renderer's copy of it must be.
    pub fn gpu_image(&self, buffer: GpuBuffer) -> Vec<u8> {
        let size = self.gpu_buffer_size(buffer) as usize;
        let mut out = vec![0u8; size];
        match buffer {
            GpuBuffer::BrickIndex => {
                let mut at = 0;
                for s in &self.slabs {
                    for v in s.gpu_index_words() {
                        out[at..at + 4].copy_from_slice(&v.to_le_bytes());
                        at += 4;
                    }
                }
            }
            GpuBuffer::Coarse => {
                let mut at = 0;
                for s in &self.slabs {
                    let bytes: &[u8] = bytemuck::cast_slice(s.coarse_words());
                    out[at..at + bytes.len()].copy_from_slice(bytes);
                    at += bytes.len();
                }
            }
            GpuBuffer::Bricks => {
                let chunk = BRICK_CHUNK as usize * std::mem::size_of::<Brick>();
                for s in &self.slabs {
                    let bytes: &[u8] = bytemuck::cast_slice(s.pool.bricks());
                    for (k, &id) in s.pool.chunk_ids().iter().enumerate() {
                        let dst = id as usize * chunk;
                        out[dst..dst + chunk].copy_from_slice(&bytes[k * chunk..(k + 1) * chunk]);
                    }
                }
            }
            GpuBuffer::MaterialBytes => {
                let chunk = MATERIAL_CHUNK as usize;
                for s in &self.slabs {
                    let bytes = s.buckets.bytes();
                    for (k, &id) in s.buckets.chunk_ids().iter().enumerate() {
                        let dst = id as usize * chunk;
                        out[dst..dst + chunk].copy_from_slice(&bytes[k * chunk..(k + 1) * chunk]);
                    }
                }
            }
            GpuBuffer::MaterialTables => {
                out.copy_from_slice(bytemuck::bytes_of(self.materials.gpu()))
            }
            GpuBuffer::Lights => self.lights.copy_range(&(0..size as u64), &mut out),
        }
        out
    }
}

impl crate::lights::VoxelSource for WorldView<'_> {
    fn grid(&self) -> GridDims {
        self.dims()
    }
    fn visit_bricks(&self, f: &mut dyn FnMut(UVec3)) {
        self.for_each_brick(|b, _, _| f(b));
    }
    fn read_brick(&self, b: UVec3, f: &mut dyn FnMut(&crate::Mask, BrickMaterials<'_>)) {
        let cell = self.world.dims.cell_index(b);
        let (mask, mats) = self.slab_for_brick_x(b.x).read(cell);
        f(&mask, mats.borrowed());
    }
    fn solid(&self, v: IVec3) -> bool {
        self.solid_at(v)
    }
}
