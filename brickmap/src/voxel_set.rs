//! `VoxelSet`: a sparse set of voxels as one 512-bit mask per touched brick (a selection, the
//! region a tool is limited to). Edits take it as a shape (`Shape::Set`, `Shape::Within`), so
//! the workers apply it brick by brick like any brush.

use crate::brick::Mask;
use glam::{IVec3, UVec3};
use std::collections::BTreeMap;

/// Voxels, by brick. Bricks whose mask would be empty are never stored.
#[derive(Clone, Debug, Default)]
pub struct VoxelSet {
    /// Brick coordinate (x, y, z) → the voxels of that brick in the set.
    bricks: BTreeMap<(u32, u32, u32), Mask>,
    /// The bounds, computed once after the last change (every worker of an edit asks).
    bounds: std::sync::OnceLock<Option<(IVec3, IVec3)>>,
}

impl PartialEq for VoxelSet {
    fn eq(&self, other: &Self) -> bool {
        // The same voxels, whether or not either has computed its bounds yet.
        self.bricks == other.bricks
    }
}

impl Eq for VoxelSet {}

/// The voxels of the brick whose minimum voxel is `brick_min` that lie in the inclusive box
/// `lo..=hi`, built a row at a time.
pub fn box_mask(brick_min: IVec3, lo: IVec3, hi: IVec3) -> Mask {
    let l = (lo - brick_min).max(IVec3::ZERO);
    let h = (hi - brick_min).min(IVec3::splat(7));
    let mut m = Mask::EMPTY;
    if l.cmpgt(h).any() {
        return m;
    }
    let row = ((1u32 << (h.x - l.x + 1)) - 1) << l.x;
    for z in l.z..=h.z {
        for y in l.y..=h.y {
            let bit = (8 * y + 64 * z) as usize;
            m.0[bit >> 5] |= row << (bit & 31);
        }
    }
    m
}

impl VoxelSet {
    /// The empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Whether no voxel is in the set.
    pub fn is_empty(&self) -> bool {
        self.bricks.is_empty()
    }

    /// Voxels in the set.
    pub fn count(&self) -> u64 {
        self.bricks.values().map(|m| m.count() as u64).sum()
    }

    /// Bricks with at least one voxel in the set.
    pub fn brick_count(&self) -> usize {
        self.bricks.len()
    }

    /// The voxels of brick `b` in the set.
    #[inline]
    pub fn brick(&self, b: UVec3) -> Mask {
        self.bricks
            .get(&(b.x, b.y, b.z))
            .copied()
            .unwrap_or(Mask::EMPTY)
    }

    /// Whether voxel `v` is in the set.
    pub fn contains(&self, v: IVec3) -> bool {
        if v.cmplt(IVec3::ZERO).any() {
            return false;
        }
        let b = (v / 8).as_uvec3();
        let l = v - (v / 8) * 8;
        self.brick(b).get(crate::brick::voxel_bit(l.x, l.y, l.z))
    }

    /// The bricks and their masks, in (x, y, z) order.
    pub fn iter(&self) -> impl Iterator<Item = (UVec3, &Mask)> + '_ {
        self.bricks
            .iter()
            .map(|(&(x, y, z), m)| (UVec3::new(x, y, z), m))
    }

    /// Every voxel of the set, brick by brick.
    pub fn voxels(&self) -> impl Iterator<Item = IVec3> + '_ {
        self.iter().flat_map(|(b, m)| {
            let base = b.as_ivec3() * 8;
            m.ones().map(move |bit| {
                base + IVec3::new((bit % 8) as i32, (bit / 8 % 8) as i32, (bit / 64) as i32)
            })
        })
    }

    /// Adds one voxel (outside the largest grid's range: ignored).
    pub fn insert(&mut self, v: IVec3) {
        self.apply_box(v, v, v + 1, false);
    }

    /// How many pieces the set is in, voxels touching by a face, edge or corner (26-connected)
    /// belonging to the same piece.
    pub fn components(&self) -> usize {
        let mut seen = std::collections::HashSet::new();
        let mut count = 0;
        for start in self.voxels() {
            if !seen.insert(start) {
                continue;
            }
            count += 1;
            let mut stack = vec![start];
            while let Some(v) = stack.pop() {
                for d in 0..27 {
                    let n = v + IVec3::new(d % 3 - 1, d / 3 % 3 - 1, d / 9 - 1);
                    if self.contains(n) && seen.insert(n) {
                        stack.push(n);
                    }
                }
            }
        }
        count
    }

    /// Replaces the mask of brick `b` (an empty mask removes it).
    pub fn set_brick(&mut self, b: UVec3, mask: Mask) {
        self.bounds = Default::default();
        if mask.is_empty() {
            self.bricks.remove(&(b.x, b.y, b.z));
        } else {
            self.bricks.insert((b.x, b.y, b.z), mask);
        }
    }

    /// Adds (or, with `remove`, takes away) the voxels of the inclusive box `lo..=hi` that lie
    /// in a grid of `voxels` voxels.
    pub fn apply_box(&mut self, lo: IVec3, hi: IVec3, voxels: IVec3, remove: bool) {
        let lo = lo.max(IVec3::ZERO);
        let hi = hi.min(voxels - 1);
        if lo.cmpgt(hi).any() {
            return;
        }
        let (blo, bhi) = (lo / 8, hi / 8);
        for x in blo.x..=bhi.x {
            for y in blo.y..=bhi.y {
                for z in blo.z..=bhi.z {
                    let b = IVec3::new(x, y, z);
                    let m = box_mask(b * 8, lo, hi);
                    let b = b.as_uvec3();
                    let old = self.brick(b);
                    self.set_brick(b, if remove { old.and_not(&m) } else { old.or(&m) });
                }
            }
        }
    }

    /// Inclusive voxel bounds of the set, or None when it is empty.
    pub fn bounds(&self) -> Option<(IVec3, IVec3)> {
        *self.bounds.get_or_init(|| {
            let mut out: Option<(IVec3, IVec3)> = None;
            for (b, m) in self.iter() {
                // From the mask's rows of 8 voxels: x from the union of the rows, y and z
                // from which rows hold anything.
                let (mut xs, mut lo, mut hi) = (0u32, IVec3::splat(8), IVec3::splat(-1));
                for z in 0..8 {
                    for y in 0..8 {
                        let row = (m.0[2 * z + y / 4] >> (8 * (y & 3))) & 0xFF;
                        if row != 0 {
                            xs |= row;
                            let (y, z) = (y as i32, z as i32);
                            (lo.y, hi.y) = (lo.y.min(y), hi.y.max(y));
                            (lo.z, hi.z) = (lo.z.min(z), hi.z.max(z));
                        }
                    }
                }
                (lo.x, hi.x) = (xs.trailing_zeros() as i32, 31 - xs.leading_zeros() as i32);
                let min = b.as_ivec3() * 8;
                let (lo, hi) = (min + lo, min + hi);
                out = Some(match out {
                    None => (lo, hi),
                    Some((a, b)) => (a.min(lo), b.max(hi)),
                });
            }
            out
        })
    }
}

/// Set operations, brick by brick (a selection's magic wand, invert, grow and shrink).
impl VoxelSet {
    /// The voxels of either set.
    pub fn union(&self, o: &VoxelSet) -> VoxelSet {
        let mut out = self.clone();
        for (&(x, y, z), m) in &o.bricks {
            let b = UVec3::new(x, y, z);
            out.set_brick(b, out.brick(b).or(m));
        }
        out
    }

    /// The voxels of this set that are not in `o`.
    pub fn difference(&self, o: &VoxelSet) -> VoxelSet {
        let mut out = VoxelSet::new();
        for (b, m) in self.iter() {
            out.set_brick(b, m.and_not(&o.brick(b)));
        }
        out
    }

    /// The voxels in both sets.
    pub fn intersection(&self, o: &VoxelSet) -> VoxelSet {
        let mut out = VoxelSet::new();
        for (b, m) in self.iter() {
            out.set_brick(b, m.and(&o.brick(b)));
        }
        out
    }

    /// The voxels of a grid of `voxels` not in the set.
    pub fn complement(&self, voxels: IVec3) -> VoxelSet {
        let mut all = VoxelSet::new();
        all.apply_box(IVec3::ZERO, voxels - 1, voxels, false);
        all.difference(self)
    }

    /// The set moved by `offset`; voxels that land below 0 on an axis are dropped.
    pub fn shifted(&self, offset: IVec3) -> VoxelSet {
        let whole = offset.div_euclid(IVec3::splat(8));
        let r = offset.rem_euclid(IVec3::splat(8));
        let mut out = VoxelSet::new();
        for (b, m) in self.iter() {
            // The source brick's part that lands in each of the (up to) 8 target bricks.
            for k in 0..8 {
                let k = IVec3::new(k & 1, k >> 1 & 1, k >> 2);
                if (k.cmpeq(IVec3::ONE) & r.cmpeq(IVec3::ZERO)).any() {
                    continue;
                }
                let t = b.as_ivec3() + whole + k;
                if t.cmplt(IVec3::ZERO).any() {
                    continue;
                }
                let part = m.shifted(r - 8 * k);
                if !part.is_empty() {
                    let t = t.as_uvec3();
                    out.set_brick(t, out.brick(t).or(&part));
                }
            }
        }
        out
    }

    /// The set and every voxel sharing a face with it, inside a grid of `voxels`.
    pub fn grown(&self, voxels: IVec3) -> VoxelSet {
        let mut out = self.clone();
        for d in FACES {
            out = out.union(&self.shifted(d));
        }
        out.intersection(&VoxelSet::new().complement(voxels))
    }

    /// The voxels of the set whose six face neighbours are all in it.
    pub fn shrunk(&self) -> VoxelSet {
        let mut out = self.clone();
        for d in FACES {
            out = out.intersection(&self.shifted(d));
        }
        out
    }
}

/// The six face directions (a voxel's face neighbours are it plus each).
pub const FACES: [IVec3; 6] = [
    IVec3::X,
    IVec3::NEG_X,
    IVec3::Y,
    IVec3::NEG_Y,
    IVec3::Z,
    IVec3::NEG_Z,
];

#[cfg(test)]
mod tests {
    use super::*;

    /// A few scattered voxels and a block across brick sides.
    fn sample() -> VoxelSet {
        let mut s = VoxelSet::new();
        s.apply_box(
            IVec3::new(5, 6, 7),
            IVec3::new(12, 9, 17),
            IVec3::splat(64),
            false,
        );
        for v in [IVec3::ZERO, IVec3::new(31, 0, 8), IVec3::new(8, 40, 63)] {
            s.insert(v);
        }
        s
    }

    #[test]
    fn set_operations_agree_with_voxel_by_voxel_ones() {
        let grid = IVec3::splat(64);
        let a = sample();
        let b = a.shifted(IVec3::new(3, -2, 9));
        let has = |s: &VoxelSet, v: IVec3| s.contains(v);
        let (u, d, i, c) = (
            a.union(&b),
            a.difference(&b),
            a.intersection(&b),
            a.complement(grid),
        );
        let (g, k) = (a.grown(grid), a.shrunk());
        let faces = |v: IVec3| FACES.map(|f| v + f);
        for x in -1..66 {
            for y in -1..66 {
                for z in -1..66 {
                    let v = IVec3::new(x, y, z);
                    let inside = v.cmpge(IVec3::ZERO).all() && v.cmplt(grid).all();
                    let from = v - IVec3::new(3, -2, 9);
                    assert_eq!(
                        has(&b, v),
                        from.cmpge(IVec3::ZERO).all() && has(&a, from),
                        "{v}"
                    );
                    assert_eq!(has(&u, v), has(&a, v) || has(&b, v));
                    assert_eq!(has(&d, v), has(&a, v) && !has(&b, v));
                    assert_eq!(has(&i, v), has(&a, v) && has(&b, v));
                    assert_eq!(has(&c, v), inside && !has(&a, v));
                    let near = has(&a, v) || faces(v).iter().any(|n| has(&a, *n));
                    assert_eq!(has(&g, v), inside && near, "grown at {v}");
                    let deep = has(&a, v) && faces(v).iter().all(|n| has(&a, *n));
                    assert_eq!(has(&k, v), deep, "shrunk at {v}");
                }
            }
        }
        assert_eq!(b.shifted(IVec3::new(-3, 2, -9)).difference(&a).count(), 0);
        assert!(k.count() > 0 && g.count() > a.count());
    }

    #[test]
    fn components_count_pieces_touching_by_corners_across_bricks() {
        let mut s = VoxelSet::new();
        assert_eq!(s.components(), 0);
        // A diagonal run across a brick corner: corner contacts join it.
        for k in 5..12 {
            s.insert(IVec3::splat(k));
        }
        assert_eq!(s.components(), 1);
        assert_eq!(s.voxels().count(), 7);
        // A gap of one voxel makes a second piece; filling it joins them.
        s.insert(IVec3::new(13, 12, 13));
        assert_eq!(s.components(), 2);
        s.insert(IVec3::new(12, 12, 12));
        assert_eq!(s.components(), 1);
        let mut all: Vec<IVec3> = s.voxels().collect();
        all.sort_by_key(|v| (v.x, v.y, v.z));
        assert_eq!(all[0], IVec3::splat(5));
        assert_eq!(all[all.len() - 1], IVec3::new(13, 12, 13));
    }

    #[test]
    fn box_masks_match_the_voxel_test() {
        let boxes = [
            (IVec3::new(3, 1, 5), IVec3::new(20, 17, 9)),
            (IVec3::new(8, 8, 8), IVec3::new(15, 15, 15)),
            (IVec3::new(-4, 2, 0), IVec3::new(0, 2, 30)),
        ];
        for (lo, hi) in boxes {
            for b in 0..27 {
                let min = IVec3::new(b % 3, b / 3 % 3, b / 9) * 8;
                let mut want = Mask::EMPTY;
                for i in 0..512 {
                    let v = min + IVec3::new(i % 8, i / 8 % 8, i / 64);
                    if v.cmpge(lo).all() && v.cmple(hi).all() {
                        want.set(i as usize);
                    }
                }
                assert_eq!(box_mask(min, lo, hi), want, "{lo} {hi} at {min}");
            }
        }
    }

    #[test]
    fn boxes_add_and_subtract_exactly() {
        let grid = IVec3::new(32, 16, 32);
        let mut s = VoxelSet::new();
        s.apply_box(IVec3::new(2, 2, 2), IVec3::new(20, 9, 11), grid, false);
        s.apply_box(IVec3::new(5, -3, 5), IVec3::new(40, 4, 6), grid, true);
        let mut count = 0;
        for x in -2..34 {
            for y in -2..18 {
                for z in -2..34 {
                    let v = IVec3::new(x, y, z);
                    let inside = |lo: IVec3, hi: IVec3| v.cmpge(lo).all() && v.cmple(hi).all();
                    let want = inside(IVec3::new(2, 2, 2), IVec3::new(20, 9, 11))
                        && !inside(IVec3::new(5, -3, 5), IVec3::new(40, 4, 6));
                    assert_eq!(s.contains(v), want, "{v}");
                    count += want as u64;
                }
            }
        }
        assert_eq!(s.count(), count);
        assert_eq!(
            s.bounds(),
            Some((IVec3::new(2, 2, 2), IVec3::new(20, 9, 11)))
        );
        s.apply_box(IVec3::ZERO, grid, grid, true);
        assert!(s.is_empty() && s.bounds().is_none());
    }
}
