//! Version 2 projects: a scene of objects. The header is version 1's (grid, camera, sun,
//! sky, settings, the material, colour and parameter tables); instead of the world's voxels
//! come the layers, the tree and the models; the world is their composite, rebuilt on load.
//!
//! ```text
//!     layers: [(name: "ground", visible: true), ..],
//!     nodes: [                                   // pre-order; a node's parent comes before it
//!         (parent: None, name: "scene", visible: true, locked: false, placement: (rot: 4, t: (0, 0, 0)), object: None),
//!         (parent: Some(0), name: "tree", visible: true, locked: false, placement: (rot: 4, t: (30, 8, 12)), object: Some((model: 3, layer: 0))),
//!     ],
//!     models: [(id: 3, size: (9, 16, 9), voxels: (encoding: "vxb1-base64", bricks: .., solid_voxels: .., data: "..")), ..],
//! ```
//! Rotations are MagicaVoxel's byte. A model's voxels are the VXB1 payload over the model's
//! own grid of bricks. Node ids are the nodes' places in that list, on load and so after it.
//! Loading checks every field, every parent link, every model's voxels, and that the objects
//! fit the grid; a version 1 project loads as one object ("scene") at identity, brick-aligned.

use super::{
    ENCODING, FormatError, Header, MaterialRecord, OBJECTS_VERSION, VoxelRecord, header, header_of,
    layout, list, payload,
};
use crate::scene::Scene;
use brickmap::objects::{
    Layer, LayerId, Model, ModelId, NewNode, NodeId, NodeKind, ObjectTree, Objects, Placement,
};
use brickmap::{BrickMaterials, GridDims, MaterialTable, World, WorldConfig};
use glam::IVec3;
use render::{Camera, RenderSettings, Sky, Sun};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Deserialize)]
struct ObjectsFile {
    #[allow(dead_code)]
    format_version: u32,
    grid_bricks: (u32, u32, u32),
    camera: Camera,
    sun: Sun,
    sky: Sky,
    settings: RenderSettings,
    materials: Vec<MaterialRecord>,
    colours: Vec<String>,
    roughness: Vec<f32>,
    ior: Vec<f32>,
    strength: Vec<f32>,
    layers: Vec<Layer>,
    nodes: Vec<NodeRecord>,
    models: Vec<ModelRecord>,
}

#[derive(Serialize, Deserialize)]
struct NodeRecord {
    parent: Option<u32>,
    name: String,
    visible: bool,
    locked: bool,
    placement: Placement,
    object: Option<ObjectRecord>,
}

#[derive(Serialize, Deserialize)]
struct ObjectRecord {
    model: u32,
    layer: u8,
}

#[derive(Serialize, Deserialize)]
struct ModelRecord {
    id: u32,
    size: (i32, i32, i32),
    voxels: VoxelRecord,
}

/// The largest translation a node may have on any axis (as in `.vox` files): 64 nested
/// levels of it stay far inside `i32`.
const MAX_TRANSLATION: i32 = 1 << 20;

/// The grid of bricks a model's payload is written over.
fn model_dims(size: IVec3) -> Result<GridDims, brickmap::BrickmapError> {
    let b = (size + 7) / 8;
    GridDims::new(b.x as u32, b.y as u32, b.z as u32)
}

/// The project text of a scene (version 2: its objects).
pub(super) fn to_string(scene: &Scene) -> String {
    let objects = scene.objects();
    let tree = objects.tree();
    let order = tree
        .subtree(ObjectTree::ROOT)
        .expect("the root is always there");
    let place: BTreeMap<NodeId, u32> = order
        .iter()
        .enumerate()
        .map(|(i, n)| (*n, i as u32))
        .collect();
    let nodes: Vec<NodeRecord> = order
        .iter()
        .map(|id| {
            let n = tree.node(*id).expect("a node of the tree");
            NodeRecord {
                parent: n.parent().map(|p| place[&p]),
                name: n.name.clone(),
                visible: n.visible,
                locked: n.locked,
                placement: n.placement,
                object: match n.kind {
                    NodeKind::Object { model, layer } => Some(ObjectRecord {
                        model: model.0,
                        layer: layer.0,
                    }),
                    NodeKind::Group { .. } => None,
                },
            }
        })
        .collect();
    let models: Vec<ModelRecord> = objects
        .models()
        .iter()
        .map(|(id, m)| model_record(*id, m))
        .collect();
    let mut fields = header(scene, OBJECTS_VERSION);
    fields.push(("layers", list(tree.layers(), 1)));
    fields.push(("nodes", list(&nodes, 1)));
    fields.push(("models", models_list(&models)));
    layout(&fields)
}

fn model_record(id: ModelId, m: &Model) -> ModelRecord {
    let dims = model_dims(m.size()).expect("a model's size is within the grid limits");
    // A model's bricks come in its grid's cell order, the payload's.
    let mut count = 0u64;
    let data = payload::encode_bricks(&dims, |f| {
        for (b, brick) in m.bricks() {
            count += 1;
            match brick.uniform() {
                Some(u) => f(b, &brick.mask, BrickMaterials::Uniform(u)),
                None => {
                    let v: Vec<u8> = brick.mask.ones().map(|bit| brick.material(bit)).collect();
                    f(b, &brick.mask, BrickMaterials::PerVoxel(&v));
                }
            }
        }
    });
    let s = m.size();
    ModelRecord {
        id: id.0,
        size: (s.x, s.y, s.z),
        voxels: VoxelRecord {
            encoding: ENCODING.into(),
            bricks: count,
            solid_voxels: m.solid_count(),
            data: super::base64_on_cores(&data),
        },
    }
}

impl ModelRecord {
    /// The record in ron's compact form, as `ron` writes it (the payload unescaped: see
    /// `VoxelRecord::text`).
    fn text(&self) -> String {
        let (x, y, z) = self.size;
        let voxels = self.voxels.text();
        let mut t = String::with_capacity(voxels.len() + 64);
        t.push_str(&format!(
            "(id: {}, size: ({x}, {y}, {z}), voxels: ",
            self.id
        ));
        t.push_str(&voxels);
        t.push(')');
        t
    }
}

/// The models as `list(models, 1)` lays them out.
fn models_list(models: &[ModelRecord]) -> String {
    let mut t = String::from("[\n");
    for (i, m) in models.iter().enumerate() {
        if i > 0 {
            t.push('\n');
        }
        t.push_str("        ");
        t.push_str(&m.text());
        t.push(',');
    }
    t.push_str("\n    ]");
    t
}

/// Parses version 2 project text (`path` only names it in errors).
pub(super) fn from_str(s: &str, path: &Path, workers: usize) -> Result<Scene, FormatError> {
    let invalid = |m: String| FormatError::invalid(path, m);
    let world_error = |e: brickmap::BrickmapError| FormatError::world(path, e);
    let file: ObjectsFile = ron::from_str(s).map_err(|e| invalid(format!("{e}")))?;
    let (params, dims, table) = header_of!(file).read(path)?;
    let tree = read_tree(&file.layers, &file.nodes).map_err(invalid)?;
    let world = World::new(dims, WorldConfig::with_workers(workers)).map_err(world_error)?;
    world
        .replace_materials(table.clone())
        .map_err(world_error)?;
    // One object over the whole grid, unturned (what a new terrain or an opened grid
    // saves as): its voxels go into the world as a grid's do, on the workers, and the
    // model is taken back from the world; any other scene is built model by model and
    // composited.
    let sole = sole_grid_model(&tree, &file.models, dims.voxels());
    let mut models = BTreeMap::new();
    for r in &file.models {
        let at = |m: String| invalid(format!("model {}: {m}", r.id));
        if Some(r.id) == sole {
            write_grid_model(r, &world, &table, path).map_err(|e| at(e.to_string()))?;
            continue;
        }
        let model = read_model(r, &table, path).map_err(|e| at(e.to_string()))?;
        if models.insert(ModelId(r.id), model).is_some() {
            return Err(at("listed twice".into()));
        }
    }
    let objects = match sole {
        Some(id) => Objects::adopting(tree, ModelId(id), models, &world),
        None => Objects::new(tree, models, &world),
    }
    .map_err(|e| invalid(e.to_string()))?;
    world.take_dirty();
    let active = Scene::first_object(&objects);
    Ok(Scene::with_objects(world, objects, active, params))
}

/// The tree from the layer and node records (pre-order, parents first).
fn read_tree(layers: &[Layer], nodes: &[NodeRecord]) -> Result<ObjectTree, String> {
    let mut tree = ObjectTree::new();
    match layers.split_first() {
        None => return Err("no layers: a scene has at least one".into()),
        Some((first, rest)) => {
            *tree.layer_mut(LayerId(0)).expect("layer 0") = first.clone();
            for l in rest {
                tree.add_layer(l.clone()).map_err(|e| e.to_string())?;
            }
        }
    }
    let Some((root, rest)) = nodes.split_first() else {
        return Err("no nodes: the first node is the scene's root group".into());
    };
    if root.parent.is_some() || root.object.is_some() {
        return Err("node 0 must be the root group (no parent, no object)".into());
    }
    let r = tree.node_mut(ObjectTree::ROOT).expect("the root");
    r.name = root.name.clone();
    r.visible = root.visible;
    r.locked = root.locked;
    r.placement = root.placement;
    for (i, n) in nodes.iter().enumerate() {
        if n.placement
            .t
            .abs()
            .cmpgt(IVec3::splat(MAX_TRANSLATION))
            .any()
        {
            return Err(format!(
                "node {i}: translation {} is beyond ±{MAX_TRANSLATION}",
                n.placement.t
            ));
        }
    }
    for (i, n) in rest.iter().enumerate() {
        let i = i + 1;
        let parent = match n.parent {
            Some(p) if (p as usize) < i => NodeId(p),
            Some(p) => return Err(format!("node {i}: parent {p} does not come before it")),
            None => return Err(format!("node {i}: only node 0 has no parent")),
        };
        let new = match &n.object {
            Some(o) => NewNode::Object {
                model: ModelId(o.model),
                layer: LayerId(o.layer),
            },
            None => NewNode::Group,
        };
        let id = tree
            .add(parent, None, n.name.clone(), n.placement, new)
            .map_err(|e| format!("node {i}: {e}"))?;
        debug_assert_eq!(id, NodeId(i as u32), "ids follow the list");
        let node = tree.node_mut(id).expect("just added");
        node.visible = n.visible;
        node.locked = n.locked;
    }
    Ok(tree)
}

/// The model that one drawn object places unturned over the whole grid, where that is the
/// scene (the model listed once, of the grid's size, its first voxel at the origin).
fn sole_grid_model(tree: &ObjectTree, records: &[ModelRecord], grid: IVec3) -> Option<u32> {
    let [drawn] = tree.drawn()[..] else {
        return None;
    };
    let mut of_it = records.iter().filter(|r| r.id == drawn.model.0);
    let (Some(r), None) = (of_it.next(), of_it.next()) else {
        return None;
    };
    let size = IVec3::new(r.size.0, r.size.1, r.size.2);
    (size == grid
        && drawn.placement.rot == brickmap::objects::Orientation::IDENTITY
        && drawn.placement.place(IVec3::ZERO, size) == IVec3::ZERO)
        .then_some(r.id)
}

/// The grid-sized model's voxels written into the (empty) world directly, checked as a
/// model's are (every brick against the grid and the table, the solid count).
fn write_grid_model(
    r: &ModelRecord,
    world: &World,
    table: &MaterialTable,
    path: &Path,
) -> Result<(), FormatError> {
    let world_error = |e: brickmap::BrickmapError| FormatError::world(path, e);
    let bricks = r.voxels.bricks(&world.dims(), table.len(), path)?;
    world
        .apply_unrecorded(brickmap::terrain::set_bricks(bricks))
        .map_err(world_error)?;
    let solid = world.read().solid_count();
    if solid != r.voxels.solid_voxels {
        return Err(FormatError::invalid(
            path,
            format!(
                "voxels hold {solid} solid voxels, the header says {}",
                r.voxels.solid_voxels
            ),
        ));
    }
    Ok(())
}

/// A model from its record, every brick checked against the model's size and the table.
fn read_model(r: &ModelRecord, table: &MaterialTable, path: &Path) -> Result<Model, FormatError> {
    let invalid = |m: String| FormatError::invalid(path, m);
    let size = IVec3::new(r.size.0, r.size.1, r.size.2);
    let world_error = |e: brickmap::BrickmapError| FormatError::world(path, e);
    // The size first: a bad one is named before any payload is read.
    Model::new(size).map_err(world_error)?;
    let dims = model_dims(size).map_err(world_error)?;
    let bricks = r.voxels.bricks(&dims, table.len(), path)?;
    let model = Model::from_bricks(size, bricks, table).map_err(world_error)?;
    if model.solid_count() != r.voxels.solid_voxels {
        return Err(invalid(format!(
            "voxels hold {} solid voxels, the header says {}",
            model.solid_count(),
            r.voxels.solid_voxels
        )));
    }
    Ok(model)
}

#[cfg(test)]
mod text_tests {
    use super::*;

    #[test]
    fn models_read_as_ron_writes_them() {
        let record = |id| ModelRecord {
            id,
            size: (9, 16, 2048),
            voxels: VoxelRecord {
                encoding: ENCODING.into(),
                bricks: 3,
                solid_voxels: 77,
                data: "VlhCMQ+/=".into(),
            },
        };
        let models = [record(3), record(40)];
        assert_eq!(models_list(&models), list(&models, 1));
        assert_eq!(models_list(&[]), list::<ModelRecord>(&[], 1));
    }
}
