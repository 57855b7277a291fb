//! How commands are undone: object ops for voxels (sparse model inverses, never snapshots),
//! the previous table (about 2 KB) for table edits, the previous value for properties; and
//! the helpers that apply edits all-or-nothing.
//!
//! In detail:
//! `Inverse`: object ops for voxels (never snapshots), the previous table (~2 KB) for table
//! edits, the previous value for properties and the selection, `Compound` (several, undone last
//! first; a failing part puts back the parts already applied); `apply_all` / `with_table` (all
//! or nothing).

use super::error::Result;
use crate::scene::Scene;
use crate::selection::Selection;
use brickmap::objects::ObjectOp;
use brickmap::{EditOp, MaterialTable};
use render::{Camera, RenderSettings, Sky, Sun};

/// How to undo a command.
#[derive(Debug)]
pub enum Inverse {
    /// Object ops (model restores, arrangements) to apply in reverse order, then (if any)
    /// the material table.
    Voxels(Vec<ObjectOp>, Option<Box<MaterialTable>>),
    /// The previous material table.
    Table(Box<MaterialTable>),
    /// The previous sun.
    Sun(Sun),
    /// The previous sky.
    Sky(Sky),
    /// The previous camera.
    Camera(Camera),
    /// The previous settings.
    Settings(RenderSettings),
    /// The previous selection.
    Selection(Option<Selection>),
    /// The previous active object.
    Active(Option<brickmap::objects::NodeId>),
    /// The previous grid: its size, and the shift that moves every voxel back into it.
    Regrid(brickmap::GridDims, glam::IVec3),
    /// Several, undone last first (a move: its voxels, then its selection).
    Compound(Vec<Inverse>),
}

impl Inverse {
    /// Heap and inline bytes this inverse holds (what the history pays for it).
    pub fn bytes(&self) -> usize {
        let table = std::mem::size_of::<MaterialTable>();
        std::mem::size_of::<Self>()
            + match self {
                Inverse::Voxels(v, t) => {
                    v.iter().map(|i| i.heap_bytes()).sum::<usize>()
                        + t.as_ref().map_or(0, |_| table)
                }
                Inverse::Table(_) => table,
                Inverse::Compound(v) => v.iter().map(|i| i.bytes()).sum(),
                Inverse::Selection(Some(s)) => {
                    s.voxels.brick_count() * (std::mem::size_of::<brickmap::Mask>() + 32)
                }
                _ => 0,
            }
    }

    /// Applies the inverse, returning the inverse of that (redo after undo, and back).
    pub fn apply(self, scene: &mut Scene) -> Result<Inverse> {
        Ok(match self {
            Inverse::Voxels(list, table) => {
                // A table that grows goes in before the voxels that use it; one that shrinks
                // after the voxels that used the dropped entries are gone.
                let grows = table
                    .as_ref()
                    .is_some_and(|t| t.len() >= scene.world.materials().len());
                let mut old = None;
                if grows && let Some(t) = table.as_ref() {
                    old = Some(Box::new(scene.world.replace_materials((**t).clone())?));
                }
                let mut back = Vec::with_capacity(list.len());
                for inv in list.into_iter().rev() {
                    back.push(scene.apply(inv)?.0);
                }
                if !grows && let Some(t) = table {
                    old = Some(Box::new(scene.world.replace_materials(*t)?));
                }
                Inverse::Voxels(back, old)
            }
            Inverse::Table(t) => Inverse::Table(Box::new(scene.world.replace_materials(*t)?)),
            Inverse::Sun(v) => Inverse::Sun(std::mem::replace(&mut scene.params.sun, v)),
            Inverse::Sky(v) => Inverse::Sky(std::mem::replace(&mut scene.params.sky, v)),
            Inverse::Camera(v) => Inverse::Camera(std::mem::replace(&mut scene.params.camera, v)),
            Inverse::Settings(v) => {
                Inverse::Settings(std::mem::replace(&mut scene.params.settings, v))
            }
            Inverse::Selection(v) => Inverse::Selection(std::mem::replace(&mut scene.selection, v)),
            Inverse::Regrid(dims, shift) => {
                let (back, undo) = scene.regrid(dims, shift)?;
                Inverse::Regrid(back, undo)
            }
            Inverse::Active(v) => {
                let now = scene.active();
                scene.set_active(v);
                Inverse::Active(now)
            }
            Inverse::Compound(list) => {
                // On a failure the parts already applied are put back (all or nothing).
                let mut back: Vec<Inverse> = Vec::with_capacity(list.len());
                for inv in list.into_iter().rev() {
                    match inv.apply(scene) {
                        Ok(i) => back.push(i),
                        Err(e) => {
                            for done in back.into_iter().rev() {
                                done.apply(scene)?;
                            }
                            return Err(e);
                        }
                    }
                }
                // Pushed in the order they were applied: applied last first, they redo in the
                // original order.
                Inverse::Compound(back)
            }
        })
    }
}

/// An executed command: how to undo it, and how many voxels it changed (for an import, how
/// many it wrote).
#[derive(Debug)]
pub struct Applied {
    /// The undo.
    pub inverse: Inverse,
    /// Voxels whose occupancy or material changed.
    pub changed_voxels: u64,
}

/// Runs a table edit, keeping the previous table as the inverse (and putting it back on error).
pub(super) fn with_table(
    scene: &Scene,
    edit: impl FnOnce(&brickmap::World) -> brickmap::Result<()>,
) -> Result<Applied> {
    let before = scene.world.materials().clone();
    if let Err(e) = edit(&scene.world) {
        scene.world.replace_materials(before)?;
        return Err(e.into());
    }
    Ok(Applied {
        inverse: Inverse::Table(Box::new(before)),
        changed_voxels: 0,
    })
}

/// Applies edits (world voxels, to the active object) in order; if one fails, the ones
/// applied are undone and the error returned.
pub(super) fn apply_all(scene: &Scene, edits: Vec<EditOp>) -> Result<Applied> {
    let mut done: Vec<ObjectOp> = Vec::with_capacity(edits.len());
    let mut changed = 0;
    for edit in edits {
        match scene.edit(edit) {
            Ok((inverse, n)) => {
                changed += n;
                done.push(inverse);
            }
            Err(e) => {
                undo_all(scene, done)?;
                return Err(e.into());
            }
        }
    }
    Ok(Applied {
        inverse: Inverse::Voxels(done, None),
        changed_voxels: changed,
    })
}

/// Applies the inverses of ops just applied, last first.
pub(super) fn undo_all(scene: &Scene, done: Vec<ObjectOp>) -> Result<()> {
    for inverse in done.into_iter().rev() {
        scene.apply(inverse)?;
    }
    Ok(())
}
