//! The brush preview: exactly the voxels a click would change (`command::preview`), drawn
//! translucent over the viewport as the outer faces of that set that face the camera. It is
//! recomputed only when the stroke it previews or the document changes (not every frame),
//! on its own thread (a radius-64 brush takes ~50 ms: the UI keeps drawing the previous
//! preview meanwhile; a small brush's arrives by the next frame), and drawn each frame from
//! the kept faces. A brush too large to examine voxel by voxel shows its bounding box.
//!
//! In detail:
//! the brush preview: `command::preview` (exactly the voxels a click changes, tested against
//! the click; computed a brick at a time from the shape's coverage and mask and the brick's
//! voxels) recomputed on its own thread only when the stroke or the document revision changes
//! (the UI draws the latest one meanwhile: a radius-64 brush takes ~50 ms); its outer faces
//! that face the camera drawn translucent under the panels; a brush over 4 M examined voxels
//! shows its bounding box. Also the empty scene's bounds and floor lines (`paint_floor`); every
//! overlay projects into the viewport's rectangle, as picking does. A box being dragged (a box
//! stroke, a selection box) says its size beside the cursor (`paint_box_size`). While a stroke
//! keeps to a layer (attach without "follow the surface", boxes) that layer's plane is outlined
//! across the grid (`paint_layer`); a paste being placed shows the clipboard's voxels
//! (`set_paste` / `paint_paste`, faces computed once per clip up to 200 000 voxels).

use super::camera::ViewCamera;
use super::files::SharedDocument;
use crate::editor::command::{BrushMode, Stroke, preview_bricks, stroke_edits};
use crate::selection::Selection;
use brickmap::EditOp;
use brickmap::Mask;
use brickmap::brick::voxel_bit;
use crossbeam_channel::{Receiver, Sender};
use glam::{DVec3, IVec3};
use std::collections::HashMap;
use std::sync::Arc;

/// What is previewed: the stroke and the document revision it was computed for.
type Key = (Stroke, u64);

/// A computed preview.
#[derive(Default)]
struct Shown {
    /// Outer faces of the voxel set: corners and outward normal.
    faces: Vec<([DVec3; 4], IVec3)>,
    /// The brush's bounding box when the set was too large to examine.
    bounds: Option<(DVec3, DVec3)>,
    mode: Option<BrushMode>,
}

/// Outer faces of a voxel set: corners and outward normal.
type Faces = Vec<([DVec3; 4], IVec3)>;

/// The largest clipboard whose voxels a paste shows (larger: its box only).
const PASTE_PREVIEW_VOXELS: u64 = 200_000;

/// The kept preview and its thread.
pub struct Preview {
    /// The clipboard's outer faces turned and with its minimum corner at the origin, for the
    /// paste or stamps being placed (the clip they are of, by address, and the turn;
    /// computed once per clip and turn).
    paste: Option<((usize, i32), Faces)>,
    /// A set selection's outer faces (the set they are of, by address).
    selection: Option<(usize, Faces)>,
    requests: Option<Sender<(SharedDocument, Key)>>,
    results: Receiver<(Key, Shown)>,
    /// The latest stroke asked for (None: nothing to show).
    wanted: Option<Key>,
    /// The one computed for, and shown.
    shown: Option<(Key, Shown)>,
}

impl Preview {
    /// Starts the preview thread; `wake` redraws the editor when a preview is ready.
    pub fn new(wake: Arc<dyn Fn() + Send + Sync>) -> Self {
        let (requests, rx) = crossbeam_channel::unbounded::<(SharedDocument, Key)>();
        let (tx, results) = crossbeam_channel::unbounded();
        std::thread::Builder::new()
            .name("voxbrick-preview".into())
            .spawn(move || {
                while let Ok(mut job) = rx.recv() {
                    // Only the latest request matters.
                    while let Ok(newer) = rx.try_recv() {
                        job = newer;
                    }
                    let (doc, key) = job;
                    let shown = {
                        let d = doc.read().unwrap_or_else(|p| p.into_inner());
                        let view = d.scene.world.read();
                        compute(&view, &key.0, d.scene.selection.as_ref())
                    };
                    if tx.send((key, shown)).is_err() {
                        break;
                    }
                    wake();
                }
            })
            .expect("spawning the preview thread");
        Self {
            paste: None,
            selection: None,
            requests: Some(requests),
            results,
            wanted: None,
            shown: None,
        }
    }

    /// Shows `stroke` (None: nothing) of `doc` at revision `revision`: asks the thread when
    /// either changed, and keeps what it last computed.
    pub fn update(&mut self, doc: &SharedDocument, stroke: Option<&Stroke>, revision: u64) {
        while let Ok(done) = self.results.try_recv() {
            self.shown = Some(done);
        }
        let Some(stroke) = stroke else {
            self.wanted = None;
            return;
        };
        let key = (stroke.clone(), revision);
        if self.wanted.as_ref() != Some(&key) {
            if let Some(r) = &self.requests {
                let _ = r.send((doc.clone(), key.clone()));
            }
            self.wanted = Some(key);
        }
    }

    /// Keeps the clipboard's faces, turned `quarters` times about the vertical, for the
    /// paste or stamp preview (recomputed only for another clip or turn; none for a clip over
    /// [`PASTE_PREVIEW_VOXELS`]).
    pub fn set_paste(&mut self, clip: Option<&Arc<crate::selection::Clip>>, quarters: i32) {
        let Some(clip) = clip.filter(|c| c.voxels <= PASTE_PREVIEW_VOXELS) else {
            self.paste = None;
            return;
        };
        let key = (Arc::as_ptr(clip) as usize, quarters);
        if self.paste.as_ref().is_none_or(|(k, _)| *k != key) {
            let rot =
                brickmap::objects::Orientation::quarter_turn(brickmap::objects::Axis::Y, quarters);
            let size = crate::editor::stamp::turned_size(clip.size, quarters);
            let mut set = brickmap::VoxelSet::new();
            for (p, _) in clip.solid_voxels() {
                set.insert(crate::editor::stamp::turned(&rot, p, clip.size, size));
            }
            let bricks: Vec<(IVec3, Mask)> = set.iter().map(|(b, m)| (b.as_ivec3(), *m)).collect();
            self.paste = Some((key, outer_faces(&bricks)));
        }
    }

    /// Keeps the outer faces of a selection made as a set (a wand, a rectangle: its boxes do
    /// not say what it holds), recomputed only for another set; none over
    /// [`PASTE_PREVIEW_VOXELS`] voxels (its bounds are outlined instead).
    pub fn set_selection(&mut self, selection: Option<&Selection>) {
        let Some(s) = selection.filter(|s| s.region.base.is_some()) else {
            self.selection = None;
            return;
        };
        // Counted and faced once per set (a frame must not walk a large set's bricks); a set
        // too large keeps no faces.
        let id = Arc::as_ptr(&s.voxels) as usize;
        if self.selection.as_ref().is_none_or(|(k, _)| *k != id) {
            let faces = if s.voxels.count() <= PASTE_PREVIEW_VOXELS {
                let bricks: Vec<(IVec3, Mask)> =
                    s.voxels.iter().map(|(b, m)| (b.as_ivec3(), *m)).collect();
                outer_faces(&bricks)
            } else {
                Vec::new()
            };
            self.selection = Some((id, faces));
        }
    }

    /// How many faces the selection's tint has (0: none kept).
    pub fn selection_faces(&self) -> usize {
        self.selection.as_ref().map_or(0, |(_, f)| f.len())
    }

    /// Paints the kept selection's voxels, translucent.
    pub fn paint_selection(&self, painter: &egui::Painter, view: &ViewCamera, rect: egui::Rect) {
        if let Some((_, faces)) = &self.selection {
            let colour = egui::Color32::from_rgba_unmultiplied(255, 210, 60, 45);
            paint_faces(painter, view, rect, faces, DVec3::ZERO, colour);
        }
    }

    /// How many faces the paste preview has (0: none kept).
    pub fn paste_faces(&self) -> usize {
        self.paste.as_ref().map_or(0, |(_, f)| f.len())
    }

    /// Paints the kept clipboard's voxels where a paste (or a stamp) at `at` puts them,
    /// translucent.
    pub fn paint_paste(
        &self,
        painter: &egui::Painter,
        view: &ViewCamera,
        rect: egui::Rect,
        at: IVec3,
    ) {
        if let Some((_, faces)) = &self.paste {
            let colour = egui::Color32::from_rgba_unmultiplied(255, 210, 60, 70);
            paint_faces(painter, view, rect, faces, at.as_dvec3(), colour);
        }
    }

    /// Paints the preview for the view's camera into `rect` (the viewport, in points): the
    /// latest computed one, while a stroke is wanted.
    pub fn paint(&self, painter: &egui::Painter, view: &ViewCamera, rect: egui::Rect) {
        let (Some(_), Some((_, shown))) = (&self.wanted, &self.shown) else {
            return;
        };
        let Some(mode) = shown.mode else { return };
        let colour = match mode {
            BrushMode::Attach => egui::Color32::from_rgba_unmultiplied(255, 255, 255, 70),
            BrushMode::Erase => egui::Color32::from_rgba_unmultiplied(255, 60, 40, 90),
            BrushMode::Paint => egui::Color32::from_rgba_unmultiplied(80, 200, 255, 80),
        };
        paint_faces(painter, view, rect, &shown.faces, DVec3::ZERO, colour);
        if let Some((lo, hi)) = shown.bounds {
            let stroke = egui::Stroke::new(1.5, colour.to_opaque());
            paint_box(painter, view, rect, lo, hi, stroke);
        }
    }
}

/// Paints the faces turned towards the camera, moved by `offset`, translucent.
fn paint_faces(
    painter: &egui::Painter,
    view: &ViewCamera,
    rect: egui::Rect,
    faces: &Faces,
    offset: DVec3,
    colour: egui::Color32,
) {
    let to_screen = |p: DVec3| screen_point(view, rect, p);
    let eye = view.camera.position;
    let forward = view.camera.forward();
    let mut mesh = egui::Mesh::default();
    for (corners, normal) in faces {
        let centre = (corners[0] + corners[2]) * 0.5 + offset;
        let towards = if view.camera.is_orthographic() {
            forward
        } else {
            centre - eye
        };
        if towards.dot(normal.as_dvec3()) >= 0.0 {
            continue;
        }
        let Some(pts) = corners
            .iter()
            .map(|c| to_screen(*c + offset))
            .collect::<Option<Vec<_>>>()
        else {
            continue;
        };
        let base = mesh.vertices.len() as u32;
        for p in pts {
            mesh.colored_vertex(p, colour);
        }
        mesh.add_triangle(base, base + 1, base + 2);
        mesh.add_triangle(base, base + 2, base + 3);
    }
    if !mesh.is_empty() {
        painter.add(egui::Shape::mesh(mesh));
    }
}

/// Draws the twelve edges of the box `lo..hi` (world corners).
pub fn paint_box(
    painter: &egui::Painter,
    view: &ViewCamera,
    rect: egui::Rect,
    lo: DVec3,
    hi: DVec3,
    stroke: egui::Stroke,
) {
    let corner = |i: usize| box_corner(lo, hi, i);
    for a in 0..8usize {
        for bit in [1, 2, 4] {
            let b = a | bit;
            if b != a
                && let (Some(p), Some(q)) = (
                    screen_point(view, rect, corner(a)),
                    screen_point(view, rect, corner(b)),
                )
            {
                painter.line_segment([p, q], stroke);
            }
        }
    }
}

/// Corner `i` (0..8: bit 0 picks x, bit 1 y, bit 2 z from `hi`, else from `lo`) of a box.
pub fn box_corner(lo: DVec3, hi: DVec3, i: usize) -> DVec3 {
    DVec3::new(
        if i & 1 == 0 { lo.x } else { hi.x },
        if i & 2 == 0 { lo.y } else { hi.y },
        if i & 4 == 0 { lo.z } else { hi.z },
    )
}

/// Where a world point appears in `rect` (the viewport, in points), if in front.
pub fn screen_point(view: &ViewCamera, rect: egui::Rect, p: DVec3) -> Option<egui::Pos2> {
    let aspect = (rect.width() / rect.height().max(1.0)) as f64;
    view.project(p, aspect).map(|(u, v)| {
        egui::pos2(
            rect.left() + (u as f32 + 1.0) * 0.5 * rect.width(),
            rect.top() + (1.0 - v as f32) * 0.5 * rect.height(),
        )
    })
}

/// An empty scene's bounds and floor: the grid's box, and lines on the floor every 8 voxels
/// (every 32 in a large grid), so there is something to aim at; a click on the floor
/// attaches there.
pub fn paint_floor(painter: &egui::Painter, view: &ViewCamera, rect: egui::Rect, dims: IVec3) {
    let size = dims.as_dvec3();
    let edge = egui::Stroke::new(
        1.0,
        egui::Color32::from_rgba_unmultiplied(220, 220, 220, 140),
    );
    paint_box(painter, view, rect, DVec3::ZERO, size, edge);
    let line = egui::Stroke::new(
        1.0,
        egui::Color32::from_rgba_unmultiplied(200, 200, 200, 70),
    );
    let step = if dims.x.max(dims.z) > 256 { 32 } else { 8 };
    let segment = |a: DVec3, b: DVec3| {
        if let (Some(p), Some(q)) = (screen_point(view, rect, a), screen_point(view, rect, b)) {
            painter.line_segment([p, q], line);
        }
    };
    for x in (step..dims.x).step_by(step as usize) {
        let x = f64::from(x);
        segment(DVec3::new(x, 0.0, 0.0), DVec3::new(x, 0.0, size.z));
    }
    for z in (step..dims.z).step_by(step as usize) {
        let z = f64::from(z);
        segment(DVec3::new(0.0, 0.0, z), DVec3::new(size.x, 0.0, z));
    }
}

/// The layer a stroke keeps to, while it is drawn: the plane through its voxels' middles,
/// outlined across the grid (attach strokes that keep to the first face, and boxes, whose
/// first and last points span a box on it).
pub fn paint_layer(
    painter: &egui::Painter,
    view: &ViewCamera,
    rect: egui::Rect,
    layer: super::tools::Layer,
    dims: IVec3,
) {
    let stroke = egui::Stroke::new(
        1.5,
        egui::Color32::from_rgba_unmultiplied(255, 255, 255, 150),
    );
    let at = f64::from(layer.layer) + 0.5;
    paint_plane(painter, view, rect, (layer.axis, at), dims, stroke);
}

/// The size of a box being dragged (a box stroke, a selection box), in voxels along x, y
/// and z, written beside the cursor: what the drag will make before the release.
pub fn paint_box_size(painter: &egui::Painter, cursor: egui::Pos2, (lo, hi): (IVec3, IVec3)) {
    paint_label(
        painter,
        cursor + egui::vec2(16.0, 12.0),
        box_size_text(lo, hi),
        false,
    );
}

/// White text on a dark plate with its top-left corner at `at` (with `above`, its
/// bottom-left): what a drag or the ruler says in the viewport.
pub fn paint_label(painter: &egui::Painter, at: egui::Pos2, text: String, above: bool) {
    let font = egui::FontId::proportional(13.0);
    let galley = painter.layout_no_wrap(text, font, egui::Color32::WHITE);
    let at = if above {
        at - egui::vec2(0.0, galley.size().y)
    } else {
        at
    };
    let back = egui::Rect::from_min_size(at, galley.size()).expand(3.0);
    painter.rect_filled(back, 3.0, egui::Color32::from_black_alpha(170));
    painter.galley(at, galley, egui::Color32::WHITE);
}

/// "w × h × d voxels" of the box from `lo` to `hi` (inclusive).
pub fn box_size_text(lo: IVec3, hi: IVec3) -> String {
    let n = (hi - lo).abs() + IVec3::ONE;
    format!("{} × {} × {} voxels", n.x, n.y, n.z)
}

/// Draws the enabled mirror planes as their outlines across the grid (x red, y green,
/// z blue).
pub fn paint_mirror(
    painter: &egui::Painter,
    view: &ViewCamera,
    rect: egui::Rect,
    mirror: [bool; 3],
    centre: DVec3,
    dims: IVec3,
) {
    let colours = [
        egui::Color32::from_rgba_unmultiplied(255, 80, 80, 160),
        egui::Color32::from_rgba_unmultiplied(80, 255, 80, 160),
        egui::Color32::from_rgba_unmultiplied(80, 140, 255, 160),
    ];
    for axis in (0..3).filter(|&a| mirror[a]) {
        let stroke = egui::Stroke::new(1.5, colours[axis]);
        paint_plane(painter, view, rect, (axis, centre[axis]), dims, stroke);
    }
}

/// The outline across the grid of the plane where coordinate `axis` is `at`.
fn paint_plane(
    painter: &egui::Painter,
    view: &ViewCamera,
    rect: egui::Rect,
    (axis, at): (usize, f64),
    dims: IVec3,
    stroke: egui::Stroke,
) {
    let size = dims.as_dvec3();
    let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
    let corner = |cu: bool, cw: bool| {
        let mut p = DVec3::ZERO;
        p[axis] = at;
        p[u] = if cu { size[u] } else { 0.0 };
        p[w] = if cw { size[w] } else { 0.0 };
        p
    };
    let ring = [
        corner(false, false),
        corner(true, false),
        corner(true, true),
        corner(false, true),
    ];
    for k in 0..4 {
        if let (Some(a), Some(b)) = (
            screen_point(view, rect, ring[k]),
            screen_point(view, rect, ring[(k + 1) % 4]),
        ) {
            painter.line_segment([a, b], stroke);
        }
    }
}

impl Drop for Preview {
    fn drop(&mut self) {
        // The thread ends when its request channel closes.
        self.requests = None;
    }
}

/// The preview of `stroke` in the world as it is.
fn compute(
    view: &brickmap::WorldView<'_>,
    stroke: &Stroke,
    selection: Option<&Selection>,
) -> Shown {
    let mut shown = Shown {
        mode: Some(stroke.mode),
        ..Default::default()
    };
    match preview_bricks(view, stroke, selection) {
        Ok(Some(bricks)) => shown.faces = outer_faces(&bricks),
        Ok(None) => shown.bounds = bounds(view, stroke, selection),
        Err(_) => shown.mode = None,
    }
    shown
}

/// The faces between the set (brick coordinates and masks) and the rest, each with its
/// outward normal: a neighbour inside the brick is a bit of its mask, one across a brick
/// face a bit of that neighbour's (looked up once per brick and side).
fn outer_faces(bricks: &[(IVec3, Mask)]) -> Vec<([DVec3; 4], IVec3)> {
    let by: HashMap<IVec3, &Mask> = bricks.iter().map(|(b, m)| (*b, m)).collect();
    let mut faces = Vec::new();
    for (b, mask) in bricks {
        let mut sides = [IVec3::ZERO; 6];
        let mut next: [Option<&Mask>; 6] = [None; 6];
        for (k, side) in sides.iter_mut().enumerate() {
            side[k / 2] = if k % 2 == 0 { -1 } else { 1 };
            next[k] = by.get(&(*b + *side)).copied();
        }
        for bit in mask.ones() {
            let l = IVec3::new(bit as i32 % 8, bit as i32 / 8 % 8, bit as i32 / 64);
            for (k, n) in sides.iter().enumerate() {
                let q = l + *n;
                let inside = if q.cmpge(IVec3::ZERO).all() && q.cmplt(IVec3::splat(8)).all() {
                    mask.get(voxel_bit(q.x, q.y, q.z))
                } else {
                    let w = q.rem_euclid(IVec3::splat(8));
                    next[k].is_some_and(|m| m.get(voxel_bit(w.x, w.y, w.z)))
                };
                if inside {
                    continue;
                }
                // The face's four corners, in order around it.
                let (axis, sign) = (k / 2, n[k / 2]);
                let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
                let mut base = (*b * 8 + l).as_dvec3();
                if sign > 0 {
                    base[axis] += 1.0;
                }
                let mut du = DVec3::ZERO;
                du[u] = 1.0;
                let mut dw = DVec3::ZERO;
                dw[w] = 1.0;
                faces.push(([base, base + du, base + du + dw, base + dw], *n));
            }
        }
    }
    faces
}

/// The union of the stroke's shapes' voxel bounds, as a box of voxel corners.
fn bounds(
    view: &brickmap::WorldView<'_>,
    stroke: &Stroke,
    selection: Option<&Selection>,
) -> Option<(DVec3, DVec3)> {
    let mut lo = IVec3::MAX;
    let mut hi = IVec3::MIN;
    for edit in stroke_edits(stroke, selection, view, None).ok()? {
        if let EditOp::Shape { shape, .. } = edit {
            let (a, b) = shape.voxel_bounds();
            lo = lo.min(a);
            hi = hi.max(b);
        }
    }
    (lo.cmple(hi).all()).then(|| (lo.as_dvec3(), hi.as_dvec3() + 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dragged_box_says_its_size_whichever_way_it_was_dragged() {
        let (a, b) = (IVec3::new(10, 4, 7), IVec3::new(3, 4, 9));
        assert_eq!(box_size_text(a.min(b), a.max(b)), "8 × 1 × 3 voxels");
        assert_eq!(box_size_text(a, b), "8 × 1 × 3 voxels");
        assert_eq!(box_size_text(a, a), "1 × 1 × 1 voxels");
    }

    #[test]
    fn one_voxel_has_six_outer_faces_and_two_touching_have_ten() {
        let set = |voxels: &[IVec3]| {
            let mut by: std::collections::BTreeMap<(i32, i32, i32), Mask> = Default::default();
            for v in voxels {
                let b = v.div_euclid(IVec3::splat(8));
                let l = v.rem_euclid(IVec3::splat(8));
                by.entry((b.x, b.y, b.z))
                    .or_default()
                    .set(voxel_bit(l.x, l.y, l.z));
            }
            by.into_iter()
                .map(|((x, y, z), m)| (IVec3::new(x, y, z), m))
                .collect::<Vec<_>>()
        };
        let one = outer_faces(&set(&[IVec3::ZERO]));
        assert_eq!(one.len(), 6);
        // Each face lies on its side of the voxel, its corners one unit apart.
        for (c, n) in &one {
            let centre = (c[0] + c[2]) * 0.5;
            assert_eq!(centre - DVec3::splat(0.5), n.as_dvec3() * 0.5);
            assert!(((c[1] - c[0]).length() - 1.0).abs() < 1e-12);
        }
        assert_eq!(outer_faces(&set(&[IVec3::ZERO, IVec3::X])).len(), 10);
        // Across a brick face: (7, 3, 3) and (8, 3, 3) touch, as do (5, -1, 2) and (5, 0, 2).
        let pair = [IVec3::new(7, 3, 3), IVec3::new(8, 3, 3)];
        assert_eq!(outer_faces(&set(&pair)).len(), 10);
        let pair = [IVec3::new(5, -1, 2), IVec3::new(5, 0, 2)];
        assert_eq!(outer_faces(&set(&pair)).len(), 10);
        // A 3 × 3 × 3 block over a brick corner: 6 × 9 faces.
        let block: Vec<IVec3> = (0..27)
            .map(|i| IVec3::new(i % 3 + 7, i / 3 % 3 + 7, i / 9 + 7))
            .collect();
        assert_eq!(outer_faces(&set(&block)).len(), 54);
    }
}
