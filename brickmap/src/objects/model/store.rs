//! A model's bricks: a dense index over the model's brick grid, in the world's cell order
//! (`GridDims::cell_index`: x, then z, then y fastest), as the world's own brick index is.
//! A cell is empty, full of one material (the index word alone, like the world's full
//! cells: most bricks inside a terrain), or a slot of a partly filled or many-material
//! brick. An empty index is allocated zeroed, so a large model that is mostly empty costs
//! pages only where it holds voxels; filling it from a world is a copy of each worker's
//! slab on its own thread ([`BrickStore::from_slabs`]).

use super::ModelBrick;
use glam::UVec3;

/// Index word: an empty cell.
const EMPTY: u32 = 0;
/// Index word flag: a full cell of material `word & 0xff`.
const FULL: u32 = 1 << 31;

/// The full one-material bricks, one per material: what a full cell reads as.
static FULL_BRICKS: [ModelBrick; 256] = {
    let mut all = [const { ModelBrick::full(0) }; 256];
    let mut m = 0;
    while m < 256 {
        // `replace` + `forget`: the old value (the same kind, no heap) is never dropped in a
        // constant.
        std::mem::forget(std::mem::replace(&mut all[m], ModelBrick::full(m as u8)));
        m += 1;
    }
    all
};

/// A model's bricks by brick coordinate.
#[derive(Clone)]
pub(super) struct BrickStore {
    /// Bricks per axis.
    dims: UVec3,
    /// Per cell: [`EMPTY`], [`FULL`] | material, or slot + 1.
    index: Vec<u32>,
    /// Partly filled or many-material bricks (a freed slot holds an empty brick until reused).
    slots: Vec<ModelBrick>,
    /// Freed slots.
    free: Vec<u32>,
}

impl BrickStore {
    /// No brick, over `dims` bricks.
    pub(super) fn new(dims: UVec3) -> Self {
        Self {
            dims,
            index: vec![EMPTY; (dims.x as usize) * (dims.y as usize) * (dims.z as usize)],
            slots: Vec::new(),
            free: Vec::new(),
        }
    }

    #[inline]
    fn cell(&self, b: UVec3) -> usize {
        debug_assert!(b.cmplt(self.dims).all(), "brick {b} outside {}", self.dims);
        ((b.x as usize * self.dims.z as usize) + b.z as usize) * self.dims.y as usize + b.y as usize
    }

    #[inline]
    fn coord(&self, i: usize) -> UVec3 {
        let y = (i % self.dims.y as usize) as u32;
        let rest = i / self.dims.y as usize;
        UVec3::new(
            (rest / self.dims.z as usize) as u32,
            y,
            (rest % self.dims.z as usize) as u32,
        )
    }

    #[inline]
    fn read(&self, word: u32) -> Option<&ModelBrick> {
        match word {
            EMPTY => None,
            w if w & FULL != 0 => Some(&FULL_BRICKS[(w & 0xff) as usize]),
            w => Some(&self.slots[w as usize - 1]),
        }
    }

    /// The brick at `b` (`None` where empty or outside).
    #[inline]
    pub(super) fn get(&self, b: UVec3) -> Option<&ModelBrick> {
        if b.cmpge(self.dims).any() {
            return None;
        }
        self.read(self.index[self.cell(b)])
    }

    /// Whether `b` holds voxels.
    #[inline]
    pub(super) fn contains(&self, b: UVec3) -> bool {
        b.cmplt(self.dims).all() && self.index[self.cell(b)] != EMPTY
    }

    /// Stores `brick` at `b` (inside the grid), replacing what was there.
    pub(super) fn insert(&mut self, b: UVec3, brick: ModelBrick) {
        let cell = self.cell(b);
        let word = self.index[cell];
        let reused = (word != EMPTY && word & FULL == 0).then_some(word);
        self.index[cell] = match (brick.mask.is_full(), brick.uniform()) {
            (true, Some(m)) => {
                if let Some(w) = reused {
                    self.release(w);
                }
                FULL | m as u32
            }
            _ => match reused {
                Some(w) => {
                    self.slots[w as usize - 1] = brick;
                    w
                }
                None => self.take_slot(brick),
            },
        };
    }

    /// Empties `b` (inside the grid).
    pub(super) fn remove(&mut self, b: UVec3) {
        let cell = self.cell(b);
        let word = std::mem::replace(&mut self.index[cell], EMPTY);
        if word != EMPTY && word & FULL == 0 {
            self.release(word);
        }
    }

    fn take_slot(&mut self, brick: ModelBrick) -> u32 {
        match self.free.pop() {
            Some(s) => {
                self.slots[s as usize] = brick;
                s + 1
            }
            None => {
                self.slots.push(brick);
                self.slots.len() as u32
            }
        }
    }

    fn release(&mut self, word: u32) {
        let s = word - 1;
        self.slots[s as usize] = ModelBrick::empty();
        self.free.push(s);
    }

    /// The non-empty bricks in cell order (x, then z, then y fastest).
    pub(super) fn iter(&self) -> impl Iterator<Item = (UVec3, &ModelBrick)> + '_ {
        self.index
            .iter()
            .enumerate()
            .filter(|(_, w)| **w != EMPTY)
            .map(|(i, w)| (self.coord(i), self.read(*w).expect("a non-empty cell")))
    }

    /// Bytes it takes: the index, the slots (with their per-voxel materials) and the free list.
    pub(super) fn bytes(&self) -> usize {
        self.index.len() * 4
            + self.slots.iter().map(ModelBrick::bytes).sum::<usize>()
            + self.free.len() * 4
    }

    /// A store over `dims` bricks filled from consecutive runs of cells, each on its own
    /// thread: `fill(run, index)` writes the run's index words (`Word`s) and returns the
    /// run's slots in the order its words name them.
    pub(super) fn from_runs(
        dims: UVec3,
        runs: &[std::ops::Range<usize>],
        fill: impl Fn(usize, &mut [u32], &mut Vec<ModelBrick>) + Sync,
    ) -> Self {
        let mut store = Self::new(dims);
        let mut parts: Vec<(usize, &mut [u32])> = Vec::with_capacity(runs.len());
        let mut rest = store.index.as_mut_slice();
        let mut at = 0;
        for (k, r) in runs.iter().enumerate() {
            debug_assert_eq!(r.start, at, "runs cover the cells in order");
            let (head, tail) = rest.split_at_mut(r.end - at);
            parts.push((k, head));
            rest = tail;
            at = r.end;
        }
        crate::census::adopted_on(parts.len());
        let fill = &fill;
        let filled: Vec<(Vec<ModelBrick>, &mut [u32])> = std::thread::scope(|s| {
            let handles: Vec<_> = parts
                .into_iter()
                .map(|(k, words)| {
                    s.spawn(move || {
                        let mut slots = Vec::new();
                        fill(k, words, &mut slots);
                        (slots, words)
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("model threads do not panic"))
                .collect()
        });
        // Each run's slot numbers start after the runs before it.
        let mut base = 0u32;
        let mut offsets = Vec::with_capacity(filled.len());
        for (slots, _) in &filled {
            offsets.push(base);
            base += slots.len() as u32;
        }
        let mut slots = Vec::with_capacity(base as usize);
        let mut fixes = Vec::with_capacity(filled.len());
        for ((part, words), offset) in filled.into_iter().zip(offsets) {
            slots.extend(part);
            fixes.push((words, offset));
        }
        std::thread::scope(|s| {
            for (words, offset) in fixes.into_iter().filter(|(_, o)| *o > 0) {
                s.spawn(move || {
                    for w in words.iter_mut().filter(|w| **w != EMPTY && **w & FULL == 0) {
                        *w += offset;
                    }
                });
            }
        });
        store.slots = slots;
        store
    }
}

/// What a run's filler writes into a cell's index word.
pub(super) struct Word;

impl Word {
    /// A full cell of one material.
    #[inline]
    pub(super) fn full(m: u8) -> u32 {
        FULL | m as u32
    }

    /// The brick just pushed onto the run's slots (`slots.len()` after the push).
    #[inline]
    pub(super) fn slot(len_after_push: usize) -> u32 {
        len_after_push as u32
    }
}

impl PartialEq for BrickStore {
    /// Equal bricks at equal cells (however the slots are numbered).
    fn eq(&self, other: &Self) -> bool {
        self.dims == other.dims && self.iter().eq(other.iter())
    }
}

impl Eq for BrickStore {}

impl std::fmt::Debug for BrickStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let full = self.index.iter().filter(|w| **w & FULL != 0).count();
        write!(
            f,
            "BrickStore({} bricks: {full} full, {} in slots)",
            self.dims,
            self.slots.len() - self.free.len()
        )
    }
}
