//! Edit operations, as submitted to the world, and their inverses.
//!
//! An inverse holds, per touched brick, the prior occupancy of exactly the touched voxels and
//! the prior materials of those that were solid (sparse, in popcount order): applying it
//! restores the prior content, and applying it returns the inverse of that in turn (redo).

use crate::brick::Mask;
use crate::error::{BrickmapError, Result};
use crate::material::MaterialTable;
use crate::shape::Shape;
use glam::{IVec3, UVec3};
use std::sync::Arc;

/// Produces whole brick columns: a terrain generator, a procedural scene. It must be a pure
/// function of its inputs (the world stays deterministic whatever the worker count); workers
/// call it in parallel, each for the columns of its own slab.
pub trait ColumnSource: Send + Sync {
    /// Calls `emit(by, mask, materials)` for every non-empty brick of column (bx, bz), with
    /// materials per set bit in popcount order (or one for all).
    fn column(&self, bx: u32, bz: u32, emit: &mut dyn FnMut(u32, Mask, PriorMaterials));
    /// Every material index it may emit (checked against the table before any worker runs).
    fn materials(&self) -> Vec<u8>;
}

/// A shared [`ColumnSource`]; equal when it is the same source.
#[derive(Clone)]
pub struct Generator(pub Arc<dyn ColumnSource>);

impl std::fmt::Debug for Generator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Generator(..)")
    }
}

impl PartialEq for Generator {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// What a shape edit does to the voxels inside the shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Make every voxel solid with this material (existing voxels take it too).
    Add(u8),
    /// Make every voxel empty.
    Remove,
    /// Give every solid voxel this material; empty voxels stay empty.
    Paint(u8),
}

/// One single-voxel write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum VoxelOp {
    /// Solid with a material.
    Set(u8),
    /// Empty.
    Clear,
    /// New material if solid.
    Paint(u8),
}

/// A single-voxel write at a position.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct VoxelEdit {
    /// Voxel coordinate (must lie in the grid).
    pub pos: IVec3,
    /// What to do there.
    pub op: VoxelOp,
}

/// An edit the world applies atomically (every brick or none, on success or error).
#[derive(Clone, Debug, PartialEq)]
pub enum EditOp {
    /// A shape with a mode; voxels outside the grid are clipped away.
    Shape {
        /// The region.
        shape: Shape,
        /// What happens inside it.
        mode: Mode,
    },
    /// A batch of single-voxel writes, applied in list order (a later write to the same
    /// voxel wins). Every position must lie in the grid.
    Voxels(Vec<VoxelEdit>),
    /// Puts back what an earlier edit changed (undo), or re-applies it (redo). With every
    /// voxel touched it is also the bulk write of whole bricks (`terrain::set_bricks`).
    Restore(EditInverse),
    /// Replaces every cell of the grid by what the generator emits (cells it leaves out
    /// become empty), generated on the workers.
    Generate(Generator),
}

/// Prior materials of the touched solid voxels of one brick.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PriorMaterials {
    /// The brick was uniform: every prior solid voxel had this material.
    Uniform(u8),
    /// One byte per voxel of `touched ∩ prior_mask`, in popcount order.
    PerVoxel(Vec<u8>),
}

/// The prior state of the touched voxels of one brick.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BrickUndo {
    /// Brick coordinate.
    pub brick: UVec3,
    /// Occupancy before the edit (only bits inside `touched` matter).
    pub prior_mask: Mask,
    /// Voxels the edit may have changed.
    pub touched: Mask,
    /// Their prior materials.
    pub prior: PriorMaterials,
}

impl PriorMaterials {
    /// Materials in popcount order, kept as one when they are all the same (or none).
    pub fn packed(held: Vec<u8>) -> Self {
        match held.first() {
            Some(&m) if held.iter().all(|x| *x == m) => PriorMaterials::Uniform(m),
            None => PriorMaterials::Uniform(0),
            _ => PriorMaterials::PerVoxel(held),
        }
    }
}

impl BrickUndo {
    /// The prior material of the `k`-th voxel of `touched ∩ prior_mask`.
    #[inline]
    pub fn prior_material(&self, k: usize) -> u8 {
        match &self.prior {
            PriorMaterials::Uniform(m) => *m,
            PriorMaterials::PerVoxel(v) => v[k],
        }
    }
}

/// Everything needed to undo an edit, sorted by brick cell (deterministic whatever the
/// worker count).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct EditInverse {
    /// One entry per touched brick.
    pub bricks: Vec<BrickUndo>,
}

impl EditInverse {
    /// Whether the edit changed nothing.
    pub fn is_empty(&self) -> bool {
        self.bricks.is_empty()
    }
    /// Heap bytes held (what an undo history pays for this step).
    pub fn heap_bytes(&self) -> usize {
        self.bricks.capacity() * std::mem::size_of::<BrickUndo>()
            + self
                .bricks
                .iter()
                .map(|b| match &b.prior {
                    PriorMaterials::Uniform(_) => 0,
                    PriorMaterials::PerVoxel(v) => v.capacity(),
                })
                .sum::<usize>()
    }
}

/// What an applied edit reports.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct EditOutcome {
    /// The inverse edit.
    pub inverse: EditInverse,
    /// Voxels whose occupancy or material changed.
    pub changed_voxels: u64,
}

/// Checks an edit against a table and a grid of `voxels` (a world's or a model's) before
/// anything changes: finite shapes, material indices in the table, single voxels and restored
/// bricks inside, restored materials counted right. Shapes are clipped, not refused.
pub(crate) fn validate(op: &EditOp, table: &MaterialTable, voxels: IVec3) -> Result<()> {
    let inside = |v: IVec3| v.cmpge(IVec3::ZERO).all() && v.cmplt(voxels).all();
    match op {
        EditOp::Shape { shape, mode } => {
            shape.validate()?;
            if let Shape::Voxel(v) = shape
                && !inside(*v)
            {
                return Err(BrickmapError::OutOfRange(*v, voxels));
            }
            if let Mode::Add(m) | Mode::Paint(m) = mode {
                table.check(*m as u32)?;
            }
        }
        EditOp::Voxels(list) => {
            for e in list {
                if !inside(e.pos) {
                    return Err(BrickmapError::OutOfRange(e.pos, voxels));
                }
                if let VoxelOp::Set(m) | VoxelOp::Paint(m) = e.op {
                    table.check(m as u32)?;
                }
            }
        }
        EditOp::Generate(g) => {
            for m in g.0.materials() {
                table.check(m as u32)?;
            }
        }
        EditOp::Restore(inv) => {
            let bricks = (voxels + 7) / 8;
            for u in &inv.bricks {
                if u.brick.as_ivec3().cmpge(bricks).any() {
                    return Err(BrickmapError::BadInverse("brick outside the grid"));
                }
                match &u.prior {
                    PriorMaterials::Uniform(m) => table.check(*m as u32)?,
                    PriorMaterials::PerVoxel(v) => {
                        if v.len() != u.prior_mask.and(&u.touched).count() as usize {
                            return Err(BrickmapError::BadInverse("material count mismatch"));
                        }
                        for m in v {
                            table.check(*m as u32)?;
                        }
                    }
                }
            }
        }
    }
    Ok(())
}
