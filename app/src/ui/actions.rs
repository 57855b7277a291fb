//! What the user asked for → the editor: key-map actions (menus and shortcuts) and the
//! panels' events, each turned into an edit on the edit thread, a file job, a camera change
//! or a panel's state.

use super::input::Action;
use super::jobs::Edit;
use super::panels::{UiEvent, UnsavedAnswer};
use super::pending::Pending;
use super::purpose::Purpose;
use super::tools::Tool;
use super::{Editor, content_bounds};
use crate::editor::command::Command;
use crate::editor::objects::ObjectCommand;
use crate::selection::SelectOp;
use crate::selection_transform::SelectionTransform;
use glam::{DVec3, IVec3};

impl Editor {
    pub(super) fn action(&mut self, action: Action) {
        match action {
            Action::Undo => self.docs.submit(Edit::Undo),
            Action::Redo => self.docs.submit(Edit::Redo),
            Action::New => self.panels.new_open = true,
            Action::Open => self.guard_unsaved(Pending::Open(None)),
            Action::Save => self.save(false),
            Action::SaveAs => self.save(true),
            Action::Import => self.docs.files.pick(Purpose::Import, self.folder(), None),
            Action::Export => {
                self.docs
                    .files
                    .pick(Purpose::Export, self.folder(), Some("scene.vox".into()))
            }
            Action::NewFromHeightmap => self.guard_unsaved(Pending::Heightmap),
            Action::ExportMesh => {
                self.docs
                    .files
                    .pick(Purpose::ExportMesh, self.folder(), Some("scene.glb".into()))
            }
            Action::Frame => {
                // In arrange mode with nodes picked: their boxes; else the scene's content.
                let picked = (self.settings.brush.tool == Tool::Arrange)
                    .then(|| {
                        let doc = self.read();
                        let objects = doc.scene.objects();
                        super::arranging::picked_boxes(&objects, &self.panels.outliner.picked)
                            .into_iter()
                            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
                    })
                    .flatten();
                let (min, max) = match picked {
                    Some((lo, hi)) => (lo.as_dvec3(), hi.as_dvec3()),
                    None => content_bounds(&self.read().scene),
                };
                let aspect = self.aspect();
                self.viewing.camera.frame(min, max, aspect);
                self.moved();
            }
            Action::ToggleProjection => {
                let size = self.read().scene.world.dims().voxels().as_dvec3();
                self.viewing.camera.toggle_projection(DVec3::ZERO, size);
                self.moved();
            }
            Action::StoreView(n) => self.viewing.store(n),
            Action::RecallView(n) => {
                if let Some(v) = self.viewing.stored(n) {
                    self.viewing.camera = v;
                    self.moved();
                }
            }
            Action::BrushSmaller => self.settings.brush.resize(-1.0),
            Action::BrushLarger => self.settings.brush.resize(1.0),
            Action::Mode(m) => {
                self.settings.brush.mode = m;
                self.settings.brush.tool = Tool::Brush;
            }
            Action::Shape(s) => {
                self.settings.brush.shape = s;
                self.settings.brush.tool = Tool::Brush;
            }
            Action::SelectTool => self.settings.brush.tool = Tool::Select,
            Action::MeasureTool => self.settings.brush.tool = Tool::Measure,
            Action::ExtrudeTool => self.settings.brush.tool = Tool::Extrude,
            Action::StampTool => self.settings.brush.tool = Tool::Stamp,
            Action::StampTurn => self.stamp_turn(1),
            Action::StampTurnBack => self.stamp_turn(-1),
            Action::NextColourMode => self.settings.brush.next_colour_mode(),
            Action::NextSelectMode => {
                self.settings.brush.tool = Tool::Select;
                self.settings.brush.select_mode = self.settings.brush.select_mode.next();
            }
            Action::ToggleGrid => self.settings.grid = !self.settings.grid,
            Action::ArrangeTool => {
                self.settings.brush.tool = if self.settings.brush.tool == Tool::Arrange {
                    Tool::Brush
                } else {
                    Tool::Arrange
                }
            }
            Action::RemoveUnusedMaterials => self.execute(Command::RemoveUnusedMaterials),
            Action::SelectAll => self.select(SelectOp::All),
            Action::SelectNone => self.select(SelectOp::None),
            Action::InvertSelection => self.select(SelectOp::Invert),
            Action::DoubleSelection => self.scale(crate::selection_scale::ScaleStep::Double),
            Action::HalveSelection => self.scale(crate::selection_scale::ScaleStep::Halve),
            Action::GrowSelection => self.select(SelectOp::Grow),
            Action::ShrinkSelection => self.select(SelectOp::Shrink),
            Action::SelectMaterial => self.select(SelectOp::Material {
                material: self.settings.brush.material,
                how: crate::wand::Combine::Replace,
            }),
            Action::DeleteSelection if self.settings.brush.tool == Tool::Arrange => {
                self.arrange_delete()
            }
            Action::DeleteSelection => self.execute(Command::DeleteSelection),
            Action::FillSelection => {
                self.execute(Command::FillSelection(self.settings.brush.material))
            }
            Action::PaintSelection => {
                self.execute(Command::PaintSelection(self.settings.brush.material))
            }
            Action::Copy => self.execute(Command::Copy),
            Action::Cut => self.execute(Command::Cut),
            // The copy is on the document once queued edits (a copy just asked for) ran;
            // until then the placement shows nothing and a click pastes nothing.
            Action::Paste => self.controls.pointer.pasting = true,
            Action::Nudge(n) if self.settings.brush.tool == Tool::Arrange => self.arrange_nudge(n),
            Action::Nudge(n) => self.nudge(n),
            Action::Turn(axis) => self.turn_or_flip(SelectionTransform::Turn { axis, quarters: 1 }),
            Action::TurnBack(axis) => {
                self.turn_or_flip(SelectionTransform::Turn { axis, quarters: -1 })
            }
            Action::Flip(axis) => self.turn_or_flip(SelectionTransform::Flip(axis)),
            Action::DuplicateObject
            | Action::InstanceObject
            | Action::MakeUnique
            | Action::GroupObjects
            | Action::Ungroup
            | Action::MergeObjects
            | Action::SplitSelection => self.object_action(action),
            Action::Help => self.panels.help_open = !self.panels.help_open,
            Action::Quit => self.guard_unsaved(Pending::Quit),
        }
    }

    /// A turn or a flip of the picked nodes in arrange mode; else of the selection's voxels
    /// when there is a selection, of the object brushes edit when not.
    /// × 2 / × ½: the selection's voxels, or without one the edited object's model.
    fn scale(&mut self, step: crate::selection_scale::ScaleStep) {
        let (selected, node) = {
            let doc = self.read();
            (doc.scene.selection.is_some(), doc.scene.active())
        };
        if selected && self.settings.brush.tool != Tool::Arrange {
            self.execute(Command::ScaleSelection(step));
        } else if let Some(node) = node {
            self.execute(Command::Object(ObjectCommand::Scale { node, step }));
        }
    }

    fn turn_or_flip(&mut self, t: SelectionTransform) {
        if self.settings.brush.tool != Tool::Arrange && self.read().scene.selection.is_some() {
            self.execute(Command::TransformSelection(t));
            return;
        }
        let nodes = self.object_targets();
        if nodes.is_empty() {
            return;
        }
        self.execute(Command::Object(match t {
            SelectionTransform::Turn { axis, quarters } => ObjectCommand::Turn {
                nodes,
                axis,
                quarters,
            },
            SelectionTransform::Flip(axis) => ObjectCommand::Flip { nodes, axis },
        }));
    }

    pub(super) fn ui_event(&mut self, e: UiEvent) {
        match e {
            UiEvent::Action(a) => self.action(a),
            UiEvent::KeyPreset(p) => {
                self.settings.key_preset = p;
                self.load_keys();
            }
            UiEvent::ReplaceMaterial { from } => self.execute(Command::ReplaceMaterial {
                from,
                to: self.settings.brush.material,
            }),
            UiEvent::OpenRecent(p) => self.guard_unsaved(Pending::Open(Some(p))),
            UiEvent::SetSun(s) => self.execute(Command::SetSun(s)),
            UiEvent::SetSky(s) => self.execute(Command::SetSky(s)),
            UiEvent::SetSettings(s) => self.execute(Command::SetSettings(s)),
            // Reading and merging a file can take a while: on the worker.
            UiEvent::Import { path, offset } => self.execute(Command::ImportVox {
                path: path.display().to_string(),
                offset: glam::IVec3::from_array(offset),
            }),
            UiEvent::SetColour { index, rgb } => self.execute(Command::SetColour { index, rgb }),
            UiEvent::SetMaterial { index, material } => {
                self.execute(Command::SetMaterial { index, material })
            }
            UiEvent::AddMaterial(m) => self.execute(Command::AddMaterial(m)),
            UiEvent::PaletteFile { save: false } => {
                self.docs
                    .files
                    .pick(Purpose::LoadPalette, self.folder(), None)
            }
            UiEvent::PaletteFile { save: true } => self.docs.files.pick(
                Purpose::SavePalette,
                self.folder(),
                Some("palette.png".into()),
            ),
            UiEvent::SetParam { kind, index, value } => {
                self.execute(Command::SetParam { kind, index, value })
            }
            UiEvent::Generate(spec) => self.execute(Command::GenerateTerrain(spec)),
            UiEvent::Objects(c) => self.execute(Command::Object(c)),
            UiEvent::NewObject(size) => {
                // Centred under the view's pivot, standing on it, inside the grid where it fits.
                let grid = self.read().scene.world.dims().voxels();
                let pivot = self.viewing.camera.pivot().floor().as_ivec3();
                let at = IVec3::new(pivot.x - size.x / 2, pivot.y, pivot.z - size.z / 2)
                    .min(grid - size)
                    .max(IVec3::ZERO);
                self.execute(Command::Object(ObjectCommand::NewObject {
                    name: "object".into(),
                    size,
                    at,
                }));
            }
            UiEvent::RenderImage => {
                let name = format!("render.{}", self.settings.render_image.format.extension());
                self.docs
                    .files
                    .pick(Purpose::RenderImage, self.folder(), Some(name))
            }
            UiEvent::EditObject(n) => {
                if self.read().scene.active() != Some(n) {
                    self.execute(Command::Object(ObjectCommand::Activate(Some(n))));
                }
                if self.settings.brush.tool == Tool::Arrange {
                    self.settings.brush.tool = Tool::Brush;
                }
            }
            UiEvent::Jump { undo, redo } => {
                for _ in 0..undo {
                    self.docs.submit(Edit::Undo);
                }
                for _ in 0..redo {
                    self.docs.submit(Edit::Redo);
                }
            }
            UiEvent::UseViewAsSceneCamera => {
                self.execute(Command::SetCamera(self.viewing.camera.camera.clone()))
            }
            UiEvent::NewScene { size, terrain } => {
                self.guard_unsaved(Pending::New { size, terrain })
            }
            UiEvent::Picked(purpose, path) => self.picked(purpose, path),
            UiEvent::PickCancelled => self.docs.waits.save_abandoned(),
            UiEvent::Unsaved(answer) => {
                self.panels.asking_unsaved = false;
                let Some(then) = self.docs.waits.answered() else {
                    return;
                };
                match answer {
                    UnsavedAnswer::Cancel => {}
                    UnsavedAnswer::Discard => self.proceed(then),
                    UnsavedAnswer::Save => {
                        self.docs.waits.after_save(then);
                        self.save(false);
                    }
                }
            }
            UiEvent::Recover(yes) => {
                if let Some(p) = self.panels.recovery.take() {
                    if yes {
                        self.docs.waits.recovering();
                        self.docs.files.load(p, self.options.workers);
                    } else {
                        self.config.remove_recovery();
                    }
                }
            }
        }
    }
}
