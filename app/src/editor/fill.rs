//! Flood fill: the connected surface of same-material voxels, as paint edits.

use super::error::{Result, invalid};
use crate::scene::Scene;
use brickmap::{VoxelEdit, VoxelOp};
use glam::IVec3;
use std::collections::VecDeque;

/// Paint edits for the connected (6-neighbour) surface of voxels sharing `start`'s material;
/// a voxel is on the surface when a face neighbour is empty or outside the grid.
pub(super) fn flood_fill(scene: &Scene, start: IVec3, material: u8) -> Result<Vec<VoxelEdit>> {
    const LIMIT: usize = 1 << 24;
    let view = scene.world.read();
    let dims = view.dims();
    let target = view
        .voxel(start)?
        .ok_or_else(|| invalid(format!("flood fill starts at {start}, which is empty")))?;
    let faces = [
        IVec3::X,
        IVec3::NEG_X,
        IVec3::Y,
        IVec3::NEG_Y,
        IVec3::Z,
        IVec3::NEG_Z,
    ];
    let on_surface = |v: IVec3| {
        faces
            .iter()
            .any(|f| !dims.contains_voxel(v + *f) || view.voxel(v + *f).ok().flatten().is_none())
    };
    if !on_surface(start) {
        return Err(invalid(format!(
            "flood fill starts at {start}, which is not on a surface"
        )));
    }
    let mut seen = std::collections::HashSet::from([start]);
    let mut queue = VecDeque::from([start]);
    let mut edits = Vec::new();
    while let Some(v) = queue.pop_front() {
        edits.push(VoxelEdit {
            pos: v,
            op: VoxelOp::Paint(material),
        });
        if edits.len() > LIMIT {
            return Err(invalid(format!(
                "flood fill reaches more than {LIMIT} voxels"
            )));
        }
        for f in faces {
            let n = v + f;
            if dims.contains_voxel(n)
                && !seen.contains(&n)
                && view.voxel(n)? == Some(target)
                && on_surface(n)
            {
                seen.insert(n);
                queue.push_back(n);
            }
        }
    }
    Ok(edits)
}
