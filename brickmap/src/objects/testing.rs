//! Helpers the objects' tests share: a small material table, a world of `GRID`, models with
//! recognisable asymmetric content, and the forward, voxel-by-voxel reference of a tree's
//! composite.

use crate::edit::{EditOp, VoxelEdit, VoxelOp};
use crate::material::{Material, MaterialKind, MaterialTable};
use crate::objects::model::Model;
use crate::objects::tree::{ModelId, ObjectTree};
use crate::{GridDims, World, WorldConfig};
use glam::IVec3;
use std::collections::{BTreeMap, HashMap};

/// The tests' grid, in voxels.
pub const GRID: IVec3 = IVec3::new(64, 32, 48);

pub fn table() -> MaterialTable {
    let mut t = MaterialTable::default();
    for i in 1..6 {
        t.push(Material {
            kind: MaterialKind::Lambertian,
            param: 0,
            colour: i,
        })
        .unwrap();
    }
    t
}

pub fn world(workers: usize) -> World {
    let w = World::new(
        GridDims::from_voxels(GRID.as_uvec3()).unwrap(),
        WorldConfig::with_workers(workers),
    )
    .unwrap();
    w.replace_materials(table()).unwrap();
    w
}

/// The reference: forward placement of every drawn object's voxels, later ones winning.
pub fn reference(tree: &ObjectTree, models: &BTreeMap<ModelId, Model>) -> HashMap<IVec3, u8> {
    let mut out = HashMap::new();
    for d in tree.drawn() {
        let m = &models[&d.model];
        for (b, brick) in m.bricks() {
            for bit in brick.mask.ones() {
                let v = b.as_ivec3() * 8
                    + IVec3::new((bit & 7) as i32, (bit >> 3 & 7) as i32, (bit >> 6) as i32);
                out.insert(d.placement.place(v, m.size()), brick.material(bit));
            }
        }
    }
    out
}

pub fn assert_matches(world: &World, want: &HashMap<IVec3, u8>) {
    let view = world.read();
    let mut solid = 0;
    view.for_each_brick(|b, mask, mats| {
        for (k, bit) in mask.ones().enumerate() {
            let v = b.as_ivec3() * 8
                + IVec3::new((bit & 7) as i32, (bit >> 3 & 7) as i32, (bit >> 6) as i32);
            assert_eq!(want.get(&v), Some(&mats.at(k)), "voxel {v}");
            solid += 1;
        }
    });
    assert_eq!(solid, want.len(), "solid voxels");
}

/// A model with a recognisable, asymmetric content (so every orientation shows).
pub fn model(size: IVec3, seed: i32) -> Model {
    let mut m = Model::new(size).unwrap();
    let mut list = Vec::new();
    for z in 0..size.z {
        for y in 0..size.y {
            for x in 0..size.x {
                let h = (x * 7 + y * 13 + z * 5 + seed * 11) % 9;
                if h < 4 || (x == 0 && y == 0) {
                    list.push(VoxelEdit {
                        pos: IVec3::new(x, y, z),
                        op: VoxelOp::Set(((h + seed) % 5 + 1) as u8),
                    });
                }
            }
        }
    }
    m.apply(&EditOp::Voxels(list), &table()).unwrap();
    m
}
