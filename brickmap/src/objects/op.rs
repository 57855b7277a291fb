//! [`ObjectOp`], one change of a scene of objects (each returns its exact inverse when
//! `Objects` applies it), and [`ObjectError`], why one was refused.

use super::composite::CompositeError;
use super::model::Model;
use super::orient::Placement;
use super::tree::{Detached, Layer, LayerId, ModelId, NewNode, NodeId, TreeError};
use crate::edit::{EditInverse, EditOp};
use crate::error::BrickmapError;

/// One change of a scene of objects. Applying it returns its inverse.
#[derive(Clone, Debug)]
pub enum ObjectOp {
    /// An edit in world voxels of an object's model (carried into the object's frame; the
    /// model's other instances follow).
    Edit {
        /// The object.
        node: NodeId,
        /// The edit, in world voxels.
        edit: EditOp,
    },
    /// An edit in an object's model's own voxels (its frame, not the world's: a generator
    /// made for the model's size fills it wherever the object stands).
    EditInModel {
        /// The object.
        node: NodeId,
        /// The edit, in model voxels.
        edit: EditOp,
    },
    /// Puts back what a model edit changed (the inverse of `Edit`, in the model's frame).
    RestoreModel {
        /// The model.
        model: ModelId,
        /// Its inverse.
        inverse: EditInverse,
    },
    /// A node's placement relative to its parent.
    Place {
        /// The node.
        node: NodeId,
        /// The new placement.
        placement: Placement,
    },
    /// Shows or hides a node and its subtree.
    Show {
        /// The node.
        node: NodeId,
        /// Visible.
        visible: bool,
    },
    /// Locks or unlocks a node.
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
        /// The name.
        name: String,
    },
    /// Moves a node under `parent` at `index` (the end when `None`).
    Move {
        /// The node.
        node: NodeId,
        /// The new parent group.
        parent: NodeId,
        /// The position among its children.
        index: Option<usize>,
    },
    /// Moves a node under `parent` at `index` and gives it a new placement, in one step
    /// (ungrouping keeps a node where it is by composing its old parent's placement in).
    Reparent {
        /// The node.
        node: NodeId,
        /// The new parent group.
        parent: NodeId,
        /// The position among its children (the end when `None`).
        index: Option<usize>,
        /// Its placement under the new parent.
        placement: Placement,
    },
    /// Adds a node (it takes the lowest free id).
    Add {
        /// The parent group.
        parent: NodeId,
        /// The position among its children (the end when `None`).
        index: Option<usize>,
        /// Its name.
        name: String,
        /// Its placement.
        placement: Placement,
        /// A group, or an object of an existing model.
        new: NewNode,
    },
    /// Removes a node and its subtree.
    Remove {
        /// The node.
        node: NodeId,
    },
    /// Puts a removed subtree back under its ids (the inverse of `Remove`).
    Restore(Detached),
    /// Makes an object place another existing model (make unique, instance).
    SetModel {
        /// The object.
        node: NodeId,
        /// The model.
        model: ModelId,
    },
    /// Adds a model under an unused id (for a duplicate or a split).
    AddModel {
        /// Its id.
        model: ModelId,
        /// Its voxels.
        voxels: Box<Model>,
    },
    /// Removes a model no object places.
    RemoveModel {
        /// Its id.
        model: ModelId,
    },
    /// Shows or hides a layer.
    ShowLayer {
        /// The layer.
        layer: LayerId,
        /// Visible.
        visible: bool,
    },
    /// Puts an object on a layer.
    SetLayer {
        /// The object.
        node: NodeId,
        /// The layer.
        layer: LayerId,
    },
    /// Renames a layer.
    RenameLayer {
        /// The layer.
        layer: LayerId,
        /// The name.
        name: String,
    },
    /// Adds a layer at the end.
    AddLayer(Layer),
    /// Removes the last layer (no object may be on it).
    RemoveLastLayer,
    /// Several ops as one: all or none (on an error the ones done are undone).
    Batch(Vec<ObjectOp>),
}

impl ObjectOp {
    /// Bytes it holds on the heap (what a history that keeps it pays): a model edit's
    /// inverse, a removed subtree, a model set aside, the ops of a batch.
    pub fn heap_bytes(&self) -> usize {
        match self {
            ObjectOp::RestoreModel { inverse, .. } => inverse.heap_bytes(),
            ObjectOp::Restore(detached) => detached.heap_bytes(),
            ObjectOp::AddModel { voxels, .. } => voxels.brick_bytes(),
            ObjectOp::Rename { name, .. } | ObjectOp::RenameLayer { name, .. } => name.capacity(),
            ObjectOp::Batch(ops) => {
                ops.capacity() * std::mem::size_of::<ObjectOp>()
                    + ops.iter().map(ObjectOp::heap_bytes).sum::<usize>()
            }
            _ => 0,
        }
    }
}

/// Why an op was refused; nothing changed.
#[derive(Debug, thiserror::Error)]
pub enum ObjectError {
    /// The tree refused (no such node, a loop, a position, the depth).
    #[error(transparent)]
    Tree(#[from] TreeError),
    /// The composite refused (an object would leave the grid, a model is missing).
    #[error(transparent)]
    Composite(#[from] CompositeError),
    /// The model or the world refused the edit.
    #[error(transparent)]
    Edit(#[from] BrickmapError),
    /// The node is locked.
    #[error("node #{} is locked", .0.0)]
    Locked(NodeId),
    /// The node is a group where an object is needed.
    #[error("node #{} is a group, not an object", .0.0)]
    NotAnObject(NodeId),
    /// No model has this id.
    #[error("no model {}", .0.0)]
    NoModel(ModelId),
    /// The id is taken by another model.
    #[error("model {} exists already", .0.0)]
    ModelTaken(ModelId),
    /// A split whose selection holds none of the object's voxels.
    #[error("the selection holds no voxel of object #{}", .0.0)]
    NothingSelected(NodeId),
    /// An edit with no object to act on (the editor's active object is none).
    #[error("no object is active to edit: choose one in the Objects window")]
    NoActiveObject,
    /// A world adopted as a model by a tree whose one drawn object does not fill the grid
    /// unturned.
    #[error("the objects do not draw model {} alone over the whole grid, unturned", .0.0)]
    NotTheWorld(ModelId),
    /// Objects still place the model.
    #[error("model {} is placed by {} objects", .0.0, .1)]
    ModelInUse(ModelId, usize),
}
