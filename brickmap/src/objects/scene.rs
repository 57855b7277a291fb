//! [`Objects`]: the tree, the models and the composite changed together, one [`ObjectOp`] at
//! a time. Every op is checked before anything changes, applied to the tree or a model, and
//! followed by the composite's update of the world; it returns its exact inverse (another
//! op), so a command's undo and redo are ops too. An op the composite refuses (an object
//! would leave the grid) is taken back and reported; the tree, the models and the world are
//! then as they were.
//!
//! Locked nodes refuse edits, placements, moves and removal (their unlocking is an op).

use super::composite::Composite;
use super::model::Model;
pub use super::op::{ObjectError, ObjectOp};
use super::orient::Placement;
use super::tree::{LayerId, ModelId, NewNode, NodeId, NodeKind, ObjectTree, TreeError};
use crate::edit::EditOp;
use crate::material::MaterialTable;
use crate::world::World;
use glam::IVec3;
use std::collections::BTreeMap;

/// A scene of objects: the tree, the models, and the composite they make in a world of a
/// fixed grid (see the module doc).
#[derive(Debug)]
pub struct Objects {
    tree: ObjectTree,
    models: BTreeMap<ModelId, Model>,
    composite: Composite,
    grid: IVec3,
}

impl Objects {
    /// A scene of a tree and its models for a world of `grid` voxels, written into `world`
    /// (every brick the objects cover).
    pub fn new(
        tree: ObjectTree,
        models: BTreeMap<ModelId, Model>,
        world: &World,
    ) -> Result<Self, ObjectError> {
        let grid = world.dims().voxels();
        let composite = Composite::new(&tree, &models, grid)?;
        composite.write(world, &composite.all_bricks(), &models)?;
        Ok(Self {
            tree,
            models,
            composite,
            grid,
        })
    }

    /// A grid's voxels as a scene of one object named "scene" that places a model of the
    /// grid's size at identity, brick-aligned: its composite is the world as it is, so
    /// nothing is written. Returns the object too.
    pub fn of_world(world: &World) -> Result<(Self, NodeId), ObjectError> {
        let grid = world.dims().voxels();
        let mut tree = ObjectTree::new();
        let object = NewNode::Object {
            model: ModelId(0),
            layer: LayerId(0),
        };
        let node = tree.add(
            ObjectTree::ROOT,
            None,
            "scene",
            Placement::at(grid / 2),
            object,
        )?;
        let objects = Self::adopting(tree, ModelId(0), BTreeMap::new(), world)?;
        Ok((objects, node))
    }

    /// A scene of `tree` over a world that already holds what it shows: its one drawn object
    /// places `model` (not among `others`) unturned over the whole grid, and that model is
    /// taken from the world's voxels (each worker's slab on its own thread); nothing is
    /// written. How a grid becomes one object, and how a file of one grid-sized object
    /// loads as fast as a grid. Refuses any other tree, changing nothing.
    pub fn adopting(
        tree: ObjectTree,
        model: ModelId,
        mut others: BTreeMap<ModelId, Model>,
        world: &World,
    ) -> Result<Self, ObjectError> {
        let grid = world.dims().voxels();
        if others.contains_key(&model) {
            return Err(ObjectError::ModelTaken(model));
        }
        others.insert(model, Model::from_world(world)?);
        let composite = Composite::new(&tree, &others, grid)?;
        if composite.sole_cover() != Some(model) {
            return Err(ObjectError::NotTheWorld(model));
        }
        Ok(Self {
            tree,
            models: others,
            composite,
            grid,
        })
    }

    /// The tree.
    pub fn tree(&self) -> &ObjectTree {
        &self.tree
    }

    /// A model.
    pub fn model(&self, id: ModelId) -> Option<&Model> {
        self.models.get(&id)
    }

    /// The models by id.
    pub fn models(&self) -> &BTreeMap<ModelId, Model> {
        &self.models
    }

    /// The lowest model id no model has.
    pub fn free_model_id(&self) -> ModelId {
        (0..)
            .map(ModelId)
            .find(|m| !self.models.contains_key(m))
            .expect("fewer than 2^32 models")
    }

    /// Applies an op to the scene and its world; returns the inverse.
    pub fn apply(
        &mut self,
        world: &World,
        op: ObjectOp,
        table: &MaterialTable,
    ) -> Result<ObjectOp, ObjectError> {
        self.run(world, op, table, &mut 0)
    }

    /// Applies an op like [`Objects::apply`]; also returns how many model voxels changed
    /// occupancy or material (a voxel of a shared model counts once).
    pub fn apply_counted(
        &mut self,
        world: &World,
        op: ObjectOp,
        table: &MaterialTable,
    ) -> Result<(ObjectOp, u64), ObjectError> {
        let mut changed = 0;
        let inverse = self.run(world, op, table, &mut changed)?;
        Ok((inverse, changed))
    }

    fn run(
        &mut self,
        world: &World,
        op: ObjectOp,
        table: &MaterialTable,
        changed: &mut u64,
    ) -> Result<ObjectOp, ObjectError> {
        match op {
            ObjectOp::Edit { node, edit } => {
                self.unlocked(node)?;
                let model = self.object_model(node)?;
                let p = self.tree.world_placement(node)?;
                let size = self.models[&model].size();
                let carried = p.edit_to_model(&edit, size)?;
                self.edit_model(world, model, &carried, table, changed)
            }
            ObjectOp::EditInModel { node, edit } => {
                self.unlocked(node)?;
                let model = self.object_model(node)?;
                self.edit_model(world, model, &edit, table, changed)
            }
            ObjectOp::RestoreModel { model, inverse } => {
                self.edit_model(world, model, &EditOp::Restore(inverse), table, changed)
            }
            ObjectOp::Place { node, placement } => {
                self.unlocked(node)?;
                let before = self.tree.node(node)?.placement;
                self.tree.node_mut(node)?.placement = placement;
                self.settle(world, &[], |t| {
                    t.node_mut(node).map(|n| n.placement = before)
                })?;
                Ok(ObjectOp::Place {
                    node,
                    placement: before,
                })
            }
            ObjectOp::Show { node, visible } => {
                let before = self.tree.node(node)?.visible;
                self.tree.node_mut(node)?.visible = visible;
                self.settle(world, &[], |t| t.node_mut(node).map(|n| n.visible = before))?;
                Ok(ObjectOp::Show {
                    node,
                    visible: before,
                })
            }
            ObjectOp::Lock { node, locked } => {
                let n = self.tree.node_mut(node)?;
                let before = std::mem::replace(&mut n.locked, locked);
                Ok(ObjectOp::Lock {
                    node,
                    locked: before,
                })
            }
            ObjectOp::Rename { node, name } => {
                let n = self.tree.node_mut(node)?;
                let before = std::mem::replace(&mut n.name, name);
                Ok(ObjectOp::Rename { node, name: before })
            }
            ObjectOp::Move {
                node,
                parent,
                index,
            } => {
                self.unlocked(node)?;
                let (old_parent, old_index) = self.tree.move_node(node, parent, index)?;
                // Its objects' place in the drawing order changed: their boxes are redrawn.
                let moved = self.tree.subtree(node)?;
                self.settle(world, &moved, |t| {
                    t.move_node(node, old_parent, Some(old_index)).map(|_| ())
                })?;
                Ok(ObjectOp::Move {
                    node,
                    parent: old_parent,
                    index: Some(old_index),
                })
            }
            ObjectOp::Reparent {
                node,
                parent,
                index,
                placement,
            } => {
                self.unlocked(node)?;
                let before = self.tree.node(node)?.placement;
                let (old_parent, old_index) = self.tree.move_node(node, parent, index)?;
                self.tree.node_mut(node)?.placement = placement;
                let moved = self.tree.subtree(node)?;
                self.settle(world, &moved, |t| {
                    t.move_node(node, old_parent, Some(old_index))?;
                    t.node_mut(node).map(|n| n.placement = before)
                })?;
                Ok(ObjectOp::Reparent {
                    node,
                    parent: old_parent,
                    index: Some(old_index),
                    placement: before,
                })
            }
            ObjectOp::Add {
                parent,
                index,
                name,
                placement,
                new,
            } => {
                if let NewNode::Object { model, .. } = new
                    && !self.models.contains_key(&model)
                {
                    return Err(ObjectError::NoModel(model));
                }
                let node = self.tree.add(parent, index, name, placement, new)?;
                self.settle(world, &[], |t| t.remove(node).map(|_| ()))?;
                Ok(ObjectOp::Remove { node })
            }
            ObjectOp::Remove { node } => {
                for n in self.tree.subtree(node)? {
                    self.unlocked(n)?;
                }
                let detached = self.tree.remove(node)?;
                let back = detached.clone();
                self.settle(world, &[], |t| t.restore(back))?;
                Ok(ObjectOp::Restore(detached))
            }
            ObjectOp::Restore(detached) => {
                let top = detached.top();
                self.tree.restore(detached)?;
                self.settle(world, &[], |t| t.remove(top).map(|_| ()))?;
                Ok(ObjectOp::Remove { node: top })
            }
            ObjectOp::SetModel { node, model } => {
                self.unlocked(node)?;
                let before = self.object_model(node)?;
                if !self.models.contains_key(&model) {
                    return Err(ObjectError::NoModel(model));
                }
                self.set_model(node, model)?;
                self.settle(world, &[], |t| Self::set_model_in(t, node, before))?;
                Ok(ObjectOp::SetModel {
                    node,
                    model: before,
                })
            }
            ObjectOp::AddModel { model, voxels } => {
                if self.models.contains_key(&model) {
                    return Err(ObjectError::ModelTaken(model));
                }
                self.models.insert(model, *voxels);
                Ok(ObjectOp::RemoveModel { model })
            }
            ObjectOp::RemoveModel { model } => {
                let users = self.tree.instances(model).len();
                if users > 0 {
                    return Err(ObjectError::ModelInUse(model, users));
                }
                let voxels = self
                    .models
                    .remove(&model)
                    .ok_or(ObjectError::NoModel(model))?;
                Ok(ObjectOp::AddModel {
                    model,
                    voxels: Box::new(voxels),
                })
            }
            ObjectOp::ShowLayer { layer, visible } => {
                let before = self.tree.layer_mut(layer)?.visible;
                self.tree.layer_mut(layer)?.visible = visible;
                self.settle(world, &[], |t| {
                    t.layer_mut(layer).map(|l| l.visible = before)
                })?;
                Ok(ObjectOp::ShowLayer {
                    layer,
                    visible: before,
                })
            }
            ObjectOp::SetLayer { node, layer } => {
                self.unlocked(node)?;
                self.object_model(node)?;
                if layer.0 as usize >= self.tree.layers().len() {
                    return Err(TreeError::NoLayer(layer).into());
                }
                let before = Self::set_layer_in(&mut self.tree, node, layer)?;
                self.settle(world, &[], |t| {
                    Self::set_layer_in(t, node, before).map(|_| ())
                })?;
                Ok(ObjectOp::SetLayer {
                    node,
                    layer: before,
                })
            }
            ObjectOp::RenameLayer { layer, name } => {
                let l = self.tree.layer_mut(layer)?;
                let before = std::mem::replace(&mut l.name, name);
                Ok(ObjectOp::RenameLayer {
                    layer,
                    name: before,
                })
            }
            ObjectOp::AddLayer(layer) => {
                // A new layer holds no object: the composite does not change.
                self.tree.add_layer(layer)?;
                Ok(ObjectOp::RemoveLastLayer)
            }
            ObjectOp::RemoveLastLayer => Ok(ObjectOp::AddLayer(self.tree.remove_last_layer()?)),
            ObjectOp::Batch(ops) => {
                let mut done: Vec<ObjectOp> = Vec::with_capacity(ops.len());
                for op in ops {
                    match self.run(world, op, table, changed) {
                        Ok(inverse) => done.push(inverse),
                        Err(e) => {
                            for inverse in done.into_iter().rev() {
                                self.apply(world, inverse, table)
                                    .expect("an inverse of an op just applied applies");
                            }
                            return Err(e);
                        }
                    }
                }
                done.reverse();
                Ok(ObjectOp::Batch(done))
            }
        }
    }

    fn unlocked(&self, node: NodeId) -> Result<(), ObjectError> {
        if self.tree.node(node)?.locked {
            return Err(ObjectError::Locked(node));
        }
        Ok(())
    }

    fn object_model(&self, node: NodeId) -> Result<ModelId, ObjectError> {
        match self.tree.node(node)?.kind {
            NodeKind::Object { model, .. } => Ok(model),
            NodeKind::Group { .. } => Err(ObjectError::NotAnObject(node)),
        }
    }

    /// Puts an object on a layer; returns the layer it was on.
    fn set_layer_in(
        tree: &mut ObjectTree,
        node: NodeId,
        layer: LayerId,
    ) -> Result<LayerId, TreeError> {
        match &mut tree.node_mut(node)?.kind {
            NodeKind::Object { layer: l, .. } => Ok(std::mem::replace(l, layer)),
            NodeKind::Group { .. } => Ok(layer),
        }
    }

    fn set_model(&mut self, node: NodeId, model: ModelId) -> Result<(), ObjectError> {
        Self::set_model_in(&mut self.tree, node, model)?;
        Ok(())
    }

    fn set_model_in(tree: &mut ObjectTree, node: NodeId, model: ModelId) -> Result<(), TreeError> {
        if let NodeKind::Object { model: m, .. } = &mut tree.node_mut(node)?.kind {
            *m = model;
        }
        Ok(())
    }

    /// A model edit (already in the model's frame) and the composite after it.
    fn edit_model(
        &mut self,
        world: &World,
        model: ModelId,
        edit: &EditOp,
        table: &MaterialTable,
        changed: &mut u64,
    ) -> Result<ObjectOp, ObjectError> {
        let m = self
            .models
            .get_mut(&model)
            .ok_or(ObjectError::NoModel(model))?;
        if self.composite.flat() == Some(model) {
            // A flat scene: the world is the model, so it takes the same edit, on its
            // workers while the model is edited here (no composite to recompute).
            let ticket = world.submit(edit.clone())?;
            let out = m.apply(edit, table);
            let written = ticket.wait();
            return match (out, written) {
                (Ok(out), Ok(_)) => {
                    *changed += out.changed_voxels;
                    Ok(ObjectOp::RestoreModel {
                        model,
                        inverse: out.inverse,
                    })
                }
                (Ok(out), Err(e)) => {
                    m.apply(&EditOp::Restore(out.inverse), table)
                        .expect("a model takes its own inverse");
                    Err(e.into())
                }
                (Err(e), Ok(w)) => {
                    world.apply(EditOp::Restore(w.inverse))?;
                    Err(e.into())
                }
                (Err(e), Err(_)) => Err(e.into()),
            };
        }
        let out = m.apply(edit, table)?;
        if let Err(e) = self
            .composite
            .model_edited(world, &self.models, model, &out.inverse)
        {
            // The world refused the write: the model goes back too.
            let m = self.models.get_mut(&model).expect("just edited");
            m.apply(&EditOp::Restore(out.inverse), table)
                .expect("a model takes its own inverse");
            return Err(e.into());
        }
        *changed += out.changed_voxels;
        Ok(ObjectOp::RestoreModel {
            model,
            inverse: out.inverse,
        })
    }

    /// Brings the composite to the tree as it now is; if it refuses, `undo` puts the tree
    /// back (the composite and the world are unchanged then).
    fn settle(
        &mut self,
        world: &World,
        also: &[NodeId],
        undo: impl FnOnce(&mut ObjectTree) -> Result<(), TreeError>,
    ) -> Result<(), ObjectError> {
        match self.composite.update(world, &self.tree, &self.models, also) {
            Ok(_) => Ok(()),
            Err(e) => {
                undo(&mut self.tree).expect("a tree change just made can be taken back");
                Err(e.into())
            }
        }
    }

    /// The object whose voxel shows at world cell `v`, if any (what a click picks).
    pub fn object_at(&self, v: IVec3) -> Option<NodeId> {
        self.composite.object_at(v, &self.models)
    }

    /// Bytes the objects hold beside the world they composite into: the models' bricks
    /// (each model once, however many objects place it), and the tree with the composite's
    /// index (its entries and region lists).
    pub fn bytes(&self) -> (usize, usize) {
        let models = self.models.values().map(Model::brick_bytes).sum();
        (models, self.tree.heap_bytes() + self.composite.heap_bytes())
    }

    /// The grid the composite fills, in voxels.
    pub fn grid(&self) -> IVec3 {
        self.grid
    }

    /// The box every object covers, shown or hidden (lowest cell, one past the highest), in
    /// world voxels; `None` without objects. A grid that holds it (after a shift by
    /// max(0, −lowest)) lets every object be shown and nothing is refused for the grid.
    pub fn extent(&self) -> Option<(IVec3, IVec3)> {
        let mut out: Option<(IVec3, IVec3)> = None;
        for id in self.tree.subtree(ObjectTree::ROOT).expect("the root") {
            let Ok(node) = self.tree.node(id) else {
                continue;
            };
            let NodeKind::Object { model, .. } = node.kind else {
                continue;
            };
            let Some(m) = self.models.get(&model) else {
                continue;
            };
            let p = self.tree.world_placement(id).expect("a node of the tree");
            let (lo, hi) = p.bounds(m.size());
            out = Some(out.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))));
        }
        out
    }

    /// Moves the scene into another world (a larger grid, for objects that grew past the
    /// old one): every object shifted by `shift` (through the root's placement), the
    /// composite written into `world`, which must be empty. On an error (an object outside
    /// the new grid too) nothing changed. The caller swaps the worlds and shifts its camera
    /// by the same voxels.
    pub fn regrid(&mut self, world: &World, shift: IVec3) -> Result<(), ObjectError> {
        let mut tree = self.tree.clone();
        tree.node_mut(ObjectTree::ROOT)?.placement.t += shift;
        let grid = world.dims().voxels();
        let composite = Composite::new(&tree, &self.models, grid)?;
        composite.write(world, &composite.all_bricks(), &self.models)?;
        self.tree = tree;
        self.composite = composite;
        self.grid = grid;
        Ok(())
    }
}

#[cfg(test)]
mod tests;
