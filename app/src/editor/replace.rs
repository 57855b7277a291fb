//! Replace one material by another: every solid voxel of material `from` in the selection —
//! or, with nothing selected, in the object brushes edit — gets material `to`, as one
//! voxel edit (undone exactly like any other).

use super::error::{EditError, Result};
use crate::scene::Scene;
use brickmap::{BrickMaterials, VoxelEdit, VoxelOp};
use glam::IVec3;

/// The paints that replace `from` by `to` (world coordinates; refused when there are none).
pub(super) fn replace_edits(scene: &Scene, from: u8, to: u8) -> Result<Vec<VoxelEdit>> {
    if from == to {
        return Err(EditError::NothingToDo("the two materials are the same"));
    }
    let alone = scene.active_world()?;
    let source = alone.as_ref().unwrap_or(&scene.world);
    let view = source.read();
    let selection = scene.selection.as_ref().map(|s| s.voxels.clone());
    let mut edits = Vec::new();
    view.for_each_brick(|b, mask, mats| {
        if matches!(mats, BrickMaterials::Uniform(m) if m != from) {
            return;
        }
        let within = match &selection {
            Some(s) => mask.and(&s.brick(b)),
            None => *mask,
        };
        let min = b.as_ivec3() * 8;
        for (k, bit) in mask.ones().enumerate() {
            if within.get(bit) && mats.at(k) == from {
                let local = IVec3::new(bit as i32 & 7, (bit as i32 >> 3) & 7, bit as i32 >> 6);
                edits.push(VoxelEdit {
                    pos: min + local,
                    op: VoxelOp::Paint(to),
                });
            }
        }
    });
    if edits.is_empty() {
        return Err(EditError::NothingToDo(if selection.is_some() {
            "no selected voxel has that material"
        } else {
            "no voxel of the edited object has that material"
        }));
    }
    Ok(edits)
}
