//! Grid dimensions and the layouts of the dense GPU-visible grids (brick indices, coarse
//! occupancy), plus the split of the grid into per-worker x-slabs.
//!
//! Both dense grids are laid out x-slowest: a worker that owns an x-slab owns a contiguous
//! range of each, and no 32-bit word of the coarse grid is shared by two slabs (coarse words
//! are padded per coarse x-column), so workers never write the same word.

use crate::error::{BrickmapError, Result};
use glam::{IVec3, UVec3};

/// Largest supported grid, in bricks along x.
pub const MAX_BRICKS_X: u32 = 512;
/// Largest supported grid, in bricks along y.
pub const MAX_BRICKS_Y: u32 = 128;
/// Largest supported grid, in bricks along z.
pub const MAX_BRICKS_Z: u32 = 512;
/// Bricks along one edge of a coarse occupancy cell.
pub const COARSE_BRICKS: u32 = 4;
/// Marks an empty cell of the brick-index grid.
pub const EMPTY_BRICK: u32 = u32::MAX;
/// Brick-index values `FULL_BRICK_BASE | m` (m in 0..256) mark a cell whose 512 voxels are
/// all solid with material m. No brick is stored for it: interior bricks of solid terrain
/// cost 4 bytes instead of 72, and a ray entering one hits without reading a mask.
pub const FULL_BRICK_BASE: u32 = 0xFFFF_FE00;

/// Grid size in bricks, validated against the supported maximum.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct GridDims {
    bricks: UVec3,
}

impl GridDims {
    /// A grid of `x × y × z` bricks (each brick 8³ voxels).
    pub fn new(x: u32, y: u32, z: u32) -> Result<Self> {
        let ok = (1..=MAX_BRICKS_X).contains(&x)
            && (1..=MAX_BRICKS_Y).contains(&y)
            && (1..=MAX_BRICKS_Z).contains(&z);
        if !ok {
            return Err(BrickmapError::GridSize {
                x,
                y,
                z,
                max: [MAX_BRICKS_X, MAX_BRICKS_Y, MAX_BRICKS_Z],
            });
        }
        Ok(Self {
            bricks: UVec3::new(x, y, z),
        })
    }

    /// The smallest grid that holds `voxels` voxels per axis.
    pub fn from_voxels(voxels: UVec3) -> Result<Self> {
        let b = (voxels + UVec3::splat(7)) / 8;
        Self::new(b.x, b.y, b.z)
    }

    /// Size in bricks.
    pub fn bricks(&self) -> UVec3 {
        self.bricks
    }
    /// Size in voxels.
    pub fn voxels(&self) -> IVec3 {
        (self.bricks * 8).as_ivec3()
    }
    /// Number of brick cells.
    pub fn brick_cells(&self) -> usize {
        (self.bricks.x * self.bricks.y * self.bricks.z) as usize
    }
    /// Size of the coarse grid in coarse cells (4³ bricks each).
    pub fn coarse(&self) -> UVec3 {
        (self.bricks + UVec3::splat(COARSE_BRICKS - 1)) / COARSE_BRICKS
    }
    /// 32-bit words per coarse x-column (one column = all coarse cells with one x).
    pub fn coarse_words_per_column(&self) -> usize {
        let c = self.coarse();
        (c.y * c.z).div_ceil(32) as usize
    }
    /// Total 32-bit words of the coarse grid.
    pub fn coarse_words(&self) -> usize {
        self.coarse().x as usize * self.coarse_words_per_column()
    }

    /// Whether a voxel coordinate lies inside the grid.
    pub fn contains_voxel(&self, v: IVec3) -> bool {
        v.cmpge(IVec3::ZERO).all() && v.cmplt(self.voxels()).all()
    }

    /// Index of a brick cell in the brick-index grid: `(bx·Z + bz)·Y + by` (x slowest).
    #[inline]
    pub fn cell_index(&self, b: UVec3) -> usize {
        ((b.x * self.bricks.z + b.z) * self.bricks.y + b.y) as usize
    }
    /// Inverse of [`GridDims::cell_index`].
    pub fn cell_coord(&self, i: usize) -> UVec3 {
        let i = i as u32;
        let y = i % self.bricks.y;
        let rest = i / self.bricks.y;
        UVec3::new(rest / self.bricks.z, y, rest % self.bricks.z)
    }
    /// Word and bit of a coarse cell in the coarse grid.
    #[inline]
    pub fn coarse_bit(&self, c: UVec3) -> (usize, u32) {
        let cd = self.coarse();
        let within = c.z * cd.y + c.y;
        (
            c.x as usize * self.coarse_words_per_column() + (within / 32) as usize,
            within % 32,
        )
    }
}

/// The bricks and coarse columns one worker owns: a contiguous range of brick x-coordinates,
/// aligned to coarse cells so a coarse cell never spans two workers.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SlabBounds {
    /// Brick x-coordinates owned.
    pub bricks_x: std::ops::Range<u32>,
    /// Coarse x-columns owned.
    pub coarse_x: std::ops::Range<u32>,
}

impl SlabBounds {
    /// Splits the grid into at most `workers` slabs of nearly equal coarse width (fewer when
    /// the grid has fewer coarse columns than workers).
    pub fn split(dims: &GridDims, workers: usize) -> Vec<SlabBounds> {
        let columns = dims.coarse().x as usize;
        let n = workers.clamp(1, columns);
        (0..n)
            .map(|w| {
                let c0 = (w * columns / n) as u32;
                let c1 = ((w + 1) * columns / n) as u32;
                SlabBounds {
                    bricks_x: c0 * COARSE_BRICKS..(c1 * COARSE_BRICKS).min(dims.bricks().x),
                    coarse_x: c0..c1,
                }
            })
            .collect()
    }
    /// Brick cells of this slab, as a range of the brick-index grid.
    pub fn cells(&self, dims: &GridDims) -> std::ops::Range<usize> {
        let per_x = (dims.bricks().y * dims.bricks().z) as usize;
        self.bricks_x.start as usize * per_x..self.bricks_x.end as usize * per_x
    }
    /// Words of this slab in the coarse grid.
    pub fn coarse_words(&self, dims: &GridDims) -> std::ops::Range<usize> {
        let per = dims.coarse_words_per_column();
        self.coarse_x.start as usize * per..self.coarse_x.end as usize * per
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_sizes() {
        assert!(GridDims::new(0, 1, 1).is_err());
        assert!(GridDims::new(513, 1, 1).is_err());
        assert!(GridDims::new(1, 129, 1).is_err());
        assert!(GridDims::new(512, 128, 512).is_ok());
    }

    #[test]
    fn cell_index_round_trips() {
        let d = GridDims::new(5, 3, 7).unwrap();
        for i in 0..d.brick_cells() {
            assert_eq!(d.cell_index(d.cell_coord(i)), i);
        }
    }

    #[test]
    fn slabs_cover_grid_and_align_to_coarse() {
        let d = GridDims::new(37, 2, 3).unwrap();
        for n in 1..12 {
            let s = SlabBounds::split(&d, n);
            assert_eq!(s.first().unwrap().bricks_x.start, 0);
            assert_eq!(s.last().unwrap().bricks_x.end, 37);
            for w in s.windows(2) {
                assert_eq!(w[0].bricks_x.end, w[1].bricks_x.start);
                assert_eq!(w[0].bricks_x.end % COARSE_BRICKS, 0);
                assert!(!w[0].bricks_x.is_empty());
            }
        }
    }
}
