//! The Tools panel's material section: the brush's material (a swatch per material) and,
//! for attach and paint, its colour mode — solid; a gradient from the material to a second
//! one along the drag; random among chosen materials; and for paint, darken or brighten each
//! voxel by a palette neighbour (the rules: `editor/paint.rs`).

use super::swatch::{kind_name, rgb, swatch};
use super::tools::{Brush, Tool};
use crate::editor::command::{BrushMode, PaintMode};
use brickmap::MaterialTable;

/// The material row and the colour mode.
pub(super) fn material(ui: &mut egui::Ui, brush: &mut Brush, table: &MaterialTable) {
    ui.label("material (Alt + click picks one)");
    if let Some(m) = swatches(ui, table, "material", 18.0, |m| m == brush.material) {
        brush.material = m;
    }
    if brush.tool != Tool::Brush || brush.mode == BrushMode::Erase {
        return;
    }
    ui.horizontal_wrapped(|ui| {
        ui.label("colour");
        let mut choices = vec![
            ("solid", PaintMode::Solid),
            ("gradient", PaintMode::Gradient { to: brush.material }),
            (
                "random",
                PaintMode::Random {
                    among: vec![brush.material],
                    seed: 1,
                },
            ),
        ];
        if brush.mode == BrushMode::Paint {
            choices.push(("darken", PaintMode::Darken));
            choices.push(("brighten", PaintMode::Brighten));
        }
        for (name, mode) in choices {
            let on = std::mem::discriminant(&brush.paint) == std::mem::discriminant(&mode);
            if ui.selectable_label(on, name).clicked() && !on {
                brush.paint = mode;
            }
        }
    });
    match &mut brush.paint {
        PaintMode::Gradient { to } => {
            ui.label("gradient along the drag, to:");
            if let Some(m) = swatches(ui, table, "gradient to", 14.0, |m| m == *to) {
                *to = m;
            }
        }
        PaintMode::Random { among, .. } => {
            ui.label("random among (click to add or remove):");
            if let Some(m) = swatches(ui, table, "random among", 14.0, |m| among.contains(&m)) {
                match among.iter().position(|x| *x == m) {
                    Some(i) if among.len() > 1 => {
                        among.remove(i);
                    }
                    Some(_) => {}
                    None => {
                        among.push(m);
                        among.sort_unstable();
                    }
                }
            }
        }
        PaintMode::Darken | PaintMode::Brighten if brush.mode == BrushMode::Attach => {
            ui.label("darken and brighten work in paint mode (P)");
        }
        PaintMode::Darken => {
            ui.label("each voxel takes its darker neighbour in the material list");
        }
        PaintMode::Brighten => {
            ui.label("each voxel takes its brighter neighbour in the material list");
        }
        PaintMode::Solid => {}
    }
}

/// A wrapped row of a swatch per material, `on` ones framed; the one clicked.
fn swatches(
    ui: &mut egui::Ui,
    table: &MaterialTable,
    row: &str,
    size: f32,
    on: impl Fn(u8) -> bool,
) -> Option<u8> {
    let mut clicked = None;
    ui.horizontal_wrapped(|ui| {
        for i in 0..table.len() {
            let Ok(m) = table.get(i as u8) else { continue };
            let r = swatch(ui, rgb(table, m.colour), Some(m.kind), on(i as u8), size)
                .on_hover_text(format!("{i}: {}", kind_name(m.kind)));
            let name = format!("{row} {i}: {}", kind_name(m.kind));
            r.widget_info(|| egui::WidgetInfo::labeled(egui::WidgetType::Button, true, &name));
            if r.clicked() {
                clicked = Some(i as u8);
            }
        }
    });
    clicked
}
