//! The editor without a window: the same [`Editor`], its frames drawn offscreen by the same
//! presenter (egui included), its input given as [`Input`] events through the same handlers a
//! window's events reach (egui gets its share first, as egui-winit gives it). The soak test
//! drives it so; nothing here is a second implementation of the editor.
//!
//! In detail:
//! `Editor::headless`: the same editor without a window (offscreen presenter with egui, no
//! native dialogs, handshake log in memory): `input`, `frame`, `pump`, `settled`, `aim`,
//! `on_ui_at`, `ray_at`, `view_area`, `palette_grid`, `notice`, `widget` (where a widget that
//! says a text was drawn, from egui's accessibility tree, which a headless editor turns on),
//! `close` — what the soak and `app/tests/editor_handlers.rs` drive.

use super::camera::ViewCamera;
use super::event::Input;
use super::files::SharedDocument;
use super::host::{Headless, Host};
use super::screen::Gfx;
use super::{Editor, EditorOptions, report, tools};
use anyhow::{Context, Result};
use glam::DVec3;
use render::present::Presenter;
use render::vulkan::{ContextOptions, GpuContext};
use std::sync::Arc;

impl Editor {
    /// An editor of `size` pixels on the device `options.device`, without a window: no native
    /// dialog is ever shown (a pick answers that none can be), the handshake log is kept in
    /// memory ([`Editor::take_report`]), fly keys move a fixed 1/60 s per frame. Opens
    /// `options.file` (or builds the default scene) like the window does.
    pub fn headless(options: EditorOptions, size: (u32, u32)) -> Result<Self> {
        let validation = options.validation;
        let device = options.device.clone();
        let mut editor = Self::new(options, Arc::new(|| {}), true)?;
        editor.report = report::Report::Memory(Vec::new());
        let ctx = GpuContext::new(&ContextOptions {
            device: crate::gpu::device_choice(&device),
            validation,
            draw_ui: true,
            ..Default::default()
        })
        .context("no usable Vulkan device")?;
        let ctx = Arc::new(ctx);
        let size = (size.0.max(1), size.1.max(1));
        let mut presenter = Presenter::offscreen(ctx.clone(), size)?;
        // Each headless frame shows what it was asked to (tests look at it).
        presenter.set_synchronous(true);
        editor.attach(ctx, presenter, Host::Headless(Headless::new(size)), size)?;
        Ok(editor)
    }

    /// One input event, as a window would pass it on: egui sees it first and may keep it.
    pub fn input(&mut self, input: Input) {
        let mods = match &input {
            Input::Modifiers(m) => *m,
            _ => self.controls.pointer.mods,
        };
        let kept = input.kept_from(&self.screen.egui);
        if let Some(Gfx {
            host: Host::Headless(h),
            ..
        }) = &mut self.screen.gfx
            && !kept
        {
            h.push(&input, mods);
        }
        let consumed = !kept && input.consumed_by(&self.screen.egui);
        self.input_with(input, consumed);
    }

    /// One frame, as a redraw of the window: finished edits and files, the backlog, a script
    /// step, egui, trace and present (skipped while an edit holds the document). A GPU error
    /// is handled as in the window (unsaved work to the recovery file) and returned.
    pub fn frame(&mut self) -> Result<()> {
        if let Err(e) = self.redraw() {
            let message = format!("{e:#}");
            self.gpu_failed(e);
            anyhow::bail!("{message}");
        }
        Ok(())
    }

    /// Takes what finished (edits, files, saves, the backlog) without drawing, when no edit
    /// holds the frame gate.
    pub fn pump(&mut self) {
        let gate = self.docs.edits.gate.clone();
        if let Ok(_frame) = gate.try_lock() {
            self.take_results();
        }
    }

    /// Whether the edit thread is alive (it never ends while the editor runs: a panic did).
    pub fn edit_thread_alive(&self) -> bool {
        self.docs.edits.alive()
    }

    /// Bumped whenever the document is replaced (open, new, recovery).
    pub fn generation(&self) -> u64 {
        self.docs.generation()
    }

    /// Whether everything asked for is done: no edit queued or running, no file job, no save
    /// waiting or unrecorded, no input in the backlog.
    pub fn settled(&self) -> bool {
        self.docs.settled() && self.controls.backlog_empty()
    }

    /// The document (shared with the edit thread and the file worker).
    pub fn document(&self) -> SharedDocument {
        self.docs.shared()
    }

    /// The handshake log's lines since the last call (a headless editor keeps them).
    pub fn take_report(&mut self) -> Vec<String> {
        self.report.take()
    }

    /// Errors the panels would show, taken (they are shown no longer).
    pub fn take_errors(&mut self) -> Vec<String> {
        std::mem::take(&mut self.panels.errors)
    }

    /// Whether the editor asked to stop (quit, a failed script, a GPU failure).
    pub fn wants_exit(&self) -> bool {
        self.exit
    }

    /// The editor is kept running after it asked to stop (a driver's "started again": the
    /// settings were saved and the recovery file removed as on a real quit).
    pub fn keep_running(&mut self) {
        self.exit = false;
        self.quitting = false;
    }

    /// Validation messages so far (0 without the layer).
    pub fn validation_errors(&self) -> u64 {
        self.screen
            .gfx
            .as_ref()
            .map_or(0, |g| g.viewport.ctx().validation_errors() as u64)
    }

    /// Where the viewport shows in the window (x, y, width, height in pixels, as last drawn).
    pub fn view_area(&self) -> (u32, u32, u32, u32) {
        self.viewing.area()
    }

    /// The view's ray through a window point (pixels): what a click there would pick.
    pub fn ray_at(&self, x: f64, y: f64) -> (DVec3, DVec3) {
        self.viewing.ray_at((x, y))
    }

    /// The window's size in physical pixels.
    pub fn size(&self) -> (u32, u32) {
        self.viewing.window()
    }

    /// The session's recording so far, as a replay script (with `options.record`).
    pub fn recording(&self) -> Option<String> {
        self.recording_text()
    }

    /// Where the world point `p` shows in the window, in pixels — None when it is behind the
    /// eye, outside the window, or under a menu, a status line or a window (as drawn in the
    /// last frame): the places a user would aim at to reach it.
    pub fn aim(&self, p: DVec3) -> Option<(f64, f64)> {
        let (x, y) = self.viewing.window_point(p)?;
        let (w, h) = self.viewing.window();
        let inside =
            (1.0..f64::from(w) - 1.0).contains(&x) && (1.0..f64::from(h) - 1.0).contains(&y);
        (inside && !self.covered((x, y))).then_some((x, y))
    }

    /// Whether a press at the window point `(x, y)` (pixels) would be the UI's (a panel, a
    /// bar or a window under it as last drawn, or a popup open) rather than the viewport's.
    pub fn on_ui_at(&self, x: f64, y: f64) -> bool {
        self.on_ui((x, y))
    }

    /// Where the palette's 16 × 16 colours show (x, y, width, height in pixels, as last
    /// drawn; None while its dock is collapsed).
    pub fn palette_grid(&self) -> Option<(f64, f64, f64, f64)> {
        Some(self.pixel_rect(self.panels.editing.palette_grid?))
    }

    /// A rectangle in points as (x, y, width, height) in window pixels.
    fn pixel_rect(&self, r: egui::Rect) -> (f64, f64, f64, f64) {
        let ppp = f64::from(self.screen.egui.pixels_per_point());
        (
            f64::from(r.min.x) * ppp,
            f64::from(r.min.y) * ppp,
            f64::from(r.width()) * ppp,
            f64::from(r.height()) * ppp,
        )
    }

    /// Where the last frame drew a widget whose text is `label` (a button's, a label's, a
    /// checkbox's): its centre in window pixels. None when no widget says that.
    pub fn widget(&self, label: &str) -> Option<(f64, f64)> {
        let Some(Gfx {
            host: Host::Headless(h),
            ..
        }) = &self.screen.gfx
        else {
            return None;
        };
        let ppp = f64::from(self.screen.egui.pixels_per_point());
        h.widgets.iter().find(|(l, _)| l == label).map(|(_, r)| {
            let c = r.center();
            (f64::from(c.x) * ppp, f64::from(c.y) * ppp)
        })
    }

    /// Where the panel window titled `title` was last drawn (x, y, width, height in window
    /// pixels); None when it is not open.
    pub fn window_rect(&self, title: &str) -> Option<(f64, f64, f64, f64)> {
        let id = super::editing::window_id(title);
        let layer = egui::LayerId::new(egui::Order::Middle, id);
        let r = self
            .screen
            .egui
            .memory(|m| {
                m.areas()
                    .visible_last_frame(&layer)
                    .then(|| m.area_rect(id))
            })
            .flatten()?;
        Some(self.pixel_rect(r))
    }

    /// How many voxel faces tint a selection made as a set (0: none, or a box selection).
    pub fn selection_tint_faces(&self) -> usize {
        self.controls.preview.selection_faces()
    }

    /// How many voxel faces the paste being placed, or the Stamp tool, shows (0: neither, or
    /// too large a clip).
    pub fn paste_preview_faces(&self) -> usize {
        self.controls.preview.paste_faces()
    }

    /// Whether the in-app file browser is open.
    pub fn browser_open(&self) -> bool {
        self.panels.browser.is_some()
    }

    /// The status line's passing message, if one shows.
    pub fn notice(&self) -> Option<&str> {
        self.panels.notice.as_ref().map(|(t, _)| t.as_str())
    }

    /// Fly keys move by the time that passed, as in a window (not 1/60 s per tick).
    pub fn fly_in_real_time(&mut self) {
        self.controls.flight.in_real_time();
    }

    /// The view camera.
    pub fn view(&self) -> &ViewCamera {
        &self.viewing.camera
    }

    /// Whether a menu or another popup is open (as of the last frame).
    pub fn popup_open(&self) -> bool {
        egui::Popup::is_any_open(&self.screen.egui)
    }

    /// Samples per pixel the viewport's image holds.
    pub fn samples(&self) -> u32 {
        self.screen.gfx.as_ref().map_or(0, |g| g.viewport.samples())
    }

    /// The view settings (kept in settings.ron).
    pub fn settings(&self) -> &super::panels::ViewSettings {
        &self.settings
    }

    /// The brush's settings as the Tools window shows them.
    pub fn brush(&self) -> &tools::Brush {
        &self.settings.brush
    }

    /// Ends the session as the window's exit does, and returns its outcome (validation errors
    /// count; the recording is written).
    pub fn close(mut self) -> Result<()> {
        self.finish();
        std::mem::replace(&mut self.outcome, Ok(()))
    }
}
