//! Helpers the objects' tests share: a small material table, a world of `GRID`, models with
//! recognisable asymmetric content, and the forward, voxel-by-voxel reference of a tree's
//! composite.

use crate::edit::{EditOp, VoxelEdit, VoxelOp};
use crate::material::{Material, MaterialKind, MaterialTable};
use crate::objects::model::Model;
use crate::objects::orient::Placement;
use crate::objects::scene::Objects;
use crate::objects::tree::{Layer, LayerId, ModelId, NewNode, ObjectTree};
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

/// A session's first scene: a group holding two objects of models 0 and 1, model 1 placed
/// again at the top level, a second layer.
pub fn start(workers: usize) -> (Objects, World) {
    let mut tree = ObjectTree::new();
    tree.add_layer(Layer {
        name: "second".into(),
        visible: true,
    })
    .unwrap();
    let g = tree
        .add(
            ObjectTree::ROOT,
            None,
            "g",
            Placement::at(IVec3::new(24, 12, 20)),
            NewNode::Group,
        )
        .unwrap();
    let object = |m: u32, layer: u8| NewNode::Object {
        model: ModelId(m),
        layer: LayerId(layer),
    };
    tree.add(
        g,
        None,
        "a",
        Placement::at(IVec3::new(-6, 0, 0)),
        object(0, 0),
    )
    .unwrap();
    tree.add(
        g,
        None,
        "b",
        Placement::at(IVec3::new(6, 2, 4)),
        object(1, 1),
    )
    .unwrap();
    tree.add(
        ObjectTree::ROOT,
        None,
        "c",
        Placement::at(IVec3::new(44, 14, 30)),
        object(1, 0),
    )
    .unwrap();
    let models = BTreeMap::from([
        (ModelId(0), model(IVec3::new(9, 6, 5), 0)),
        (ModelId(1), model(IVec3::new(7, 8, 10), 1)),
    ]);
    let w = world(workers);
    let objects = Objects::new(tree, models, &w).unwrap();
    (objects, w)
}
