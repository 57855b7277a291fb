//! The object commands (arrange mode, the Objects window): which object edits act on, show,
//! lock, rename, move, turn and flip an object, duplicate, instance, make unique, delete,
//! group, ungroup, merge, split the selection into a new object, move nodes into a group,
//! put objects on a layer, add a layer, show a layer. Each is an
//! [`ObjectOp`] (a batch for the compound ones, built by `brickmap::objects::arrange`) with
//! its exact inverse; a command that removes the active object makes the first remaining
//! one active, and its undo makes it active again. An object moved, turned, copied or
//! shown past the grid grows it (and moves everything by whole bricks where it passed
//! the origin), up to the largest grid; the undo shrinks it back exactly.

use super::error::{EditError, Result, invalid};
use super::inverse::{Applied, Inverse};
use crate::scene::Scene;
use brickmap::GridDims;
use brickmap::objects::{
    Axis, CompositeError, LayerId, NodeId, NodeKind, ObjectError, ObjectOp, Orientation, Placement,
    arrange,
};
use glam::IVec3;
use serde::{Deserialize, Serialize};

/// One object command (node ids are the tree's: stable through undo and redo, so a script's
/// ids stay valid).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ObjectCommand {
    /// Voxel edits act on this object (none: on nothing).
    Activate(Option<NodeId>),
    /// Shows or hides a node and its subtree.
    Show {
        /// The node.
        node: NodeId,
        /// Visible.
        visible: bool,
    },
    /// Locks or unlocks a node (a locked one refuses edits and moves).
    Lock {
        /// The node.
        node: NodeId,
        /// Locked.
        locked: bool,
    },
    /// Renames a node.
    Rename {
        /// The node.
        node: NodeId,
        /// Its new name.
        name: String,
    },
    /// Moves nodes by whole voxels (each in its parent's frame).
    Translate {
        /// The nodes.
        nodes: Vec<NodeId>,
        /// The move.
        by: IVec3,
    },
    /// Turns nodes by quarter turns, each about an axis through its own pivot.
    Turn {
        /// The nodes (a script may name one as `node: N`).
        #[serde(alias = "node", deserialize_with = "one_or_many")]
        nodes: Vec<NodeId>,
        /// The axis.
        axis: Axis,
        /// Quarter turns (counter-clockwise looking down the axis).
        quarters: i32,
    },
    /// Mirrors nodes, each along an axis through its own pivot.
    Flip {
        /// The nodes (a script may name one as `node: N`).
        #[serde(alias = "node", deserialize_with = "one_or_many")]
        nodes: Vec<NodeId>,
        /// The axis.
        axis: Axis,
    },
    /// Another object placing a copy of the node's model, moved by `offset`.
    Duplicate {
        /// The object.
        node: NodeId,
        /// Where the copy goes, relative to it.
        offset: IVec3,
    },
    /// Another object placing the same model (edits of one show in both).
    Instance {
        /// The object.
        node: NodeId,
        /// Where the instance goes, relative to it.
        offset: IVec3,
    },
    /// The object gets its own copy of its shared model.
    MakeUnique(NodeId),
    /// Removes nodes, their subtrees and the models only they placed.
    Delete(Vec<NodeId>),
    /// A new group holding the nodes, where the first one was.
    Group {
        /// The nodes.
        nodes: Vec<NodeId>,
        /// The group's name.
        name: String,
    },
    /// The group's children take its place; the group goes.
    Ungroup(NodeId),
    /// One new object holding what the objects show (later ones win where they overlap).
    Merge {
        /// The objects.
        nodes: Vec<NodeId>,
        /// The new object's name.
        name: String,
    },
    /// The active object's selected voxels move to a new object.
    SplitSelection,
    /// Moves nodes under a group, before one of its children (at its end when `None`), each
    /// staying where it is in the world.
    Reparent {
        /// The nodes, in the order they take.
        nodes: Vec<NodeId>,
        /// The group.
        parent: NodeId,
        /// The child they go before.
        before: Option<NodeId>,
    },
    /// Puts the objects among the nodes and in their subtrees on a layer.
    SetLayer {
        /// The nodes.
        nodes: Vec<NodeId>,
        /// The layer.
        layer: LayerId,
    },
    /// A new layer at the end of the list, shown.
    AddLayer(String),
    /// A new empty object of its own model, its lowest corner at `at` (world voxels), at
    /// the end of the drawing order; brushes edit it next.
    NewObject {
        /// Its name.
        name: String,
        /// Its model's size in voxels.
        size: IVec3,
        /// Where its lowest corner goes.
        at: IVec3,
    },
    /// Scale an object's model × 2 or × ½ about its centre (its pivot stays).
    Scale {
        /// The object.
        node: NodeId,
        /// × 2 or × ½.
        step: crate::selection_scale::ScaleStep,
    },
    /// Changes an object's model's canvas ([`super::canvas`]): fit, crop or resize.
    Canvas {
        /// The object.
        node: NodeId,
        /// What to do.
        how: super::canvas::Canvas,
    },
    /// Shows or hides a layer.
    ShowLayer {
        /// The layer.
        layer: LayerId,
        /// Visible.
        visible: bool,
    },
}

impl ObjectCommand {
    /// A label for the history list.
    pub fn label(&self) -> String {
        match self {
            Self::Activate(Some(n)) => format!("Edit object #{}", n.0),
            Self::Activate(None) => "Edit no object".into(),
            Self::Show { node, visible } => {
                format!("{} #{}", if *visible { "Show" } else { "Hide" }, node.0)
            }
            Self::Lock { node, locked } => {
                format!("{} #{}", if *locked { "Lock" } else { "Unlock" }, node.0)
            }
            Self::Rename { node, name } => format!("Rename #{} to {name:?}", node.0),
            Self::Translate { nodes, by } => format!("Move {} by {by}", names(nodes)),
            Self::Turn {
                nodes,
                axis,
                quarters,
            } => format!("Turn {} {}° about {axis:?}", names(nodes), quarters * 90),
            Self::Flip { nodes, axis } => format!("Flip {} along {axis:?}", names(nodes)),
            Self::Duplicate { node, .. } => format!("Duplicate #{}", node.0),
            Self::Instance { node, .. } => format!("Instance #{}", node.0),
            Self::MakeUnique(n) => format!("Make #{} unique", n.0),
            Self::Delete(nodes) => format!("Delete {}", names(nodes)),
            Self::Group { nodes, .. } => format!("Group {} nodes", nodes.len()),
            Self::Ungroup(n) => format!("Ungroup #{}", n.0),
            Self::Merge { nodes, .. } => format!("Merge {} objects", nodes.len()),
            Self::SplitSelection => "Split the selection into an object".into(),
            Self::Reparent { nodes, parent, .. } => {
                format!("Move {} into #{}", names(nodes), parent.0)
            }
            Self::SetLayer { nodes, layer } => format!("Put {} on layer {}", names(nodes), layer.0),
            Self::AddLayer(name) => format!("Add layer {name:?}"),
            Self::NewObject { name, size, .. } => {
                format!("New object {name:?} {}×{}×{}", size.x, size.y, size.z)
            }
            Self::Canvas { node, how } => format!("Canvas of #{}: {how:?}", node.0),
            Self::Scale { node, step } => format!("Scale #{}: {step:?}", node.0),
            Self::ShowLayer { layer, visible } => format!(
                "{} layer {}",
                if *visible { "Show" } else { "Hide" },
                layer.0
            ),
        }
    }

    /// Executes the command. On error the scene is as it was.
    pub fn apply(&self, scene: &mut Scene) -> Result<Applied> {
        let before = scene.active();
        if let Self::Activate(node) = self {
            if let Some(n) = node {
                let objects = scene.objects();
                if !matches!(objects.tree().node(*n)?.kind, NodeKind::Object { .. }) {
                    return Err(brickmap::objects::ObjectError::NotAnObject(*n).into());
                }
            }
            scene.set_active(*node);
            return Ok(Applied {
                inverse: Inverse::Active(before),
                changed_voxels: 0,
            });
        }
        let new_node = scene.objects().tree().next_id();
        let (inverse, changed_voxels) = apply_growing(scene, |scene| self.op(scene))?;
        // A new object is the one brushes edit.
        if matches!(self, Self::NewObject { .. }) {
            scene.set_active(Some(new_node));
            return Ok(Applied {
                inverse: Inverse::Compound(vec![inverse, Inverse::Active(before)]),
                changed_voxels,
            });
        }
        // The active object gone (deleted, merged, ungrouped away): the first one left.
        let gone = before.is_some_and(|n| {
            !scene
                .objects()
                .tree()
                .node(n)
                .is_ok_and(|n| matches!(n.kind, NodeKind::Object { .. }))
        });
        let inverse = if gone {
            let first = Scene::first_object(&scene.objects());
            scene.set_active(first);
            Inverse::Compound(vec![inverse, Inverse::Active(before)])
        } else {
            inverse
        };
        Ok(Applied {
            inverse,
            changed_voxels,
        })
    }

    /// The op that does it, built from the scene as it is (again after a regrid: what it
    /// reads of the world moved).
    fn op(&self, scene: &Scene) -> Result<ObjectOp> {
        let table = scene.world.materials().clone();
        let objects = scene.objects();
        // Each node placed anew by `f` of its placement, in one batch.
        let each = |nodes: &[NodeId], f: &dyn Fn(Placement) -> Placement| -> Result<ObjectOp> {
            let places = nodes.iter().map(|&node| {
                let p = objects.tree().node(node)?.placement;
                Ok(ObjectOp::Place {
                    node,
                    placement: f(p),
                })
            });
            Ok(ObjectOp::Batch(places.collect::<Result<_>>()?))
        };
        let op = match self {
            Self::Activate(_) => unreachable!("handled before"),
            Self::Show { node, visible } => ObjectOp::Show {
                node: *node,
                visible: *visible,
            },
            Self::Lock { node, locked } => ObjectOp::Lock {
                node: *node,
                locked: *locked,
            },
            Self::Rename { node, name } => {
                if name.trim().is_empty() {
                    return Err(invalid("a name needs at least one visible character"));
                }
                ObjectOp::Rename {
                    node: *node,
                    name: name.clone(),
                }
            }
            Self::Translate { nodes, by } => each(nodes, &|p| Placement { t: p.t + *by, ..p })?,
            Self::Turn {
                nodes,
                axis,
                quarters,
            } => each(nodes, &|p| Placement {
                rot: Orientation::quarter_turn(*axis, *quarters).after(&p.rot),
                ..p
            })?,
            Self::Flip { nodes, axis } => each(nodes, &|p| Placement {
                rot: Orientation::flip(*axis).after(&p.rot),
                ..p
            })?,
            Self::Duplicate { node, offset } => arrange::duplicate(&objects, *node, *offset)?,
            Self::Instance { node, offset } => arrange::instance(&objects, *node, *offset)?,
            Self::MakeUnique(node) => arrange::make_unique(&objects, *node)?,
            Self::Canvas { node, how } => super::canvas::canvas_op(&objects, *node, *how, &table)?,
            Self::Scale { node, step } => super::canvas::scale_op(&objects, *node, *step, &table)?,
            Self::Delete(nodes) => arrange::delete(&objects, nodes)?,
            Self::Group { nodes, name } => arrange::group(&objects, nodes, name)?,
            Self::Ungroup(node) => arrange::ungroup(&objects, *node)?,
            Self::Merge { nodes, name } => arrange::merge(&objects, nodes, name, &table)?,
            Self::SplitSelection => {
                let node = scene
                    .active()
                    .ok_or(brickmap::objects::ObjectError::NoActiveObject)?;
                let selection = scene
                    .selection
                    .as_ref()
                    .ok_or(EditError::NothingToDo("nothing is selected"))?;
                arrange::split(&objects, node, &selection.voxels, &table)?
            }
            Self::Reparent {
                nodes,
                parent,
                before,
            } => arrange::reparent(&objects, nodes, *parent, *before)?,
            Self::SetLayer { nodes, layer } => {
                let tree = objects.tree();
                let mut seen = std::collections::BTreeSet::new();
                let mut ops = Vec::new();
                for n in nodes {
                    for node in tree.subtree(*n)? {
                        if matches!(tree.node(node)?.kind, NodeKind::Object { .. })
                            && seen.insert(node)
                        {
                            ops.push(ObjectOp::SetLayer {
                                node,
                                layer: *layer,
                            });
                        }
                    }
                }
                ObjectOp::Batch(ops)
            }
            Self::AddLayer(name) => {
                if name.trim().is_empty() {
                    return Err(invalid("a name needs at least one visible character"));
                }
                ObjectOp::AddLayer(brickmap::objects::Layer {
                    name: name.clone(),
                    visible: true,
                })
            }
            Self::NewObject { name, size, at } => {
                if name.trim().is_empty() {
                    return Err(invalid("a name needs at least one visible character"));
                }
                let model = objects.free_model_id();
                let voxels = brickmap::objects::Model::new(*size)?;
                let layer = active_layer(scene, &objects);
                ObjectOp::Batch(vec![
                    ObjectOp::AddModel {
                        model,
                        voxels: Box::new(voxels),
                    },
                    ObjectOp::Add {
                        parent: brickmap::objects::ObjectTree::ROOT,
                        index: None,
                        name: name.clone(),
                        // The model's centre (its pivot) goes at the corner plus half its size.
                        placement: Placement::at(*at + *size / 2),
                        new: brickmap::objects::NewNode::Object { model, layer },
                    },
                ])
            }
            Self::ShowLayer { layer, visible } => ObjectOp::ShowLayer {
                layer: *layer,
                visible: *visible,
            },
        };
        Ok(op)
    }
}

/// Applies the op `build` makes of the scene; where it would place an object past the grid,
/// the grid grows first (a regrid, after which the op is built again: what it reads of the
/// world moved) and the inverse shrinks it back after undoing the op. Past the largest grid
/// the refusal names it; on any error the scene is as it was.
pub(super) fn apply_growing(
    scene: &mut Scene,
    build: impl Fn(&Scene) -> Result<ObjectOp>,
) -> Result<(Inverse, u64)> {
    let mut regrids = Vec::new();
    let (inverse, changed_voxels) =
        loop {
            let done = build(scene).and_then(|op| Ok(scene.apply(op)?));
            let grown =
                match &done {
                    Err(EditError::Objects(ObjectError::Composite(
                        CompositeError::OutsideGrid { lo, hi, grid, .. },
                    ))) if regrids.len() < MAX_REGRIDS => larger(*lo, *hi, *grid),
                    _ => None,
                };
            match (done, grown) {
                (Ok(done), _) => break done,
                (Err(_), Some((dims, shift))) => regrids.push(scene.regrid(dims, shift)?),
                (Err(e), None) => {
                    for (dims, shift) in regrids.into_iter().rev() {
                        scene.regrid(dims, shift)?;
                    }
                    return Err(match e {
                        EditError::Objects(ObjectError::Composite(
                            CompositeError::OutsideGrid { node, lo, hi, grid },
                        )) => invalid(format!(
                            "object #{} would cover {lo}..{hi}: that needs a grid past the \
                         largest, {}×{}×{} voxels (the grid is {}×{}×{})",
                            node.0, MAX_GRID.x, MAX_GRID.y, MAX_GRID.z, grid.x, grid.y, grid.z
                        )),
                        e => e,
                    });
                }
            }
        };
    let mut inverse = Inverse::Voxels(vec![inverse], None);
    if !regrids.is_empty() {
        let mut parts: Vec<Inverse> = regrids
            .into_iter()
            .map(|(dims, shift)| Inverse::Regrid(dims, shift))
            .collect();
        parts.push(inverse);
        inverse = Inverse::Compound(parts);
    }
    Ok((inverse, changed_voxels))
}

/// The ops that add a `.vox` file's objects (from `formats::vox::objects_into`) to the
/// scene: its models under unused ids, a group named `name` at the end of the drawing
/// order holding the file's tree (the root's placement its own), hidden and locked nodes as
/// the file has them. Node ids are predicted as the tree will give them (the lowest free,
/// in order).
pub(super) fn import_ops(
    scene: &Scene,
    into: crate::formats::vox::ObjectsInto,
    name: &str,
) -> Result<ObjectOp> {
    use brickmap::objects::{ModelId, NewNode, ObjectTree};
    let objects = scene.objects();
    let tree = objects.tree();
    let mut free_nodes = (0u32..).map(NodeId).filter(|n| tree.node(*n).is_err());
    let mut free_models = (0u32..)
        .map(ModelId)
        .filter(|m| objects.model(*m).is_none());
    let mut ops = Vec::new();
    let mut model_ids = std::collections::BTreeMap::new();
    for (id, model) in into.models {
        let new = free_models.next().expect("fewer than 2^32 models");
        model_ids.insert(id, new);
        ops.push(ObjectOp::AddModel {
            model: new,
            voxels: Box::new(model),
        });
    }
    let file = &into.tree;
    let layer = active_layer(scene, &objects);
    let mut node_ids = std::collections::BTreeMap::new();
    let mut flags = Vec::new();
    for id in file.subtree(ObjectTree::ROOT)? {
        let n = file.node(id)?;
        let parent = n.parent().map_or(ObjectTree::ROOT, |p| node_ids[&p]);
        let (name, new, on_hidden_layer) = match &n.kind {
            _ if id == ObjectTree::ROOT => (name.to_string(), NewNode::Group, false),
            NodeKind::Group { .. } => (n.name.clone(), NewNode::Group, false),
            NodeKind::Object { model, layer: on } => (
                n.name.clone(),
                NewNode::Object {
                    model: model_ids[model],
                    layer,
                },
                // Objects on a hidden layer of the file come in hidden.
                file.layers().get(on.0 as usize).is_some_and(|l| !l.visible),
            ),
        };
        let new_id = free_nodes.next().expect("fewer than 2^32 nodes");
        node_ids.insert(id, new_id);
        ops.push(ObjectOp::Add {
            parent,
            index: None,
            name,
            placement: n.placement,
            new,
        });
        if !n.visible || on_hidden_layer {
            flags.push(ObjectOp::Show {
                node: new_id,
                visible: false,
            });
        }
        if n.locked {
            flags.push(ObjectOp::Lock {
                node: new_id,
                locked: true,
            });
        }
    }
    ops.extend(flags);
    Ok(ObjectOp::Batch(ops))
}

/// The layer of the object brushes edit (new objects go on it), else the first.
fn active_layer(scene: &Scene, objects: &brickmap::objects::Objects) -> LayerId {
    scene
        .active()
        .and_then(|n| match objects.tree().node(n).ok()?.kind {
            NodeKind::Object { layer, .. } => Some(layer),
            NodeKind::Group { .. } => None,
        })
        .unwrap_or(LayerId(0))
}

/// The largest grid, in voxels.
const MAX_GRID: IVec3 = IVec3::new(
    brickmap::grid::MAX_BRICKS_X as i32 * 8,
    brickmap::grid::MAX_BRICKS_Y as i32 * 8,
    brickmap::grid::MAX_BRICKS_Z as i32 * 8,
);

/// Regrids one command may make before it is refused (each takes in at least the object the
/// composite refused; a group's move may need one per object).
const MAX_REGRIDS: usize = 16;

/// The grid that holds the box `lo..hi` as well as the grid `grid`, and the shift (whole
/// bricks) that brings `lo` to the origin; `None` past the largest grid.
fn larger(lo: IVec3, hi: IVec3, grid: IVec3) -> Option<(GridDims, IVec3)> {
    let shift = ((-lo).max(IVec3::ZERO) + 7) / 8 * 8;
    let need = hi.max(grid) + shift;
    let dims = GridDims::from_voxels(need.as_uvec3()).ok()?;
    Some((dims, shift))
}

/// A list of nodes, or one node alone (the form scripts wrote before a turn or a flip took
/// several): `(2)`, `[(2), (5)]` or `[2, 5]` (RON writes a node id as a one-field tuple).
fn one_or_many<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> std::result::Result<Vec<NodeId>, D::Error> {
    use serde::de::{SeqAccess, Visitor};
    use std::fmt;
    /// Node ids: a bare number, or a sequence of bare or wrapped ones.
    struct Ids;
    impl<'de> Visitor<'de> for Ids {
        type Value = Vec<NodeId>;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a node id or a list of node ids")
        }
        fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<Self::Value, E> {
            let id = u32::try_from(v).map_err(|_| E::custom(format!("node id {v} too large")))?;
            Ok(vec![NodeId(id)])
        }
        fn visit_newtype_struct<D: serde::Deserializer<'de>>(
            self,
            d: D,
        ) -> std::result::Result<Self::Value, D::Error> {
            d.deserialize_any(Ids)
        }
        fn visit_seq<A: SeqAccess<'de>>(
            self,
            mut seq: A,
        ) -> std::result::Result<Self::Value, A::Error> {
            let mut out = Vec::new();
            while let Some(ids) = seq.next_element_seed(IdsSeed)? {
                out.extend(ids);
            }
            Ok(out)
        }
    }
    struct IdsSeed;
    impl<'de> serde::de::DeserializeSeed<'de> for IdsSeed {
        type Value = Vec<NodeId>;
        fn deserialize<D: serde::Deserializer<'de>>(
            self,
            d: D,
        ) -> std::result::Result<Self::Value, D::Error> {
            d.deserialize_any(Ids)
        }
    }
    d.deserialize_any(Ids)
}

/// Node ids for a label: "#3" or "3 nodes".
fn names(nodes: &[NodeId]) -> String {
    match nodes {
        [n] => format!("#{}", n.0),
        _ => format!("{} nodes", nodes.len()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_turn_or_a_flip_reads_one_node_or_several() {
        let one: ObjectCommand = ron::from_str("Turn(node: (2), axis: Y, quarters: 1)").unwrap();
        let many: ObjectCommand =
            ron::from_str("Turn(nodes: [(2), (5)], axis: Y, quarters: 1)").unwrap();
        let flip: ObjectCommand = ron::from_str("Flip(node: (7), axis: Z)").unwrap();
        assert_eq!(
            one,
            ObjectCommand::Turn {
                nodes: vec![NodeId(2)],
                axis: Axis::Y,
                quarters: 1
            }
        );
        assert_eq!(
            many,
            ObjectCommand::Turn {
                nodes: vec![NodeId(2), NodeId(5)],
                axis: Axis::Y,
                quarters: 1
            }
        );
        assert_eq!(
            flip,
            ObjectCommand::Flip {
                nodes: vec![NodeId(7)],
                axis: Axis::Z
            }
        );
        // What is written reads back.
        let text = ron::to_string(&many).unwrap();
        assert_eq!(ron::from_str::<ObjectCommand>(&text).unwrap(), many);
        assert!(ron::from_str::<ObjectCommand>("Turn(node: \"x\", axis: Y, quarters: 1)").is_err());
    }
}
