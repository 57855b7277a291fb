//! The pointer and the gesture it is making: the modifier keys held, the cursor, a camera
//! drag, a stroke being drawn, a selection box being dragged, a paste following the cursor,
//! picked objects being dragged or a box select of objects (arrange mode).
//! `handle.rs` and `selecting.rs` change it; the frame reads it (the paste preview, whether a
//! stroke is drawn); replacing the document ends every gesture.

use super::input::{Drag, Mods};
use super::selecting::SelectDrag;
use super::tools;

/// A stroke being drawn: the layer it keeps to, its first and its last voxel sent, and every
/// voxel sent (a gradient's preview shows the whole drag).
pub(super) struct Drawing {
    pub(super) layer: tools::Layer,
    pub(super) first: glam::IVec3,
    pub(super) last: glam::IVec3,
    pub(super) points: Vec<glam::IVec3>,
}

/// Picked objects being dragged (arrange mode) over the horizontal plane at height `y`
/// through the voxel the press hit: where the drag started on it, and the whole voxels moved
/// so far (applied as one move at the release).
pub(super) struct MoveDrag {
    pub(super) y: f64,
    pub(super) start: glam::DVec3,
    pub(super) by: glam::IVec3,
}

/// What the pointer is doing.
#[derive(Default)]
pub(super) struct Pointer {
    /// Modifier keys held.
    pub(super) mods: Mods,
    /// Where the cursor is, in window pixels.
    pub(super) cursor: (f64, f64),
    /// A camera drag and where it was last.
    pub(super) drag: Option<(Drag, (f64, f64))>,
    /// The stroke being drawn with the left button.
    pub(super) drawing: Option<Drawing>,
    /// A brush press on nothing (the sky), still held: the stroke begins where the
    /// cursor's path first meets the scene.
    pub(super) sky_held: bool,
    /// The selection box being dragged.
    pub(super) selecting: Option<SelectDrag>,
    /// A paste follows the cursor until a click.
    pub(super) pasting: bool,
    /// Picked objects being dragged.
    pub(super) moving: Option<MoveDrag>,
    /// A box select of objects (arrange mode): where it started, in window pixels.
    pub(super) boxing: Option<(f64, f64)>,
    /// The ruler's ends (the Measure tool).
    pub(super) ruler: super::measure::Ruler,
    /// A face being extruded (the Extrude tool).
    pub(super) extruding: Option<super::extruding::ExtrudeDrag>,
    /// A stamp drag (the Stamp tool).
    pub(super) stamping: Option<super::stamping::StampDrag>,
    /// A screen rectangle being dragged (the selection tool).
    pub(super) rect_selecting: Option<super::rect_selecting::RectDrag>,
}

impl Pointer {
    /// Ends a paste and a selection drag (Escape, or a new document); whether one was on.
    pub(super) fn cancel_placing(&mut self) -> bool {
        let was = self.pasting
            || self.selecting.is_some()
            || self.moving.is_some()
            || self.boxing.is_some()
            || self.ruler.a.is_some()
            || self.extruding.is_some()
            || self.stamping.is_some()
            || self.rect_selecting.is_some();
        self.pasting = false;
        self.selecting = None;
        self.moving = None;
        self.boxing = None;
        self.ruler = Default::default();
        self.extruding = None;
        self.stamping = None;
        self.rect_selecting = None;
        was
    }

    /// Whether a stroke is being drawn (the frame draws at the moving scale then).
    pub(super) fn is_drawing(&self) -> bool {
        self.drawing.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cancelling_ends_a_paste_and_a_selection_drag_and_says_so() {
        let mut p = Pointer::default();
        assert!(!p.cancel_placing());
        p.pasting = true;
        assert!(p.cancel_placing());
        assert!(!p.pasting && !p.cancel_placing());
    }
}
