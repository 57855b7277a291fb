//! `.vox` import and export as a scene of objects: the file's groups, objects (names, hidden flags,
//! layers) and shared models kept as `brickmap::objects` — hidden ones too, hidden — and the
//! visible ones composited into the new scene's world. The grid fits every object, shown or
//! hidden, so showing one later needs no larger grid. Colours and materials are installed as
//! the flattening import installs them; its checks on hostile files apply unchanged (the
//! same parse, the same scene-graph walk).

use super::graph::{Hidden, axes, model_size, model_voxel, read_tree};
use super::*;
use brickmap::objects::{Model as VoxelModel, ModelId, NodeId, NodeKind, ObjectTree, Objects};
use std::collections::BTreeSet;

/// A `.vox` file imported as objects: the scene (its objects, and its world holding their
/// composite) and the report.
pub struct ObjectImport {
    /// The new scene, framed on the visible content.
    pub scene: Scene,
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
    let world =
        World::new(dims, brickmap::WorldConfig::with_workers(workers)).map_err(world_error)?;
    for (i, c) in palette_of(&data).iter().enumerate() {
        world.set_colour(i as u8, [c.r, c.g, c.b]);
    }
    let indices: Vec<(IVec3, u8)> = (0..=255u8)
        .filter(|i| used[*i as usize])
        .map(|i| (IVec3::ZERO, i))
        .collect();
    let map = install_materials(&world, &data, &indices, &mut report, Ok).map_err(invalid)?;
    let table = world.materials().clone();
    let mut voxels = BTreeMap::new();
    for id in models {
        let m = &data.models[id.0 as usize];
        voxels.insert(id, model_of(m, &map, &table).map_err(world_error)?);
    }
    let objects = Objects::new(tree, voxels, &world)
        .map_err(|e| FormatError::invalid(path, format!("the objects do not fit together: {e}")))?;
    world.take_dirty();
    let mut params = render::SceneParams::framing(dims.voxels().as_dvec3());
    let view = world.read();
    report.instances = objects.tree().drawn().len();
    report.voxels = view.solid_count();
    if let Some((a, b)) = view.occupied_bounds() {
        params.camera = params.camera.framing(a.as_dvec3(), b.as_dvec3()).0;
    }
    drop(view);
    let active = Scene::first_object(&objects);
    Ok(ObjectImport {
        scene: Scene::with_objects(world, objects, active, params),
        report,
    })
}

/// A `.vox` file's objects for an existing scene: its tree (the root's placement moved so
/// the file's lowest voxel lands at `offset`, as a flattening import puts it) and its
/// placed models, their materials merged into `world`'s table (an identical colour or
/// material reused, as [`import_into`] merges them).
pub struct ObjectsInto {
    /// The file's tree (hidden nodes kept hidden).
    pub tree: ObjectTree,
    /// Its placed models, by the file's model index.
    pub models: BTreeMap<ModelId, VoxelModel>,
    /// What was imported and what was left out.
    pub report: ImportReport,
}

/// Reads `.vox` bytes as objects to add to the scene of `world` (see [`ObjectsInto`]).
pub fn objects_into(world: &World, bytes: &[u8], offset: IVec3) -> Result<ObjectsInto, VoxError> {
    let data = parse(bytes)?;
    let mut report = ImportReport {
        models: data.models.len(),
        ..Default::default()
    };
    let mut tree = read_tree(&data, Hidden::Keep, &mut report)?;
    let mut used = [false; 256];
    let mut placed = BTreeSet::new();
    let mut lo = IVec3::MAX;
    for id in tree
        .subtree(ObjectTree::ROOT)
        .map_err(|e| VoxError::Malformed(e.to_string()))?
    {
        let Ok(node) = tree.node(id) else { continue };
        let NodeKind::Object { model, .. } = node.kind else {
            continue;
        };
        let m = &data.models[model.0 as usize];
        let p = tree.world_placement(id).expect("a node of the tree");
        // The lowest placed voxel (not the model's box): the content's corner goes to
        // `offset`, as in a flattening import.
        let size = model_size(m);
        for v in &m.voxels {
            lo = lo.min(p.place(model_voxel(v, m), size));
        }
        placed.insert(model);
        for v in &m.voxels {
            used[v.i as usize] = true;
        }
    }
    if placed.is_empty() || lo == IVec3::MAX {
        return Err(VoxError::NothingPlaced {
            models: data.models.len(),
            voxels: data.models.iter().map(|m| m.voxels.len() as u64).sum(),
            why: "no model is placed by the scene graph".into(),
        });
    }
    let root = tree.node_mut(ObjectTree::ROOT).expect("the root");
    root.placement.t += (-lo).max(IVec3::ZERO) + offset;
    let indices: Vec<(IVec3, u8)> = (0..=255u8)
        .filter(|i| used[*i as usize])
        .map(|i| (IVec3::ZERO, i))
        .collect();
    let palette = palette_of(&data);
    let mut taken = std::collections::HashSet::new();
    let map = install_materials(world, &data, &indices, &mut report, |i| {
        colour_slot(world, palette[i as usize], &mut taken)
    })?;
    let table = world.materials().clone();
    let mut models = BTreeMap::new();
    for id in placed {
        let m = &data.models[id.0 as usize];
        models.insert(id, model_of(m, &map, &table)?);
    }
    report.instances = tree.drawn().len();
    report.voxels = models
        .iter()
        .map(|(id, m)| m.solid_count() * tree.instances(*id).len() as u64)
        .sum();
    Ok(ObjectsInto {
        tree,
        models,
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
    let voxels = m
        .voxels
        .iter()
        .map(|v| (model_voxel(v, m), map[v.i as usize]));
    VoxelModel::from_voxels(model_size(m), voxels, table)
}

/// The `.vox` data of a scene of objects: one nTRN + nGRP per group and nTRN + nSHP per
/// object (names, hidden flags, rotations, layers), one model per placed model (shared
/// between its instances), a palette slot per used material (at most 255) with MATL chunks.
/// MagicaVoxel's models are at most 256 on a side: a larger model is written as chunks of
/// at most 256 under a group that takes the object's place (so it comes back as a group).
pub fn export_objects_data(
    objects: &Objects,
    table: &brickmap::MaterialTable,
) -> Result<DotVoxData, VoxError> {
    let tree = objects.tree();
    let mut slots = super::export::Slots::default();
    let mut index: BTreeMap<ModelId, (IVec3, Vec<Chunk>)> = BTreeMap::new();
    let mut models = Vec::new();
    for (id, m) in objects.models() {
        if tree.instances(*id).is_empty() {
            continue;
        }
        let s = m.size();
        let mv = IVec3::new(s.x, s.z, s.y);
        // A model over 256 on a side is written as chunks of at most 256 (MagicaVoxel's
        // limit), each placed in a group where its voxels were.
        let mut chunks: BTreeMap<[i32; 3], Vec<Voxel>> = BTreeMap::new();
        for (b, brick) in m.bricks() {
            for bit in brick.mask.ones() {
                let u = b.as_ivec3() * 8
                    + IVec3::new((bit % 8) as i32, (bit / 8 % 8) as i32, (bit / 64) as i32);
                let v = IVec3::new(u.x, s.z - 1 - u.z, u.y);
                let c = v.div_euclid(IVec3::splat(256));
                let l = v - c * 256;
                chunks.entry(c.to_array()).or_default().push(Voxel {
                    x: l.x as u8,
                    y: l.y as u8,
                    z: l.z as u8,
                    i: slots.slot(brick.material(bit))?,
                });
            }
        }
        if chunks.is_empty() && mv.cmple(IVec3::splat(256)).all() {
            // An empty model stays one (empty) model.
            chunks.insert([0, 0, 0], Vec::new());
        }
        let mut list = Vec::new();
        for (c, voxels) in chunks {
            let offset = IVec3::from_array(c) * 256;
            let size = (mv - offset).min(IVec3::splat(256));
            list.push(Chunk {
                model: models.len() as u32,
                offset,
                size,
            });
            models.push(super::export::vox_model(size, voxels));
        }
        index.insert(*id, (mv, list));
    }
    let mut scenes = Vec::new();
    write_node(objects, ObjectTree::ROOT, &index, &mut scenes);
    let colours = slots.palette_and_materials(table)?;
    let layers = tree
        .layers()
        .iter()
        .map(|l| {
            let mut a = dot_vox::Dict::new();
            a.insert("_name".into(), l.name.clone());
            if !l.visible {
                a.insert("_hidden".into(), "1".into());
            }
            dot_vox::Layer { attributes: a }
        })
        .collect();
    Ok(super::export::vox_data(models, colours, scenes, layers))
}

/// One ≤ 256³ piece of a model: its `.vox` model, its offset in the whole model and its
/// size (both in the file's axes).
struct Chunk {
    model: u32,
    offset: IVec3,
    size: IVec3,
}

/// The transform node of a shape, with a name, a translation and a layer.
fn shape_transform(name: String, t: IVec3, child: u32, layer_id: u32) -> SceneNode {
    let mut frame = dot_vox::Dict::new();
    frame.insert("_t".into(), format!("{} {} {}", t.x, t.y, t.z));
    let mut attributes = dot_vox::Dict::new();
    attributes.insert("_name".into(), name);
    SceneNode::Transform {
        attributes,
        frames: vec![dot_vox::Frame::new(frame)],
        child,
        layer_id,
    }
}

fn shape(model: u32) -> SceneNode {
    SceneNode::Shape {
        attributes: Default::default(),
        models: vec![dot_vox::ShapeModel {
            model_id: model,
            attributes: Default::default(),
        }],
    }
}

/// Writes a node (nTRN, then its nGRP or nSHP) and its subtree; returns its nTRN's index.
fn write_node(
    objects: &Objects,
    id: NodeId,
    index: &BTreeMap<ModelId, (IVec3, Vec<Chunk>)>,
    scenes: &mut Vec<SceneNode>,
) -> u32 {
    let tree = objects.tree();
    let node = tree.node(id).expect("a node of the tree");
    let back = axes().inverse();
    let rot = node.placement.rot.conjugate(&back);
    // An object's translation takes back the half-voxel pivot shift of an odd model height.
    let t = match node.kind {
        NodeKind::Object { model, .. } => {
            let odd = objects.model(model).expect("placed models exist").size().z % 2;
            node.placement.t + node.placement.rot.apply(IVec3::new(0, 0, odd))
        }
        NodeKind::Group { .. } => node.placement.t,
    };
    let t = back.apply(t);
    let mut frame = dot_vox::Dict::new();
    frame.insert("_t".into(), format!("{} {} {}", t.x, t.y, t.z));
    if rot != brickmap::objects::Orientation::IDENTITY {
        frame.insert("_r".into(), rot.to_vox_byte().to_string());
    }
    let mut attributes = dot_vox::Dict::new();
    attributes.insert("_name".into(), node.name.clone());
    if !node.visible {
        attributes.insert("_hidden".into(), "1".into());
    }
    let at = scenes.len() as u32;
    let layer_id = match node.kind {
        NodeKind::Object { layer, .. } => u32::from(layer.0),
        NodeKind::Group { .. } => u32::MAX,
    };
    scenes.push(SceneNode::Transform {
        attributes,
        frames: vec![dot_vox::Frame::new(frame)],
        child: at + 1,
        layer_id,
    });
    match &node.kind {
        NodeKind::Group { children } => {
            scenes.push(SceneNode::Group {
                attributes: Default::default(),
                children: Vec::new(),
            });
            let mut kids = Vec::with_capacity(children.len());
            for c in children {
                kids.push(write_node(objects, *c, index, scenes));
            }
            if let SceneNode::Group { children, .. } = &mut scenes[at as usize + 1] {
                *children = kids;
            }
        }
        NodeKind::Object { model, .. } => match &index[model] {
            (whole, chunks) if chunks.len() == 1 && chunks[0].size == *whole => {
                scenes.push(shape(chunks[0].model))
            }
            (whole, chunks) => {
                // x = v + ½ − ⌊s/2⌋ of the whole model = u + ½ − ⌊s_c/2⌋ + T_c of a chunk.
                let whole = *whole;
                let group = scenes.len();
                scenes.push(SceneNode::Group {
                    attributes: Default::default(),
                    children: Vec::new(),
                });
                let mut kids = Vec::new();
                for (i, c) in chunks.iter().enumerate() {
                    let t = c.offset + c.size / 2 - whole / 2;
                    let at = scenes.len() as u32;
                    kids.push(at);
                    scenes.push(shape_transform(
                        format!("{} {i}", node.name),
                        t,
                        at + 1,
                        layer_id,
                    ));
                    scenes.push(shape(c.model));
                }
                if let SceneNode::Group { children, .. } = &mut scenes[group] {
                    *children = kids;
                }
            }
        },
    }
    at
}

/// Exports a scene of objects to a `.vox` file, atomically.
pub fn export_objects(
    objects: &Objects,
    table: &brickmap::MaterialTable,
    path: &Path,
) -> Result<ExportReport, FormatError> {
    let data = export_objects_data(objects, table).map_err(|e| FormatError::vox(path, e))?;
    super::export::write_data(&data, path)
}
