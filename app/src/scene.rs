//! The scene document: the objects (tree, models, layers) and the world they composite into
//! (with its material and colour tables), and the camera, sun, sky and render settings. Files
//! in and out are `formats::load` / `save`; the built-in scenes are in `builtin`.
//!
//! Every voxel write goes through the objects ([`Scene::edit`], [`Scene::apply`]): the world
//! is their composite, what the renderer, picking and statistics read. Writing the world
//! directly would leave the models (what is saved) behind; only a world not yet in a scene
//! is written directly (a generator building one, then [`Scene::new`] adopting it).

use crate::selection::{Clip, Selection};
use brickmap::objects::{
    Composite, LayerId, Model, ModelId, ModelSource, NewNode, NodeId, NodeKind, ObjectError,
    ObjectOp, ObjectTree, Objects,
};
use brickmap::{EditOp, GridDims, World, WorldConfig};
use glam::IVec3;
use render::SceneParams;
use std::sync::{Arc, Mutex, MutexGuard};

/// A scene: everything a file carries.
#[derive(Debug)]
pub struct Scene {
    /// The composite of the visible objects, with the materials and colours: read it
    /// freely, write voxels only through [`Scene::edit`] / [`Scene::apply`].
    pub world: World,
    /// The objects. A lock of their own: edits hold the document's read lock and change the
    /// world through its interior mutability; the objects change the same way.
    objects: Mutex<Objects>,
    /// The object voxel edits act on (edit mode), if any.
    active: Option<NodeId>,
    /// Counts the worlds this scene has had (a regrid makes a new one): a viewport holding
    /// an older one uploads the new one whole.
    epoch: u64,
    /// How far every voxel has moved since the scene was made (the sum of the regrids'
    /// shifts): a view camera kept outside the scene follows by the difference.
    shifted: IVec3,
    /// Camera, sun, sky, render settings.
    pub params: SceneParams,
    /// The editing session's selection (never saved).
    pub selection: Option<Selection>,
    /// The editing session's clipboard (never saved; the editor carries it to the next
    /// document it opens).
    pub clipboard: Option<Arc<Clip>>,
}

impl Scene {
    /// An empty scene of a grid size (one empty object filling the grid), framed by the
    /// default camera.
    pub fn empty(dims: GridDims, workers: usize) -> brickmap::Result<Self> {
        let world = World::new(dims, WorldConfig::with_workers(workers))?;
        Ok(Self::new(
            world,
            SceneParams::framing(dims.voxels().as_dvec3()),
        ))
    }

    /// A world's voxels as a scene of one object ("scene", the grid's size, at the origin:
    /// a flat grid, a version 1 project, a generated scene), nothing selected.
    pub fn new(world: World, params: SceneParams) -> Self {
        let (objects, node) = Objects::of_world(&world)
            .expect("a world's own voxels fit a model of its size, against its own table");
        Self::with_objects(world, objects, Some(node), params)
    }

    /// The scene as one object: what its visible objects show (its world), the same camera,
    /// sun, sky and settings; hidden objects are gone.
    pub fn flattened(self) -> Self {
        Self::new(self.world, self.params)
    }

    /// A scene of objects already composited into `world`, editing `active`.
    pub fn with_objects(
        world: World,
        objects: Objects,
        active: Option<NodeId>,
        params: SceneParams,
    ) -> Self {
        Self {
            world,
            objects: Mutex::new(objects),
            active,
            epoch: 0,
            shifted: IVec3::ZERO,
            params,
            selection: None,
            clipboard: None,
        }
    }

    /// An imported scene of objects composited into `world`: the default sun and sky, the
    /// camera framing the content, editing the first object.
    pub fn imported(world: World, objects: Objects) -> Self {
        world.take_dirty();
        let mut params = SceneParams::framing(world.read().dims().voxels().as_dvec3());
        if let Some((a, b)) = world.read().occupied_bounds() {
            params.camera = params.camera.framing(a.as_dvec3(), b.as_dvec3()).0;
        }
        let active = Self::first_object(&objects);
        Self::with_objects(world, objects, active, params)
    }

    /// The first object of a tree in drawing order, shown or hidden (what a loaded scene
    /// edits first).
    pub fn first_object(objects: &Objects) -> Option<NodeId> {
        let tree = objects.tree();
        tree.subtree(ObjectTree::ROOT).ok()?.into_iter().find(|id| {
            tree.node(*id)
                .is_ok_and(|n| matches!(n.kind, NodeKind::Object { .. }))
        })
    }

    /// The objects (held while the guard lives: keep it short).
    pub fn objects(&self) -> MutexGuard<'_, Objects> {
        self.objects.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The objects, without the lock (the scene is held exclusively: a regrid).
    fn objects_mut(&mut self) -> &mut Objects {
        self.objects.get_mut().unwrap_or_else(|p| p.into_inner())
    }

    /// The object voxel edits act on.
    pub fn active(&self) -> Option<NodeId> {
        self.active
    }

    /// The size of the active object's model, in voxels (`None` without one).
    pub fn active_size(&self) -> Option<IVec3> {
        let objects = self.objects();
        match objects.tree().node(self.active?).ok()?.kind {
            NodeKind::Object { model, .. } => objects.model(model).map(|m| m.size()),
            NodeKind::Group { .. } => None,
        }
    }

    /// The world box of the object voxel edits act on: its lowest voxel and one past its
    /// highest (`None` without one).
    pub fn active_box(&self) -> Option<(IVec3, IVec3)> {
        let objects = self.objects();
        let tree = objects.tree();
        let node = self.active?;
        match tree.node(node).ok()?.kind {
            NodeKind::Object { model, .. } => {
                let size = objects.model(model)?.size();
                Some(tree.world_placement(node).ok()?.bounds(size))
            }
            NodeKind::Group { .. } => None,
        }
    }

    /// Makes `node` the object voxel edits act on (`None`: none).
    pub fn set_active(&mut self, node: Option<NodeId>) {
        self.active = node;
    }

    /// Counts the worlds this scene has had (see the field).
    pub fn epoch(&self) -> u64 {
        self.epoch
    }

    /// How far every voxel has moved since the scene was made.
    pub fn shifted(&self) -> IVec3 {
        self.shifted
    }

    /// Moves the scene into a new world of `dims`, every voxel moved by `shift` (a whole
    /// number of bricks keeps a flat scene's object brick-aligned), and the camera, the
    /// sun and the selection with them. Returns the grid and shift that undo it. On an error
    /// (the objects do not fit the new grid) nothing changed.
    pub fn regrid(
        &mut self,
        dims: GridDims,
        shift: IVec3,
    ) -> Result<(GridDims, IVec3), ObjectError> {
        let world = World::new(dims, WorldConfig::with_workers(self.world.workers()))?;
        world.replace_materials(self.world.materials().clone())?;
        self.objects_mut().regrid(&world, shift)?;
        world.take_dirty();
        let old = std::mem::replace(&mut self.world, world).dims();
        let d = shift.as_dvec3();
        self.params.camera.position += d;
        self.params.sun.position += d;
        if let Some(sel) = &self.selection {
            self.selection = Some(Selection::new(sel.region.translated(shift), dims.voxels()));
        }
        self.epoch += 1;
        self.shifted += shift;
        Ok((old, -shift))
    }

    /// The world as the active object alone draws it (shown or hidden), for the reads that
    /// must see only the object edits act on: copy, move, the flood fill. `None` where the
    /// scene's own world is that (a flat scene, or no other object drawn). It costs a world
    /// of the grid's size holding the object's box.
    pub fn active_world(&self) -> Result<Option<World>, ObjectError> {
        let Some(node) = self.active else {
            return Ok(None);
        };
        let objects = self.objects();
        let tree = objects.tree();
        let drawn = tree.drawn();
        if drawn.len() == 1 && drawn[0].node == node {
            return Ok(None);
        }
        let NodeKind::Object { model, .. } = tree.node(node)?.kind else {
            return Err(ObjectError::NotAnObject(node));
        };
        let m = objects.model(model).ok_or(ObjectError::NoModel(model))?;
        let mut alone = ObjectTree::new();
        let placement = tree.world_placement(node)?;
        alone.add(
            ObjectTree::ROOT,
            None,
            "alone",
            placement,
            NewNode::Object {
                model,
                layer: LayerId(0),
            },
        )?;
        let world = World::new(
            self.world.dims(),
            WorldConfig::with_workers(self.world.workers()),
        )?;
        world.replace_materials(self.world.materials().clone())?;
        let source = One(model, m);
        let composite = Composite::new(&alone, &source, self.world.dims().voxels())?;
        composite.write(&world, &composite.all_bricks(), &source)?;
        Ok(Some(world))
    }

    /// A voxel edit, in world voxels, of the active object (carried into its frame; its
    /// instances follow). Returns the inverse and the voxels changed.
    pub fn edit(&self, edit: EditOp) -> Result<(ObjectOp, u64), ObjectError> {
        let node = self.active.ok_or(ObjectError::NoActiveObject)?;
        self.apply(ObjectOp::Edit { node, edit })
    }

    /// Applies an object op (an edit, an undo, an arrangement). Returns the inverse and the
    /// model voxels changed; on an error nothing changed.
    pub fn apply(&self, op: ObjectOp) -> Result<(ObjectOp, u64), ObjectError> {
        let table = self.world.materials().clone();
        self.objects().apply_counted(&self.world, op, &table)
    }
}

/// One model, as the composite reads models.
struct One<'a>(ModelId, &'a Model);

impl ModelSource for One<'_> {
    fn model(&self, id: ModelId) -> Option<&Model> {
        (id == self.0).then_some(self.1)
    }
}
