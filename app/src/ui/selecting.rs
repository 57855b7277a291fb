//! The selection tool and the operations on a selection in the window. A drag with the tool
//! spans a rectangle on the plane of the face first clicked, `depth` voxels deep into the
//! surface (Shift adds the box, Ctrl subtracts it, both intersect; a click on nothing selects
//! nothing; the wands select with a click, the screen rectangles in `rect_selecting.rs`); the
//! arrow keys move the selection (the horizontal axes as the camera sees them; Page Up /
//! Down vertically; Shift: a brick at a time); a paste follows the cursor, sitting on the
//! face under it, until a click puts it down (Esc cancels). Every operation is a command.
//! The selection's boxes are drawn as outlines: added boxes yellow, subtracted red.

use super::Editor;
use super::camera::ViewCamera;
use super::intent::{Mods, Nudge};
use super::jobs::Edit;
use super::tools::{self, Layer};
use crate::editor::Document;
use crate::editor::command::{BrushMode, Command};
use crate::selection::{SelectOp, Selection};
use glam::{DVec3, IVec3};

/// How a drag changes the selection (by the modifiers held when it starts).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DragKind {
    /// The box becomes the selection.
    Replace,
    /// Shift: added.
    Add,
    /// Ctrl: taken away.
    Subtract,
    /// Shift + Ctrl: only what both hold stays.
    Intersect,
}

impl DragKind {
    /// The kind for the modifiers held.
    pub fn of(mods: Mods) -> Self {
        if mods.shift && mods.ctrl {
            DragKind::Intersect
        } else if mods.shift {
            DragKind::Add
        } else if mods.ctrl {
            DragKind::Subtract
        } else {
            DragKind::Replace
        }
    }

    fn op(self, (min, max): (IVec3, IVec3)) -> SelectOp {
        match self {
            DragKind::Replace => SelectOp::Replace { min, max },
            DragKind::Add => SelectOp::Add { min, max },
            DragKind::Subtract => SelectOp::Subtract { min, max },
            DragKind::Intersect => SelectOp::Intersect { min, max },
        }
    }
}

/// A selection box being dragged.
pub struct SelectDrag {
    layer: Layer,
    /// +1 or −1: the direction into the surface along the layer's axis.
    inward: i32,
    first: IVec3,
    last: IVec3,
    kind: DragKind,
}

/// The box of a drag from `first` to `last` (both on `layer`), `depth` (≥ 1) voxels deep in
/// the `inward` direction along the layer's axis.
pub fn drag_box(
    first: IVec3,
    last: IVec3,
    layer: Layer,
    inward: i32,
    depth: i32,
) -> (IVec3, IVec3) {
    let (mut lo, mut hi) = (first.min(last), first.max(last));
    let a = layer.axis;
    let d = depth.max(1) - 1;
    if inward > 0 {
        hi[a] = lo[a] + d;
    } else {
        lo[a] = hi[a] - d;
    }
    (lo, hi)
}

/// The grid step of a nudge for a camera looking along `forward`: the horizontal axis
/// closest to the screen's right (or to the view direction), with its sign.
pub fn nudge_offset(n: Nudge, forward: DVec3) -> IVec3 {
    let flat = DVec3::new(forward.x, 0.0, forward.z);
    let flat = if flat.length_squared() > 1e-12 {
        flat.normalize()
    } else {
        DVec3::NEG_Z
    };
    let right = flat.cross(DVec3::Y);
    let axis_step = |v: DVec3| {
        if v.x.abs() >= v.z.abs() {
            IVec3::new(v.x.signum() as i32, 0, 0)
        } else {
            IVec3::new(0, 0, v.z.signum() as i32)
        }
    };
    match n {
        Nudge::Right => axis_step(right),
        Nudge::Left => -axis_step(right),
        Nudge::Away => axis_step(flat),
        Nudge::Towards => -axis_step(flat),
        Nudge::Up => IVec3::Y,
        Nudge::Down => IVec3::NEG_Y,
    }
}

/// Where a paste of `size` goes when the cursor is on the empty voxel `v` in front of a
/// face: its bottom centre there.
pub fn paste_at(v: IVec3, size: IVec3) -> IVec3 {
    v - IVec3::new(size.x / 2, 0, size.z / 2)
}

impl Editor {
    /// Left button down with the selection tool: a drag starts on the face under the
    /// cursor; a plain click on nothing selects nothing.
    pub(super) fn select_press(&mut self) {
        let (origin, dir) = self.cursor_ray();
        let brush = &self.settings.brush;
        if matches!(
            brush.select_mode,
            super::tools::SelectMode::Rect | super::tools::SelectMode::RectVisible
        ) {
            self.rect_select_press();
            return;
        }
        if brush.select_mode == super::tools::SelectMode::WandFace {
            let how = crate::wand::Combine::of(
                self.controls.pointer.mods.shift,
                self.controls.pointer.mods.ctrl,
            );
            let diagonal = brush.wand_diagonal;
            let hit = {
                let doc = self.read();
                let view = doc.scene.world.read();
                tools::pick(&view, origin, dir).map(|(h, _)| h)
            };
            match hit {
                Some(h) => self.select(SelectOp::Face {
                    start: h.voxel,
                    normal: h.normal,
                    by_material: false,
                    diagonal,
                    how,
                }),
                None if how == crate::wand::Combine::Replace => self.select(SelectOp::None),
                None => {}
            }
            return;
        }
        if brush.select_mode != super::tools::SelectMode::Box {
            // The magic wand: a click on a voxel (on nothing: a plain click selects nothing).
            let (by_material, diagonal) = (
                brush.select_mode == super::tools::SelectMode::WandColour,
                brush.wand_diagonal,
            );
            let mods = self.controls.pointer.mods;
            let how = crate::wand::Combine::of(mods.shift, mods.ctrl);
            let hit = {
                let doc = self.read();
                let view = doc.scene.world.read();
                tools::pick(&view, origin, dir).map(|(h, _)| h.voxel)
            };
            match hit {
                Some(start) => self.select(SelectOp::Wand {
                    start,
                    by_material,
                    diagonal,
                    how,
                }),
                None if how == crate::wand::Combine::Replace => self.select(SelectOp::None),
                None => {}
            }
            return;
        }
        let kind = DragKind::of(self.controls.pointer.mods);
        let start = {
            let doc = self.read();
            let view = doc.scene.world.read();
            // The solid voxel under the cursor and its face's layer.
            tools::start(&view, BrushMode::Paint, origin, dir).zip(tools::pick(&view, origin, dir))
        };
        match start {
            Some(((v, layer), (hit, _))) => {
                self.controls.pointer.selecting = Some(SelectDrag {
                    layer,
                    inward: -hit.normal[layer.axis],
                    first: v,
                    last: v,
                    kind,
                })
            }
            None if kind == DragKind::Replace => self.select(SelectOp::None),
            None => {}
        }
    }

    /// While dragging a selection box: its corner follows the cursor on the first face's
    /// plane.
    pub(super) fn select_to_cursor(&mut self) {
        let Some(d) = &self.controls.pointer.selecting else {
            return;
        };
        let (origin, dir) = self.cursor_ray();
        let dims = self.read().scene.world.dims().voxels();
        if let Some(v) = tools::on_layer(d.layer, origin, dir, dims)
            && let Some(d) = &mut self.controls.pointer.selecting
        {
            d.last = v;
        }
    }

    /// The box being dragged, if any.
    pub(super) fn dragged_box(&self) -> Option<(IVec3, IVec3, DragKind)> {
        let d = self.controls.pointer.selecting.as_ref()?;
        let depth = self.settings.brush.select_depth;
        let (lo, hi) = drag_box(d.first, d.last, d.layer, d.inward, depth);
        Some((lo, hi, d.kind))
    }

    /// Left button up: the dragged box changes the selection (one command).
    pub(super) fn select_release(&mut self) {
        if let Some((lo, hi, kind)) = self.dragged_box() {
            self.controls.pointer.selecting = None;
            self.select(kind.op((lo, hi)));
        }
    }

    /// Changes the selection.
    pub(super) fn select(&mut self, op: SelectOp) {
        self.execute(Command::Select(op));
    }

    /// Moves the selection one step (a brick with Shift) by a nudge key.
    pub(super) fn nudge(&mut self, n: Nudge) {
        if self.read().scene.selection.is_none() {
            return;
        }
        let step = nudge_offset(n, self.viewing.camera.camera.forward());
        let step = if self.controls.pointer.mods.shift {
            step * 8
        } else {
            step
        };
        self.execute(Command::MoveSelection(step));
    }

    /// Where the paste being placed would go now in `doc` (its minimum corner and size).
    pub(super) fn paste_target(&self, doc: &Document) -> Option<(IVec3, IVec3)> {
        if !self.controls.pointer.pasting {
            return None;
        }
        let size = doc.scene.clipboard.as_ref()?.size;
        let (origin, dir) = self.cursor_ray();
        let (v, _) = tools::start(&doc.scene.world.read(), BrushMode::Attach, origin, dir)?;
        Some((paste_at(v, size), size))
    }

    /// A click while placing a paste: it goes down there.
    pub(super) fn paste_press(&mut self) {
        let target = self.paste_target(&self.read());
        self.controls.pointer.pasting = false;
        if let Some((at, _)) = target {
            self.docs.submit(Edit::Command(Command::Paste { at }));
        }
    }
}

/// Draws the selection's boxes (clipped to the grid), the box being dragged and the paste
/// being placed, as outlines.
pub fn paint(
    painter: &egui::Painter,
    view: &ViewCamera,
    rect: egui::Rect,
    selection: Option<&Selection>,
    dims: IVec3,
    dragged: Option<(IVec3, IVec3, DragKind)>,
    paste: Option<(IVec3, IVec3)>,
) {
    let added = egui::Color32::from_rgb(255, 210, 60);
    let taken = egui::Color32::from_rgb(255, 70, 60);
    let outline = |lo: IVec3, hi: IVec3, colour, width| {
        let (lo, hi) = (lo.max(IVec3::ZERO), hi.min(dims - 1));
        if lo.cmple(hi).all() {
            let stroke = egui::Stroke::new(width, colour);
            super::preview::paint_box(
                painter,
                view,
                rect,
                lo.as_dvec3(),
                hi.as_dvec3() + 1.0,
                stroke,
            );
        }
    };
    if let Some(s) = selection {
        // A set (a magic wand…) is outlined by its bounds.
        if s.region.base.is_some()
            && let Some((lo, hi)) = s.voxels.bounds()
        {
            outline(lo, hi, added, 1.5);
        }
        for b in &s.region.boxes {
            outline(b.min, b.max, if b.subtract { taken } else { added }, 1.5);
        }
    }
    if let Some((lo, hi, kind)) = dragged {
        let colour = if kind == DragKind::Subtract {
            taken
        } else {
            added
        };
        outline(lo, hi, colour, 2.5);
    }
    if let Some((at, size)) = paste {
        outline(
            at,
            at + size - 1,
            egui::Color32::from_rgb(90, 220, 255),
            2.0,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_drag_box_goes_depth_voxels_into_the_surface() {
        let top = Layer { axis: 1, layer: 20 };
        let (a, b) = (IVec3::new(5, 20, 9), IVec3::new(2, 20, 14));
        // A top face: its normal is +y, so inward is −y.
        assert_eq!(
            drag_box(a, b, top, -1, 4),
            (IVec3::new(2, 17, 9), IVec3::new(5, 20, 14))
        );
        // A face seen from below (normal −y): into the voxels is +y.
        assert_eq!(
            drag_box(a, b, top, 1, 4),
            (IVec3::new(2, 20, 9), IVec3::new(5, 23, 14))
        );
        assert_eq!(
            drag_box(a, a, top, -1, 0),
            (a, a),
            "at least one voxel deep"
        );
    }

    #[test]
    fn nudges_follow_the_camera() {
        // Looking along −z: right is +x, away is −z.
        let f = DVec3::new(0.1, -0.5, -1.0);
        assert_eq!(nudge_offset(Nudge::Right, f), IVec3::X);
        assert_eq!(nudge_offset(Nudge::Left, f), IVec3::NEG_X);
        assert_eq!(nudge_offset(Nudge::Away, f), IVec3::NEG_Z);
        assert_eq!(nudge_offset(Nudge::Towards, f), IVec3::Z);
        // Looking along +x: right is +z.
        let f = DVec3::new(1.0, 0.2, 0.3);
        assert_eq!(nudge_offset(Nudge::Right, f), IVec3::Z);
        assert_eq!(nudge_offset(Nudge::Away, f), IVec3::X);
        assert_eq!(nudge_offset(Nudge::Up, f), IVec3::Y);
        // Straight down still gives horizontal steps.
        assert_eq!(nudge_offset(Nudge::Away, DVec3::NEG_Y), IVec3::NEG_Z);
    }

    #[test]
    fn a_paste_sits_on_the_cursor_voxel_centred() {
        assert_eq!(
            paste_at(IVec3::new(50, 10, 50), IVec3::new(9, 4, 10)),
            IVec3::new(46, 10, 45)
        );
    }
}
