//! The selection tool's screen rectangles ("rectangle", "rectangle: visible"): press anywhere
//! in the viewport, drag, release — the solid voxels inside the rectangle through all depth,
//! or the ones it shows (`crate::rect_select`), combined as the modifiers held at the press
//! say (Shift adds, Ctrl takes away, both intersect). The rectangle is drawn while dragging;
//! Esc cancels; a click without a drag on the replace mode selects nothing.

use super::Editor;
use super::tools::SelectMode;
use crate::rect_select::ScreenRect;
use crate::selection::SelectOp;
use crate::wand::Combine;

/// A rectangle being dragged: where it started (window pixels) and how it combines.
pub(super) struct RectDrag {
    pub(super) from: (f64, f64),
    how: Combine,
}

impl Editor {
    /// A press with a rectangle mode: the drag starts (over the scene or not).
    pub(super) fn rect_select_press(&mut self) {
        let mods = self.controls.pointer.mods;
        self.controls.pointer.rect_selecting = Some(RectDrag {
            from: self.controls.pointer.cursor,
            how: Combine::of(mods.shift, mods.ctrl),
        });
    }

    /// The release: the rectangle's voxels (a click selects nothing when replacing).
    pub(super) fn rect_select_release(&mut self) {
        let Some(d) = self.controls.pointer.rect_selecting.take() else {
            return;
        };
        let to = self.controls.pointer.cursor;
        if (to.0 - d.from.0).abs() < 2.0 && (to.1 - d.from.1).abs() < 2.0 {
            if d.how == Combine::Replace {
                self.select(SelectOp::None);
            }
            return;
        }
        let (_, _, w, h) = self.viewing.area();
        let rect = ScreenRect {
            camera: self.viewing.camera.camera.clone(),
            aspect: self.aspect(),
            pixels: (w, h),
            a: self.ndc(d.from),
            b: self.ndc(to),
            visible_only: self.settings.brush.select_mode == SelectMode::RectVisible,
        };
        self.select(SelectOp::Rect {
            rect: Box::new(rect),
            how: d.how,
        });
    }
}

/// The rectangle being dragged, in points, from its start to the cursor.
pub fn paint(painter: &egui::Painter, from: egui::Pos2, to: egui::Pos2, how: bool) {
    let colour = if how {
        egui::Color32::from_rgb(255, 210, 60)
    } else {
        egui::Color32::from_rgb(255, 70, 60)
    };
    let r = egui::Rect::from_two_pos(from, to);
    painter.rect_filled(r, 0.0, colour.gamma_multiply(0.12));
    painter.rect_stroke(
        r,
        0.0,
        egui::Stroke::new(1.5, colour),
        egui::StrokeKind::Middle,
    );
}

impl RectDrag {
    /// Whether it adds to the selection or replaces it (drawn yellow), rather than taking
    /// away (red).
    pub(super) fn adds(&self) -> bool {
        self.how != Combine::Subtract
    }
}
