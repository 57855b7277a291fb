//! Objects: a scene as a tree of groups and objects, each object placing a model with one
//! of the 48 axis-aligned orientations and an integer translation (MagicaVoxel's world
//! editor's model). `orient` holds the orientations and the placement rule, `tree` the
//! groups, objects, layers and the drawing order that decides which voxel shows where
//! objects overlap.
//!
//! The composite (the visible objects written into the one `World` the renderers trace)
//! builds on these: see docs/DESIGN.md, "Objects".

pub mod arrange;
pub mod composite;
pub mod frame;
pub mod model;
pub mod op;
pub mod orient;
mod outline;
pub mod scene;
#[cfg(test)]
mod testing;
pub mod tree;

pub use composite::{Composite, CompositeError, ModelSource};
pub use model::{MAX_MODEL_VOXELS, Model, ModelBrick};
pub use orient::{Axis, Orientation, Placement};
pub use scene::{ObjectError, ObjectOp, Objects};
pub use tree::{
    Detached, Drawn, Layer, LayerId, ModelId, NewNode, Node, NodeId, NodeKind, ObjectTree,
    TreeError,
};
