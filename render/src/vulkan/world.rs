//! The world on the GPU: one device-local buffer per region (brick index, bricks, coarse
//! grid, material bytes, material tables, light faces), bound at 0..4 (and 10) by every
//! shader (`shaders/brickmap.glsl`), and kept equal to the CPU world by incremental uploads.
//! One buffer per region keeps each within the device's allocation and storage-range limits
//! (a single buffer of them all passed lavapipe's 2²⁷-byte range on large worlds); a region
//! the limits cannot hold is refused ([`GpuError::Limit`]) rather than bound past them.
//!
//! Each frame [`GpuWorld::update`] drains the world's dirty ranges, reads their current bytes
//! under one read lock, and compares them word by word with a host copy of what the GPU
//! holds (the *shadow*), so only words that really changed are queued: dirty ranges that
//! were coarsened (a whole 68-byte brick for one voxel, merged ranges) cost no upload
//! beyond the words that differ. Queued uploads own their bytes and go through the
//! [`StagingRing`]: one flush per frame, the rest deferred to the next frame. When the world
//! outgrows a region, that region's buffer is replaced by a larger one (50 % headroom, within
//! the limits) and its old contents are copied on the GPU, so nothing is re-read or lost.

use super::barrier::{after_transfer, before_transfer};
use super::buffer::{Binding, HostBuffer, read_device};
use super::staging::{StagingRing, Upload};
use super::{GpuContext, GpuError};
use ash::vk;
use brickmap::{GpuBuffer, World, WorldView};
use gpu_allocator::MemoryLocation;
use std::collections::VecDeque;
use std::ops::Range;

/// Regions: one per [`GpuBuffer`].
const N: usize = GpuBuffer::ALL.len();

/// Staging buffers in the ring.
pub const RING_SLOTS: usize = 3;
/// Bytes per staging buffer: what one frame uploads at most.
pub const RING_SLOT_BYTES: u64 = 4 << 20;
/// Changed runs at most this many bytes apart are uploaded as one copy region (so a small
/// edit's upload stays within 1.5× of the changed words).
const MERGE_GAP: usize = 4;
/// Copy regions one update is allowed: past it the gap that joins runs grows (× 4 at a
/// time) until the runs fit. A copy region costs the driver far more than a few KiB of
/// bytes, and the synchronization validation layer far more again (a 256 × 128 × 256 world
/// of 40 boxes, as one edit, was 23,721 regions: 10.5 ms on lavapipe, 45 s under
/// validation); a brush stroke's few hundred runs stay as they are. The gap bytes come from
/// the shadow, which equals the world there (a byte outside every dirty range is unchanged).
pub const REGION_BUDGET: usize = 256;

/// What one update did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UploadReport {
    /// Bytes the world reported dirty.
    pub dirty_bytes: u64,
    /// Bytes queued: the words that differ from what the GPU holds (plus merged gaps).
    pub queued_bytes: u64,
    /// Bytes copied to the GPU.
    pub uploaded_bytes: u64,
    /// Copy regions recorded.
    pub copy_regions: u32,
    /// Flushes submitted.
    pub flushes: u32,
    /// Bytes still queued for later frames.
    pub deferred_bytes: u64,
    /// Whether a region's buffer was replaced by a larger one.
    pub grew: bool,
}

impl UploadReport {
    fn add(&mut self, o: &UploadReport) {
        self.dirty_bytes += o.dirty_bytes;
        self.queued_bytes += o.queued_bytes;
        self.uploaded_bytes += o.uploaded_bytes;
        self.copy_regions += o.copy_regions;
        self.flushes += o.flushes;
        self.deferred_bytes = o.deferred_bytes;
        self.grew |= o.grew;
    }

    /// Whether the GPU's world changed (a render must restart its accumulation).
    pub fn changed(&self) -> bool {
        self.uploaded_bytes > 0 || self.grew
    }
}

/// The world's buffers on the GPU.
pub struct GpuWorld {
    /// One device-local buffer per region, in [`GpuBuffer::ALL`] order.
    buffers: Vec<HostBuffer>,
    shadow: [Vec<u8>; N],
    ring: StagingRing,
    queue: VecDeque<Upload>,
    dims: [u32; 3],
    words_per_column: u32,
    /// This world among those made in the process, and how many times its bytes on the GPU
    /// changed ([`GpuWorld::state`]).
    id: u64,
    changes: u64,
}

/// Ids of the GPU worlds made so far.
static WORLDS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

fn align(x: u64, a: u64) -> u64 {
    x.div_ceil(a) * a
}

/// What a region is called in errors.
fn region_name(b: GpuBuffer) -> &'static str {
    match b {
        GpuBuffer::BrickIndex => "the world's brick index",
        GpuBuffer::Bricks => "the world's bricks",
        GpuBuffer::Coarse => "the world's coarse grid",
        GpuBuffer::MaterialBytes => "the world's material bytes",
        GpuBuffer::MaterialTables => "the world's material tables",
        GpuBuffer::Lights => "the world's light faces",
    }
}

/// The capacity a region of `size` bytes gets, given its current capacity (0: none yet):
/// regions that grow with the content get headroom (25 % at first, 50 % more when they
/// outgrow it), never past `max` (the device's bound-buffer limit); a size above `max` is
/// refused.
fn region_capacity(b: GpuBuffer, size: u64, current: u64, max: u64) -> Result<u64, GpuError> {
    let max = max & !3;
    if size > max {
        return Err(GpuError::Limit {
            what: region_name(b).to_string(),
            bytes: size,
            limit: "maxStorageBufferRange / maxMemoryAllocationSize",
            max,
        });
    }
    let grows = matches!(
        b,
        GpuBuffer::Bricks | GpuBuffer::MaterialBytes | GpuBuffer::Lights
    );
    let wanted = match (current, grows) {
        (0, true) => size + size / 4,
        (0, false) => size,
        (cap, _) => size.max(cap + cap / 2),
    };
    Ok(align(wanted.max(4), 4).min(max).max(align(size.max(4), 4)))
}

/// A device-local buffer of `size` bytes, zero-filled.
fn zeroed_buffer(ctx: &GpuContext, size: u64) -> Result<HostBuffer, GpuError> {
    let buffer = HostBuffer::new(ctx, "world", size, MemoryLocation::GpuOnly)?;
    let filled = ctx.submit_and_wait(|cmd| {
        // SAFETY: the buffer lives until after the wait; the barrier orders the fill before
        // every later copy and shader read.
        unsafe {
            ctx.device
                .cmd_fill_buffer(cmd, buffer.raw, 0, vk::WHOLE_SIZE, 0);
            after_transfer(ctx, cmd);
        }
    });
    match filled {
        Ok(()) => Ok(buffer),
        Err(e) => {
            buffer.destroy(ctx);
            Err(e)
        }
    }
}

/// Runs of words of `new` that differ from `old` (equal lengths), as byte ranges relative to
/// both; runs at most `gap` bytes apart are merged.
fn changed_runs(old: &[u8], new: &[u8], gap: usize) -> Vec<Range<usize>> {
    let mut runs: Vec<Range<usize>> = Vec::new();
    let mut at = 0;
    while at < new.len() {
        let end = (at + 64).min(new.len());
        if old[at..end] == new[at..end] {
            at = end;
            continue;
        }
        for w in (at..end).step_by(4) {
            let we = (w + 4).min(end);
            if old[w..we] == new[w..we] {
                continue;
            }
            match runs.last_mut() {
                Some(last) if w <= last.end + gap => last.end = we,
                _ => runs.push(w..we),
            }
        }
        at = end;
    }
    runs
}

/// The gap that brings `runs` (each region's runs, sorted and disjoint) to at most `budget`
/// copy regions in all: [`MERGE_GAP`], or × 4 until they fit.
fn budget_gap(runs: &[Vec<Range<usize>>], budget: usize) -> usize {
    let count = |gap: usize| -> usize {
        runs.iter()
            .filter(|r| !r.is_empty())
            .map(|r| 1 + r.windows(2).filter(|w| w[1].start > w[0].end + gap).count())
            .sum()
    };
    let mut gap = MERGE_GAP;
    let longest = runs
        .iter()
        .filter_map(|r| r.last())
        .map(|r| r.end)
        .max()
        .unwrap_or(0);
    while count(gap) > budget && gap < longest {
        gap *= 4;
    }
    gap
}

/// `runs` (sorted, disjoint) joined where at most `gap` bytes apart.
fn merge_runs(runs: &[Range<usize>], gap: usize) -> Vec<Range<usize>> {
    let mut out: Vec<Range<usize>> = Vec::new();
    for r in runs {
        match out.last_mut() {
            Some(last) if r.start <= last.end + gap => last.end = last.end.max(r.end),
            _ => out.push(r.clone()),
        }
    }
    out
}

impl GpuWorld {
    /// Uploads a world's current buffers (waits until they are on the GPU), with the default
    /// ring ([`RING_SLOTS`] × [`RING_SLOT_BYTES`]).
    pub fn upload(ctx: &GpuContext, view: &WorldView<'_>) -> Result<Self, GpuError> {
        Self::with_ring(ctx, view, RING_SLOTS, RING_SLOT_BYTES)
    }

    /// [`GpuWorld::upload`] with a ring of `slots` staging buffers of `slot_bytes` each.
    pub fn with_ring(
        ctx: &GpuContext,
        view: &WorldView<'_>,
        slots: usize,
        slot_bytes: u64,
    ) -> Result<Self, GpuError> {
        let sizes = GpuBuffer::ALL.map(|b| view.gpu_buffer_size(b));
        let max = ctx.limits.bound_buffer();
        let mut buffers: Vec<HostBuffer> = Vec::with_capacity(N);
        let made = (|| {
            for (i, b) in GpuBuffer::ALL.into_iter().enumerate() {
                let capacity = region_capacity(b, sizes[i], 0, max)?;
                buffers.push(zeroed_buffer(ctx, capacity)?);
            }
            StagingRing::new(ctx, slots, slot_bytes.max(4))
        })();
        let ring = match made {
            Ok(r) => r,
            Err(e) => {
                buffers.into_iter().for_each(|b| b.destroy(ctx));
                return Err(e);
            }
        };
        let dims = view.dims();
        let mut world = Self {
            buffers,
            shadow: Default::default(),
            ring,
            queue: VecDeque::new(),
            dims: dims.bricks().to_array(),
            words_per_column: dims.coarse_words_per_column() as u32,
            id: WORLDS.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            changes: 0,
        };
        let whole = sizes.map(|s| std::iter::once(0..s).collect());
        let staged = world
            .stage(ctx, view, &whole)
            .and_then(|_| world.drain(ctx));
        match staged {
            Ok(_) => Ok(world),
            Err(e) => {
                world.destroy(ctx);
                Err(e)
            }
        }
    }

    /// One frame's upload: drains the world's changes, queues the words that differ from
    /// the GPU's copy, and submits one flush of at most one ring slot; the rest waits
    /// for the next frames. A GPU error leaves every byte queued or in the shadow, so the
    /// next call resumes without losing anything.
    pub fn update(&mut self, ctx: &GpuContext, world: &World) -> Result<UploadReport, GpuError> {
        let dirty = world.take_dirty();
        let view = world.read();
        let mut report = self.stage(ctx, &view, &dirty.ranges)?;
        drop(view);
        report.add(&self.flush(ctx)?);
        Ok(report)
    }

    /// [`GpuWorld::update`], then flushes until nothing is deferred and waits for the copies.
    pub fn sync(&mut self, ctx: &GpuContext, world: &World) -> Result<UploadReport, GpuError> {
        let mut report = self.update(ctx, world)?;
        report.add(&self.drain(ctx)?);
        Ok(report)
    }

    fn drain(&mut self, ctx: &GpuContext) -> Result<UploadReport, GpuError> {
        let mut report = UploadReport::default();
        while !self.queue.is_empty() {
            report.add(&self.flush(ctx)?);
        }
        self.ring.wait_idle(ctx)?;
        Ok(report)
    }

    fn flush(&mut self, ctx: &GpuContext) -> Result<UploadReport, GpuError> {
        let buffers: [vk::Buffer; N] = std::array::from_fn(|i| self.buffers[i].raw);
        let flushed = self.ring.flush(ctx, &mut self.queue, |r| (buffers[r], 0))?;
        self.changes += u64::from(flushed.bytes > 0);
        Ok(UploadReport {
            uploaded_bytes: flushed.bytes,
            copy_regions: flushed.regions,
            flushes: u32::from(flushed.bytes > 0),
            deferred_bytes: self.deferred_bytes(),
            ..Default::default()
        })
    }

    /// Grows regions that the world outgrew, then queues the changed words of `ranges`:
    /// runs [`MERGE_GAP`] bytes apart as one, farther ones too while there are more than
    /// [`REGION_BUDGET`] runs.
    fn stage(
        &mut self,
        ctx: &GpuContext,
        view: &WorldView<'_>,
        ranges: &[Vec<Range<u64>>; N],
    ) -> Result<UploadReport, GpuError> {
        let mut report = UploadReport::default();
        let sizes = GpuBuffer::ALL.map(|b| view.gpu_buffer_size(b));
        if sizes.iter().zip(&self.buffers).any(|(s, b)| *s > b.size) {
            self.grow(ctx, sizes)?;
            report.grew = true;
            self.changes += 1;
        }
        let mut bytes = Vec::new();
        let mut runs: [Vec<Range<usize>>; N] = Default::default();
        for (i, which) in GpuBuffer::ALL.into_iter().enumerate() {
            let size = sizes[i];
            if (self.shadow[i].len() as u64) < size {
                // The GPU's region beyond the old size holds zeros (zeroed_buffer).
                self.shadow[i].resize(size as usize, 0);
            }
            for r in &ranges[i] {
                let (start, end) = (r.start & !3, align(r.end, 4).min(size));
                if start >= end {
                    continue;
                }
                report.dirty_bytes += r.end.min(size).saturating_sub(r.start);
                bytes.clear();
                view.copy_gpu_range(which, start..end, &mut bytes);
                let old = &mut self.shadow[i][start as usize..end as usize];
                for run in changed_runs(old, &bytes, MERGE_GAP) {
                    old[run.clone()].copy_from_slice(&bytes[run.clone()]);
                    let at = start as usize;
                    runs[i].push(at + run.start..at + run.end);
                }
            }
            // Overlapping dirty ranges find their overlap unchanged the second time, so the
            // runs are disjoint; sorted, they can be joined.
            runs[i].sort_unstable_by_key(|r| r.start);
        }
        let gap = budget_gap(&runs, REGION_BUDGET);
        for (i, region) in runs.iter().enumerate() {
            for run in merge_runs(region, gap) {
                report.queued_bytes += run.len() as u64;
                self.queue.push_back(Upload {
                    region: i,
                    offset: run.start as u64,
                    bytes: self.shadow[i][run].to_vec(),
                    done: 0,
                });
            }
        }
        Ok(report)
    }

    /// Replaces the buffers of the regions that outgrew them by larger ones, copying their
    /// old contents on the GPU. A region the limits cannot hold fails before anything changes.
    fn grow(&mut self, ctx: &GpuContext, sizes: [u64; N]) -> Result<(), GpuError> {
        let max = ctx.limits.bound_buffer();
        let mut plan = Vec::new();
        for (i, b) in GpuBuffer::ALL.into_iter().enumerate() {
            let cap = self.buffers[i].size;
            if sizes[i] > cap {
                plan.push((i, region_capacity(b, sizes[i], cap, max)?));
            }
        }
        self.ring.wait_idle(ctx)?;
        for (i, capacity) in plan {
            let buffer = zeroed_buffer(ctx, capacity)?;
            let (old, new) = (self.buffers[i].raw, buffer.raw);
            let copy = vk::BufferCopy {
                src_offset: 0,
                dst_offset: 0,
                size: self.shadow[i].len() as u64,
            };
            let copied = ctx.submit_and_wait(|cmd| {
                // SAFETY: both buffers live until after the wait; barriers order the copy
                // after earlier shader reads and copies and before later ones.
                unsafe {
                    before_transfer(ctx, cmd);
                    if copy.size > 0 {
                        ctx.device.cmd_copy_buffer(cmd, old, new, &[copy]);
                    }
                    after_transfer(ctx, cmd);
                }
            });
            if let Err(e) = copied {
                buffer.destroy(ctx);
                return Err(e);
            }
            std::mem::replace(&mut self.buffers[i], buffer).destroy(ctx);
        }
        Ok(())
    }

    /// Reads a region back from the GPU (its bytes in use): tests compare it with
    /// [`WorldView::gpu_image`]. Call after [`GpuWorld::sync`].
    pub fn read_back(&self, ctx: &GpuContext, which: GpuBuffer) -> Result<Vec<u8>, GpuError> {
        let i = which as usize;
        read_device(
            ctx,
            Binding {
                buffer: self.buffers[i].raw,
                offset: 0,
                range: self.shadow[i].len() as u64,
            },
        )
    }

    /// Frees the buffers and the ring (waits for pending copies).
    pub fn destroy(self, ctx: &GpuContext) {
        self.ring.destroy(ctx);
        self.buffers.into_iter().for_each(|b| b.destroy(ctx));
    }
}

impl GpuWorld {
    /// The voxel regions as bindings 0..4 (not the lights).
    pub fn bindings(&self) -> Vec<Binding> {
        self.buffers[..GpuBuffer::Lights as usize]
            .iter()
            .map(HostBuffer::binding)
            .collect()
    }

    /// Which world this is and how many times its GPU bytes changed: equal states hold the
    /// same voxels and lights (the tracer's light visibility cache is kept while it is).
    pub fn state(&self) -> (u64, u64) {
        (self.id, self.changes)
    }

    /// The light faces' region ([`brickmap::lights`]; binding 10 of the tracer).
    pub fn light_binding(&self) -> Binding {
        self.buffers[GpuBuffer::Lights as usize].binding()
    }
    /// Grid size in bricks.
    pub fn dims(&self) -> [u32; 3] {
        self.dims
    }
    /// Coarse words per coarse x-column.
    pub fn words_per_column(&self) -> u32 {
        self.words_per_column
    }
    /// Bytes queued and not yet copied.
    pub fn deferred_bytes(&self) -> u64 {
        self.queue
            .iter()
            .map(|u| (u.bytes.len() - u.done) as u64)
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changed_runs_are_the_differing_words_merged_across_small_gaps() {
        let old = vec![0u8; 200];
        let mut new = old.clone();
        new[5] = 1; // word 4..8
        new[13] = 1; // word 12..16: gap of 4 bytes → merged with 4..8
        new[100] = 1; // far away: own run
        new[199] = 1; // last word
        assert_eq!(
            changed_runs(&old, &new, MERGE_GAP),
            vec![4..16, 100..104, 196..200]
        );
        assert!(changed_runs(&old, &old, MERGE_GAP).is_empty());
        // A 2-word gap is not merged.
        let mut n2 = old.clone();
        n2[0] = 1;
        n2[12] = 1;
        assert_eq!(changed_runs(&old, &n2, MERGE_GAP), vec![0..4, 12..16]);
        // A wider gap joins runs that far apart, not farther.
        assert_eq!(changed_runs(&old, &new, 88), vec![4..104, 196..200]);
        assert_eq!(changed_runs(&old, &new, 96), vec![4..200]);
    }

    #[test]
    fn runs_past_the_region_budget_are_joined_across_wider_gaps() {
        // 100 runs of one word, 64 bytes apart, in one region; 3 far apart in another.
        let a: Vec<Range<usize>> = (0..100).map(|k| k * 68..k * 68 + 4).collect();
        let b = vec![0..4, 10_000..10_004, 20_000..20_004];
        let runs = [a.clone(), b.clone()];
        // Within budget: the small-edit rule, nothing joined.
        assert_eq!(budget_gap(&runs, 103), MERGE_GAP);
        assert_eq!(merge_runs(&a, MERGE_GAP), a);
        // Over budget: the gap grows by 4× until the runs fit (4 → 16 → 64 joins `a`).
        assert_eq!(budget_gap(&runs, 102), 64);
        assert_eq!(merge_runs(&a, 64), vec![0..99 * 68 + 4]);
        assert_eq!(merge_runs(&b, 64), b);
        // A budget below what the regions can reach stops at one run per region.
        let gap = budget_gap(&runs, 1);
        assert!(gap >= 20_000, "{gap}");
        assert_eq!(merge_runs(&b, gap), vec![0..20_004]);
        assert!(budget_gap(&[vec![], vec![]], 0) == MERGE_GAP);
    }

    #[test]
    fn region_capacities_have_headroom_within_the_limit() {
        let max = 1 << 20;
        // First sizes: growing regions 25 % more, fixed ones exact, in words.
        assert_eq!(
            region_capacity(GpuBuffer::Bricks, 680, 0, max).unwrap(),
            852
        );
        assert_eq!(
            region_capacity(GpuBuffer::BrickIndex, 10, 0, max).unwrap(),
            12
        );
        assert_eq!(region_capacity(GpuBuffer::Coarse, 0, 0, max).unwrap(), 4);
        // Outgrown: 50 % more, or the size when that is more.
        assert_eq!(
            region_capacity(GpuBuffer::MaterialBytes, 1100, 1000, max).unwrap(),
            1500
        );
        assert_eq!(
            region_capacity(GpuBuffer::MaterialBytes, 4000, 1000, max).unwrap(),
            4000
        );
        // Headroom stops at the limit; the limit itself still fits; past it is refused.
        assert_eq!(
            region_capacity(GpuBuffer::Bricks, max - 8, 0, max).unwrap(),
            max
        );
        assert_eq!(
            region_capacity(GpuBuffer::Bricks, max, max - 8, max).unwrap(),
            max
        );
        let e = region_capacity(GpuBuffer::MaterialBytes, max + 1, max, max).unwrap_err();
        assert!(e.to_string().contains("material bytes"), "{e}");
    }
}
