//! The scene document: the voxel world (with its material and colour tables) and the
//! camera, sun, sky and render settings. Files in and out are `formats::load` / `save`; the
//! built-in scenes are in `builtin`.

use crate::selection::{Clip, Selection};
use brickmap::{GridDims, World, WorldConfig};
use render::SceneParams;
use std::sync::Arc;

/// A scene: everything a file carries.
#[derive(Debug)]
pub struct Scene {
    /// Voxels, materials, colours.
    pub world: World,
    /// Camera, sun, sky, render settings.
    pub params: SceneParams,
    /// The editing session's selection (never saved).
    pub selection: Option<Selection>,
    /// The editing session's clipboard (never saved; the editor carries it to the next
    /// document it opens).
    pub clipboard: Option<Arc<Clip>>,
}

impl Scene {
    /// An empty scene of a grid size, framed by the default camera.
    pub fn empty(dims: GridDims, workers: usize) -> brickmap::Result<Self> {
        let world = World::new(dims, WorldConfig::with_workers(workers))?;
        Ok(Self::new(
            world,
            SceneParams::framing(dims.voxels().as_dvec3()),
        ))
    }

    /// A scene of a world and its parameters, nothing selected.
    pub fn new(world: World, params: SceneParams) -> Self {
        Self {
            world,
            params,
            selection: None,
            clipboard: None,
        }
    }
}
