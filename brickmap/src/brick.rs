//! One 8×8×8 brick as the GPU reads it: a 512-bit occupancy mask and one material word.
//!
//! Bit order: voxel (x, y, z), each in 0..8, has linear index `i = x + 8·y + 64·z`; it is bit
//! `i % 32` of `mask[i / 32]`. Material bytes of a non-uniform brick are stored in that order
//! for solid voxels only, so a voxel's slot is the number of set bits before it (its rank).

use bytemuck::{Pod, Zeroable};

/// Voxels along one brick edge.
pub const BRICK_EDGE: i32 = 8;
/// Voxels in one brick.
pub const BRICK_VOXELS: usize = 512;
/// Set in [`Brick::material`] when every solid voxel of the brick uses one material; the low
/// 8 bits are then that material index and the brick owns no material bytes.
pub const UNIFORM_FLAG: u32 = 1 << 31;

/// Linear index of a voxel inside its brick (coordinates in 0..8).
#[inline]
pub fn voxel_bit(x: i32, y: i32, z: i32) -> usize {
    debug_assert!((0..8).contains(&x) && (0..8).contains(&y) && (0..8).contains(&z));
    (x + 8 * y + 64 * z) as usize
}

/// The 512-bit occupancy mask of a brick. Keep in sync with `Brick.mask` in the shaders.
#[repr(transparent)]
#[derive(Clone, Copy, PartialEq, Eq, Hash, Pod, Zeroable, Default)]
pub struct Mask(pub [u32; 16]);

impl std::fmt::Debug for Mask {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Mask({} set)", self.count())
    }
}

impl Mask {
    /// No voxel set.
    pub const EMPTY: Mask = Mask([0; 16]);
    /// Every voxel set.
    pub const FULL: Mask = Mask([u32::MAX; 16]);

    /// Whether voxel `i` is set.
    #[inline]
    pub fn get(&self, i: usize) -> bool {
        self.0[i >> 5] >> (i & 31) & 1 != 0
    }
    /// Sets voxel `i`.
    #[inline]
    pub fn set(&mut self, i: usize) {
        self.0[i >> 5] |= 1 << (i & 31);
    }
    /// Clears voxel `i`.
    #[inline]
    pub fn clear(&mut self, i: usize) {
        self.0[i >> 5] &= !(1 << (i & 31));
    }
    /// The mask moved by `o` voxels (each component in −7..=7): voxel v is set in the result
    /// where v − o is set here; voxels moved past the brick's sides are dropped.
    pub fn shifted(&self, o: glam::IVec3) -> Mask {
        debug_assert!(o.abs().max_element() < 8);
        // A z-slice is one u64 (bit x + 8·y); x keeps to its row: after the shift only the
        // bits whose new x lies in 0..8 are kept, per byte.
        let keep = if o.x >= 0 {
            (0xffu64 << o.x) & 0xff
        } else {
            0xffu64 >> -o.x
        } * 0x0101_0101_0101_0101;
        let mut out = Mask::EMPTY;
        for z in 0..8i32 {
            let to = z + o.z;
            if !(0..8).contains(&to) {
                continue;
            }
            let (lo, hi) = (self.0[2 * z as usize], self.0[2 * z as usize + 1]);
            let mut slice = u64::from(lo) | (u64::from(hi) << 32);
            if slice == 0 {
                continue;
            }
            slice = if o.x >= 0 {
                slice << o.x
            } else {
                slice >> -o.x
            } & keep;
            slice = if o.y >= 0 {
                slice << (8 * o.y)
            } else {
                slice >> (8 * -o.y)
            };
            out.0[2 * to as usize] = slice as u32;
            out.0[2 * to as usize + 1] = (slice >> 32) as u32;
        }
        out
    }
    /// Number of set voxels.
    #[inline]
    pub fn count(&self) -> u32 {
        self.0.iter().map(|w| w.count_ones()).sum()
    }
    /// Number of set voxels before voxel `i`: the slot of voxel `i` in popcount order.
    #[inline]
    pub fn rank(&self, i: usize) -> usize {
        let word = i >> 5;
        let below: u32 = self.0[..word].iter().map(|w| w.count_ones()).sum();
        let partial = self.0[word] & ((1u32 << (i & 31)) - 1);
        (below + partial.count_ones()) as usize
    }
    /// No voxel set.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.0.iter().all(|&w| w == 0)
    }
    /// All voxels set.
    #[inline]
    pub fn is_full(&self) -> bool {
        self.0.iter().all(|&w| w == u32::MAX)
    }
    /// Bitwise and.
    #[inline]
    pub fn and(&self, o: &Mask) -> Mask {
        Mask(std::array::from_fn(|i| self.0[i] & o.0[i]))
    }
    /// Bitwise or.
    #[inline]
    pub fn or(&self, o: &Mask) -> Mask {
        Mask(std::array::from_fn(|i| self.0[i] | o.0[i]))
    }
    /// `self & !o`.
    #[inline]
    pub fn and_not(&self, o: &Mask) -> Mask {
        Mask(std::array::from_fn(|i| self.0[i] & !o.0[i]))
    }
    /// Indices of the set voxels, ascending (popcount order).
    pub fn ones(&self) -> impl Iterator<Item = usize> + '_ {
        self.0.iter().enumerate().flat_map(|(w, &bits)| {
            let mut b = bits;
            std::iter::from_fn(move || {
                if b == 0 {
                    return None;
                }
                let t = b.trailing_zeros() as usize;
                b &= b - 1;
                Some(w * 32 + t)
            })
        })
    }
}

/// A brick as stored in the GPU brick buffer (68 bytes). Keep in sync with `struct Brick` in
/// `shaders/brickmap.glsl`.
#[repr(C)]
#[derive(Clone, Copy, PartialEq, Eq, Pod, Zeroable, Default, Debug)]
pub struct Brick {
    /// Occupancy, bit order as in the module docs.
    pub mask: Mask,
    /// [`UNIFORM_FLAG`] set: low 8 bits are the material index of every solid voxel.
    /// Clear: global byte offset of this brick's first material byte in the material buffer.
    pub material: u32,
}
const _: () = assert!(std::mem::size_of::<Brick>() == 68);

impl Brick {
    /// Whether every solid voxel shares one material stored in the word itself.
    #[inline]
    pub fn is_uniform(&self) -> bool {
        self.material & UNIFORM_FLAG != 0
    }
}

/// The materials of one brick, borrowed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BrickMaterials<'a> {
    /// Every solid voxel has this material.
    Uniform(u8),
    /// One material per solid voxel, in popcount order.
    PerVoxel(&'a [u8]),
}

impl BrickMaterials<'_> {
    /// The material of the brick's `k`-th solid voxel (popcount order).
    #[inline]
    pub fn at(&self, k: usize) -> u8 {
        match self {
            BrickMaterials::Uniform(m) => *m,
            BrickMaterials::PerVoxel(v) => v[k],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shifted_mask_moves_every_voxel_and_drops_those_past_the_sides() {
        let mut state = 0x1234_5678_9abc_def1u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..300 {
            let mut m = Mask::EMPTY;
            for w in &mut m.0 {
                *w = next() as u32 & next() as u32;
            }
            let o = glam::IVec3::new(
                (next() % 15) as i32 - 7,
                (next() % 15) as i32 - 7,
                (next() % 15) as i32 - 7,
            );
            let got = m.shifted(o);
            for z in 0..8 {
                for y in 0..8 {
                    for x in 0..8 {
                        let from = glam::IVec3::new(x, y, z) - o;
                        let want = from.cmpge(glam::IVec3::ZERO).all()
                            && from.cmplt(glam::IVec3::splat(8)).all()
                            && m.get(voxel_bit(from.x, from.y, from.z));
                        assert_eq!(got.get(voxel_bit(x, y, z)), want, "{o} at {x} {y} {z}");
                    }
                }
            }
        }
    }

    #[test]
    fn rank_counts_bits_before() {
        let mut m = Mask::EMPTY;
        for i in [0, 5, 31, 32, 33, 200, 511] {
            m.set(i);
        }
        assert_eq!(m.rank(0), 0);
        assert_eq!(m.rank(5), 1);
        assert_eq!(m.rank(32), 3);
        assert_eq!(m.rank(511), 6);
        assert_eq!(m.count(), 7);
        assert_eq!(
            m.ones().collect::<Vec<_>>(),
            vec![0, 5, 31, 32, 33, 200, 511]
        );
        m.clear(33);
        assert!(!m.get(33) && m.get(32));
    }

    #[test]
    fn bit_order_is_x_fastest() {
        assert_eq!(voxel_bit(1, 0, 0), 1);
        assert_eq!(voxel_bit(0, 1, 0), 8);
        assert_eq!(voxel_bit(0, 0, 1), 64);
        assert_eq!(voxel_bit(7, 7, 7), 511);
    }
}
