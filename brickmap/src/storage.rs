//! Per-worker storage carved from global address spaces: brick slots ([`BrickPool`]) and
//! per-voxel material bytes ([`MaterialBuckets`]).
//!
//! Workers claim whole chunks of each global buffer with one atomic add ([`ChunkCounters`]),
//! so the GPU buffers stay dense and no worker ever waits for another. Inside its chunks a
//! worker allocates without synchronisation.
//!
//! Material buckets: a chunk is split into 2 KiB pages; a page is dedicated to one bucket size
//! when first needed and returns to the worker's free pages when its last bucket is freed.
//! Pages of different sizes therefore interleave inside a chunk in the order bricks were
//! edited, which keeps the data of neighbouring bricks close (the thesis's lesson of its
//! Figure 3.1). Free buckets of each size sit on an intrusive doubly linked list, so
//! allocating, freeing and reclaiming a page are O(1) (a page holds at most 128 buckets).

use crate::brick::Brick;
use crate::error::{BrickmapError, Result};
use std::sync::atomic::{AtomicU32, Ordering};

/// Bricks per brick chunk.
pub const BRICK_CHUNK: u32 = 1024;
/// Bytes per material chunk.
pub const MATERIAL_CHUNK: u32 = 64 * 1024;
/// Bytes per material page.
pub const PAGE_BYTES: u32 = 2048;
/// Material byte offsets must fit in the 31 low bits of a brick's material word.
const MATERIAL_CHUNKS_MAX: u32 = (1u32 << 31) / MATERIAL_CHUNK;
/// Brick indices must stay below [`crate::grid::EMPTY_BRICK`].
const BRICK_CHUNKS_MAX: u32 = u32::MAX / BRICK_CHUNK - 1;
const NONE: u32 = u32::MAX;
const FREE_PAGE: u8 = u8::MAX;

/// Next unclaimed chunk of each global buffer, shared by all workers, and the budgets.
#[derive(Debug)]
pub struct ChunkCounters {
    bricks: AtomicU32,
    material: AtomicU32,
    brick_limit: u32,
    material_limit: u32,
}

impl Default for ChunkCounters {
    fn default() -> Self {
        Self::with_budget(u64::MAX, u64::MAX)
    }
}

impl ChunkCounters {
    /// Counters that refuse to grow the brick buffer beyond `max_bricks` bricks or the
    /// material buffer beyond `max_material_bytes` (rounded up to whole chunks; never beyond
    /// what the 32-bit indices can address).
    pub fn with_budget(max_bricks: u64, max_material_bytes: u64) -> Self {
        let chunks = |n: u64, per: u32, cap: u32| n.div_ceil(per as u64).min(cap as u64) as u32;
        Self {
            bricks: AtomicU32::new(0),
            material: AtomicU32::new(0),
            brick_limit: chunks(max_bricks, BRICK_CHUNK, BRICK_CHUNKS_MAX),
            material_limit: chunks(max_material_bytes, MATERIAL_CHUNK, MATERIAL_CHUNKS_MAX),
        }
    }

    fn claim(counter: &AtomicU32, max: u32, what: &'static str) -> Result<u32> {
        let id = counter.fetch_add(1, Ordering::Relaxed);
        if id >= max {
            counter.fetch_sub(1, Ordering::Relaxed);
            return Err(BrickmapError::OutOfSpace(what));
        }
        Ok(id)
    }
    /// Brick chunks claimed so far (the brick buffer holds this many × [`BRICK_CHUNK`]).
    pub fn brick_chunks(&self) -> u32 {
        self.bricks.load(Ordering::Relaxed)
    }
    /// Material chunks claimed so far.
    pub fn material_chunks(&self) -> u32 {
        self.material.load(Ordering::Relaxed)
    }
}

/// The bucket sizes material bytes are allocated in (powers of two, ascending, 16..=512,
/// the largest 512 so any brick fits).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BucketSizes(Vec<u32>);

impl Default for BucketSizes {
    fn default() -> Self {
        Self(vec![64, 128, 256, 512])
    }
}

impl BucketSizes {
    /// Validates a list of bucket sizes.
    pub fn new(sizes: Vec<u32>) -> Result<Self> {
        let pow2 = sizes
            .iter()
            .all(|s| s.is_power_of_two() && (16..=512).contains(s));
        let ascending = sizes.windows(2).all(|w| w[0] < w[1]);
        if !pow2 || !ascending || sizes.last() != Some(&512) {
            return Err(BrickmapError::Config(format!(
                "bucket sizes {sizes:?}: need ascending powers of two in 16..=512 ending with 512"
            )));
        }
        Ok(Self(sizes))
    }
    /// The sizes.
    pub fn sizes(&self) -> &[u32] {
        &self.0
    }
    /// The smallest class that holds `n` bytes.
    pub fn class_for(&self, n: u32) -> u8 {
        self.0
            .iter()
            .position(|&s| s >= n)
            .unwrap_or(self.0.len() - 1) as u8
    }
    /// Size of a class.
    pub fn size(&self, class: u8) -> u32 {
        self.0[class as usize]
    }
    /// Whether a bucket of `class` should keep holding `n` bytes: it fits, and it has not
    /// shrunk below a quarter of the bucket (hysteresis, so a brick hovering around a
    /// boundary does not move on every edit).
    pub fn keeps(&self, class: u8, n: u32) -> bool {
        let s = self.size(class);
        n <= s && (class == 0 || n * 4 >= s)
    }
}

#[derive(Clone, Copy, Debug)]
struct Page {
    class: u8,
    used: u16,
}

/// One worker's material bytes: its chunks, pages and free lists.
#[derive(Debug)]
pub struct MaterialBuckets {
    sizes: BucketSizes,
    unit: u32,
    bytes: Vec<u8>,
    chunk_ids: Vec<u32>,
    pages: Vec<Page>,
    free_pages: Vec<u32>,
    heads: Vec<u32>,
    next: Vec<u32>,
    prev: Vec<u32>,
    used_buckets: u64,
}

impl MaterialBuckets {
    /// Empty storage with the given bucket sizes.
    pub fn new(sizes: BucketSizes) -> Self {
        let classes = sizes.sizes().len();
        Self {
            unit: sizes.sizes()[0],
            sizes,
            bytes: Vec::new(),
            chunk_ids: Vec::new(),
            pages: Vec::new(),
            free_pages: Vec::new(),
            heads: vec![NONE; classes],
            next: Vec::new(),
            prev: Vec::new(),
            used_buckets: 0,
        }
    }

    /// The bucket sizes.
    pub fn sizes(&self) -> &BucketSizes {
        &self.sizes
    }

    /// Allocates a bucket of `class`, returning its local offset.
    pub fn alloc(&mut self, class: u8, counters: &ChunkCounters) -> Result<u32> {
        if self.heads[class as usize] == NONE {
            let page = match self.free_pages.pop() {
                Some(p) => p,
                None => {
                    self.grow(counters)?;
                    self.free_pages.pop().expect("grow adds pages")
                }
            };
            self.carve(page, class);
        }
        let unit = self.heads[class as usize];
        self.unlink(unit, class);
        let off = unit * self.unit;
        self.pages[(off / PAGE_BYTES) as usize].used += 1;
        self.used_buckets += 1;
        Ok(off)
    }

    /// Frees the bucket of `class` at local offset `off`.
    pub fn free(&mut self, off: u32, class: u8) {
        let page = (off / PAGE_BYTES) as usize;
        debug_assert_eq!(self.pages[page].class, class);
        self.push_front(off / self.unit, class);
        self.used_buckets -= 1;
        self.pages[page].used -= 1;
        if self.pages[page].used == 0 {
            let size = self.sizes.size(class);
            let base = page as u32 * PAGE_BYTES;
            for b in (base..base + PAGE_BYTES).step_by(size as usize) {
                self.unlink(b / self.unit, class);
            }
            self.pages[page].class = FREE_PAGE;
            self.free_pages.push(page as u32);
        }
    }

    fn grow(&mut self, counters: &ChunkCounters) -> Result<()> {
        let id =
            ChunkCounters::claim(&counters.material, counters.material_limit, "material byte")?;
        let first_page = self.pages.len() as u32;
        self.chunk_ids.push(id);
        self.bytes
            .resize(self.bytes.len() + MATERIAL_CHUNK as usize, 0);
        let units = self.bytes.len() / self.unit as usize;
        self.next.resize(units, NONE);
        self.prev.resize(units, NONE);
        let pages = MATERIAL_CHUNK / PAGE_BYTES;
        self.pages.extend((0..pages).map(|_| Page {
            class: FREE_PAGE,
            used: 0,
        }));
        // Pushed in reverse so pages are handed out in address order.
        self.free_pages
            .extend((first_page..first_page + pages).rev());
        Ok(())
    }

    fn carve(&mut self, page: u32, class: u8) {
        self.pages[page as usize] = Page { class, used: 0 };
        let size = self.sizes.size(class);
        let base = page * PAGE_BYTES;
        for b in (base..base + PAGE_BYTES).step_by(size as usize).rev() {
            self.push_front(b / self.unit, class);
        }
    }

    fn push_front(&mut self, unit: u32, class: u8) {
        let head = self.heads[class as usize];
        self.next[unit as usize] = head;
        self.prev[unit as usize] = NONE;
        if head != NONE {
            self.prev[head as usize] = unit;
        }
        self.heads[class as usize] = unit;
    }

    fn unlink(&mut self, unit: u32, class: u8) {
        let (p, n) = (self.prev[unit as usize], self.next[unit as usize]);
        if p == NONE {
            self.heads[class as usize] = n;
        } else {
            self.next[p as usize] = n;
        }
        if n != NONE {
            self.prev[n as usize] = p;
        }
    }

    /// Global byte offset of a local offset (what a brick's material word holds).
    #[inline]
    pub fn global(&self, off: u32) -> u32 {
        self.chunk_ids[(off / MATERIAL_CHUNK) as usize] * MATERIAL_CHUNK + off % MATERIAL_CHUNK
    }
    /// Bytes at a local offset.
    #[inline]
    pub fn slice(&self, off: u32, len: usize) -> &[u8] {
        &self.bytes[off as usize..off as usize + len]
    }
    /// Mutable bytes at a local offset.
    #[inline]
    pub fn slice_mut(&mut self, off: u32, len: usize) -> &mut [u8] {
        &mut self.bytes[off as usize..off as usize + len]
    }
    /// Global chunk ids owned, in local order.
    pub fn chunk_ids(&self) -> &[u32] {
        &self.chunk_ids
    }
    /// All local bytes (chunk after chunk in [`MaterialBuckets::chunk_ids`] order).
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }
    /// Buckets handed out and not freed.
    pub fn used_buckets(&self) -> u64 {
        self.used_buckets
    }
    /// Bytes of pages currently dedicated to a size (what the GPU must hold).
    pub fn bytes_in_use(&self) -> u64 {
        self.pages.iter().filter(|p| p.class != FREE_PAGE).count() as u64 * PAGE_BYTES as u64
    }
    /// Bytes reserved (every claimed chunk).
    pub fn bytes_reserved(&self) -> u64 {
        self.bytes.len() as u64
    }

    /// Checks the allocator's accounting against the buckets the bricks hold: every held
    /// bucket lies in a page of its size, no two overlap, page use counts match, and every
    /// other bucket of a carved page is on its free list exactly once.
    pub fn validate(&self, held: &[(u32, u8)]) -> std::result::Result<(), String> {
        let units = self.next.len();
        let mut state = vec![0u8; units]; // 0 not a bucket start, 1 held, 2 free
        let mut per_page = vec![0u16; self.pages.len()];
        for &(off, class) in held {
            if off % self.sizes.size(class) != 0 {
                return Err(format!("bucket {off} misaligned for class {class}"));
            }
            let page = (off / PAGE_BYTES) as usize;
            if self.pages.get(page).map(|p| p.class) != Some(class) {
                return Err(format!(
                    "bucket {off} of class {class} in a page of another class"
                ));
            }
            let u = (off / self.unit) as usize;
            if state[u] != 0 {
                return Err(format!("bucket {off} held twice"));
            }
            state[u] = 1;
            per_page[page] += 1;
        }
        for (class, &head) in self.heads.iter().enumerate() {
            let mut u = head;
            let mut prev = NONE;
            while u != NONE {
                let off = u * self.unit;
                let page = (off / PAGE_BYTES) as usize;
                if self.pages[page].class != class as u8 {
                    return Err(format!("free bucket {off} listed under class {class}"));
                }
                if state[u as usize] != 0 {
                    return Err(format!("bucket {off} both free and held (or listed twice)"));
                }
                if self.prev[u as usize] != prev {
                    return Err(format!("broken back link at {off}"));
                }
                state[u as usize] = 2;
                prev = u;
                u = self.next[u as usize];
            }
        }
        for (i, page) in self.pages.iter().enumerate() {
            if page.class == FREE_PAGE {
                if per_page[i] != 0 {
                    return Err(format!("page {i} is free but holds buckets"));
                }
                continue;
            }
            if page.used != per_page[i] || page.used == 0 {
                return Err(format!(
                    "page {i}: count {} but {} held",
                    page.used, per_page[i]
                ));
            }
            let size = self.sizes.size(page.class);
            let base = i as u32 * PAGE_BYTES;
            for b in (base..base + PAGE_BYTES).step_by(size as usize) {
                if state[(b / self.unit) as usize] == 0 {
                    return Err(format!("bucket {b} leaked: neither held nor free"));
                }
            }
        }
        if self.used_buckets != held.len() as u64 {
            return Err(format!(
                "{} buckets counted, {} held",
                self.used_buckets,
                held.len()
            ));
        }
        let free_pages: std::collections::HashSet<_> = self.free_pages.iter().collect();
        let free_count = self.pages.iter().filter(|p| p.class == FREE_PAGE).count();
        if free_pages.len() != self.free_pages.len() || free_count != self.free_pages.len() {
            return Err("free page list does not match free pages".into());
        }
        Ok(())
    }
}

/// One worker's brick slots, chunk by chunk, with a free list that recycles removed bricks.
#[derive(Debug, Default)]
pub struct BrickPool {
    bricks: Vec<Brick>,
    chunk_ids: Vec<u32>,
    free: Vec<u32>,
}

impl BrickPool {
    /// Takes a slot (recycled when one is free).
    pub fn alloc(&mut self, counters: &ChunkCounters) -> Result<u32> {
        if self.free.is_empty() {
            let id = ChunkCounters::claim(&counters.bricks, counters.brick_limit, "brick")?;
            let first = self.bricks.len() as u32;
            self.chunk_ids.push(id);
            self.bricks
                .resize(self.bricks.len() + BRICK_CHUNK as usize, Brick::default());
            self.free.extend((first..first + BRICK_CHUNK).rev());
        }
        Ok(self.free.pop().expect("just refilled"))
    }
    /// Returns a slot.
    pub fn free(&mut self, slot: u32) {
        self.free.push(slot);
    }
    /// Global brick index of a local slot.
    #[inline]
    pub fn global(&self, slot: u32) -> u32 {
        self.chunk_ids[(slot / BRICK_CHUNK) as usize] * BRICK_CHUNK + slot % BRICK_CHUNK
    }
    /// The brick in a slot.
    #[inline]
    pub fn get(&self, slot: u32) -> &Brick {
        &self.bricks[slot as usize]
    }
    /// The brick in a slot, mutably.
    #[inline]
    pub fn get_mut(&mut self, slot: u32) -> &mut Brick {
        &mut self.bricks[slot as usize]
    }
    /// Slots in use.
    pub fn used(&self) -> usize {
        self.bricks.len() - self.free.len()
    }
    /// Slots reserved.
    pub fn reserved(&self) -> usize {
        self.bricks.len()
    }
    /// Global chunk ids owned, in local order.
    pub fn chunk_ids(&self) -> &[u32] {
        &self.chunk_ids
    }
    /// All local bricks.
    pub fn bricks(&self) -> &[Brick] {
        &self.bricks
    }
    /// Free slots (for validation).
    pub fn free_slots(&self) -> &[u32] {
        &self.free
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_reclaim_pages_and_never_overlap() {
        let counters = ChunkCounters::default();
        let mut b = MaterialBuckets::new(BucketSizes::default());
        let mut held = Vec::new();
        for i in 0..200u32 {
            // 50 buckets of each size: 48 KiB, one chunk.
            let class = (i % 4) as u8;
            held.push((b.alloc(class, &counters).unwrap(), class));
        }
        b.validate(&held).unwrap();
        for (off, class) in held.drain(..).rev() {
            b.free(off, class);
        }
        b.validate(&held).unwrap();
        assert_eq!(b.bytes_in_use(), 0, "every page is free again");
        assert_eq!(counters.material_chunks(), 1);
    }

    #[test]
    fn sizes_validate() {
        assert!(BucketSizes::new(vec![64, 128, 256, 512]).is_ok());
        assert!(BucketSizes::new(vec![32, 512]).is_ok());
        assert!(BucketSizes::new(vec![64, 256]).is_err());
        assert!(BucketSizes::new(vec![100, 512]).is_err());
        assert!(BucketSizes::new(vec![]).is_err());
        let s = BucketSizes::default();
        assert_eq!(s.class_for(1), 0);
        assert_eq!(s.class_for(65), 1);
        assert_eq!(s.class_for(512), 3);
        assert!(s.keeps(3, 128) && !s.keeps(3, 127) && s.keeps(0, 1));
    }
}
