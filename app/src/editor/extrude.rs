//! Face extrude (push-pull) and plane fill, both flood fills over one plane of voxels:
//!
//! - **Extrude**: the connected coplanar region of the clicked face — the solid voxels of its
//!   layer whose face on that side is exposed, joined through their edges in the plane (with
//!   `same_material`, only those of the clicked voxel's material; with a selection, only
//!   selected ones) — grows `distance` voxels along the face's normal, each column in its
//!   voxel's material; a negative distance pushes the region in, emptying that many layers.
//! - **Plane fill**: the empty voxels of the layer in front of the clicked face, joined
//!   through their edges in the plane, become solid with a material.
//!
//! Both stay inside the edited object's box and the grid; each is one voxel edit with an
//! exact inverse.

use super::error::{EditError, Result};
use crate::scene::Scene;
use brickmap::{VoxelEdit, VoxelOp, WorldView};
use glam::IVec3;

/// A unit axis vector, or an error naming it.
fn axis_normal(normal: IVec3) -> Result<IVec3> {
    if normal.abs().element_sum() == 1 && normal.abs().max_element() == 1 {
        Ok(normal)
    } else {
        Err(super::error::invalid(format!(
            "{normal} is not a face's normal (one axis, ±1)"
        )))
    }
}

/// The box edits may touch: the edited object's, within the grid (lo inclusive, hi
/// exclusive).
fn bounds(scene: &Scene) -> (IVec3, IVec3) {
    let grid = scene.world.dims().voxels();
    match scene.active_box() {
        Some((lo, hi)) => (lo.max(IVec3::ZERO), hi.min(grid)),
        None => (IVec3::ZERO, grid),
    }
}

/// The edits of an extrude from the face of `voxel` facing `normal` by `distance`.
pub(super) fn extrude_edits(
    scene: &Scene,
    voxel: IVec3,
    normal: IVec3,
    distance: i32,
    same_material: bool,
) -> Result<Vec<VoxelEdit>> {
    let normal = axis_normal(normal)?;
    if distance == 0 {
        return Err(EditError::NothingToDo("an extrude of 0 voxels"));
    }
    let alone = scene.active_world()?;
    let source = alone.as_ref().unwrap_or(&scene.world);
    let view = source.read();
    let at = |v: IVec3| view.voxel(v).ok().flatten();
    let material = at(voxel).ok_or(EditError::NothingToDo("no voxel there to extrude"))?;
    let (lo, hi) = bounds(scene);
    let selection = scene.selection.as_ref().map(|s| s.voxels.clone());
    let exposed = |v: IVec3| {
        at(v).is_some_and(|m| !same_material || m == material)
            && at(v + normal).is_none()
            && selection.as_ref().is_none_or(|s| s.contains(v))
    };
    let region = crate::wand::plane_flood(voxel, normal, (lo, hi), false, exposed);
    if region.is_empty() {
        return Err(EditError::NothingToDo("that face is not exposed"));
    }
    let inside = |v: IVec3| v.cmpge(lo).all() && v.cmplt(hi).all();
    let mut edits = Vec::new();
    for v in region {
        if distance > 0 {
            let m = at(v).expect("the region is solid");
            edits.extend(
                (1..=distance)
                    .map(|i| v + normal * i)
                    .filter(|p| inside(*p))
                    .map(|pos| VoxelEdit {
                        pos,
                        op: VoxelOp::Set(m),
                    }),
            );
        } else {
            edits.extend(
                (0..-distance)
                    .map(|i| v - normal * i)
                    .filter(|p| inside(*p))
                    .map(|pos| VoxelEdit {
                        pos,
                        op: VoxelOp::Clear,
                    }),
            );
        }
    }
    Ok(edits)
}

/// The edits of a plane fill of the layer in front of the face of `voxel` facing `normal`.
pub(super) fn plane_fill_edits(
    scene: &Scene,
    voxel: IVec3,
    normal: IVec3,
    material: u8,
) -> Result<Vec<VoxelEdit>> {
    let normal = axis_normal(normal)?;
    let alone = scene.active_world()?;
    let source = alone.as_ref().unwrap_or(&scene.world);
    let view: WorldView<'_> = source.read();
    let empty = |v: IVec3| view.voxel(v).is_ok_and(|m| m.is_none());
    let region = crate::wand::plane_flood(voxel + normal, normal, bounds(scene), false, empty);
    if region.is_empty() {
        return Err(EditError::NothingToDo(
            "no empty voxel in front of that face",
        ));
    }
    Ok(region
        .into_iter()
        .map(|pos| VoxelEdit {
            pos,
            op: VoxelOp::Set(material),
        })
        .collect())
}
