//! Arrange mode (Tab, the Arrange tool): the left button picks the object whose voxel is
//! under the cursor (Shift adds it to the picked nodes, Ctrl takes it away; a click on
//! nothing clears them) and makes a single picked object the one brushes edit; a drag that
//! starts on a picked object moves the picked ones over the horizontal plane it started on
//! (their outlines follow; one move at the release, Esc cancels); a drag that starts on
//! nothing is a box select (the visible objects whose box it meets; Shift adds, Ctrl takes
//! away); the nudge keys move the picked nodes (Shift: a brick), the turn and flip keys
//! turn and mirror them, Delete deletes them. The picked nodes are the Objects window's.

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
        let mods = self.controls.pointer.mods;
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
        // A press on nothing starts a box select (a click without moving only clears).
        if node.is_none() {
            self.controls.pointer.boxing = Some(self.controls.pointer.cursor);
        }
        // A press on a picked object (no modifier) starts dragging the picked ones.
        if let (Some(v), Some(n)) = (hit, node)
            && !mods.shift
            && !mods.ctrl
            && picked.contains(&n)
        {
            let y = f64::from(v.y) + 0.5;
            self.controls.pointer.moving = on_plane(origin, dir, y).map(|start| MoveDrag {
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
        let Some(m) = &self.controls.pointer.moving else {
            return;
        };
        let (origin, dir) = self.cursor_ray();
        if let Some(p) = on_plane(origin, dir, m.y) {
            let d = (p - m.start).round();
            let by = IVec3::new(d.x as i32, 0, d.z as i32);
            if let Some(m) = &mut self.controls.pointer.moving {
                m.by = by;
            }
        }
    }

    /// The release of a drag of picked objects: one move by what the drag showed; of a box
    /// select: the objects in the box picked (Shift: added, Ctrl: taken away).
    pub(super) fn arrange_release(&mut self) {
        if let Some(from) = self.controls.pointer.boxing.take() {
            let band = band(from, self.controls.pointer.cursor);
            if band.1.0 - band.0.0 < MIN_BAND && band.1.1 - band.0.1 < MIN_BAND {
                return;
            }
            let inside = {
                let doc = self.read();
                let objects = doc.scene.objects();
                in_band(&objects, band, |p| self.viewing.window_point(p))
            };
            let mods = self.controls.pointer.mods;
            let picked = &mut self.panels.outliner.picked;
            if mods.ctrl {
                picked.retain(|p| !inside.contains(p));
            } else {
                for n in inside {
                    if !picked.contains(&n) {
                        picked.push(n);
                    }
                }
            }
            return;
        }
        let Some(m) = self.controls.pointer.moving.take() else {
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
        self.controls
            .pointer
            .moving
            .as_ref()
            .map_or(IVec3::ZERO, |m| m.by)
    }

    /// A nudge key in arrange mode: the picked nodes move a voxel (Shift: a brick).
    pub(super) fn arrange_nudge(&mut self, n: Nudge) {
        let nodes = self.panels.outliner.picked.clone();
        if nodes.is_empty() {
            return;
        }
        let step = nudge_offset(n, self.viewing.camera.camera.forward());
        let by = if self.controls.pointer.mods.shift {
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

/// A box select moved less than this (window pixels) on both axes is a click.
const MIN_BAND: f64 = 4.0;

/// The rectangle between two window points: (lowest x and y, highest x and y).
pub fn band(a: (f64, f64), b: (f64, f64)) -> ((f64, f64), (f64, f64)) {
    ((a.0.min(b.0), a.1.min(b.1)), (a.0.max(b.0), a.1.max(b.1)))
}

/// The box select being dragged, in window pixels.
pub(super) fn boxing_band(editor: &Editor) -> Option<((f64, f64), (f64, f64))> {
    editor
        .controls
        .pointer
        .boxing
        .map(|from| band(from, editor.controls.pointer.cursor))
        .filter(|(lo, hi)| hi.0 - lo.0 >= MIN_BAND || hi.1 - lo.1 >= MIN_BAND)
}

/// The visible objects whose box, as `project` shows it in the window, meets the rectangle
/// `band`, in drawing order. A box wholly behind the eye is not in it; one partly behind
/// counts by its corners in front.
pub fn in_band(
    objects: &Objects,
    (lo, hi): ((f64, f64), (f64, f64)),
    project: impl Fn(DVec3) -> Option<(f64, f64)>,
) -> Vec<NodeId> {
    let mut out = Vec::new();
    for d in objects.tree().drawn() {
        let Some(m) = objects.model(d.model) else {
            continue;
        };
        let (a, b) = d.placement.bounds(m.size());
        let (a, b) = (a.as_dvec3(), b.as_dvec3());
        let mut seen: Option<((f64, f64), (f64, f64))> = None;
        for i in 0..8 {
            if let Some(p) = project(super::preview::box_corner(a, b, i)) {
                seen = Some(match seen {
                    None => (p, p),
                    Some((l, h)) => ((l.0.min(p.0), l.1.min(p.1)), (h.0.max(p.0), h.1.max(p.1))),
                });
            }
        }
        if let Some((l, h)) = seen
            && l.0 <= hi.0
            && h.0 >= lo.0
            && l.1 <= hi.1
            && h.1 >= lo.1
        {
            out.push(d.node);
        }
    }
    out
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

/// The world box of the object brushes edit, when the scene has another one (in a scene of
/// one object its box is the grid's).
pub fn edited_box(scene: &crate::scene::Scene) -> Option<(IVec3, IVec3)> {
    let active = scene.active()?;
    let objects = scene.objects();
    // The root and one object: nothing else to tell it from.
    if objects.tree().len() <= 2 {
        return None;
    }
    picked_boxes(&objects, &[active]).into_iter().next()
}

/// Outlines the picked objects' boxes, and the box select being dragged (`band`, in
/// points).
pub fn paint(
    painter: &egui::Painter,
    view: &ViewCamera,
    rect: egui::Rect,
    boxes: &[(IVec3, IVec3)],
    band: Option<egui::Rect>,
) {
    let colour = egui::Color32::from_rgb(120, 200, 255);
    let stroke = egui::Stroke::new(2.0, colour);
    for (lo, hi) in boxes {
        super::preview::paint_box(painter, view, rect, lo.as_dvec3(), hi.as_dvec3(), stroke);
    }
    if let Some(band) = band {
        painter.rect_filled(band, 0.0, colour.gamma_multiply(0.15));
        painter.rect_stroke(
            band,
            0.0,
            egui::Stroke::new(1.0, colour),
            egui::StrokeKind::Inside,
        );
    }
}
