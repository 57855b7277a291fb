//! The slab's invariants checked from scratch (tests and the model test's every step):
//! index ↔ slots, the free list, coarse counts and bits, the solid count, bucket accounting.

use super::*;

impl Slab {
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
