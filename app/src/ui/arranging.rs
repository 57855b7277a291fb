//! Arrange mode (Tab, the Arrange tool): the left button picks the object whose voxel is
//! under the cursor (Shift adds it to the picked nodes, Ctrl takes it away; a click on
//! nothing clears them) and makes a single picked object the one brushes edit; a drag that
//! starts on a picked object moves the picked ones over the horizontal plane it started on
//! (their outlines follow; one move at the release, Esc cancels); the nudge keys move the
//! picked nodes (Shift: a brick), Delete deletes them. The picked nodes are the Objects
//! window's.

use super::Editor;
use super::camera::ViewCamera;
use super::intent::Nudge;
use super::pointer::MoveDrag;
use super::selecting::nudge_offset;
use super::tools;
use crate::editor::command::Command;
use crate::editor::objects::ObjectCommand;
use brickmap::objects::{NodeId, NodeKind, Objects};
use glam::{DVec3, IVec3};

impl Editor {
    /// A click in arrange mode: picks the object under the cursor.
    pub(super) fn arrange_press(&mut self) {
        let (origin, dir) = self.cursor_ray();
        let (hit, node, is_object, active) = {
            let doc = self.read();
            let hit = tools::pick(&doc.scene.world.read(), origin, dir).map(|(h, _)| h.voxel);
            let node = hit.and_then(|v| doc.scene.objects().object_at(v));
            (hit, node, node.is_some(), doc.scene.active())
        };
        let mods = self.pointer.mods;
        let picked = &mut self.panels.outliner.picked;
        match node {
            Some(n) if mods.shift => {
                if !picked.contains(&n) {
                    picked.push(n);
                }
            }
            Some(n) if mods.ctrl => picked.retain(|p| *p != n),
            Some(n) => *picked = vec![n],
            None if mods.shift || mods.ctrl => {}
            None => picked.clear(),
        }
        // A press on a picked object (no modifier) starts dragging the picked ones.
        if let (Some(v), Some(n)) = (hit, node)
            && !mods.shift
            && !mods.ctrl
            && picked.contains(&n)
        {
            let y = f64::from(v.y) + 0.5;
            self.pointer.moving = on_plane(origin, dir, y).map(|start| MoveDrag {
                y,
                start,
                by: IVec3::ZERO,
            });
        }
        if let [n] = self.panels.outliner.picked.as_slice()
            && is_object
            && active != Some(*n)
        {
            let n = *n;
            self.execute(Command::Object(ObjectCommand::Activate(Some(n))));
        }
    }

    /// While dragging picked objects: the whole voxels the cursor moved on the drag's plane.
    pub(super) fn arrange_to_cursor(&mut self) {
        let Some(m) = &self.pointer.moving else {
            return;
        };
        let (origin, dir) = self.cursor_ray();
        if let Some(p) = on_plane(origin, dir, m.y) {
            let d = (p - m.start).round();
            let by = IVec3::new(d.x as i32, 0, d.z as i32);
            if let Some(m) = &mut self.pointer.moving {
                m.by = by;
            }
        }
    }

    /// The release of a drag of picked objects: one move by what the drag showed.
    pub(super) fn arrange_release(&mut self) {
        let Some(m) = self.pointer.moving.take() else {
            return;
        };
        let nodes = self.panels.outliner.picked.clone();
        if m.by != IVec3::ZERO && !nodes.is_empty() {
            self.execute(Command::Object(ObjectCommand::Translate {
                nodes,
                by: m.by,
            }));
        }
    }

    /// How far picked objects being dragged have moved (zero when none is).
    pub(super) fn dragged_by(&self) -> IVec3 {
        self.pointer.moving.as_ref().map_or(IVec3::ZERO, |m| m.by)
    }

    /// A nudge key in arrange mode: the picked nodes move a voxel (Shift: a brick).
    pub(super) fn arrange_nudge(&mut self, n: Nudge) {
        let nodes = self.panels.outliner.picked.clone();
        if nodes.is_empty() {
            return;
        }
        let step = nudge_offset(n, self.viewing.camera.camera.forward());
        let by = if self.pointer.mods.shift {
            step * 8
        } else {
            step
        };
        self.execute(Command::Object(ObjectCommand::Translate { nodes, by }));
    }

    /// Delete in arrange mode: the picked nodes go.
    pub(super) fn arrange_delete(&mut self) {
        let nodes = std::mem::take(&mut self.panels.outliner.picked);
        if !nodes.is_empty() {
            self.execute(Command::Object(ObjectCommand::Delete(nodes)));
        }
    }
}

/// Where a ray meets the horizontal plane at height `y` (ahead of it, within a long way:
/// a ray nearly along the plane has no useful point on it).
fn on_plane(origin: DVec3, dir: DVec3, y: f64) -> Option<DVec3> {
    if dir.y.abs() < 1e-6 {
        return None;
    }
    let t = (y - origin.y) / dir.y;
    (t > 0.0 && t < 1e5).then(|| origin + dir * t)
}

/// The world boxes of the picked objects (lowest cell, one past the highest).
pub fn picked_boxes(objects: &Objects, picked: &[NodeId]) -> Vec<(IVec3, IVec3)> {
    let tree = objects.tree();
    let mut out = Vec::new();
    for p in picked {
        for n in tree.subtree(*p).unwrap_or_default() {
            let Ok(node) = tree.node(n) else { continue };
            if let NodeKind::Object { model, .. } = node.kind
                && let (Some(m), Ok(at)) = (objects.model(model), tree.world_placement(n))
            {
                out.push(at.bounds(m.size()));
            }
        }
    }
    out
}

/// Outlines the picked objects' boxes.
pub fn paint(
    painter: &egui::Painter,
    view: &ViewCamera,
    rect: egui::Rect,
    boxes: &[(IVec3, IVec3)],
) {
    let stroke = egui::Stroke::new(2.0, egui::Color32::from_rgb(120, 200, 255));
    for (lo, hi) in boxes {
        super::preview::paint_box(painter, view, rect, lo.as_dvec3(), hi.as_dvec3(), stroke);
    }
}
