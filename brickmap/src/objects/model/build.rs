//! A model built whole: from bricks (a file's, an import's), from voxels, or from a world
//! (a grid becoming one object: each worker's slab copied on its own thread).

use super::store::{BrickStore, Word};
use super::{BrickMaterials, Model, ModelBrick, check_size, key};
use crate::brick::{Mask, voxel_bit};
use crate::edit::{BrickUndo, EditInverse, EditOp, PriorMaterials};
use crate::error::{BrickmapError, Result};
use crate::material::MaterialTable;
use glam::{IVec3, UVec3};
use std::collections::BTreeMap;

impl Model {
    /// A model of `size` holding these bricks (solid voxels with their materials in popcount
    /// order), checked against the model's box and `table` like any edit (a brick restored
    /// over exactly its solid voxels; a later one of the same brick over an earlier).
    pub fn from_bricks(
        size: IVec3,
        bricks: impl IntoIterator<Item = (UVec3, Mask, PriorMaterials)>,
        table: &MaterialTable,
    ) -> Result<Self> {
        let mut model = Self::new(size)?;
        let grid = model.bricks_size();
        for (brick, mask, prior) in bricks {
            let u = BrickUndo {
                brick,
                prior_mask: mask,
                touched: mask,
                prior,
            };
            if model.bricks.contains(brick) {
                // A brick named twice: the second restored over the first, as an edit.
                let again = EditOp::Restore(EditInverse { bricks: vec![u] });
                model.apply(&again, table)?;
                continue;
            }
            // Into an empty brick: the same checks as a restore's, then the brick stored as
            // it is (no undo to record: the model is being built).
            if brick.cmpge(grid).any() {
                return Err(BrickmapError::BadInverse("brick outside the grid"));
            }
            match &u.prior {
                PriorMaterials::Uniform(m) => table.check(*m as u32)?,
                PriorMaterials::PerVoxel(v) => {
                    if v.len() != mask.count() as usize {
                        return Err(BrickmapError::BadInverse("material count mismatch"));
                    }
                    for m in v {
                        table.check(*m as u32)?;
                    }
                }
            }
            if !mask.and_not(&model.inside(brick)).is_empty() {
                return Err(BrickmapError::BadInverse("voxels outside the model"));
            }
            if mask.is_empty() {
                continue;
            }
            let stored = match &u.prior {
                PriorMaterials::Uniform(m) => ModelBrick {
                    mask,
                    materials: BrickMaterials::Uniform(*m),
                },
                PriorMaterials::PerVoxel(v) => {
                    let mut per = Box::new([0u8; 512]);
                    for (k, bit) in mask.ones().enumerate() {
                        per[bit] = v[k];
                    }
                    ModelBrick::packed(mask, per)
                }
            };
            model.bricks.insert(brick, stored);
        }
        Ok(model)
    }

    /// A model of `size` holding these solid voxels (position in the model, material; a
    /// later one at the same position wins).
    pub fn from_voxels(
        size: IVec3,
        voxels: impl IntoIterator<Item = (IVec3, u8)>,
        table: &MaterialTable,
    ) -> Result<Self> {
        let mut bricks: BTreeMap<[u32; 3], (Mask, Box<[u8; 512]>)> = BTreeMap::new();
        for (v, m) in voxels {
            if v.cmplt(IVec3::ZERO).any() || v.cmpge(size).any() {
                return Err(BrickmapError::OutOfRange(v, size));
            }
            let bit = voxel_bit(v.x & 7, v.y & 7, v.z & 7);
            let (mask, mats) = bricks
                .entry(key((v / 8).as_uvec3()))
                .or_insert_with(|| (Mask::EMPTY, Box::new([0; 512])));
            mask.set(bit);
            mats[bit] = m;
        }
        let bricks = bricks.into_iter().map(|(k, (mask, mats))| {
            let held = mask.ones().map(|bit| mats[bit]).collect();
            (UVec3::from_array(k), mask, PriorMaterials::PerVoxel(held))
        });
        Self::from_bricks(size, bricks, table)
    }

    /// A world's voxels as one model of the world's size (a grid becoming one object): each
    /// worker's slab copied on its own thread, full cells as index words (nothing checked
    /// again: the world's voxels already hold to its table and grid).
    pub fn from_world(world: &crate::World) -> Result<Self> {
        use crate::brick::BrickMaterials as Held;
        let view = world.read();
        let size = view.dims().voxels();
        check_size(size)?;
        let runs = view.slab_cells();
        let bricks = BrickStore::from_runs(view.dims().bricks(), &runs, |k, words, slots| {
            let base = runs[k].start;
            view.visit_slab(k, &mut |cell, mask, held| {
                words[cell - base] = match held {
                    Held::Uniform(m) if mask.is_full() => Word::full(m),
                    Held::Uniform(m) => {
                        slots.push(ModelBrick {
                            mask: *mask,
                            materials: BrickMaterials::Uniform(m),
                        });
                        Word::slot(slots.len())
                    }
                    Held::PerVoxel(v) => {
                        let mut per = Box::new([0u8; 512]);
                        for (k, bit) in mask.ones().enumerate() {
                            per[bit] = v[k];
                        }
                        slots.push(ModelBrick::packed(*mask, per));
                        Word::slot(slots.len())
                    }
                };
            });
        });
        Ok(Self { size, bricks })
    }
}
