//! The Object menu and its shortcuts: duplicate, instance, make unique, group, ungroup,
//! merge, split the selection into an object, and whether the objects not being edited are
//! dimmed. They act on the picked nodes in arrange mode and on the object brushes edit
//! otherwise (the turn and flip keys do the same); what they cannot act on is said on the
//! status line.

use super::Editor;
use super::intent::{Action, UiEvent};
use super::tools::Tool;
use crate::editor::Document;
use crate::editor::command::Command;
use crate::editor::objects::ObjectCommand;
use brickmap::objects::{NodeId, NodeKind, ObjectTree, Objects};
use glam::IVec3;

/// The menu's commands: label with its keys, action.
const ENTRIES: [(&str, Action); 7] = [
    ("Duplicate  Ctrl+Shift+D", Action::DuplicateObject),
    ("Instance  Ctrl+Shift+I", Action::InstanceObject),
    ("Make unique  Ctrl+U", Action::MakeUnique),
    ("Group  Ctrl+G", Action::GroupObjects),
    ("Ungroup  Ctrl+Shift+G", Action::Ungroup),
    ("Merge  Ctrl+J", Action::MergeObjects),
    (
        "Selection to new object  Ctrl+Shift+N",
        Action::SplitSelection,
    ),
];

/// The command an object action makes of the nodes it acts on, or why there is none.
pub fn command(
    action: Action,
    objects: &Objects,
    nodes: &[NodeId],
    has_selection: bool,
) -> Result<ObjectCommand, &'static str> {
    let tree = objects.tree();
    let is_object = |n: &&NodeId| {
        tree.node(**n)
            .is_ok_and(|n| matches!(n.kind, NodeKind::Object { .. }))
    };
    let object = nodes.iter().find(is_object).copied();
    let group = nodes
        .iter()
        .find(|n| !is_object(n) && **n != ObjectTree::ROOT && tree.node(**n).is_ok())
        .copied();
    const PICK: &str = "pick an object first (Tab: arrange mode, click one)";
    let c = match action {
        Action::DuplicateObject => ObjectCommand::Duplicate {
            node: object.ok_or(PICK)?,
            offset: IVec3::ZERO,
        },
        Action::InstanceObject => ObjectCommand::Instance {
            node: object.ok_or(PICK)?,
            offset: IVec3::ZERO,
        },
        Action::MakeUnique => ObjectCommand::MakeUnique(object.ok_or(PICK)?),
        Action::GroupObjects if nodes.iter().any(|n| *n != ObjectTree::ROOT) => {
            ObjectCommand::Group {
                nodes: nodes.to_vec(),
                name: "group".into(),
            }
        }
        Action::GroupObjects => return Err(PICK),
        Action::Ungroup => ObjectCommand::Ungroup(group.ok_or("pick a group first")?),
        Action::MergeObjects => {
            let picked: Vec<NodeId> = nodes.iter().filter(is_object).copied().collect();
            if picked.len() < 2 {
                return Err("pick two objects or more to merge (Shift + click adds one)");
            }
            ObjectCommand::Merge {
                nodes: picked,
                name: "merged".into(),
            }
        }
        Action::SplitSelection if has_selection => ObjectCommand::SplitSelection,
        Action::SplitSelection => return Err("select voxels first (M: the selection tool)"),
        _ => return Err("not an object action"),
    };
    Ok(c)
}

impl Editor {
    /// The nodes the object actions, turns and flips act on: the picked ones in arrange
    /// mode, else the object brushes edit.
    pub(super) fn object_targets(&self) -> Vec<NodeId> {
        if self.settings.brush.tool == Tool::Arrange {
            self.panels.outliner.picked.clone()
        } else {
            self.read().scene.active().into_iter().collect()
        }
    }

    /// Duplicate, instance, make unique, group, ungroup, merge or split, as [`command`] says.
    pub(super) fn object_action(&mut self, action: Action) {
        let nodes = self.object_targets();
        let made = {
            let doc = self.read();
            command(
                action,
                &doc.scene.objects(),
                &nodes,
                doc.scene.selection.is_some(),
            )
        };
        match made {
            Ok(c) => {
                if matches!(c, ObjectCommand::Merge { .. }) {
                    // The merged objects go.
                    self.panels.outliner.picked.clear();
                }
                self.execute(Command::Object(c));
            }
            Err(why) => self.panels.notify(why),
        }
    }
}

/// The Resize canvas fields: for which object, its new size, the anchor (per axis −1 low,
/// 0 centre, 1 high).
#[derive(Clone, Copy, Debug, Default)]
pub struct CanvasForm {
    node: Option<NodeId>,
    size: [i32; 3],
    anchor: [i32; 3],
}

/// The canvas entries: fit, crop to the selection, resize (on the object brushes edit).
fn canvas(ui: &mut egui::Ui, doc: &Document, form: &mut CanvasForm, out: &mut Vec<UiEvent>) {
    use crate::editor::canvas::Canvas;
    let Some(node) = doc.scene.active() else {
        ui.label("canvas: no object to edit");
        return;
    };
    let send = |out: &mut Vec<UiEvent>, how| {
        out.push(UiEvent::Objects(ObjectCommand::Canvas { node, how }));
    };
    for (name, step) in [
        (
            "Scale the object × 2",
            crate::selection_scale::ScaleStep::Double,
        ),
        (
            "Scale the object × ½",
            crate::selection_scale::ScaleStep::Halve,
        ),
    ] {
        if ui
            .button(name)
            .on_hover_text("its model, about its pivot (× ½: the majority of each 2 × 2 × 2)")
            .clicked()
        {
            out.push(UiEvent::Objects(ObjectCommand::Scale { node, step }));
        }
    }
    if ui.button("Fit canvas to content").clicked() {
        send(out, Canvas::Fit);
    }
    let selected = doc.scene.selection.as_ref().and_then(|s| s.voxels.bounds());
    if ui
        .add_enabled(
            selected.is_some(),
            egui::Button::new("Crop canvas to the selection"),
        )
        .clicked()
        && let Some((min, max)) = selected
    {
        send(out, Canvas::Crop { min, max });
    }
    if form.node != Some(node) {
        let size = doc.scene.active_size().unwrap_or(IVec3::ONE);
        *form = CanvasForm {
            node: Some(node),
            size: size.to_array(),
            anchor: [0, -1, 0],
        };
    }
    ui.menu_button("Resize canvas", |ui| {
        ui.horizontal(|ui| {
            ui.label("size");
            for v in &mut form.size {
                ui.add(egui::DragValue::new(v).range(1..=4096));
            }
        });
        ui.horizontal(|ui| {
            ui.label("keep at");
            for (a, axis) in form.anchor.iter_mut().zip(["x", "y", "z"]) {
                let name = match *a {
                    -1 => format!("{axis} low"),
                    0 => format!("{axis} centre"),
                    _ => format!("{axis} high"),
                };
                if ui.button(name).clicked() {
                    *a = if *a == 1 { -1 } else { *a + 1 };
                }
            }
        });
        if ui.button("Resize").clicked() {
            send(
                out,
                Canvas::Resize {
                    size: IVec3::from_array(form.size),
                    anchor: IVec3::from_array(form.anchor),
                },
            );
        }
    });
}

/// Draws the Object menu's entries (`dim_others`: the view setting).
pub fn menu(
    ui: &mut egui::Ui,
    doc: &Document,
    tool: Tool,
    dim_others: &mut bool,
    form: &mut CanvasForm,
    out: &mut Vec<UiEvent>,
) {
    let mut arrange = tool == Tool::Arrange;
    if ui.checkbox(&mut arrange, "Arrange mode  Tab").changed() {
        out.push(UiEvent::Action(Action::ArrangeTool));
    }
    ui.separator();
    let selection = doc.scene.selection.is_some();
    for (label, action) in ENTRIES {
        let enabled = action != Action::SplitSelection || selection;
        if ui.add_enabled(enabled, egui::Button::new(label)).clicked() {
            out.push(UiEvent::Action(action));
        }
    }
    ui.separator();
    canvas(ui, doc, form, out);
    ui.separator();
    ui.checkbox(dim_others, "Dim the objects not edited")
        .on_hover_text(
            "Outside arrange mode, darken what the camera sees outside the edited object's box",
        );
}
