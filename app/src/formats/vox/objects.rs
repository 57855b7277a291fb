//! `.vox` import as a scene of objects: the file's groups, objects (names, hidden flags,
//! layers) and shared models kept as `brickmap::objects` — hidden ones too, hidden — and the
//! visible ones composited into the new scene's world. The grid fits every object, shown or
//! hidden, so showing one later needs no larger grid. Colours and materials are installed as
//! the flattening import installs them; its checks on hostile files apply unchanged (the
//! same parse, the same scene-graph walk).

use super::graph::{Hidden, model_size, model_voxel, read_tree};
use super::*;
use brickmap::objects::{Model as VoxelModel, NodeKind, ObjectTree, Objects};
use std::collections::BTreeSet;

/// A `.vox` file imported as objects: the scene (its world holds the composite) and the
/// objects that make it.
pub struct ObjectImport {
    /// The new scene, framed on the visible content.
    pub scene: Scene,
    /// The tree, the models and the composite.
    pub objects: Objects,
    /// What was imported and what was left out.
    pub report: ImportReport,
}

/// Imports `.vox` bytes as a new scene of objects (`path` only names the file in errors).
pub fn import_objects(
    bytes: &[u8],
    path: &Path,
    workers: usize,
) -> Result<ObjectImport, FormatError> {
    let invalid = |e: VoxError| FormatError::vox(path, e);
    let world_error = |e: brickmap::BrickmapError| FormatError::world(path, e);
    let data = parse(bytes).map_err(invalid)?;
    let mut report = ImportReport {
        models: data.models.len(),
        ..Default::default()
    };
    let mut tree = read_tree(&data, Hidden::Keep, &mut report).map_err(invalid)?;
    // Every object, shown or hidden, with its model and its box before the shift.
    let mut used = [false; 256];
    let mut models = BTreeSet::new();
    let mut lo = IVec3::MAX;
    let mut hi = IVec3::MIN;
    for id in tree
        .subtree(ObjectTree::ROOT)
        .map_err(|e| invalid(VoxError::Malformed(e.to_string())))?
    {
        let Ok(node) = tree.node(id) else { continue };
        let NodeKind::Object { model, .. } = node.kind else {
            continue;
        };
        let m = &data.models[model.0 as usize];
        let p = tree.world_placement(id).expect("a node of the tree");
        let (a, b) = p.bounds(model_size(m));
        lo = lo.min(a);
        hi = hi.max(b);
        models.insert(model);
        for v in &m.voxels {
            used[v.i as usize] = true;
        }
    }
    let declared: u64 = data.models.iter().map(|m| m.voxels.len() as u64).sum();
    if models.is_empty() {
        if declared > 0 {
            return Err(invalid(VoxError::NothingPlaced {
                models: data.models.len(),
                voxels: declared,
                why: "no model is placed by the scene graph".into(),
            }));
        }
        lo = IVec3::ZERO;
        hi = IVec3::ONE;
    }
    // Shift everything into the grid through the root's placement.
    let shift = (-lo).max(IVec3::ZERO);
    tree.node_mut(ObjectTree::ROOT)
        .expect("the root")
        .placement
        .t += shift;
    let top = hi + shift;
    let dims = GridDims::from_voxels(top.max(IVec3::ONE).as_uvec3())
        .map_err(|_| invalid(VoxError::TooLarge(top)))?;
    let mut scene = Scene::empty(dims, workers).map_err(world_error)?;
    for (i, c) in palette_of(&data).iter().enumerate() {
        scene.world.set_colour(i as u8, [c.r, c.g, c.b]);
    }
    let indices: Vec<(IVec3, u8)> = (0..=255u8)
        .filter(|i| used[*i as usize])
        .map(|i| (IVec3::ZERO, i))
        .collect();
    let map = install_materials(&scene.world, &data, &indices, &mut report, Ok).map_err(invalid)?;
    let table = scene.world.materials().clone();
    let mut voxels = BTreeMap::new();
    for id in models {
        let m = &data.models[id.0 as usize];
        voxels.insert(id, model_of(m, &map, &table).map_err(world_error)?);
    }
    let objects = Objects::new(tree, voxels, &scene.world)
        .map_err(|e| FormatError::invalid(path, format!("the objects do not fit together: {e}")))?;
    scene.world.take_dirty();
    let view = scene.world.read();
    report.instances = objects.tree().drawn().len();
    report.voxels = view.solid_count();
    if let Some((a, b)) = view.occupied_bounds() {
        scene.params.camera = scene.params.camera.framing(a.as_dvec3(), b.as_dvec3()).0;
    }
    drop(view);
    Ok(ObjectImport {
        scene,
        objects,
        report,
    })
}

/// A `.vox` model in voxbrick's axes, its palette indices mapped to materials, built a brick
/// at a time.
fn model_of(
    m: &Model,
    map: &[u8; 256],
    table: &brickmap::MaterialTable,
) -> brickmap::Result<VoxelModel> {
    let mut model = VoxelModel::new(model_size(m))?;
    let mut bricks: BTreeMap<[u32; 3], (Mask, Box<[u8; 512]>)> = BTreeMap::new();
    for v in &m.voxels {
        let p = model_voxel(v, m);
        let l = p % 8;
        let bit = brickmap::brick::voxel_bit(l.x, l.y, l.z);
        let (mask, mats) = bricks
            .entry((p / 8).as_uvec3().to_array())
            .or_insert_with(|| (Mask::EMPTY, Box::new([0; 512])));
        mask.set(bit);
        mats[bit] = map[v.i as usize];
    }
    // Each brick restored over exactly its solid voxels (a restore of whole bricks would
    // reach past a model whose size is not a multiple of 8).
    let list = bricks
        .into_iter()
        .map(|(k, (mask, mats))| brickmap::BrickUndo {
            brick: glam::UVec3::from_array(k),
            prior_mask: mask,
            touched: mask,
            prior: brickmap::PriorMaterials::PerVoxel(mask.ones().map(|bit| mats[bit]).collect()),
        })
        .collect();
    model.apply(
        &brickmap::EditOp::Restore(brickmap::EditInverse { bricks: list }),
        table,
    )?;
    Ok(model)
}
