//! The Tools panel's Selection section: what is selected, how the selection tool selects
//! (a box dragged on a face, "box depth" deep; or the magic wand: a click takes the connected
//! voxels of the clicked one's material, or every connected solid one, through faces or also
//! edges and corners), "brush only inside the selection", and the operations as buttons
//! (select all / none, invert, grow, shrink, delete, fill, paint, copy, cut, paste, move,
//! turn and mirror).

use super::intent::{Action, Nudge, UiEvent};
use super::tools::{Brush, SelectMode, Tool};
use crate::editor::Document;

/// The selection section: what is selected, the tool's depth, and the operations.
pub(super) fn selection(
    ui: &mut egui::Ui,
    brush: &mut Brush,
    doc: &Document,
    out: &mut Vec<UiEvent>,
) {
    let selected = doc.scene.selection.as_ref();
    match selected.and_then(|s| s.voxels.bounds().map(|b| (b, s.voxels.count()))) {
        Some(((lo, hi), n)) => {
            ui.label(format!("selection: {n} voxels in {lo} … {hi}"));
        }
        None => {
            ui.label("selection: none (M, then drag a box on a face)");
        }
    }
    if brush.tool == Tool::Select {
        ui.horizontal_wrapped(|ui| {
            for (m, name, tip) in [
                (SelectMode::Box, "box", "drag a box on a face"),
                (
                    SelectMode::WandColour,
                    "wand: colour",
                    "click: the connected voxels of its material",
                ),
                (
                    SelectMode::WandSolid,
                    "wand: solid",
                    "click: the connected solid voxels",
                ),
                (
                    SelectMode::WandFace,
                    "wand: face",
                    "click a face: its connected coplanar region (the voxels of that layer whose face on that side shows)",
                ),
                (
                    SelectMode::Rect,
                    "rectangle",
                    "drag a rectangle on the screen: every solid voxel inside it, through all depth",
                ),
                (
                    SelectMode::RectVisible,
                    "rectangle: visible",
                    "drag a rectangle on the screen: the voxels it shows",
                ),
            ] {
                ui.selectable_value(&mut brush.select_mode, m, name)
                    .on_hover_text(format!(
                        "{tip}; Shift adds, Ctrl takes away, both intersect"
                    ));
            }
        });
        match brush.select_mode {
            SelectMode::Box => {
                ui.add(egui::Slider::new(&mut brush.select_depth, 1..=256).text("box depth"));
            }
            SelectMode::Rect | SelectMode::RectVisible => {}
            SelectMode::WandFace => {
                ui.checkbox(&mut brush.wand_diagonal, "through corners too");
            }
            SelectMode::WandColour | SelectMode::WandSolid => {
                ui.checkbox(&mut brush.wand_diagonal, "through edges and corners too");
            }
        }
    }
    ui.checkbox(&mut brush.in_selection, "brush only inside the selection");
    let has = selected.is_some();
    let has_copy = doc.scene.clipboard.is_some();
    ui.horizontal_wrapped(|ui| {
        let mut button = |ui: &mut egui::Ui, enabled: bool, name: &str, hint: &str, a| {
            if ui
                .add_enabled(enabled, egui::Button::new(name))
                .on_hover_text(hint)
                .clicked()
            {
                out.push(UiEvent::Action(a));
            }
        };
        button(ui, true, "All", "Ctrl+A", Action::SelectAll);
        button(ui, has, "None", "Ctrl+D", Action::SelectNone);
        button(
            ui,
            true,
            "Invert",
            "what is not selected",
            Action::InvertSelection,
        );
        button(
            ui,
            has,
            "Grow",
            "a voxel more on every side",
            Action::GrowSelection,
        );
        button(
            ui,
            has,
            "Shrink",
            "a voxel less on every side",
            Action::ShrinkSelection,
        );
        button(
            ui,
            true,
            "Material",
            "every voxel of the current material",
            Action::SelectMaterial,
        );
        button(ui, has, "Delete", "Delete", Action::DeleteSelection);
        button(
            ui,
            has,
            "Fill",
            "Ctrl+F: the current material",
            Action::FillSelection,
        );
        button(
            ui,
            has,
            "Paint",
            "Ctrl+P: the current material",
            Action::PaintSelection,
        );
        button(ui, has, "Copy", "Ctrl+C", Action::Copy);
        button(ui, has, "Cut", "Ctrl+X", Action::Cut);
        button(ui, has_copy, "Paste", "Ctrl+V, then click", Action::Paste);
    });
    ui.add_enabled_ui(has, |ui| {
        ui.horizontal_wrapped(|ui| {
            ui.label("move");
            for (name, n) in [
                ("left", Nudge::Left),
                ("right", Nudge::Right),
                ("away", Nudge::Away),
                ("near", Nudge::Towards),
                ("up", Nudge::Up),
                ("down", Nudge::Down),
            ] {
                if ui
                    .button(name)
                    .on_hover_text("arrow keys, Page Up / Down")
                    .clicked()
                {
                    out.push(UiEvent::Action(Action::Nudge(n)));
                }
            }
        });
        ui.horizontal_wrapped(|ui| {
            use brickmap::objects::Axis::{X, Y, Z};
            ui.label("turn");
            for (name, a) in [
                ("X", Action::Turn(X)),
                ("Y", Action::Turn(Y)),
                ("Z", Action::Turn(Z)),
                ("mirror X", Action::Flip(X)),
                ("Y", Action::Flip(Y)),
                ("Z", Action::Flip(Z)),
                ("×2", Action::DoubleSelection),
                ("×½", Action::HalveSelection),
            ] {
                let tip = "about the selection's centre: Alt + X / Y / Z (Shift: back), mirror: Ctrl + Alt";
                if ui.button(name).on_hover_text(tip).clicked() {
                    out.push(UiEvent::Action(a));
                }
            }
        });
    });
}
