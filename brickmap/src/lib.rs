//! The extended brickmap: a voxel world of 8³ bricks with per-voxel materials stored in
//! popcount order inside power-of-two buckets, edited by worker threads that each own an
//! x-slab, with dirty ranges for the renderer and an exact CPU ray cast.
//!
//! ```
//! use brickmap::{EditOp, GridDims, Mode, Shape, World, WorldConfig};
//! use glam::DVec3;
//!
//! let world = World::new(GridDims::new(8, 4, 8).unwrap(), WorldConfig::default()).unwrap();
//! let sphere = Shape::Sphere { centre: DVec3::splat(20.0), radius: 6.0 };
//! let done = world.apply(EditOp::Shape { shape: sphere, mode: Mode::Add(0) }).unwrap();
//! assert!(world.read().solid_count() > 800);
//! world.apply(EditOp::Restore(done.inverse)).unwrap(); // undo
//! assert_eq!(world.read().solid_count(), 0);
//! ```

pub mod brick;
pub mod census;
pub mod dirty;
pub mod edit;
pub mod error;
pub mod grid;
pub mod lights;
pub mod material;
pub mod objects;
pub mod raycast;
pub mod shape;
mod slab;
pub mod storage;
pub mod terrain;
pub mod voxel_set;
pub mod world;

pub use brick::{Brick, Mask};
pub use edit::{
    BrickUndo, EditInverse, EditOp, EditOutcome, Mode, PriorMaterials, VoxelEdit, VoxelOp,
};
pub use error::{BrickmapError, Result};
pub use grid::GridDims;
pub use lights::{LightFace, Lights};
pub use material::{Material, MaterialKind, MaterialTable};
pub use raycast::{Occupancy, Ray, RayHit, cast, cast_from_cell};
pub use shape::Shape;
pub use storage::BucketSizes;
pub use voxel_set::{FACES, VoxelSet};
pub use world::{BrickMaterials, DirtySet, GpuBuffer, MemoryStats, World, WorldConfig, WorldView};
