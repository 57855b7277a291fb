//! The ruler (the Measure tool, K): a click on a voxel sets one end, the next click the
//! other; until then the other end follows the voxel under the cursor. The viewport draws the
//! line between the two voxels' centres with the distance along each axis and in all, and the
//! status line says the same; a third click starts a new measurement, Esc or another tool
//! ends it. A view aid: nothing in the scene or the history changes.

use super::Editor;
use super::camera::ViewCamera;
use super::tools;
use glam::{DVec3, IVec3};

/// The ends set so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Ruler {
    /// The first end.
    pub a: Option<IVec3>,
    /// The second end (none: the hovered voxel stands in).
    pub b: Option<IVec3>,
}

impl Ruler {
    /// A click on voxel `v`: the second end after the first, else a new first end.
    pub fn click(&mut self, v: IVec3) {
        match (self.a, self.b) {
            (Some(_), None) => self.b = Some(v),
            _ => {
                *self = Self {
                    a: Some(v),
                    b: None,
                }
            }
        }
    }

    /// The two ends to show: the first and the second, or the hovered voxel.
    pub fn ends(&self, hovered: Option<IVec3>) -> Option<(IVec3, IVec3)> {
        Some((self.a?, self.b.or(hovered)?))
    }
}

/// "Δ x · y · z voxels, d in all" between the centres of `a` and `b`.
pub fn text(a: IVec3, b: IVec3) -> String {
    let d = (b - a).abs();
    format!(
        "Δ {} · {} · {} voxels, {:.2} in all",
        d.x,
        d.y,
        d.z,
        (b - a).as_dvec3().length()
    )
}

/// Draws the ruler from `a` to `b` with its text at the middle.
pub fn paint(painter: &egui::Painter, view: &ViewCamera, rect: egui::Rect, (a, b): (IVec3, IVec3)) {
    let colour = egui::Color32::from_rgb(255, 210, 80);
    let centre = |v: IVec3| v.as_dvec3() + DVec3::splat(0.5);
    let (Some(p), Some(q)) = (
        super::preview::screen_point(view, rect, centre(a)),
        super::preview::screen_point(view, rect, centre(b)),
    ) else {
        return;
    };
    painter.line_segment([p, q], egui::Stroke::new(2.0, colour));
    for end in [p, q] {
        painter.circle_filled(end, 3.5, colour);
    }
    super::preview::paint_label(
        painter,
        p.lerp(q, 0.5) + egui::vec2(8.0, -8.0),
        text(a, b),
        true,
    );
}

/// "voxel [x, y, z] +y face" for a hit.
pub fn hover_text(voxel: IVec3, normal: IVec3) -> String {
    let face = match normal.to_array() {
        [1, 0, 0] => "+x",
        [-1, 0, 0] => "−x",
        [0, 1, 0] => "+y",
        [0, -1, 0] => "−y",
        [0, 0, 1] => "+z",
        _ => "−z",
    };
    format!("voxel [{}, {}, {}] {face} face", voxel.x, voxel.y, voxel.z)
}

impl Editor {
    /// The voxel under the cursor and the face the cursor is on (none off the viewport or
    /// over nothing).
    pub(super) fn hovered(&self) -> Option<(IVec3, IVec3)> {
        let (x, y, w, h) = self.viewing.area();
        let (cx, cy) = self.controls.pointer.cursor;
        if cx < x as f64 || cy < y as f64 || cx >= (x + w) as f64 || cy >= (y + h) as f64 {
            return None;
        }
        let (origin, dir) = self.cursor_ray();
        let doc = self.read();
        let view = doc.scene.world.read();
        tools::pick(&view, origin, dir).map(|(hit, _)| (hit.voxel, hit.normal))
    }

    /// A click with the Measure tool.
    pub(super) fn measure_press(&mut self) {
        if let Some((v, _)) = self.hovered() {
            self.controls.pointer.ruler.click(v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_clicks_measure_and_a_third_starts_again() {
        let mut r = Ruler::default();
        assert_eq!(r.ends(Some(IVec3::ONE)), None, "no end yet");
        r.click(IVec3::new(1, 2, 3));
        let hovered = IVec3::new(4, 6, 3);
        assert_eq!(r.ends(Some(hovered)), Some((IVec3::new(1, 2, 3), hovered)));
        r.click(IVec3::new(13, 2, 8));
        assert_eq!(
            r.ends(Some(hovered)),
            Some((IVec3::new(1, 2, 3), IVec3::new(13, 2, 8))),
            "the second end stays"
        );
        assert_eq!(
            text(IVec3::new(1, 2, 3), IVec3::new(13, 2, 8)),
            "Δ 12 · 0 · 5 voxels, 13.00 in all"
        );
        r.click(IVec3::ZERO);
        assert_eq!(r.ends(None), None, "a new first end waits for its second");
        assert_eq!(
            hover_text(IVec3::new(1, 2, 3), IVec3::NEG_Y),
            "voxel [1, 2, 3] −y face"
        );
    }
}
