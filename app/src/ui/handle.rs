//! Input → the editor: each [`Input`] (from the window's events, or from a headless driver)
//! passes the frame gate or waits in the backlog, in order; egui's share is left to egui;
//! keys go through the key map (Esc cancels what is being dragged), buttons start strokes,
//! selections, pastes, the eyedropper, flood fills or view drags, moves extend them, the
//! wheel zooms to the cursor, held movement keys fly.
//!
//! In detail:
//! input → the editor: the frame gate and backlog (order kept), keys through the key map (Esc
//! cancels a drag), buttons start strokes / selections / pastes / eyedropper / flood fill /
//! view drags, moves extend them, wheel zoom, fly. A press or wheel step is the UI's or the
//! viewport's by its own position against the layers of the last frame drawn (`on_ui`: a
//! window, the bars, the docks, or any open popup), never by egui's pointer state, which is a
//! frame behind (a press right after leaving a window was lost; a drag from a slider edited the
//! scene). Fly keys move by elapsed time up to the release (no per-frame clamp; a headless
//! editor steps 1/60 s per tick unless `fly_in_real_time`).

use super::Editor;
use super::event::Input;
use super::input::{self, Action, Drag};
use super::jobs::Edit;
use super::pending::Pending;
use super::tools::{self, Tool};
use crate::editor::command::{Command, PaintMode};
use std::time::Instant;
use winit::event::MouseButton;
use winit::keyboard::KeyCode;

impl Editor {
    /// One input, with whether egui kept it: handled now, or after the edit that holds the
    /// frame gate (the backlog keeps the order); reported once handled.
    pub(super) fn input_with(&mut self, input: Input, consumed: bool) {
        if !input.gated() {
            self.handle_logged(input, consumed);
            return;
        }
        let gate = self.docs.edits.gate.clone();
        let Ok(_between_frames) = gate.try_lock() else {
            self.controls.defer(input, consumed);
            return;
        };
        for (earlier, c) in self.controls.take_backlog() {
            self.handle_logged(earlier, c);
        }
        self.handle_logged(input, consumed);
    }

    /// An input, the frame gate held (or not needed: a resize), then its report line.
    pub(super) fn handle_logged(&mut self, input: Input, consumed: bool) {
        let line = self.report.on().then(|| input.report_line()).flatten();
        self.handle_input(input, consumed);
        self.screen.frames.awaited = true;
        if let Some(line) = line {
            self.report.line(format_args!("input {line}"));
        }
    }

    fn handle_input(&mut self, input: Input, consumed: bool) {
        if self.screen.gfx.is_none() {
            return;
        }
        let to_ui = match &input {
            Input::Moved { x, y } => self.on_ui((*x, *y)),
            Input::Button { .. } | Input::Wheel(_) => self.on_ui(self.controls.pointer.cursor),
            Input::Key { .. } => consumed || self.screen.egui.egui_wants_keyboard_input(),
            Input::Text(_) => true,
            _ => false,
        };
        if to_ui {
            self.controls.touch_ui(Instant::now());
        }
        match input {
            Input::Close => self.action(Action::Quit),
            Input::Resized(w, h) => {
                self.viewing.set_window((w, h));
                if let Some(gfx) = &mut self.screen.gfx {
                    gfx.presenter.resize((w, h));
                    gfx.host.request_redraw();
                }
            }
            Input::Dropped(path) => {
                if crate::formats::Format::of(&path).is_ok() {
                    self.guard_unsaved(Pending::Open(Some(path)));
                } else {
                    self.panels.errors.push(format!(
                        "{} is not a .ron, .vox, .qb or .schem file",
                        path.display()
                    ));
                }
            }
            Input::Modifiers(m) => self.controls.pointer.mods = m,
            // egui's alone.
            Input::Text(_) => {}
            Input::Key {
                code,
                pressed,
                repeat,
            } => self.key(code, pressed, repeat, consumed),
            // Pointer input is judged by where it happens against the UI as last drawn (what
            // the user saw), not by egui's idea of the pointer, which is a frame behind.
            Input::Button { button, pressed } => self.button(button, pressed),
            Input::Moved { x, y } => self.cursor_moved(x, y),
            Input::Wheel(steps) => {
                if self.on_ui(self.controls.pointer.cursor) {
                    return;
                }
                self.zoom(steps);
            }
        }
    }

    fn key(&mut self, code: KeyCode, pressed: bool, repeat: bool, consumed: bool) {
        if !pressed {
            if self.controls.flight.holds(code) {
                // The flight lasts until the release, not until the last frame before it.
                self.tick_fly();
                self.controls.flight.release(code);
            }
            return;
        }
        if consumed || self.screen.egui.egui_wants_keyboard_input() {
            return;
        }
        if code == KeyCode::Escape {
            self.controls.pointer.sky_held = false;
        }
        if code == KeyCode::Escape && self.controls.pointer.drawing.take().is_some() {
            self.docs.submit(Edit::StrokeAbort);
            return;
        }
        if code == KeyCode::Escape && self.controls.pointer.cancel_placing() {
            return;
        }
        if let Some(a) = self
            .controls
            .keymap
            .action(code, self.controls.pointer.mods)
        {
            if !repeat {
                self.action(a);
            }
        } else if !self.controls.pointer.mods.ctrl && input::fly_axis(code).is_some() {
            // Keys already held fly until now in their old direction.
            if self.controls.flight.is_flying() {
                self.tick_fly();
            }
            self.controls.flight.press(code);
            self.moved();
        }
    }

    /// Whether the window point `(x, y)` (pixels) is the UI's as the last frame drew it: a
    /// window, a menu bar or status line over it, or any point while a menu or another popup
    /// is open (a click then only closes it). A press there belongs to the UI until its
    /// release; the viewport never sees it.
    pub(super) fn on_ui(&self, at: (f64, f64)) -> bool {
        egui::Popup::is_any_open(&self.screen.egui) || self.covered(at)
    }

    /// Whether a panel, the bars or a window cover the window point `(x, y)` (pixels), as
    /// drawn in the last frame; outside the viewport's rectangle counts as covered.
    pub(super) fn covered(&self, (x, y): (f64, f64)) -> bool {
        let ppp = f64::from(self.screen.egui.pixels_per_point());
        let pos = egui::pos2((x / ppp) as f32, (y / ppp) as f32);
        let over_window = self
            .screen
            .egui
            .layer_id_at(pos)
            .is_some_and(|l| l.order != egui::Order::Background);
        over_window || !self.panels.viewport.is_some_and(|r| r.contains(pos))
    }

    fn button(&mut self, button: MouseButton, pressed: bool) {
        self.request_redraw();
        let free = !self.on_ui(self.controls.pointer.cursor);
        if !pressed && button == MouseButton::Left {
            self.controls.pointer.sky_held = false;
        }
        match (pressed, button) {
            (true, MouseButton::Left) if free => self.press(),
            (false, MouseButton::Left) if self.controls.pointer.drawing.is_some() => {
                // The release position was the last move's, already taken (taking it again
                // would dig an erase stroke deeper where the cursor stopped).
                if let Some(d) = &self.controls.pointer.drawing {
                    self.report.line(format_args!(
                        "stroke release {} {} voxel {} {} {}",
                        self.controls.pointer.cursor.0,
                        self.controls.pointer.cursor.1,
                        d.last.x,
                        d.last.y,
                        d.last.z
                    ));
                }
                self.controls.pointer.drawing = None;
                self.docs.submit(Edit::StrokeEnd);
                // The next random-paint stroke varies differently.
                if let PaintMode::Random { seed, .. } = &mut self.settings.brush.paint {
                    *seed = seed.wrapping_add(1);
                }
                // Back to the full internal size shortly after, as after a move.
                self.controls.motion.settling();
            }
            (false, MouseButton::Left) if self.controls.pointer.selecting.is_some() => {
                self.select_release()
            }
            (false, MouseButton::Left) if self.controls.pointer.extruding.is_some() => {
                self.extrude_release()
            }
            (false, MouseButton::Left) if self.controls.pointer.stamping.is_some() => {
                self.stamp_release()
            }
            (false, MouseButton::Left) if self.controls.pointer.rect_selecting.is_some() => {
                self.rect_select_release()
            }
            (false, MouseButton::Left)
                if self.controls.pointer.moving.is_some()
                    || self.controls.pointer.boxing.is_some() =>
            {
                self.arrange_release()
            }
            (true, _) if free => {
                self.controls.pointer.drag =
                    input::drag_for_button(button, self.controls.pointer.mods)
                        .map(|d| (d, self.controls.pointer.cursor));
            }
            (false, _) => self.controls.pointer.drag = None,
            _ => {}
        }
    }

    fn cursor_moved(&mut self, x: f64, y: f64) {
        let previous = self.controls.pointer.cursor;
        self.controls.pointer.cursor = (x, y);
        // The preview follows the cursor.
        self.request_redraw();
        if let Some((drag, _)) = self.controls.pointer.drag {
            let h = self.viewing.area().3.max(1) as f64;
            let (dx, dy) = (
                self.controls.pointer.cursor.0 - previous.0,
                self.controls.pointer.cursor.1 - previous.1,
            );
            match drag {
                Drag::Orbit => self.viewing.camera.orbit(-dx * 0.3, -dy * 0.3),
                Drag::Pan => {
                    let aspect = self.aspect();
                    self.viewing.camera.pan(dx / h, -dy / h, aspect)
                }
            }
            self.moved();
        }
        if self.controls.pointer.sky_held && self.controls.pointer.drawing.is_none() {
            self.stroke_from_sky(previous);
        } else {
            self.stroke_to_cursor();
        }
        self.select_to_cursor();
        self.arrange_to_cursor();
        self.extrude_to_cursor();
        self.stamp_to_cursor();
    }

    /// Left button down: a paste being placed goes down, the eyedropper (Alt), the selection
    /// tool, or a new stroke under the cursor.
    pub(super) fn press(&mut self) {
        if self.controls.pointer.pasting {
            self.paste_press();
            return;
        }
        if self.settings.brush.tool == Tool::Select && !self.controls.pointer.mods.alt {
            self.select_press();
            return;
        }
        if self.settings.brush.tool == Tool::Arrange && !self.controls.pointer.mods.alt {
            self.arrange_press();
            return;
        }
        if self.settings.brush.tool == Tool::Measure {
            self.measure_press();
            return;
        }
        if self.settings.brush.tool == Tool::Stamp && !self.controls.pointer.mods.alt {
            self.stamp_press();
            return;
        }
        if self.settings.brush.tool == Tool::Extrude && !self.controls.pointer.mods.alt {
            self.extrude_press();
            return;
        }
        let (origin, dir) = self.cursor_ray();
        let doc = self.docs.shared();
        let doc = doc.read().unwrap_or_else(|p| p.into_inner());
        let view = doc.scene.world.read();
        if self.controls.pointer.mods.alt {
            if let Some((_, material)) = tools::pick(&view, origin, dir) {
                self.settings.brush.material = material;
            }
            return;
        }
        if self.controls.pointer.mods.shift
            && self.settings.brush.mode == crate::editor::command::BrushMode::Paint
        {
            // Flood fill: the connected surface of the clicked voxel's material.
            if let Some((hit, _)) = tools::pick(&view, origin, dir) {
                let material = self.settings.brush.material;
                drop(view);
                drop(doc);
                self.execute(Command::FloodFill {
                    start: hit.voxel,
                    material,
                });
            }
            return;
        }
        if self.controls.pointer.mods.shift
            && self.settings.brush.mode == crate::editor::command::BrushMode::Attach
        {
            // Plane fill: the empty layer in front of the clicked face.
            if let Some((hit, _)) = tools::pick(&view, origin, dir) {
                let material = self.settings.brush.material;
                drop(view);
                drop(doc);
                self.execute(Command::PlaneFill {
                    voxel: hit.voxel,
                    normal: hit.normal,
                    material,
                });
            }
            return;
        }
        let brush = &self.settings.brush;
        let Some((v, layer)) = tools::start(&view, brush.mode, origin, dir) else {
            // On the sky: the stroke waits for the drag to reach the scene.
            self.controls.pointer.sky_held = true;
            return;
        };
        drop(view);
        drop(doc);
        self.begin_stroke(v, layer);
    }

    /// A stroke's first voxel `v` (in `layer`), at the cursor.
    fn begin_stroke(&mut self, v: glam::IVec3, layer: tools::Layer) {
        let dims = self.read().scene.world.dims().voxels();
        let stroke = self.settings.brush.stroke(vec![tools::centre(v)], dims);
        self.report.line(format_args!(
            "stroke begin {} {} voxel {} {} {}",
            self.controls.pointer.cursor.0, self.controls.pointer.cursor.1, v.x, v.y, v.z
        ));
        self.controls.pointer.drawing = Some(super::pointer::Drawing {
            layer,
            first: v,
            last: v,
            points: vec![v],
        });
        self.docs.submit(Edit::StrokeBegin(stroke));
    }

    /// A brush press held since it hit nothing: the cursor's path from `from` to where it is
    /// now, walked every [`PATH_STEP`] pixels; the stroke begins at the first point whose ray
    /// meets the scene and follows the rest of the path (so a fast drag off the sky draws
    /// from where it crossed onto the ground, not from where the next event landed).
    fn stroke_from_sky(&mut self, from: (f64, f64)) {
        let to = self.controls.pointer.cursor;
        let length = (to.0 - from.0).hypot(to.1 - from.1);
        let steps = ((length / PATH_STEP).ceil() as usize).clamp(1, MAX_PATH_STEPS);
        let at = |i: usize| {
            let f = i as f64 / steps as f64;
            (from.0 + (to.0 - from.0) * f, from.1 + (to.1 - from.1) * f)
        };
        for i in 1..=steps {
            self.controls.pointer.cursor = at(i);
            if self.controls.pointer.drawing.is_some() {
                self.stroke_to_cursor();
                continue;
            }
            let (origin, dir) = self.cursor_ray();
            let first = {
                let doc = self.read();
                let view = doc.scene.world.read();
                tools::start(&view, self.settings.brush.mode, origin, dir)
            };
            if let Some((v, layer)) = first {
                self.controls.pointer.sky_held = false;
                self.begin_stroke(v, layer);
            }
        }
        self.controls.pointer.cursor = to;
    }

    /// While drawing: the stroke's next point, when the cursor reached another voxel.
    pub(super) fn stroke_to_cursor(&mut self) {
        let Some(d) = &self.controls.pointer.drawing else {
            return;
        };
        let (origin, dir) = self.cursor_ray();
        let next = {
            let doc = self.read();
            let view = doc.scene.world.read();
            tools::next(&view, &self.settings.brush, d.layer, origin, dir)
        };
        if let Some(v) = next
            && v != d.last
        {
            if let Some(d) = &mut self.controls.pointer.drawing {
                d.last = v;
                d.points.push(v);
            }
            self.report.line(format_args!(
                "stroke point {} {} voxel {} {} {}",
                self.controls.pointer.cursor.0, self.controls.pointer.cursor.1, v.x, v.y, v.z
            ));
            self.docs.submit(Edit::StrokeExtend(vec![tools::centre(v)]));
        }
    }

    /// The stroke a click would make now (the preview's), or a box being dragged.
    pub(super) fn previewed_stroke(
        &self,
        view: &brickmap::WorldView<'_>,
    ) -> Option<crate::editor::command::Stroke> {
        let brush = &self.settings.brush;
        let dims = view.dims().voxels();
        if brush.tool != Tool::Brush || self.controls.pointer.pasting {
            return None;
        }
        match &self.controls.pointer.drawing {
            Some(d) if brush.shape == crate::editor::command::BrushShape::Box => {
                Some(brush.stroke(vec![tools::centre(d.first), tools::centre(d.last)], dims))
            }
            // A gradient is applied at the release: the whole drag is previewed.
            Some(d) if brush.stroke(Vec::new(), dims).paint.needs_whole_stroke() => {
                Some(brush.stroke(d.points.iter().map(|v| tools::centre(*v)).collect(), dims))
            }
            Some(_) => None,
            None => {
                if self.on_ui(self.controls.pointer.cursor) {
                    return None;
                }
                let (origin, dir) = self.cursor_ray();
                let (v, _) = tools::start(view, brush.mode, origin, dir)?;
                Some(brush.stroke(vec![tools::centre(v)], dims))
            }
        }
    }

    pub(super) fn zoom(&mut self, steps: f64) {
        let aspect = self.aspect();
        let (u, v) = self.cursor_ndc();
        let (origin, dir) = self.viewing.camera.ray(u, v, aspect);
        let ray = brickmap::Ray { origin, dir };
        // The surface under the cursor (exact CPU cast), else the pivot plane.
        let hit = self
            .read()
            .scene
            .world
            .read()
            .ray_cast(&ray, f64::INFINITY)
            .ok()
            .flatten();
        let target = match hit {
            Some((h, _)) => ray.origin + dir * h.t,
            None => self.viewing.camera.pivot_plane_point(u, v, aspect),
        };
        self.viewing
            .camera
            .zoom_towards(target, 0.85f64.powf(steps));
        self.moved();
    }

    /// Held movement keys move the camera by the time since the last tick ([`flight`]):
    /// half the view distance per second (Shift: twice it), at least 8 voxels' worth.
    pub(super) fn tick_fly(&mut self) {
        let speed = self.viewing.camera.distance.max(8.0)
            * if self.controls.pointer.mods.shift {
                2.0
            } else {
                0.5
            };
        if let Some(step) = self.controls.flight.step(speed) {
            self.viewing.camera.fly(step);
            self.moved();
        }
    }
}

/// Pixels between the points of a cursor path walked for the scene (a press held on the sky).
const PATH_STEP: f64 = 2.0;
/// The most points walked along one cursor move.
const MAX_PATH_STEPS: usize = 1024;
