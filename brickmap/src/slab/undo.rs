//! What a slab's part of an edit records to put it back. Recorded edits (the ones history
//! keeps) get one [`BrickUndo`] per changed brick. A bulk write nobody will undo into (a new
//! scene, a load: [`crate::World::apply_unrecorded`]) records a brick written whole into an
//! empty cell as its position alone (16 bytes instead of a `BrickUndo`'s ~170), which is all
//! the rollback of a failed edit needs to clear it again. A 4096 × 1024 × 4096 terrain writes
//! ~16 M such bricks.

use crate::brick::Mask;
use crate::edit::{BrickUndo, PriorMaterials};
use glam::UVec3;

/// One slab's record of an edit, in the order its bricks were written.
#[derive(Default)]
pub(crate) struct Undo {
    /// Prior states of changed bricks.
    bricks: Vec<BrickUndo>,
    /// Compact only: bricks written whole into an empty cell, each with how many entries
    /// `bricks` had when it was written (its place in the writing order).
    cleared: Vec<(usize, UVec3)>,
    compact: bool,
}

impl Undo {
    /// An empty record; `compact` keeps whole-brick writes into empty cells as positions.
    pub(crate) fn new(compact: bool) -> Self {
        Self {
            compact,
            ..Self::default()
        }
    }

    /// A brick's prior state.
    pub(crate) fn push(&mut self, u: BrickUndo) {
        self.bricks.push(u);
    }

    /// A brick that was empty and was written whole.
    pub(crate) fn was_empty(&mut self, brick: UVec3) {
        if self.compact {
            self.cleared.push((self.bricks.len(), brick));
        } else {
            self.bricks.push(cleared(brick));
        }
    }

    /// Every brick the edit wrote (each once per write).
    pub(crate) fn bricks(&self) -> impl Iterator<Item = UVec3> + '_ {
        self.bricks
            .iter()
            .map(|u| u.brick)
            .chain(self.cleared.iter().map(|c| c.1))
    }

    /// Whole records kept (`BrickUndo`s; the compact positions not counted).
    pub(crate) fn records(&self) -> usize {
        self.bricks.len()
    }

    /// Nothing recorded.
    #[cfg(test)]
    pub(crate) fn is_empty(&self) -> bool {
        self.bricks.is_empty() && self.cleared.is_empty()
    }

    /// The record as the restores that put the slab back, in the order to apply them: the
    /// reverse of the writing order (a brick written twice in one edit — a restore naming it
    /// twice — is put back to its state before the first write, not the second).
    pub(crate) fn into_inverse(self) -> Vec<BrickUndo> {
        let mut out = self.into_ordered();
        out.reverse();
        out
    }

    /// The record as restores in writing order. Free when nothing was compact.
    fn into_ordered(self) -> Vec<BrickUndo> {
        if self.cleared.is_empty() {
            return self.bricks;
        }
        let mut out = Vec::with_capacity(self.bricks.len() + self.cleared.len());
        let mut cleared = self.cleared.into_iter().peekable();
        for (i, u) in self.bricks.into_iter().enumerate() {
            while let Some((_, b)) = cleared.next_if(|c| c.0 == i) {
                out.push(self::cleared(b));
            }
            out.push(u);
        }
        out.extend(cleared.map(|c| self::cleared(c.1)));
        out
    }
}

/// The restore that empties a brick written whole into an empty cell.
fn cleared(brick: UVec3) -> BrickUndo {
    BrickUndo {
        brick,
        prior_mask: Mask::EMPTY,
        touched: Mask::FULL,
        prior: PriorMaterials::PerVoxel(Vec::new()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn full(x: u32) -> BrickUndo {
        BrickUndo {
            brick: UVec3::new(x, 0, 0),
            prior_mask: Mask::FULL,
            touched: Mask::FULL,
            prior: PriorMaterials::Uniform(1),
        }
    }

    fn order(u: Undo) -> Vec<(u32, bool)> {
        let mut inverse = u.into_inverse();
        inverse.reverse();
        inverse
            .iter()
            .map(|b| (b.brick.x, b.prior_mask.is_empty()))
            .collect()
    }

    #[test]
    fn compact_and_full_records_give_the_same_writing_order() {
        let write = |compact| {
            let mut u = Undo::new(compact);
            u.was_empty(UVec3::new(0, 0, 0));
            u.push(full(1));
            u.was_empty(UVec3::new(2, 0, 0));
            u.was_empty(UVec3::new(3, 0, 0));
            u.push(full(4));
            u.was_empty(UVec3::new(5, 0, 0));
            u
        };
        let compact = write(true);
        assert_eq!(compact.bricks.len(), 2, "empty cells kept as positions");
        let expected = vec![
            (0, true),
            (1, false),
            (2, true),
            (3, true),
            (4, false),
            (5, true),
        ];
        assert_eq!(order(compact), expected);
        assert_eq!(order(write(false)), expected);
    }

    #[test]
    fn bricks_lists_every_write() {
        let mut u = Undo::new(true);
        assert!(u.is_empty());
        u.was_empty(UVec3::new(7, 0, 0));
        u.push(full(1));
        let mut b: Vec<u32> = u.bricks().map(|b| b.x).collect();
        b.sort();
        assert_eq!(b, vec![1, 7]);
    }
}
