//! The Stamp tool (J): the clipboard as a brush. Press on a face and drag: a stamp goes down
//! where the press was and again each time the cursor has moved a whole stamp's width along
//! an axis (stamps in a row touch, never overlap), keeping to the first face's layer; the
//! release puts them all down as one undo step (`Command::Stamp`). H turns the stamp a
//! quarter turn about the vertical (Shift + H back). The stamps show translucent where they
//! will go, and under the cursor before the press; Esc cancels a drag.
//!
//! A stamp is placed as a paste is: the clip's bottom centre on the voxel in front of the
//! face under the cursor.

use super::Editor;
use super::tools::{self, Layer};
use crate::editor::Document;
use crate::editor::command::{BrushMode, Command};
use crate::editor::stamp::{MAX_STAMPS, turned_size};
use glam::IVec3;

/// A stamp drag: the layer it keeps to and the stamps so far (minimum corners).
pub(super) struct StampDrag {
    layer: Layer,
    pub(super) at: Vec<IVec3>,
}

/// Whether a stamp at `next` leaves the one at `last` whole: apart by at least the stamp's
/// size along some axis.
pub fn apart(last: IVec3, next: IVec3, size: IVec3) -> bool {
    (next - last).abs().cmpge(size).any()
}

impl Editor {
    /// Where a stamp under the cursor would go now (its minimum corner) and its turned size;
    /// on `layer` while dragging.
    pub(super) fn stamp_target(
        &self,
        doc: &Document,
        layer: Option<Layer>,
    ) -> Option<(IVec3, IVec3)> {
        let size = turned_size(
            doc.scene.clipboard.as_ref()?.size,
            self.settings.brush.stamp_quarters,
        );
        let (origin, dir) = self.cursor_ray();
        let view = doc.scene.world.read();
        let v = match layer {
            Some(l) => tools::on_layer(l, origin, dir, view.dims().voxels())?,
            None => tools::start(&view, BrushMode::Attach, origin, dir)?.0,
        };
        Some((super::selecting::paste_at(v, size), size))
    }

    /// A press with the Stamp tool: the first stamp (nothing happens without a clipboard).
    pub(super) fn stamp_press(&mut self) {
        let (origin, dir) = self.cursor_ray();
        let start = {
            let doc = self.read();
            if doc.scene.clipboard.is_none() {
                None
            } else {
                let view = doc.scene.world.read();
                tools::start(&view, BrushMode::Attach, origin, dir).map(|(_, layer)| layer)
            }
        };
        let Some(layer) = start else {
            self.panels
                .notify("Stamp: copy something first (select, then Ctrl + C)");
            return;
        };
        let Some((at, _)) = self.stamp_target(&self.read(), None) else {
            return;
        };
        self.controls.pointer.stamping = Some(StampDrag {
            layer,
            at: vec![at],
        });
    }

    /// While dragging: another stamp once the cursor is a stamp's width from the last.
    pub(super) fn stamp_to_cursor(&mut self) {
        let Some(layer) = self.controls.pointer.stamping.as_ref().map(|d| d.layer) else {
            return;
        };
        let Some((next, size)) = self.stamp_target(&self.read(), Some(layer)) else {
            return;
        };
        if let Some(d) = &mut self.controls.pointer.stamping
            && d.at.len() < MAX_STAMPS
            && d.at.last().is_none_or(|last| apart(*last, next, size))
        {
            d.at.push(next);
        }
    }

    /// The release: every stamp of the drag, one step.
    pub(super) fn stamp_release(&mut self) {
        if let Some(d) = self.controls.pointer.stamping.take() {
            self.execute(Command::Stamp {
                at: d.at,
                quarters: self.settings.brush.stamp_quarters,
            });
        }
    }

    /// H / Shift + H: the stamp a quarter turn further (or back).
    pub(super) fn stamp_turn(&mut self, quarters: i32) {
        let q = &mut self.settings.brush.stamp_quarters;
        *q = (*q + quarters).rem_euclid(4);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_in_a_row_touch_and_never_overlap() {
        let size = IVec3::new(4, 3, 2);
        assert!(!apart(IVec3::ZERO, IVec3::new(3, 0, 1), size));
        assert!(apart(IVec3::ZERO, IVec3::new(4, 0, 0), size));
        assert!(apart(IVec3::ZERO, IVec3::new(1, 0, -2), size));
    }
}
