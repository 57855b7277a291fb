//! The Extrude tool (U): press on a face and drag along its normal; at the release the
//! connected exposed region of that face grows by the dragged number of voxels (dragged
//! inward: is pushed in), one undo step (`Command::Extrude`). The distance shows beside the
//! cursor while dragging; Esc cancels. Tools → "same material only" keeps the region to the
//! clicked voxel's material.

use super::Editor;
use super::tools;
use crate::editor::command::Command;
use glam::{DVec3, IVec3};

/// A face being extruded: the voxel, its face's normal, where the face's centre and one voxel
/// along the normal show in the window (pixels), and the distance so far.
pub(super) struct ExtrudeDrag {
    pub(super) voxel: IVec3,
    pub(super) normal: IVec3,
    from: (f64, f64),
    step: (f64, f64),
    pub(super) distance: i32,
}

impl Editor {
    /// A press with the Extrude tool: the face under the cursor.
    pub(super) fn extrude_press(&mut self) {
        let (origin, dir) = self.cursor_ray();
        let hit = {
            let doc = self.read();
            let view = doc.scene.world.read();
            tools::pick(&view, origin, dir).map(|(h, _)| h)
        };
        let Some(hit) = hit else { return };
        let centre = hit.voxel.as_dvec3() + DVec3::splat(0.5) + hit.normal.as_dvec3() * 0.5;
        let (Some(a), Some(b)) = (
            self.viewing.window_point(centre),
            self.viewing.window_point(centre + hit.normal.as_dvec3()),
        ) else {
            return;
        };
        self.controls.pointer.extruding = Some(ExtrudeDrag {
            voxel: hit.voxel,
            normal: hit.normal,
            from: self.controls.pointer.cursor,
            step: (b.0 - a.0, b.1 - a.1),
            distance: 0,
        });
    }

    /// While dragging: the distance is the cursor's move along the normal as the screen shows
    /// it, in voxels (a normal pointing at the camera shows no length: nothing to drag).
    pub(super) fn extrude_to_cursor(&mut self) {
        let cursor = self.controls.pointer.cursor;
        let Some(d) = &mut self.controls.pointer.extruding else {
            return;
        };
        let len2 = d.step.0 * d.step.0 + d.step.1 * d.step.1;
        if len2 < 1.0 {
            return;
        }
        let moved = (cursor.0 - d.from.0) * d.step.0 + (cursor.1 - d.from.1) * d.step.1;
        d.distance = (moved / len2).round() as i32;
    }

    /// The release: the extrude, when the drag went anywhere.
    pub(super) fn extrude_release(&mut self) {
        let Some(d) = self.controls.pointer.extruding.take() else {
            return;
        };
        if d.distance != 0 {
            self.execute(Command::Extrude {
                voxel: d.voxel,
                normal: d.normal,
                distance: d.distance,
                same_material: self.settings.brush.extrude_same_material,
            });
        }
    }
}

/// "+3 voxels" beside the cursor while dragging.
pub fn paint_distance(painter: &egui::Painter, cursor: egui::Pos2, distance: i32) {
    let text = format!("{distance:+} voxels");
    super::preview::paint_label(painter, cursor + egui::vec2(16.0, 12.0), text, false);
}
