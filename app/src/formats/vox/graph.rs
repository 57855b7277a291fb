//! The `.vox` scene graph read as an object tree (`brickmap::objects::ObjectTree`, in
//! voxbrick's axes): nTRN + nGRP become groups, nTRN + nSHP objects, with the nTRN's `_name`,
//! `_hidden` and layer, the file's LAYR layers, and model ids kept (instances stay shared).
//! MagicaVoxel's rotation bytes are read by `Orientation::from_vox_byte` (checked there,
//! because `dot_vox` asserts on bad bytes). The flattening import places the tree's drawn
//! objects, in drawing order (a later voxel wins).
//!
//! Axes: MagicaVoxel's cell centre c is voxbrick's A·c with A = (x, y, z) ↦ (x, z, −y), so a
//! transform (R, t) becomes (A·R·A⁻¹, A·t); a model of size s becomes one of size
//! (sx, sz, sy) with voxel v at (vx, vz, sy − 1 − vy). Its pivot ⌊s/2⌋ then sits half a
//! voxel off on an odd sy, which an object's translation absorbs exactly: t − R'·(0, 0, sy mod 2).

use super::*;
use brickmap::objects::{
    Layer, LayerId, ModelId, NewNode, NodeId, ObjectTree, Orientation, Placement,
};

/// What the walk does with hidden nodes and nodes on hidden layers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Hidden {
    /// Leave them out (reported).
    Skip,
    /// Keep them, shown.
    Show,
    /// Keep them, hidden as in the file.
    Keep,
}

/// MagicaVoxel's axes to voxbrick's, on cell centres.
pub(super) fn axes() -> Orientation {
    Orientation::from_matrix([[1, 0, 0], [0, 0, 1], [0, -1, 0]]).expect("a rotation")
}

/// A model's size in voxbrick axes.
pub(super) fn model_size(m: &Model) -> IVec3 {
    IVec3::new(m.size.x as i32, m.size.z as i32, m.size.y as i32)
}

/// A model voxel in voxbrick axes, in the model's own frame.
pub(super) fn model_voxel(v: &Voxel, m: &Model) -> IVec3 {
    IVec3::new(v.x as i32, v.z as i32, m.size.y as i32 - 1 - v.y as i32)
}

/// A group's transform in voxbrick axes.
fn group_placement(mv: Placement) -> Placement {
    let a = axes();
    Placement {
        rot: mv.rot.conjugate(&a),
        t: a.apply(mv.t),
    }
}

/// An object's transform in voxbrick axes, about the converted model's pivot.
fn object_placement(mv: Placement, m: &Model) -> Placement {
    let g = group_placement(mv);
    Placement {
        rot: g.rot,
        t: g.t - g.rot.apply(IVec3::new(0, 0, m.size.y as i32 % 2)),
    }
}

/// Every placed voxel (voxbrick coordinates, before the shift) with its 0-based palette index.
pub(super) fn place_instances(
    data: &DotVoxData,
    options: &ImportOptions,
    report: &mut ImportReport,
) -> Result<Vec<(IVec3, u8)>, VoxError> {
    let hidden = if options.include_hidden {
        Hidden::Show
    } else {
        Hidden::Skip
    };
    let tree = read_tree(data, hidden, report)?;
    let mut out = Vec::new();
    for d in tree.drawn() {
        let model = &data.models[d.model.0 as usize];
        if out.len() as u64 + model.voxels.len() as u64 > MAX_PLACED_VOXELS {
            return Err(VoxError::TooManyVoxels);
        }
        let size = model_size(model);
        for v in &model.voxels {
            out.push((d.placement.place(model_voxel(v, model), size), v.i));
        }
        report.instances += 1;
    }
    Ok(out)
}

/// The file's scene graph as an object tree (voxbrick axes; `ModelId(i)` is the file's model
/// i, checked to exist). What is left out or changed is added to the report.
pub(super) fn read_tree(
    data: &DotVoxData,
    hidden: Hidden,
    report: &mut ImportReport,
) -> Result<ObjectTree, VoxError> {
    let tree_error = |e: brickmap::objects::TreeError| VoxError::Malformed(e.to_string());
    let mut tree = ObjectTree::new();
    for (i, l) in data.layers.iter().enumerate() {
        let layer = Layer {
            name: l.name().unwrap_or_else(|| format!("layer {i}")),
            visible: !l.hidden() || hidden == Hidden::Show,
        };
        if i == 0 {
            *tree.layer_mut(LayerId(0)).map_err(tree_error)? = layer;
        } else {
            tree.add_layer(layer).map_err(tree_error)?;
        }
    }
    if data.scenes.is_empty() {
        // Without a scene graph (files before MagicaVoxel 0.99), several SIZE/XYZI pairs are
        // the frames of one animated model, as MagicaVoxel reads them: keep the first.
        if let Some(model) = data.models.first() {
            let new = NewNode::Object {
                model: ModelId(0),
                layer: LayerId(0),
            };
            let p = object_placement(Placement::IDENTITY, model);
            tree.add(ObjectTree::ROOT, None, "model 0", p, new)
                .map_err(tree_error)?;
        }
        if data.models.len() > 1 {
            report.dropped.push(format!(
                "animation frames after the first ignored (×{}; a file without a scene graph holds frames of one model)",
                data.models.len() - 1
            ));
        }
        return Ok(tree);
    }
    let mut walk = Walk {
        data,
        hidden,
        tree,
        root_used: false,
        notes: BTreeMap::new(),
    };
    walk.node(0, ObjectTree::ROOT, Pending::default(), 0)?;
    report.add_dropped(walk.notes);
    Ok(walk.tree)
}

/// What the nTRN nodes above a group or shape said: their composed transform (MagicaVoxel
/// axes) and the nearest one's name, visibility and layer.
#[derive(Clone, Default)]
struct Pending {
    transform: Placement,
    name: Option<String>,
    hidden: bool,
    layer: Option<u32>,
}

struct Walk<'a> {
    data: &'a DotVoxData,
    hidden: Hidden,
    tree: ObjectTree,
    /// Whether the file's top group has become the tree's root.
    root_used: bool,
    notes: BTreeMap<String, usize>,
}

impl Walk<'_> {
    fn note(&mut self, what: impl Into<String>) {
        *self.notes.entry(what.into()).or_default() += 1;
    }

    fn add(
        &mut self,
        parent: NodeId,
        name: String,
        p: Placement,
        new: NewNode,
        visible: bool,
    ) -> Result<NodeId, VoxError> {
        let id = self
            .tree
            .add(parent, None, name, p, new)
            .map_err(|e| VoxError::Malformed(e.to_string()))?;
        self.tree.node_mut(id).expect("just added").visible = visible;
        Ok(id)
    }

    fn node(
        &mut self,
        node: u32,
        parent: NodeId,
        above: Pending,
        depth: usize,
    ) -> Result<(), VoxError> {
        if depth > MAX_DEPTH {
            return Err(VoxError::TooDeep);
        }
        let data = self.data;
        let Some(n) = data.scenes.get(node as usize) else {
            return Err(VoxError::MissingNode(node));
        };
        let hidden = |attrs: &dot_vox::Dict| attrs.get("_hidden").is_some_and(|v| v == "1");
        match n {
            SceneNode::Transform {
                attributes,
                frames,
                child,
                layer_id,
            } => {
                let layer_hidden = data
                    .layers
                    .get(*layer_id as usize)
                    .is_some_and(|l| l.hidden());
                if (hidden(attributes) || layer_hidden) && self.hidden == Hidden::Skip {
                    self.note(if layer_hidden {
                        format!("hidden layer {layer_id} skipped")
                    } else {
                        "hidden node skipped".into()
                    });
                    return Ok(());
                }
                if frames.len() > 1 {
                    self.note("animation frames after the first ignored");
                }
                let mut local = Placement::IDENTITY;
                if let Some(frame) = frames.first() {
                    if let Some(t) = frame.attributes.get("_t") {
                        let v: Vec<i32> = t
                            .split_whitespace()
                            .filter_map(|s| s.parse().ok())
                            .collect();
                        if v.len() != 3 || v.iter().any(|c| c.abs() > 1 << 20) {
                            return Err(VoxError::BadTranslation {
                                node,
                                value: t.clone(),
                            });
                        }
                        local.t = IVec3::new(v[0], v[1], v[2]);
                    }
                    if let Some(r) = frame.attributes.get("_r") {
                        match r
                            .trim()
                            .parse::<u8>()
                            .ok()
                            .and_then(Orientation::from_vox_byte)
                        {
                            Some(rot) => local.rot = rot,
                            None => self.note(format!("invalid rotation {r:?} replaced by none")),
                        }
                    }
                }
                let here = Pending {
                    transform: above.transform.then(&local),
                    name: attributes.get("_name").cloned().or(above.name),
                    hidden: above.hidden || (self.hidden == Hidden::Keep && hidden(attributes)),
                    layer: Some(*layer_id),
                };
                self.node(*child, parent, here, depth + 1)
            }
            SceneNode::Group {
                attributes,
                children,
            } => {
                if hidden(attributes) && self.hidden == Hidden::Skip {
                    self.note("hidden group skipped");
                    return Ok(());
                }
                let own = self.hidden == Hidden::Keep && hidden(attributes);
                let visible = !(above.hidden || own);
                let p = group_placement(above.transform);
                let group = if parent == ObjectTree::ROOT && !self.root_used {
                    // The file's top group is the scene itself.
                    self.root_used = true;
                    let root = self.tree.node_mut(ObjectTree::ROOT).expect("the root");
                    root.placement = p;
                    root.visible = visible;
                    if let Some(name) = above.name {
                        root.name = name;
                    }
                    ObjectTree::ROOT
                } else {
                    let name = above.name.unwrap_or_else(|| format!("group {node}"));
                    self.add(parent, name, p, NewNode::Group, visible)?
                };
                for c in children {
                    self.node(*c, group, Pending::default(), depth + 1)?;
                }
                Ok(())
            }
            SceneNode::Shape { models, .. } => {
                if models.len() > 1 {
                    self.note("animated shape: models after the first ignored");
                }
                if let Some(m) = models.first() {
                    let model =
                        data.models
                            .get(m.model_id as usize)
                            .ok_or(VoxError::MissingModel {
                                model: m.model_id,
                                unread: Vec::new(),
                            })?;
                    let layer = above
                        .layer
                        .filter(|l| (*l as usize) < data.layers.len())
                        .map_or(LayerId(0), |l| LayerId(l as u8));
                    let new = NewNode::Object {
                        model: ModelId(m.model_id),
                        layer,
                    };
                    let name = above
                        .name
                        .unwrap_or_else(|| format!("model {}", m.model_id));
                    let p = object_placement(above.transform, model);
                    self.add(parent, name, p, new, !above.hidden)?;
                }
                Ok(())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use brickmap::objects::NodeKind;
    use dot_vox::{Dict, Frame, ShapeModel};

    fn dict(pairs: &[(&str, &str)]) -> Dict {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    }

    fn transform(attrs: &[(&str, &str)], t: &str, child: u32, layer_id: u32) -> SceneNode {
        SceneNode::Transform {
            attributes: dict(attrs),
            frames: vec![Frame::new(dict(&[("_t", t)]))],
            child,
            layer_id,
        }
    }

    fn shape(model_id: u32) -> SceneNode {
        SceneNode::Shape {
            attributes: Dict::new(),
            models: vec![ShapeModel {
                model_id,
                attributes: Dict::new(),
            }],
        }
    }

    /// A house group (wall, hidden door) and two trees sharing a model, the second on a
    /// hidden layer.
    fn village() -> DotVoxData {
        let model = |x, y, z| Model {
            size: dot_vox::Size { x, y, z },
            voxels: vec![Voxel {
                x: 0,
                y: 0,
                z: 0,
                i: 1,
            }],
        };
        let scenes = vec![
            transform(&[], "0 0 0", 1, u32::MAX),
            SceneNode::Group {
                attributes: Dict::new(),
                children: vec![2, 8, 10],
            },
            transform(&[("_name", "house")], "10 0 0", 3, u32::MAX),
            SceneNode::Group {
                attributes: Dict::new(),
                children: vec![4, 6],
            },
            transform(&[("_name", "wall")], "0 0 4", 5, 0),
            shape(0),
            transform(&[("_name", "door"), ("_hidden", "1")], "0 1 0", 7, 0),
            shape(1),
            transform(&[("_name", "tree")], "30 0 0", 9, 0),
            shape(2),
            transform(&[], "40 0 0", 11, 1),
            shape(2),
        ];
        DotVoxData {
            version: 150,
            index_map: dot_vox::DEFAULT_INDEX_MAP.to_vec(),
            models: vec![model(8, 2, 6), model(2, 1, 3), model(3, 3, 9)],
            palette: dot_vox::DEFAULT_PALETTE.to_vec(),
            materials: vec![],
            scenes,
            layers: vec![
                dot_vox::Layer {
                    attributes: dict(&[("_name", "ground")]),
                },
                dot_vox::Layer {
                    attributes: dict(&[("_name", "scaffolding"), ("_hidden", "1")]),
                },
            ],
        }
    }

    fn names(tree: &ObjectTree, ids: &[NodeId]) -> Vec<String> {
        ids.iter()
            .map(|n| tree.node(*n).unwrap().name.clone())
            .collect()
    }

    #[test]
    fn the_graph_keeps_names_groups_hidden_flags_layers_and_shared_models() {
        let data = village();
        let mut report = ImportReport::default();
        let tree = read_tree(&data, Hidden::Keep, &mut report).unwrap();
        let root = tree.node(ObjectTree::ROOT).unwrap();
        assert_eq!(names(&tree, root.children()), ["house", "tree", "model 2"]);
        let house = root.children()[0];
        let kids = tree.node(house).unwrap().children().to_vec();
        assert_eq!(names(&tree, &kids), ["wall", "door"]);
        assert!(matches!(
            tree.node(house).unwrap().kind,
            NodeKind::Group { .. }
        ));
        assert!(!tree.node(kids[1]).unwrap().visible, "the door is hidden");
        assert_eq!(
            tree.layers()
                .iter()
                .map(|l| (l.name.as_str(), l.visible))
                .collect::<Vec<_>>(),
            [("ground", true), ("scaffolding", false)]
        );
        // The two trees share model 2; the second is on the hidden layer.
        let trees = tree.instances(ModelId(2));
        assert_eq!(trees, root.children()[1..]);
        assert_eq!(
            tree.node(trees[1]).unwrap().kind,
            NodeKind::Object {
                model: ModelId(2),
                layer: LayerId(1)
            }
        );
        // Drawn: the wall and the first tree.
        let drawn: Vec<_> = tree.drawn().iter().map(|d| d.node).collect();
        assert_eq!(drawn, [kids[0], trees[0]]);
        assert!(report.dropped.is_empty(), "{:?}", report.dropped);
        // Translations in voxbrick axes: MagicaVoxel's (10, 0, 0) + (0, 0, 4) is x 10, y 4.
        let wall = tree.world_placement(kids[0]).unwrap();
        assert_eq!(wall.t, IVec3::new(10, 4, 0));
        // Skipping hidden parts leaves them out of the tree and says so.
        let mut report = ImportReport::default();
        let skipped = read_tree(&data, Hidden::Skip, &mut report).unwrap();
        assert_eq!(skipped.len(), 4, "root, house, wall, tree");
        assert_eq!(
            report.dropped,
            ["hidden layer 1 skipped", "hidden node skipped"]
        );
    }
}
