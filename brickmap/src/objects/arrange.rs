//! The arrange-mode operations as [`ObjectOp`] batches, built from the scene as it is: apply
//! one with [`Objects::apply`] and its inverse undoes it exactly, like any op. Each checks
//! what it needs first and returns an error naming it, building nothing.
//!
//! - **instance**: another object placing the same model, offset by `offset`;
//! - **duplicate**: a copy of the model placed by a new object, offset;
//! - **make unique**: the object gets its own copy of its model;
//! - **group**: a new group (identity) where the first node was, holding the nodes;
//! - **ungroup**: the group's children take its place (their world placements kept), the
//!   group goes;
//! - **merge**: one new object (identity, a model the size of the objects' joint box) holding
//!   what the objects show, where they overlap the later one's voxel (the drawing order);
//!   the objects go;
//! - **reparent**: nodes move under a group, before one of its children or at its end, each
//!   where it was in the world (its placement composed anew under the group);
//! - **delete**: the node and its subtree go, with the models only they placed;
//! - **split**: the voxels of an object inside a world voxel set move to a new object whose
//!   model is their box, placed so that they stay where they are.

use super::model::Model;
use super::orient::{Orientation, Placement};
use super::scene::{ObjectError, ObjectOp, Objects};
use super::tree::{ModelId, NewNode, NodeId, NodeKind, ObjectTree, TreeError};
use crate::edit::{EditOp, Mode};
use crate::material::MaterialTable;
use crate::shape::Shape;
use crate::voxel_set::VoxelSet;
use glam::IVec3;
use std::collections::BTreeMap;
use std::sync::Arc;

/// The object's model and layer.
fn object(o: &Objects, node: NodeId) -> Result<(ModelId, super::tree::LayerId), ObjectError> {
    match o.tree().node(node)?.kind {
        NodeKind::Object { model, layer } => Ok((model, layer)),
        NodeKind::Group { .. } => Err(ObjectError::NotAnObject(node)),
    }
}

/// Where a node sits: its parent and its index there.
fn slot(tree: &ObjectTree, node: NodeId) -> Result<(NodeId, usize), ObjectError> {
    let parent = tree.node(node)?.parent().ok_or(TreeError::Root)?;
    let index = tree
        .node(parent)?
        .children()
        .iter()
        .position(|c| *c == node)
        .expect("a node is among its parent's children");
    Ok((parent, index))
}

/// The node added right after `node`, with a placement moved by `offset`.
fn add_after(
    o: &Objects,
    node: NodeId,
    name: String,
    model: ModelId,
    offset: IVec3,
) -> Result<ObjectOp, ObjectError> {
    let (parent, index) = slot(o.tree(), node)?;
    let n = o.tree().node(node)?;
    let (_, layer) = object(o, node)?;
    Ok(ObjectOp::Add {
        parent,
        index: Some(index + 1),
        name,
        placement: Placement {
            rot: n.placement.rot,
            t: n.placement.t + offset,
        },
        new: NewNode::Object { model, layer },
    })
}

/// Removes nodes with their subtrees (a node inside another one removed goes with it), and
/// the models only they placed (a file saved after it holds no model nothing places).
pub fn delete(o: &Objects, nodes: &[NodeId]) -> Result<ObjectOp, ObjectError> {
    let tree = o.tree();
    let mut tops: Vec<NodeId> = Vec::new();
    let mut gone: Vec<NodeId> = Vec::new();
    for n in nodes {
        if !gone.contains(n) {
            for g in tree.subtree(*n)? {
                if let Some(i) = tops.iter().position(|t| *t == g) {
                    tops.remove(i);
                }
                gone.push(g);
            }
            tops.push(*n);
        }
    }
    let mut models = std::collections::BTreeSet::new();
    for n in &gone {
        if let NodeKind::Object { model, .. } = tree.node(*n)?.kind {
            models.insert(model);
        }
    }
    let mut ops: Vec<ObjectOp> = tops.iter().map(|n| ObjectOp::Remove { node: *n }).collect();
    for model in models {
        if tree.instances(model).iter().all(|i| gone.contains(i)) {
            ops.push(ObjectOp::RemoveModel { model });
        }
    }
    Ok(ObjectOp::Batch(ops))
}

/// Another object placing the same model, after it, moved by `offset`.
pub fn instance(o: &Objects, node: NodeId, offset: IVec3) -> Result<ObjectOp, ObjectError> {
    let (model, _) = object(o, node)?;
    let name = o.tree().node(node)?.name.clone();
    add_after(o, node, name, model, offset)
}

/// A copy of the object's model, placed by a new object after it, moved by `offset`.
pub fn duplicate(o: &Objects, node: NodeId, offset: IVec3) -> Result<ObjectOp, ObjectError> {
    let (model, _) = object(o, node)?;
    let copy = o.free_model_id();
    let voxels = o.model(model).ok_or(ObjectError::NoModel(model))?.clone();
    let name = format!("{} copy", o.tree().node(node)?.name);
    Ok(ObjectOp::Batch(vec![
        ObjectOp::AddModel {
            model: copy,
            voxels: Box::new(voxels),
        },
        add_after(o, node, name, copy, offset)?,
    ]))
}

/// The object gets its own copy of its model (its former instances keep the original).
pub fn make_unique(o: &Objects, node: NodeId) -> Result<ObjectOp, ObjectError> {
    let (model, _) = object(o, node)?;
    let copy = o.free_model_id();
    let voxels = o.model(model).ok_or(ObjectError::NoModel(model))?.clone();
    Ok(ObjectOp::Batch(vec![
        ObjectOp::AddModel {
            model: copy,
            voxels: Box::new(voxels),
        },
        ObjectOp::SetModel { node, model: copy },
    ]))
}

/// A new group where the first node is, holding the nodes in their order (all must share
/// that parent; the group's placement is the identity, so nothing moves).
pub fn group(o: &Objects, nodes: &[NodeId], name: &str) -> Result<ObjectOp, ObjectError> {
    let first = *nodes.first().ok_or(TreeError::Root)?;
    let (parent, index) = slot(o.tree(), first)?;
    for n in nodes {
        if slot(o.tree(), *n)?.0 != parent {
            return Err(ObjectError::Tree(TreeError::IntoItself {
                node: *n,
                parent,
            }));
        }
    }
    // The group takes the lowest free id, as the add will give it.
    let group = o.tree().next_id();
    let mut ops = vec![ObjectOp::Add {
        parent,
        index: Some(index),
        name: name.to_string(),
        placement: Placement::IDENTITY,
        new: NewNode::Group,
    }];
    ops.extend(nodes.iter().map(|n| ObjectOp::Move {
        node: *n,
        parent: group,
        index: None,
    }));
    Ok(ObjectOp::Batch(ops))
}

/// The group's children move to its parent where it was (their world placements kept: the
/// group's placement composed into each), then the group goes.
pub fn ungroup(o: &Objects, group: NodeId) -> Result<ObjectOp, ObjectError> {
    let tree = o.tree();
    let g = tree.node(group)?;
    let NodeKind::Group { children } = &g.kind else {
        return Err(ObjectError::NotAnObject(group));
    };
    let (parent, index) = slot(tree, group)?;
    let mut ops = Vec::new();
    for (k, c) in children.iter().enumerate() {
        ops.push(ObjectOp::Reparent {
            node: *c,
            parent,
            index: Some(index + 1 + k),
            placement: g.placement.then(&tree.node(*c)?.placement),
        });
    }
    ops.push(ObjectOp::Remove { node: group });
    Ok(ObjectOp::Batch(ops))
}

/// Moves nodes under the group `parent`, before its child `before` (at its end when `None`),
/// in their order, each staying where it is in the world (its placement composed anew under
/// the parent). A node inside another one moved goes with it. Refused: the root, a parent
/// that is not a group or lies inside a moved node, `before` not a child of the parent.
pub fn reparent(
    o: &Objects,
    nodes: &[NodeId],
    parent: NodeId,
    before: Option<NodeId>,
) -> Result<ObjectOp, ObjectError> {
    let tree = o.tree();
    let NodeKind::Group { children } = &tree.node(parent)?.kind else {
        return Err(TreeError::NotAGroup(parent).into());
    };
    let mut moved: Vec<NodeId> = Vec::new();
    for &n in nodes {
        let mut up = tree.node(n)?.parent().ok_or(TreeError::Root)?;
        let inside = loop {
            if nodes.contains(&up) {
                break true;
            }
            match tree.node(up)?.parent() {
                Some(p) => up = p,
                None => break false,
            }
        };
        if !inside && !moved.contains(&n) {
            moved.push(n);
        }
    }
    let mut up = Some(parent);
    while let Some(u) = up {
        if let Some(&node) = moved.iter().find(|m| **m == u) {
            return Err(TreeError::IntoItself { node, parent }.into());
        }
        up = tree.node(u)?.parent();
    }
    // What the moved nodes go before: `before`, or the first child after it not moved.
    let anchor = match before {
        None => None,
        Some(b) => {
            let at = children
                .iter()
                .position(|c| *c == b)
                .ok_or(TreeError::NotAChild {
                    node: b,
                    group: parent,
                })?;
            children[at..].iter().copied().find(|c| !moved.contains(c))
        }
    };
    let into = inverse(&tree.world_placement(parent)?);
    // The parent's children as each move leaves them (an index counts after the node left).
    let mut list = children.clone();
    let mut ops = Vec::new();
    let mut previous: Option<NodeId> = None;
    for n in moved {
        list.retain(|c| *c != n);
        let at = |x: NodeId, list: &[NodeId]| list.iter().position(|c| *c == x);
        let index = match previous {
            Some(p) => at(p, &list).map_or(list.len(), |i| i + 1),
            None => anchor.and_then(|a| at(a, &list)).unwrap_or(list.len()),
        };
        list.insert(index, n);
        ops.push(ObjectOp::Reparent {
            node: n,
            parent,
            index: Some(index),
            placement: into.then(&tree.world_placement(n)?),
        });
        previous = Some(n);
    }
    Ok(ObjectOp::Batch(ops))
}

/// One object holding what the objects show (the later one's voxel where they overlap),
/// where the first of them was; the objects go. Hidden ones contribute nothing.
pub fn merge(
    o: &Objects,
    nodes: &[NodeId],
    name: &str,
    table: &MaterialTable,
) -> Result<ObjectOp, ObjectError> {
    let first = *nodes.first().ok_or(TreeError::Root)?;
    let (parent, index) = slot(o.tree(), first)?;
    let (_, layer) = object(o, first)?;
    // The visible ones among them, in drawing order.
    let drawn: Vec<_> = o
        .tree()
        .drawn()
        .into_iter()
        .filter(|d| nodes.contains(&d.node))
        .collect();
    let mut voxels: BTreeMap<[i32; 3], u8> = BTreeMap::new();
    for d in &drawn {
        let m = o.model(d.model).ok_or(ObjectError::NoModel(d.model))?;
        for (b, brick) in m.bricks() {
            for bit in brick.mask.ones() {
                let v = b.as_ivec3() * 8
                    + IVec3::new((bit & 7) as i32, (bit >> 3 & 7) as i32, (bit >> 6) as i32);
                voxels.insert(
                    d.placement.place(v, m.size()).to_array(),
                    brick.material(bit),
                );
            }
        }
    }
    let (lo, hi) = voxels.keys().fold((IVec3::MAX, IVec3::MIN), |(lo, hi), k| {
        let p = IVec3::from_array(*k);
        (lo.min(p), hi.max(p))
    });
    let size = if voxels.is_empty() {
        IVec3::ONE
    } else {
        hi - lo + 1
    };
    let lo = if voxels.is_empty() { IVec3::ZERO } else { lo };
    // In the merged model's frame: v = world − lo. The object is placed at identity in the
    // world: its parent's placement is undone (exact: placements are invertible).
    let relative = voxels.iter().map(|(k, m)| (IVec3::from_array(*k) - lo, *m));
    let model = Model::from_voxels(size, relative, table)?;
    let world = Placement::at(lo + size / 2);
    let above = o.tree().world_placement(parent)?;
    let local = inverse(&above).then(&world);
    let id = o.free_model_id();
    let mut ops = vec![
        ObjectOp::AddModel {
            model: id,
            voxels: Box::new(model),
        },
        ObjectOp::Add {
            parent,
            index: Some(index),
            name: name.to_string(),
            placement: local,
            new: NewNode::Object { model: id, layer },
        },
    ];
    ops.extend(nodes.iter().map(|n| ObjectOp::Remove { node: *n }));
    Ok(ObjectOp::Batch(ops))
}

/// The voxels of the object inside `selection` (world voxels) move to a new object after
/// it, whose model is their box, placed so that they stay where they are.
pub fn split(
    o: &Objects,
    node: NodeId,
    selection: &VoxelSet,
    table: &MaterialTable,
) -> Result<ObjectOp, ObjectError> {
    let (model, layer) = object(o, node)?;
    let m = o.model(model).ok_or(ObjectError::NoModel(model))?;
    let p = o.tree().world_placement(node)?;
    let inside = p.set_to_model(selection, m.size());
    // The new model: the original's voxels inside the selection, in their box.
    let held: Vec<(IVec3, u8)> = inside
        .voxels()
        .filter_map(|v| m.voxel(v).map(|mat| (v, mat)))
        .collect();
    let lo = held.iter().fold(IVec3::MAX, |a, (v, _)| a.min(*v));
    let hi = held.iter().fold(IVec3::MIN, |a, (v, _)| a.max(*v));
    if held.is_empty() {
        return Err(ObjectError::NothingSelected(node));
    }
    let size = hi - lo + 1;
    let part = Model::from_voxels(size, held.iter().map(|(v, mat)| (*v - lo, *mat)), table)?;
    let id = o.free_model_id();
    let (parent, index) = slot(o.tree(), node)?;
    let n = o.tree().node(node)?;
    // Placed so each voxel stays where it was: R(v − lo + ½ − ⌊s′/2⌋) + t′ = R(v + ½ −
    // ⌊s/2⌋) + t.
    let placement = Placement {
        rot: n.placement.rot,
        t: n.placement.t + n.placement.rot.apply(lo - m.size() / 2 + size / 2),
    };
    Ok(ObjectOp::Batch(vec![
        ObjectOp::AddModel {
            model: id,
            voxels: Box::new(part),
        },
        ObjectOp::Add {
            parent,
            index: Some(index + 1),
            name: format!("{} part", n.name),
            placement,
            new: NewNode::Object { model: id, layer },
        },
        ObjectOp::Edit {
            node,
            edit: EditOp::Shape {
                shape: Shape::Set(Arc::new(selection.clone())),
                mode: Mode::Remove,
            },
        },
    ]))
}

/// The inverse of a placement (on points: p ↦ R⁻¹·(p − t)).
fn inverse(p: &Placement) -> Placement {
    let rot: Orientation = p.rot.inverse();
    Placement {
        rot,
        t: -rot.apply(p.t),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::World;
    use crate::objects::orient::Axis;
    use crate::objects::testing::{assert_matches, reference, start, table};

    /// Applies an op, checks the world against the reference, undoes it and checks that
    /// everything is as before; returns the objects after a redo.
    fn round(o: &mut Objects, w: &World, op: ObjectOp) -> ObjectOp {
        let t = table();
        let before = (o.tree().clone(), w.read().content_hash());
        let inverse = o.apply(w, op, &t).unwrap();
        assert_matches(w, &reference(o.tree(), o.models()));
        let redo = o.apply(w, inverse, &t).unwrap();
        assert_eq!((o.tree().clone(), w.read().content_hash()), before);
        o.apply(w, redo, &t).unwrap()
    }

    #[test]
    fn instances_duplicates_and_unique_copies() {
        let (mut o, w) = start(2);
        let a = NodeId(2);
        let op = instance(&o, a, IVec3::new(0, 0, 9)).unwrap();
        round(&mut o, &w, op);
        let (m, _) = object(&o, a).unwrap();
        assert_eq!(o.tree().instances(m).len(), 2);
        let op = duplicate(&o, a, IVec3::new(0, 8, 0)).unwrap();
        round(&mut o, &w, op);
        assert_eq!(o.models().len(), 3, "a new model");
        let copy = *o.models().keys().last().unwrap();
        assert_eq!(o.model(copy).unwrap(), o.model(m).unwrap());
        let op = make_unique(&o, a).unwrap();
        round(&mut o, &w, op);
        assert_ne!(object(&o, a).unwrap().0, m, "a owns a copy now");
        assert_eq!(
            o.tree().instances(m).len(),
            1,
            "the instance keeps the original"
        );
    }

    #[test]
    fn group_and_ungroup_move_nothing_even_under_a_turned_group() {
        let (mut o, w) = start(2);
        let t = table();
        let hash = w.read().content_hash();
        // Turn the group holding a and b about y, then ungroup it: a and b stay put.
        let g = NodeId(1);
        let p = o.tree().node(g).unwrap().placement;
        let turned = Placement {
            rot: Orientation::quarter_turn(Axis::Y, 1),
            t: p.t,
        };
        o.apply(
            &w,
            ObjectOp::Place {
                node: g,
                placement: turned,
            },
            &t,
        )
        .unwrap();
        let turned_hash = w.read().content_hash();
        assert_ne!(turned_hash, hash);
        let op = ungroup(&o, g).unwrap();
        round(&mut o, &w, op);
        assert_eq!(w.read().content_hash(), turned_hash, "nothing moved");
        assert!(o.tree().node(g).is_err(), "the group is gone");
        let root = o.tree().node(ObjectTree::ROOT).unwrap().children().to_vec();
        let op = group(&o, &root[..2], "pair").unwrap();
        round(&mut o, &w, op);
        assert_eq!(w.read().content_hash(), turned_hash, "nothing moved");
        let pair = o.tree().node(ObjectTree::ROOT).unwrap().children()[0];
        assert_eq!(o.tree().node(pair).unwrap().children(), &root[..2]);
    }

    #[test]
    fn reparent_keeps_world_placements_and_orders_as_asked() {
        let (mut o, w) = start(2);
        let t = table();
        let (g, a, b, c) = (NodeId(1), NodeId(2), NodeId(3), NodeId(4));
        let p = o.tree().node(g).unwrap().placement;
        let turned = Placement {
            rot: Orientation::quarter_turn(Axis::Y, 1).after(&Orientation::flip(Axis::X)),
            t: p.t,
        };
        let place = ObjectOp::Place {
            node: g,
            placement: turned,
        };
        o.apply(&w, place, &t).unwrap();
        let world = |o: &Objects| {
            [a, b, c].map(|n| {
                let m = object(o, n).unwrap().0;
                let at = o.tree().world_placement(n).unwrap();
                (at.bounds(o.model(m).unwrap().size()), at.rot)
            })
        };
        let children = |o: &Objects, n: NodeId| o.tree().node(n).unwrap().children().to_vec();
        let before = world(&o);
        // c into the turned, mirrored group, before b: nothing moves in the world.
        let op = reparent(&o, &[c], g, Some(b)).unwrap();
        round(&mut o, &w, op);
        assert_eq!(world(&o), before);
        assert_eq!(children(&o, g), vec![a, c, b]);
        // b and a (in that order) before c, where a is already before it.
        let op = reparent(&o, &[b, a], g, Some(c)).unwrap();
        round(&mut o, &w, op);
        assert_eq!(children(&o, g), vec![b, a, c]);
        // Before a moved node: before the first child after it not moved.
        let op = reparent(&o, &[b], g, Some(b)).unwrap();
        round(&mut o, &w, op);
        assert_eq!(children(&o, g), vec![b, a, c]);
        // The group and one of its children out to the root's end: the child goes with it.
        let op = reparent(&o, &[a, g], ObjectTree::ROOT, None).unwrap();
        round(&mut o, &w, op);
        assert_eq!(children(&o, ObjectTree::ROOT), vec![g]);
        assert_eq!(children(&o, g), vec![b, a, c]);
        assert_eq!(world(&o), before);
        // Refusals.
        assert!(matches!(
            reparent(&o, &[a], g, Some(g)),
            Err(ObjectError::Tree(TreeError::NotAChild { .. }))
        ));
        assert!(reparent(&o, &[ObjectTree::ROOT], g, None).is_err());
        assert!(matches!(
            reparent(&o, &[g], a, None),
            Err(ObjectError::Tree(TreeError::NotAGroup(_)))
        ));
        assert!(matches!(
            reparent(&o, &[g], g, None),
            Err(ObjectError::Tree(TreeError::IntoItself { .. }))
        ));
        assert_eq!(children(&o, ObjectTree::ROOT), vec![g]);
    }

    #[test]
    fn merge_keeps_what_shows_and_split_takes_a_part_out() {
        let (mut o, w) = start(3);
        let t = table();
        let hash = w.read().content_hash();
        // Merge a (in the turned-free group) and c (top level): the merged object goes
        // where a was.
        let (a, c) = (NodeId(2), NodeId(4));
        let op = merge(&o, &[a, c], "merged", &t).unwrap();
        round(&mut o, &w, op);
        assert_eq!(w.read().content_hash(), hash, "the same voxels show");
        assert!(o.tree().node(a).is_err() && o.tree().node(c).is_err());
        // Split the merged object along a box of world voxels.
        let merged = *o
            .tree()
            .drawn()
            .iter()
            .map(|d| d.node)
            .find(|n| o.tree().node(*n).unwrap().name == "merged")
            .iter()
            .next()
            .unwrap();
        let mut half = VoxelSet::new();
        for x in 0..40 {
            for y in 0..32 {
                for z in 0..48 {
                    half.insert(IVec3::new(x, y, z));
                }
            }
        }
        let (m, _) = object(&o, merged).unwrap();
        let solid = o.model(m).unwrap().solid_count();
        let op = split(&o, merged, &half, &t).unwrap();
        round(&mut o, &w, op);
        assert_eq!(w.read().content_hash(), hash, "the same voxels show");
        let part = o
            .tree()
            .node(o.tree().node(merged).unwrap().parent().unwrap())
            .unwrap()
            .children()
            .iter()
            .copied()
            .find(|n| o.tree().node(*n).unwrap().name == "merged part")
            .unwrap();
        let (pm, _) = object(&o, part).unwrap();
        let left = o.model(m).unwrap().solid_count();
        let taken = o.model(pm).unwrap().solid_count();
        assert!(
            taken > 0 && left > 0,
            "both halves hold voxels: {taken} + {left}"
        );
        assert_eq!(taken + left, solid);
        // A turned part splits in place too: its new part is its selected voxels' box,
        // every voxel where it was.
        let at = o.tree().node(part).unwrap().placement;
        let turned = Placement {
            rot: Orientation::quarter_turn(Axis::Y, 2).after(&at.rot),
            ..at
        };
        round(
            &mut o,
            &w,
            ObjectOp::Place {
                node: part,
                placement: turned,
            },
        );
        let hash = w.read().content_hash();
        let mut corner = VoxelSet::new();
        for x in 0..24 {
            for y in 0..32 {
                for z in 0..24 {
                    corner.insert(IVec3::new(x, y, z));
                }
            }
        }
        let op = split(&o, part, &corner, &t).unwrap();
        round(&mut o, &w, op);
        assert_eq!(w.read().content_hash(), hash, "the same voxels show");
        let empty = VoxelSet::new();
        assert!(matches!(
            split(&o, part, &empty, &t),
            Err(ObjectError::NothingSelected(_))
        ));
    }
}
