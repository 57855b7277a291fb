//! Everything the editor can do to a document, as serializable commands (scripts and the
//! recorder use the same form). `apply` executes one and returns how to undo it
//! ([`Inverse`]). Strokes are in `brush`, flood fill in `fill`.
//!
//! In detail:
//! every editor command (serde, shared by scripts and the recorder): label, coalescing key,
//! `apply` (returns its `Inverse`; on error the scene is as it was). Selection commands:
//! `Select`, `DeleteSelection` / `FillSelection` / `PaintSelection` (a `Shape::Set` edit),
//! `MoveSelection` and `Paste` (voxels and the selection in one `Compound` inverse), `Cut`;
//! `RemoveUnusedMaterials` (one `Restore` rewriting the bricks whose indices move down, then
//! the shorter table; undo puts the table back first); `Copy` changes only the clipboard
//! (`changes_document` is false: recorded, no history step, the document stays clean).

pub use super::brush::{
    Axis, BrushMode, BrushShape, Mirror, PREVIEW_LIMIT, PaintMode, Stroke, preview, preview_bricks,
    stroke_edits,
};
pub use super::inverse::{Applied, Inverse};
pub use super::paint::{hash as paint_hash, neighbours};

use super::error::{EditError, Result};
use super::inverse::{apply_all, with_table};
use crate::scene::Scene;
use crate::selection::{self, Clip, SelectOp, Selection, select};
pub use brickmap::terrain::NoiseKind;
use brickmap::terrain::NoiseTerrain;
use brickmap::{EditOp, Mode, Shape};
use glam::IVec3;
use render::{Camera, RenderSettings, Sky, Sun};
use serde::{Deserialize, Serialize};

pub use super::specs::{Bands, KindSpec, MaterialSpec, TerrainSpec};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Command {
    /// A brush stroke.
    Stroke(Stroke),
    /// Repaint the connected surface of same-material voxels containing `start`.
    FloodFill {
        /// A solid voxel of the surface.
        start: IVec3,
        /// The new material.
        material: u8,
    },
    /// Grow (a negative `distance`: push in) the connected exposed region of the face of
    /// `voxel` facing `normal` along it, each column in its voxel's material
    /// ([`super::extrude`]).
    Extrude {
        /// A voxel of the face.
        voxel: IVec3,
        /// The face's normal (one axis, ±1).
        normal: IVec3,
        /// Voxels to grow (negative: to push in).
        distance: i32,
        /// Only the region's voxels of `voxel`'s material.
        same_material: bool,
    },
    /// Fill the empty connected region of the layer in front of the face of `voxel` facing
    /// `normal` with a material.
    PlaneFill {
        /// The voxel whose face was clicked.
        voxel: IVec3,
        /// The face's normal (one axis, ±1).
        normal: IVec3,
        /// The material.
        material: u8,
    },
    /// Give every solid voxel of material `from` in the selection (without one: in the
    /// object brushes edit) material `to`.
    ReplaceMaterial {
        /// The material replaced.
        from: u8,
        /// The material it becomes.
        to: u8,
    },
    /// Append a material.
    AddMaterial(MaterialSpec),
    /// Replace a material.
    SetMaterial {
        /// Table index.
        index: u8,
        /// New value.
        material: MaterialSpec,
    },
    /// Replace a colour of the colour table.
    SetColour {
        /// Colour index.
        index: u8,
        /// sRGB.
        rgb: [u8; 3],
    },
    /// Replace the whole colour table (a loaded palette: exactly 256 sRGB colours).
    SetPalette(Vec<[u8; 3]>),
    /// Set a parameter-table value (roughness, IOR, strength).
    SetParam {
        /// Which table.
        kind: KindSpec,
        /// Index 0..64.
        index: u8,
        /// Value.
        value: f32,
    },
    /// Replace the sun.
    SetSun(Sun),
    /// Replace the sky.
    SetSky(Sky),
    /// Replace the camera.
    SetCamera(Camera),
    /// Replace the render settings.
    SetSettings(RenderSettings),
    /// Replace the whole grid by noise terrain with water (adds its materials).
    GenerateTerrain(TerrainSpec),
    /// Import a .vox file at an offset (path relative to the working folder).
    ImportVox {
        /// The file.
        path: String,
        /// Offset added after the shift into the grid.
        offset: IVec3,
    },
    /// Remove every voxel.
    Clear,
    /// Remove the materials no voxel uses (the ones after them move down; voxels follow).
    RemoveUnusedMaterials,
    /// Change the selection.
    Select(SelectOp),
    /// Empty every selected voxel.
    DeleteSelection,
    /// Make every selected voxel solid with a material.
    FillSelection(u8),
    /// Give every selected solid voxel a material.
    PaintSelection(u8),
    /// Move the selected solid voxels (and the selection) by an offset.
    MoveSelection(IVec3),
    /// Scale the selected solid voxels (and the selection) × 2 or × ½ about its centre.
    ScaleSelection(crate::selection_scale::ScaleStep),
    /// Turn or mirror the selected solid voxels (and the selection) about its centre.
    TransformSelection(crate::selection_transform::SelectionTransform),
    /// Copy the selected solid voxels to the clipboard (no history step: nothing changes).
    Copy,
    /// Copy, then delete the selection.
    Cut,
    /// Put the clipboard down with its minimum corner at `at`; the pasted region becomes the
    /// selection.
    Paste {
        /// Where the copied selection's minimum corner goes.
        at: IVec3,
    },
    /// Put the clipboard's solid voxels down at each of `at` (minimum corners), turned
    /// `quarters` quarter turns about the vertical (the Stamp tool's drag).
    Stamp {
        /// Where each stamp's minimum corner goes.
        at: Vec<IVec3>,
        /// Quarter turns about the vertical (counter-clockwise seen from above).
        quarters: i32,
    },
    /// An object command (arrange mode, the Objects window).
    Object(super::objects::ObjectCommand),
}

impl Command {
    /// A label for the history list.
    pub fn label(&self) -> String {
        match self {
            Command::Stroke(s) => format!(
                "{:?} {:?} stroke ({} points)",
                s.mode,
                s.shape,
                s.points.len()
            ),
            Command::FloodFill { start, material } => {
                format!("Fill from {start} with material {material}")
            }
            Command::ReplaceMaterial { from, to } => {
                format!("Replace material {from} by {to}")
            }
            Command::Extrude {
                voxel, distance, ..
            } => format!("Extrude the face at {voxel} by {distance}"),
            Command::PlaneFill {
                voxel, material, ..
            } => format!("Fill the plane at {voxel} with material {material}"),
            Command::AddMaterial(_) => "Add material".into(),
            Command::SetMaterial { index, .. } => format!("Edit material {index}"),
            Command::SetColour { index, .. } => format!("Edit colour {index}"),
            Command::SetPalette(_) => "Load palette".into(),
            Command::SetParam { kind, index, .. } => format!("Edit {kind:?} parameter {index}"),
            Command::SetSun(_) => "Edit sun".into(),
            Command::SetSky(_) => "Edit sky".into(),
            Command::SetCamera(_) => "Move camera".into(),
            Command::SetSettings(_) => "Edit render settings".into(),
            Command::GenerateTerrain(t) => format!("Generate terrain (seed {})", t.seed),
            Command::ImportVox { path, .. } => format!("Import {path}"),
            Command::Clear => "Clear".into(),
            Command::RemoveUnusedMaterials => "Remove unused materials".into(),
            Command::Select(op) => match op {
                SelectOp::Replace { .. } => "Select box".into(),
                SelectOp::Add { .. } => "Add box to selection".into(),
                SelectOp::Subtract { .. } => "Subtract box from selection".into(),
                SelectOp::Intersect { .. } => "Intersect selection with box".into(),
                SelectOp::Face { start, normal, .. } => {
                    format!("Select the face region at {start} ({normal})")
                }
                SelectOp::Rect { rect, how } => format!(
                    "Select a screen rectangle ({}, {how:?})",
                    if rect.visible_only {
                        "visible voxels"
                    } else {
                        "all depth"
                    }
                ),
                SelectOp::All => "Select all".into(),
                SelectOp::None => "Select none".into(),
                SelectOp::Wand { start, how, .. } => format!("Magic wand at {start} ({how:?})"),
                SelectOp::Material { material, how } => {
                    format!("Select material {material} ({how:?})")
                }
                SelectOp::Invert => "Invert selection".into(),
                SelectOp::Grow => "Grow selection".into(),
                SelectOp::Shrink => "Shrink selection".into(),
            },
            Command::DeleteSelection => "Delete selection".into(),
            Command::FillSelection(m) => format!("Fill selection with material {m}"),
            Command::PaintSelection(m) => format!("Paint selection with material {m}"),
            Command::MoveSelection(d) => format!("Move selection by {d}"),
            Command::ScaleSelection(step) => format!("Scale selection ({step:?})"),
            Command::TransformSelection(t) => match t {
                crate::selection_transform::SelectionTransform::Turn { axis, quarters } => {
                    format!("Turn selection {}° about {axis:?}", 90 * quarters)
                }
                crate::selection_transform::SelectionTransform::Flip(axis) => {
                    format!("Mirror selection along {axis:?}")
                }
            },
            Command::Copy => "Copy".into(),
            Command::Cut => "Cut".into(),
            Command::Paste { at } => format!("Paste at {at}"),
            Command::Stamp { at, .. } => format!("Stamp the clipboard ({} places)", at.len()),
            Command::Object(c) => c.label(),
        }
    }

    /// Commands with equal keys that follow each other merge into one step (dragging a slider).
    pub fn coalesce_key(&self) -> Option<String> {
        match self {
            Command::SetColour { index, .. } => Some(format!("colour {index}")),
            Command::SetParam { kind, index, .. } => Some(format!("param {kind:?} {index}")),
            Command::SetMaterial { index, .. } => Some(format!("material {index}")),
            Command::SetSun(_) => Some("sun".into()),
            Command::SetSky(_) => Some("sky".into()),
            Command::SetCamera(_) => Some("camera".into()),
            Command::SetSettings(_) => Some("settings".into()),
            _ => None,
        }
    }

    /// Whether the command changes the document (a copy changes only the clipboard: it is
    /// recorded, but is no history step and leaves the document clean).
    pub fn changes_document(&self) -> bool {
        !matches!(self, Command::Copy)
    }

    /// Executes the command. On error the scene is as it was.
    pub fn apply(&self, scene: &mut Scene, folder: &std::path::Path) -> Result<Applied> {
        self.apply_with(scene, folder, &Default::default())
    }

    /// [`Command::apply`], reporting how far a terrain generation got to `progress`
    /// (columns generated of the grid's columns).
    pub fn apply_with(
        &self,
        scene: &mut Scene,
        folder: &std::path::Path,
        progress: &std::sync::Arc<super::progress::Progress>,
    ) -> Result<Applied> {
        let world = &scene.world;
        let unchanged = |inverse| Applied {
            inverse,
            changed_voxels: 0,
        };
        Ok(match self {
            Command::Stroke(s) => {
                let edits = stroke_edits(s, scene.selection.as_ref(), &scene.world.read(), None)?;
                apply_all(scene, edits)?
            }
            Command::RemoveUnusedMaterials => remove_unused_materials(scene)?,
            Command::Object(c) => c.apply(scene)?,
            Command::Select(op) => {
                let alone = scene.active_world()?;
                let source = alone.as_ref().unwrap_or(world);
                let next = select(scene.selection.as_ref(), op.clone(), &source.read());
                unchanged(Inverse::Selection(std::mem::replace(
                    &mut scene.selection,
                    next,
                )))
            }
            Command::DeleteSelection => selection_edit(scene, Mode::Remove)?,
            Command::FillSelection(m) => {
                world.materials().check(*m as u32)?;
                selection_edit(scene, Mode::Add(*m))?
            }
            Command::PaintSelection(m) => {
                world.materials().check(*m as u32)?;
                selection_edit(scene, Mode::Paint(*m))?
            }
            Command::MoveSelection(offset) => {
                let selection = selected(scene)?.clone();
                let alone = scene.active_world()?;
                let source = alone.as_ref().unwrap_or(world);
                let edit = selection::move_edit(&source.read(), &selection, *offset);
                let moved =
                    Selection::new(selection.region.translated(*offset), world.dims().voxels());
                with_selection(scene, edit, Some(moved))?
            }
            Command::ScaleSelection(step) => reshape(scene, |view, selection| {
                crate::selection_scale::scale_edit(view, selection, *step)
            })?,
            Command::TransformSelection(t) => reshape(scene, |view, selection| {
                crate::selection_transform::transform_edit(view, selection, *t)
            })?,
            Command::Copy => {
                let alone = scene.active_world()?;
                let source = alone.as_ref().unwrap_or(world);
                let clip = Clip::copy(&source.read(), selected(scene)?)
                    .ok_or(super::error::EditError::NothingToDo("nothing is selected"))?;
                scene.clipboard = Some(std::sync::Arc::new(clip));
                unchanged(Inverse::Compound(Vec::new()))
            }
            Command::Cut => {
                let alone = scene.active_world()?;
                let source = alone.as_ref().unwrap_or(world);
                let clip = Clip::copy(&source.read(), selected(scene)?)
                    .ok_or(super::error::EditError::NothingToDo("nothing is selected"))?;
                let applied = selection_edit(scene, Mode::Remove)?;
                scene.clipboard = Some(std::sync::Arc::new(clip));
                applied
            }
            Command::Paste { at } => {
                let clip = scene
                    .clipboard
                    .clone()
                    .ok_or(super::error::EditError::NothingToDo(
                        "the clipboard is empty",
                    ))?;
                let voxels = world.dims().voxels();
                let edit = selection::paste_edit(&clip, *at, voxels);
                let pasted = Selection::new(clip.region.translated(*at), voxels);
                let pasted = (!pasted.voxels.is_empty()).then_some(pasted);
                with_selection(scene, edit, pasted)?
            }
            Command::Stamp { at, quarters } => {
                let edit = super::stamp::stamp_edit(
                    scene.clipboard.as_deref(),
                    at,
                    *quarters,
                    world.dims().voxels(),
                )?;
                apply_all(scene, vec![edit])?
            }
            Command::Extrude {
                voxel,
                normal,
                distance,
                same_material,
            } => {
                let edits = super::extrude::extrude_edits(
                    scene,
                    *voxel,
                    *normal,
                    *distance,
                    *same_material,
                )?;
                apply_all(scene, vec![EditOp::Voxels(edits)])?
            }
            Command::PlaneFill {
                voxel,
                normal,
                material,
            } => {
                world.materials().check(*material as u32)?;
                let edits = super::extrude::plane_fill_edits(scene, *voxel, *normal, *material)?;
                apply_all(scene, vec![EditOp::Voxels(edits)])?
            }
            Command::ReplaceMaterial { from, to } => {
                world.materials().check(*to as u32)?;
                let edits = super::replace::replace_edits(scene, *from, *to)?;
                apply_all(scene, vec![EditOp::Voxels(edits)])?
            }
            Command::FloodFill { start, material } => {
                world.materials().check(*material as u32)?;
                let edits = super::fill::flood_fill(scene, *start, *material)?;
                apply_all(scene, vec![EditOp::Voxels(edits)])?
            }
            Command::Clear => {
                let max = world.dims().voxels() - 1;
                let clear = EditOp::Shape {
                    shape: Shape::Box {
                        min: IVec3::ZERO,
                        max,
                    },
                    mode: Mode::Remove,
                };
                apply_all(scene, vec![clear])?
            }
            Command::AddMaterial(m) => {
                with_table(scene, |w| w.push_material((*m).into()).map(|_| ()))?
            }
            Command::SetMaterial { index, material } => with_table(scene, |w| {
                w.set_material(*index, (*material).into()).map(|_| ())
            })?,
            Command::SetColour { index, rgb } => with_table(scene, |w| {
                w.set_colour(*index, *rgb);
                Ok(())
            })?,
            Command::SetPalette(colours) => {
                if colours.len() != 256 {
                    return Err(super::error::invalid(format!(
                        "a palette has 256 colours, not {}",
                        colours.len()
                    )));
                }
                with_table(scene, |w| {
                    for (i, c) in colours.iter().enumerate() {
                        w.set_colour(i as u8, *c);
                    }
                    Ok(())
                })?
            }
            Command::SetParam { kind, index, value } => with_table(scene, |w| {
                w.set_param((*kind).into(), *index, *value).map(|_| ())
            })?,
            Command::SetSun(v) => {
                v.validate()?;
                unchanged(Inverse::Sun(std::mem::replace(
                    &mut scene.params.sun,
                    v.clone(),
                )))
            }
            Command::SetSky(v) => {
                v.validate()?;
                unchanged(Inverse::Sky(std::mem::replace(
                    &mut scene.params.sky,
                    v.clone(),
                )))
            }
            Command::SetCamera(v) => {
                v.validate()?;
                unchanged(Inverse::Camera(std::mem::replace(
                    &mut scene.params.camera,
                    v.clone(),
                )))
            }
            Command::SetSettings(v) => {
                v.validate()?;
                unchanged(Inverse::Settings(std::mem::replace(
                    &mut scene.params.settings,
                    v.clone(),
                )))
            }
            Command::GenerateTerrain(t) => {
                let before = world.materials().clone();
                let result = (|| {
                    // The terrain fills the active object's model, wherever it stands.
                    let node = scene
                        .active()
                        .ok_or(brickmap::objects::ObjectError::NoActiveObject)?;
                    let size = scene
                        .active_size()
                        .ok_or(brickmap::objects::ObjectError::NotAnObject(node))?;
                    let dims = brickmap::GridDims::from_voxels(size.as_uvec3())?;
                    let materials = crate::builtin::terrain_materials(world)?;
                    let mut params = crate::builtin::thesis_terrain(materials, size.y as u32);
                    (params.seed, params.noise, params.scale, params.octaves) =
                        (t.seed, t.noise, t.scale, t.octaves);
                    (params.height_range, params.water_level) = (t.height_range, t.water_level);
                    (params.rock_line, params.snow_line, params.soil_depth) =
                        (t.bands.rock_line, t.bands.snow_line, t.bands.soil_depth);
                    let b = dims.bricks();
                    let edit = match NoiseTerrain::new(params, dims)?.edit() {
                        EditOp::Generate(g) => {
                            EditOp::Generate(brickmap::edit::Generator(std::sync::Arc::new(
                                super::progress::Counted::new(g.0, progress.clone(), (b.x, b.z)),
                            )))
                        }
                        other => other,
                    };
                    let out = scene.apply(brickmap::objects::ObjectOp::EditInModel { node, edit });
                    progress.finish();
                    Ok::<_, EditError>(out?)
                })();
                match result {
                    Ok((inverse, changed_voxels)) => Applied {
                        inverse: Inverse::Voxels(vec![inverse], Some(Box::new(before))),
                        changed_voxels,
                    },
                    Err(e) => {
                        world.replace_materials(before)?;
                        return Err(e);
                    }
                }
            }
            Command::ImportVox { path, offset } => {
                // The file's objects (its groups, names, hidden parts, shared models) join
                // the scene as a group named after the file, drawn last.
                let file = folder.join(path);
                let bytes =
                    std::fs::read(&file).map_err(|e| crate::formats::FormatError::io(&file, e))?;
                let before = world.materials().clone();
                let name = file
                    .file_stem()
                    .map_or_else(|| "import".into(), |s| s.to_string_lossy().into_owned());
                let imported = (|| {
                    let into = crate::formats::vox::objects_into(&scene.world, &bytes, *offset)
                        .map_err(|e| crate::formats::FormatError::vox(&file, e))?;
                    let voxels = into.report.voxels;
                    let op = super::objects::import_ops(scene, into, &name)?;
                    let (inverse, _) = super::objects::apply_growing(scene, |_| Ok(op.clone()))?;
                    Ok::<_, EditError>((inverse, voxels))
                })();
                match imported {
                    Ok((inverse, voxels)) => Applied {
                        inverse: Inverse::Compound(vec![Inverse::Table(Box::new(before)), inverse]),
                        changed_voxels: voxels,
                    },
                    Err(e) => {
                        scene.world.replace_materials(before)?;
                        return Err(e);
                    }
                }
            }
        })
    }
}

/// The current selection, or the error that says there is none.
fn selected(scene: &Scene) -> Result<&Selection> {
    scene
        .selection
        .as_ref()
        .ok_or(super::error::EditError::NothingToDo("nothing is selected"))
}

/// A mode applied to exactly the selected voxels.
fn selection_edit(scene: &Scene, mode: Mode) -> Result<Applied> {
    let shape = Shape::Set(selected(scene)?.voxels.clone());
    apply_all(scene, vec![EditOp::Shape { shape, mode }])
}

/// A turn, mirror or scale of the selection: `make` gives the edit and the region from the
/// edited object's voxels; the region's voxels become the selection.
fn reshape(
    scene: &mut Scene,
    make: impl FnOnce(&brickmap::WorldView<'_>, &Selection) -> Option<(EditOp, selection::Region)>,
) -> Result<Applied> {
    let selection = selected(scene)?.clone();
    let alone = scene.active_world()?;
    let source = alone.as_ref().unwrap_or(&scene.world);
    let (edit, region) = make(&source.read(), &selection)
        .ok_or(super::error::EditError::NothingToDo("nothing is selected"))?;
    let next = Selection::new(region, scene.world.dims().voxels());
    let next = (!next.voxels.is_empty()).then_some(next);
    with_selection(scene, edit, next)
}

/// Applies a voxel edit and then makes `next` the selection; the inverse puts both back.
fn with_selection(scene: &mut Scene, edit: EditOp, next: Option<Selection>) -> Result<Applied> {
    let applied = apply_all(scene, vec![edit])?;
    let before = std::mem::replace(&mut scene.selection, next);
    Ok(Applied {
        inverse: Inverse::Compound(vec![applied.inverse, Inverse::Selection(before)]),
        changed_voxels: applied.changed_voxels,
    })
}

/// Drops the unused materials (used: by any model, shown or hidden): every model brick with
/// a material whose index changes is rewritten (one batch of model restores), then the
/// shorter table goes in. The inverse puts the old table back first, then the voxels.
fn remove_unused_materials(scene: &Scene) -> Result<Applied> {
    use brickmap::objects::ObjectOp;
    use brickmap::{BrickUndo, EditInverse, PriorMaterials};
    let before = scene.world.materials().clone();
    let mut used = [false; 256];
    let ops = {
        let objects = scene.objects();
        for model in objects.models().values() {
            for (_, b) in model.bricks() {
                match b.uniform() {
                    Some(m) => used[m as usize] = true,
                    None => b
                        .mask
                        .ones()
                        .for_each(|bit| used[b.material(bit) as usize] = true),
                }
            }
        }
        if (0..before.len()).all(|i| used[i]) {
            return Err(super::error::EditError::NothingToDo(
                "every material is in use",
            ));
        }
        if !used.iter().any(|u| *u) {
            // An empty scene keeps its first material (brushes need one).
            used[0] = true;
        }
        let mut remap = [0u8; 256];
        let mut next = 0u8;
        for i in 0..before.len() {
            if used[i] {
                remap[i] = next;
                next = next.wrapping_add(1);
            }
        }
        let mut ops = Vec::new();
        for (id, model) in objects.models() {
            let bricks: Vec<BrickUndo> = model
                .bricks()
                .filter(|(_, b)| {
                    b.mask
                        .ones()
                        .any(|bit| remap[b.material(bit) as usize] != b.material(bit))
                })
                .map(|(brick, b)| BrickUndo {
                    brick,
                    prior_mask: b.mask,
                    touched: b.mask,
                    prior: PriorMaterials::packed(
                        b.mask
                            .ones()
                            .map(|bit| remap[b.material(bit) as usize])
                            .collect(),
                    ),
                })
                .collect();
            if !bricks.is_empty() {
                ops.push(ObjectOp::RestoreModel {
                    model: *id,
                    inverse: EditInverse { bricks },
                });
            }
        }
        ops
    };
    let table = before.retain(&used)?;
    let (inverse, changed_voxels) = scene.apply(ObjectOp::Batch(ops))?;
    if let Err(e) = scene.world.replace_materials(table) {
        scene.apply(inverse)?;
        return Err(e.into());
    }
    Ok(Applied {
        inverse: Inverse::Voxels(vec![inverse], Some(Box::new(before))),
        changed_voxels,
    })
}
