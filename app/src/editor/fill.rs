//! Flood fill: the connected surface of same-material voxels, as paint edits.

use super::error::{Result, invalid};
use crate::scene::Scene;
use brickmap::{FACES, VoxelEdit, VoxelOp};
use glam::IVec3;
use std::collections::VecDeque;

/// The 26 neighbours of a voxel.
const NEIGHBOURS: [IVec3; 26] = {
    let mut n = [IVec3::ZERO; 26];
    let mut k = 0;
    let mut i = 0;
    while i < 27 {
        if i != 13 {
            n[k] = IVec3::new(i % 3 - 1, i / 3 % 3 - 1, i / 9 - 1);
            k += 1;
        }
        i += 1;
    }
    n
};

/// Paint edits for the connected surface of the active object's voxels sharing `start`'s
/// material, seen from the camera or not; a voxel is on the surface when a face neighbour is empty or outside the
/// grid. Surface voxels connect through faces, edges and corners (26 neighbours): a curved
/// surface's voxels often touch only along an edge (a sphere's, a hill's), and face
/// neighbours alone stopped a fill at the first such step.
pub(super) fn flood_fill(scene: &Scene, start: IVec3, material: u8) -> Result<Vec<VoxelEdit>> {
    const LIMIT: usize = 1 << 24;
    // The active object's voxels alone (in a scene of several objects, another's voxels
    // neither join nor bound the surface).
    let alone = scene.active_world()?;
    let view = alone.as_ref().unwrap_or(&scene.world).read();
    let dims = view.dims();
    let target = view
        .voxel(start)?
        .ok_or_else(|| invalid(format!("flood fill starts at {start}, which is empty")))?;
    let on_surface = |v: IVec3| {
        FACES
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
        for f in NEIGHBOURS {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::editor::command::{Command, KindSpec, MaterialSpec};
    use brickmap::{EditOp, GridDims};
    use std::collections::HashSet;

    /// A sand sphere (material 2, radius 8) resting on a grass floor (material 1).
    fn sphere_on_a_floor() -> (Scene, Vec<IVec3>) {
        let mut scene = Scene::empty(GridDims::new(3, 3, 3).unwrap(), 1).unwrap();
        for colour in [10, 20] {
            Command::AddMaterial(MaterialSpec {
                kind: KindSpec::Lambertian,
                param: 0,
                colour,
            })
            .apply(&mut scene, std::path::Path::new("."))
            .unwrap();
        }
        let mut edits = Vec::new();
        for (x, z) in (0..24).flat_map(|x| (0..24).map(move |z| (x, z))) {
            edits.push(VoxelEdit {
                pos: IVec3::new(x, 0, z),
                op: VoxelOp::Set(1),
            });
        }
        let c = IVec3::new(12, 9, 12);
        let mut sphere = Vec::new();
        for x in 4..=20 {
            for y in 1..=17 {
                for z in 4..=20 {
                    let v = IVec3::new(x, y, z);
                    if (v - c).length_squared() <= 64 {
                        sphere.push(v);
                        edits.push(VoxelEdit {
                            pos: v,
                            op: VoxelOp::Set(2),
                        });
                    }
                }
            }
        }
        scene.edit(EditOp::Voxels(edits)).unwrap();
        (scene, sphere)
    }

    #[test]
    fn a_flood_fill_paints_the_whole_surface_of_a_sphere_seen_or_not() {
        let (scene, sphere) = sphere_on_a_floor();
        let view = scene.world.read();
        let empty_beside = |v: IVec3| {
            FACES
                .iter()
                .any(|f| view.voxel(v + *f).ok().flatten().is_none())
        };
        let surface: HashSet<IVec3> = sphere.into_iter().filter(|v| empty_beside(*v)).collect();
        drop(view);
        let painted: HashSet<IVec3> = flood_fill(&scene, IVec3::new(12, 17, 12), 0)
            .unwrap()
            .iter()
            .map(|e| e.pos)
            .collect();
        assert_eq!(
            painted.len(),
            surface.len(),
            "{} of the sphere's {} surface voxels painted",
            painted.len(),
            surface.len()
        );
        assert_eq!(painted, surface, "exactly the sphere's surface");
    }

    #[test]
    fn a_flood_fill_stays_on_its_material() {
        let (scene, _) = sphere_on_a_floor();
        let edits = flood_fill(&scene, IVec3::new(0, 0, 0), 0).unwrap();
        let view = scene.world.read();
        assert!(
            edits
                .iter()
                .all(|e| view.voxel(e.pos).unwrap() == Some(1) && e.pos.y == 0)
        );
        // The whole floor's top shows (the sphere covers a few voxels, which stay grass but
        // are not on a surface).
        assert!(edits.len() > 24 * 24 - 10, "{}", edits.len());
    }
}
