//! The editor's frames: the window's GPU session (made on the first `resumed`), one frame
//! per redraw (results of edits and files, backlog input, fly keys, a script step, the
//! panels, trace and present), progressive refinement and the samples-per-frame controller,
//! and the script run's capture.
//!
//! In detail:
//! the editor's frames: attaching the GPU session to a host, `redraw`/`draw` (results, backlog
//! input, fly keys, a script step, panels, trace, present), refinement and the
//! samples-per-frame controller, the script capture. The UI first: for `UI_FIRST` (0.35 s)
//! after pointer or key input on the UI (`ui_touched`, set in handle.rs), while a popup is open
//! or a widget is dragged, refinement waits (target 1 sample: a change still shows at once) and
//! such frames do not keep the loop busy (`about_to_wait` wakes it when the wait ends), so no
//! trace delays a menu. The viewport is drawn in its rectangle only (`view_area`, from the
//! panels' last layout; a script run: the whole window, as the captures are compared with
//! whole-window renders): aspect, picking, framing (`Camera::framing_in`: the narrower field of
//! view) and the traced size follow it.

use super::host::Host;
use super::jobs::Edit;
use super::screen::Gfx;
use super::{Editor, files, panels, preview, selecting};
use anyhow::{Context, Result};
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use render::present::{EguiFrame, Presented, Presenter, Show};
use render::viewport::Viewport;
use render::vulkan::{ContextOptions, GpuContext, WindowHandles};
use std::sync::Arc;
use std::time::Instant;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

impl Editor {
    pub(super) fn create_gfx(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let (w, h) = self.options.size;
        let attrs = Window::default_attributes()
            .with_title("voxbrick")
            .with_inner_size(winit::dpi::PhysicalSize::new(w.max(64), h.max(64)));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .context("creating the window")?,
        );
        let handles = WindowHandles {
            display: window.display_handle().context("display handle")?.as_raw(),
            window: window.window_handle().context("window handle")?.as_raw(),
        };
        let ctx = GpuContext::new(&ContextOptions {
            device: crate::gpu::device_choice(&self.options.device),
            validation: self.options.validation,
            window: Some(handles),
            draw_ui: true,
            ..Default::default()
        })
        .context("no Vulkan device can draw this window")?;
        let ctx = Arc::new(ctx);
        let size = window.inner_size();
        let presenter = Presenter::new(ctx.clone(), (size.width, size.height))?;
        let egui_state = Box::new(egui_winit::State::new(
            self.screen.egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            None,
        ));
        self.attach(
            ctx,
            presenter,
            Host::Window {
                egui_state,
                window,
                clock: super::host::InputClock::new(),
            },
            (size.width, size.height),
        )
    }

    /// The GPU session for the window (or its headless stand-in) of `size`.
    pub(super) fn attach(
        &mut self,
        ctx: Arc<GpuContext>,
        presenter: Presenter,
        host: Host,
        size: (u32, u32),
    ) -> Result<()> {
        self.viewing.set_window(size);
        self.viewing.set_area((0, 0, size.0, size.1));
        let (viewport, epoch) = {
            let doc = self.read();
            let view = doc.scene.world.read();
            let epoch = (doc.scene.epoch(), doc.scene.shifted());
            (Viewport::new(ctx, &view)?, epoch)
        };
        self.screen.gfx = Some(Gfx::new(
            presenter,
            viewport,
            host,
            self.docs.generation(),
            epoch,
        ));
        self.refresh_stats();
        // The accessibility tree names the widgets drawn: a headless driver asks for them
        // (`Editor::widget`), a report file is told where they are.
        if matches!(
            self.screen.gfx.as_ref().map(|g| &g.host),
            Some(Host::Headless(_))
        ) || self.report.to_file()
        {
            self.screen.egui.enable_accesskit();
        }
        Ok(())
    }

    /// One frame: script step, file results, egui, trace, present. Skipped (not waited
    /// for) while a command runs on the worker; its completion wakes the loop.
    pub(super) fn redraw(&mut self) -> Result<()> {
        let gate = self.docs.edits.gate.clone();
        let Ok(_frame) = gate.try_lock() else {
            // No frame can be drawn while an edit holds the document; a long one (terrain)
            // shows its progress in the title, refreshed by `about_to_wait`'s timer.
            if let (Some(f), Some(g)) = (self.docs.progress(), &mut self.screen.gfx) {
                g.set_title(format!("voxbrick — generating terrain {:.0} %", f * 100.0));
            }
            return Ok(());
        };
        self.take_results();
        self.tick_fly();
        self.step_script();
        self.autosave();
        let Some(mut gfx) = self.screen.gfx.take() else {
            return Ok(());
        };
        let result = self.draw(&mut gfx);
        self.screen.gfx = Some(gfx);
        result
    }

    /// What finished since the last frame (files, edits, saves; the backlog's input), the
    /// frame gate held.
    pub(super) fn take_results(&mut self) {
        while let Ok(done) = self.docs.files.done.try_recv() {
            self.file_done(done);
            self.screen.frames.awaited = true;
        }
        while let Ok(edited) = self.docs.edits.done.try_recv() {
            self.edited(edited);
            self.screen.frames.awaited = true;
        }
        self.render_finished();
        self.docs.start_waiting_saves();
        self.docs.mark_saved();
        for (input, consumed) in self.controls.take_backlog() {
            self.handle_logged(input, consumed);
        }
    }

    pub(super) fn draw(&mut self, gfx: &mut Gfx) -> Result<()> {
        self.screen.frames.count += 1;
        #[cfg(feature = "test-hooks")]
        if self.screen.frames.fail_at == Some(self.screen.frames.count) {
            return Err(render::vulkan::GpuError::Vk {
                call: "vkQueueSubmit (simulated: VOXBRICK_TEST_GPU_FAILURE_AT_FRAME)",
                result: ash::vk::Result::ERROR_DEVICE_LOST,
            }
            .into());
        }
        let epoch = {
            let doc = self.read();
            (doc.scene.epoch(), doc.scene.shifted())
        };
        if gfx.generation != self.docs.generation() || gfx.epoch.0 != epoch.0 {
            // A new document, or the scene moved into a larger grid: a new GPU world on the
            // same device (the old one goes first). Within a document the view follows the
            // scene's shift.
            if gfx.generation == self.docs.generation() {
                self.viewing.shift((epoch.1 - gfx.epoch.1).as_dvec3());
            }
            let ctx = gfx.viewport.ctx().clone();
            let next = {
                let doc = self.read();
                let view = doc.scene.world.read();
                Viewport::new(ctx, &view)?
            };
            gfx.viewport = next;
            gfx.generation = self.docs.generation();
            gfx.epoch = epoch;
            self.refresh_stats();
        }
        let capture_now = self
            .script
            .as_ref()
            .is_some_and(|s| s.captured_at.is_none() && s.finished && self.outcome.is_ok())
            && gfx.viewport.samples() >= self.settings.target_spp;
        // The status line and the panels.
        self.panels.busy = self.docs.files.running.clone();
        self.panels
            .busy
            .extend(self.docs.edits.pending.iter().cloned());
        let samples = gfx.viewport.samples();
        let gpu_ms = gfx.viewport.last_gpu_seconds().map_or(0.0, |s| s * 1e3);
        let size = gfx.host.inner_size();
        let shown = (self.viewing.area().2, self.viewing.area().3);
        let internal = gfx.viewport.fit_internal(self.internal_size(shown));
        let paths = internal.0 as f64 * internal.1 as f64 * self.screen.frames.last_added as f64;
        let figures = format!(
            "{samples}/{} spp · GPU {gpu_ms:.2} ms/frame · {:.1} Mpaths/s · internal {}x{}{} · {}{}",
            self.settings.target_spp,
            if gpu_ms > 0.0 {
                paths / gpu_ms / 1e3
            } else {
                0.0
            },
            internal.0,
            internal.1,
            if self.viewing.camera.camera.is_orthographic() {
                " · orthographic"
            } else {
                ""
            },
            gfx.viewport.ctx().name,
            self.controls
                .motion
                .latency()
                .map_or_else(String::new, |l| format!(
                    " · input to photon {:.1} ms",
                    l.as_secs_f64() * 1e3
                )),
        );
        // One pick ray a frame: the status line and the ruler share it.
        let hovered = self.hovered();
        self.panels.status = self.status_line(&figures, hovered);
        gfx.set_title(files::title(&self.read()));
        let raw = gfx.host.take_egui_input();
        let egui_ctx = self.screen.egui.clone();
        let mut events = Vec::new();
        let output = {
            let doc = self.docs.shared();
            let doc = doc.read().unwrap_or_else(|p| p.into_inner());
            {
                let view = doc.scene.world.read();
                let stroke = self.previewed_stroke(&view);
                drop(view);
                self.controls
                    .preview
                    .update(&self.docs.shared(), stroke.as_ref(), doc.revision);
            }
            let paste = self.paste_target(&doc);
            // The Stamp tool's stamps: the drag's, or the one a press would put down.
            let stamping = self.settings.brush.tool == super::tools::Tool::Stamp
                && !self.controls.pointer.pasting;
            let stamps: Vec<(glam::IVec3, glam::IVec3)> = match &self.controls.pointer.stamping {
                Some(d) => {
                    let size = doc.scene.clipboard.as_ref().map_or(glam::IVec3::ONE, |c| {
                        crate::editor::stamp::turned_size(
                            c.size,
                            self.settings.brush.stamp_quarters,
                        )
                    });
                    d.at.iter().map(|a| (*a, size)).collect()
                }
                None if stamping && !self.on_ui(self.controls.pointer.cursor) => {
                    self.stamp_target(&doc, None).into_iter().collect()
                }
                None => Vec::new(),
            };
            self.controls.preview.set_paste(
                doc.scene
                    .clipboard
                    .as_ref()
                    .filter(|_| self.controls.pointer.pasting || stamping),
                if stamping {
                    self.settings.brush.stamp_quarters
                } else {
                    0
                },
            );
            let view_area = self.viewing.area();
            let brush = &self.settings.brush;
            let keeps_layer = brush.shape == crate::editor::command::BrushShape::Box
                || (brush.mode == crate::editor::command::BrushMode::Attach
                    && !brush.follow_surface);
            let layer = self
                .controls
                .pointer
                .drawing
                .as_ref()
                .filter(|_| keeps_layer)
                .map(|d| d.layer);
            let drawn_box = self
                .controls
                .pointer
                .drawing
                .as_ref()
                .filter(|_| brush.shape == crate::editor::command::BrushShape::Box)
                .map(|d| (d.first, d.last));
            let empty = doc.scene.world.read().solid_count() == 0;
            let dragged = self.dragged_box();
            // The picked objects' boxes, where a drag of them would put them.
            let by = self.dragged_by();
            let picked: Vec<_> =
                super::arranging::picked_boxes(&doc.scene.objects(), &self.panels.outliner.picked)
                    .into_iter()
                    .map(|(lo, hi)| (lo + by, hi + by))
                    .collect();
            let band = super::arranging::boxing_band(self);
            // The ruler (Measure tool): its ends, the second following the cursor.
            let ruler = (self.settings.brush.tool == super::tools::Tool::Measure)
                .then(|| self.controls.pointer.ruler.ends(hovered.map(|(v, _)| v)))
                .flatten();
            // Outside arrange mode, the box of the object brushes edit (when it is not the
            // scene's only object).
            let edited = (self.settings.brush.tool != super::tools::Tool::Arrange)
                .then(|| super::arranging::edited_box(&doc.scene))
                .flatten();
            egui_ctx.run_ui(raw, |ui| {
                // Under every panel and window, over the viewport image.
                let painter = ui.ctx().layer_painter(egui::LayerId::background());
                // The viewport's rectangle as picking used it (the last layout's).
                let ppp = ui.ctx().pixels_per_point();
                let (x, y, w, h) = view_area;
                let rect = egui::Rect::from_min_size(
                    egui::pos2(x as f32 / ppp, y as f32 / ppp),
                    egui::vec2(w as f32 / ppp, h as f32 / ppp),
                );
                self.controls
                    .preview
                    .paint(&painter, &self.viewing.camera, rect);
                let brush = &self.settings.brush;
                let dims = doc.scene.world.dims().voxels();
                self.controls
                    .preview
                    .set_selection(doc.scene.selection.as_ref());
                self.controls
                    .preview
                    .paint_selection(&painter, &self.viewing.camera, rect);
                selecting::paint(
                    &painter,
                    &self.viewing.camera,
                    rect,
                    doc.scene.selection.as_ref(),
                    dims,
                    dragged,
                    paste,
                );
                let band = band.map(|((x0, y0), (x1, y1))| {
                    egui::Rect::from_min_max(
                        egui::pos2(x0 as f32 / ppp, y0 as f32 / ppp),
                        egui::pos2(x1 as f32 / ppp, y1 as f32 / ppp),
                    )
                });
                super::arranging::paint(&painter, &self.viewing.camera, rect, &picked, band);
                if let Some((lo, hi)) = edited {
                    let stroke = egui::Stroke::new(
                        1.0,
                        egui::Color32::from_rgba_unmultiplied(255, 255, 255, 110),
                    );
                    preview::paint_box(
                        &painter,
                        &self.viewing.camera,
                        rect,
                        lo.as_dvec3(),
                        hi.as_dvec3(),
                        stroke,
                    );
                }
                if empty {
                    preview::paint_floor(&painter, &self.viewing.camera, rect, dims);
                }
                if let Some(layer) = layer {
                    preview::paint_layer(&painter, &self.viewing.camera, rect, layer, dims);
                }
                if let Some(ends) = ruler {
                    super::measure::paint(&painter, &self.viewing.camera, rect, ends);
                }
                // A box being dragged says its size beside the cursor.
                let cursor = egui::pos2(
                    self.controls.pointer.cursor.0 as f32 / ppp,
                    self.controls.pointer.cursor.1 as f32 / ppp,
                );
                if let Some(b) = drawn_box.or(dragged.map(|(lo, hi, _)| (lo, hi))) {
                    preview::paint_box_size(&painter, cursor, b);
                }
                if let Some(d) = &self.controls.pointer.rect_selecting {
                    let from = egui::pos2(d.from.0 as f32 / ppp, d.from.1 as f32 / ppp);
                    super::rect_selecting::paint(&painter, from, cursor, d.adds());
                }
                if let Some(d) = &self.controls.pointer.extruding {
                    super::extruding::paint_distance(&painter, cursor, d.distance);
                }
                // The voxels a click pastes, where it pastes them (the box is drawn above).
                if let Some((at, _)) = paste {
                    self.controls
                        .preview
                        .paint_paste(&painter, &self.viewing.camera, rect, at);
                }
                for (at, size) in &stamps {
                    self.controls
                        .preview
                        .paint_paste(&painter, &self.viewing.camera, rect, *at);
                    let stroke = egui::Stroke::new(1.0, egui::Color32::from_rgb(255, 210, 60));
                    preview::paint_box(
                        &painter,
                        &self.viewing.camera,
                        rect,
                        at.as_dvec3(),
                        (*at + *size).as_dvec3(),
                        stroke,
                    );
                }
                preview::paint_mirror(
                    &painter,
                    &self.viewing.camera,
                    rect,
                    brush.mirror,
                    brush.centre(dims),
                    dims,
                );
                events = panels::draw(ui, &mut self.panels, &doc, &mut self.settings);
                if let Some((path, p)) = &self.docs.mesh_task {
                    super::progress::window(
                        ui.ctx(),
                        "Exporting a mesh",
                        &path.display().to_string(),
                        p,
                    );
                }
                events.extend(super::render_image::window(
                    ui.ctx(),
                    &mut self.panels.render_image_open,
                    &mut self.settings.render_image,
                    self.docs.render_task.as_ref(),
                ));
            })
        };
        for e in events {
            self.ui_event(e);
        }
        // The viewport is what the bars and docks left this frame (a script run's capture
        // is compared with whole-window renders: the whole window, the panels over it).
        let area = match self.panels.viewport {
            Some(r) if self.script.is_none() => {
                pixel_area(r, self.screen.egui.pixels_per_point(), size)
            }
            _ => (0, 0, size.0, size.1),
        };
        if self.viewing.set_area(area) {
            let (x, y, w, h) = area;
            self.report.line(format_args!("viewport {x} {y} {w} {h}"));
        }
        let shown = (area.2, area.3);
        let internal = gfx.viewport.fit_internal(self.internal_size(shown));
        let egui::FullOutput {
            platform_output,
            textures_delta,
            shapes,
            pixels_per_point,
            viewport_output,
        } = output;
        // A driver outside the process learns where the labelled widgets are.
        let mut platform_output = platform_output;
        if self.report.to_file()
            && let Some(update) = platform_output.accesskit_update.take()
        {
            let widgets = super::host::labelled_widgets(&update);
            self.report.widgets(&widgets, pixels_per_point);
        }
        gfx.host.handle_platform_output(platform_output);
        // Texture changes wait here until a frame with the UI applies them.
        self.screen.frames.textures.append(textures_delta);
        let primitives = egui_ctx.tessellate(shapes, pixels_per_point);
        // While the camera moves and while a stroke is drawn: the moving scale, so each
        // change shows in the next, cheaper frame.
        let moving = self.controls.motion.is_moving() || self.controls.pointer.is_drawing();
        let still = internal;
        let internal = if moving {
            self.budgeted(super::pacing::scaled(
                shown,
                self.settings.moving_scale.min(self.settings.internal_scale),
            ))
        } else {
            internal
        };
        // While the user works in the UI (a menu or popup open, a widget or window dragged,
        // pointer or key input on the UI in the last UI_FIRST) refinement waits: a frame
        // is then the UI's and the display's only, so no trace delays the menus and panels.
        // A change made there (the sun, a material) still gets its first sample at once.
        let ui_first = !moving
            && self.script.is_none()
            && (egui::Popup::is_any_open(&egui_ctx)
                || egui_ctx.egui_is_using_pointer()
                || self.controls.ui_first(Instant::now()));
        let target_spp = if ui_first {
            1
        } else {
            self.settings.target_spp
        };
        self.screen.frames.asked = (internal, target_spp);
        let doc = self.docs.shared();
        let doc = doc.read().unwrap_or_else(|p| p.into_inner());
        let mut params = doc.scene.params.clone();
        params.camera = self.viewing.camera.camera.clone();
        let request = self.request(&doc, &params, internal, shown, target_spp);
        let ui = (!capture_now).then(|| EguiFrame {
            primitives: &primitives,
            pixels_per_point,
            textures: &self.screen.frames.textures,
        });
        let framed = gfx.presenter.frame(
            &mut gfx.viewport,
            &doc.scene.world,
            &request,
            Some(self.viewing.area()),
            ui,
            if capture_now {
                Show::Capture
            } else {
                Show::Show
            },
        )?;
        drop(doc);
        self.traced(gfx, &framed, (still, internal));
        match framed.presented {
            Presented::Shown => {
                if !capture_now {
                    self.screen.frames.textures.clear();
                }
                self.screen.frames.shown_job = framed.image.map(|i| i.job);
                // "pending": the image shown is older than what the last input or result
                // asked of the trace (the UI shows it already; the traced image follows).
                let shown = framed.image.map_or(0, |i| i.job);
                let pending = self.screen.frames.awaited
                    || self.screen.frames.input_job.is_some_and(|j| shown < j);
                self.report.line(format_args!(
                    "frame {} spp {}{}",
                    self.screen.frames.count,
                    framed.image.map_or(0, |i| i.samples),
                    if pending { " pending" } else { "" }
                ));
                self.controls.motion.shown();
            }
            Presented::Skipped => {}
            Presented::NotReady | Presented::Recreated => gfx.host.request_redraw(),
        }
        let captured = framed.capture;
        if let Some(c) = captured {
            self.finish_capture(gfx, c)?;
        }
        if let Some(s) = &self.script
            && let Some(at) = s.captured_at
            && at.elapsed() >= self.options.linger
        {
            let errors = gfx.viewport.ctx().validation_errors();
            if errors > 0 {
                anyhow::bail!("{errors} Vulkan validation errors");
            }
            self.exit = true;
        }
        if self.quitting {
            self.exit = true;
        }
        // Keep drawing while moving, running a script or waiting for files; while refining,
        // look again soon for the trace job's end (`pump_trace`): its image gets a frame then.
        // (Refinement that waits for the UI is not: the end of the wait wakes the loop.)
        if (gfx.viewport.samples() < self.settings.target_spp && !ui_first)
            || gfx.viewport.in_flight()? > 0
        {
            self.screen.frames.pump_at = Some(Instant::now() + super::pacing::PUMP);
        }
        let busy = moving
            || self.controls.flight.is_flying()
            || self.script.is_some()
            || !self.docs.files.running.is_empty()
            || self.docs.edits.busy()
            || !self.docs.saves.settled()
            || viewport_output.values().any(|v| v.repaint_delay.is_zero());
        if busy {
            gfx.host.request_redraw();
        }
        Ok(())
    }

    /// Runs the script's next step, one per frame, so the viewport shows each edit; a camera
    /// step resets the view to the scene camera (what the capture is compared against).
    /// Queues the script's next step on the edit thread (the same path as the UI's own
    /// edits), one at a time: the frame after a step shows it.
    pub(super) fn step_script(&mut self) {
        let Some(s) = &mut self.script else {
            return;
        };
        if s.finished {
            return;
        }
        if let Some(run) = s.run.take() {
            self.docs.submit(Edit::ScriptStep(s.script.clone(), run));
        }
    }

    pub(super) fn finish_capture(&mut self, gfx: &Gfx, c: render::present::Capture) -> Result<()> {
        let Some(s) = &mut self.script else {
            return Ok(());
        };
        s.captured_at = Some(Instant::now());
        if let Some(path) = &s.capture {
            let bytes: Vec<u8> = c.rgb.iter().flatten().copied().collect();
            crate::atomic::write_atomic(path, |w| {
                render::image::write_png_rgb8(w, c.width, c.height, &bytes)
            })
            .with_context(|| format!("writing {}", path.display()))?;
            println!(
                "captured {}x{} at {} spp to {}",
                c.width,
                c.height,
                gfx.viewport.samples(),
                path.display()
            );
        }
        Ok(())
    }
}

/// A rectangle in points as whole pixels inside a window of `size`: at least one pixel.
fn pixel_area(r: egui::Rect, ppp: f32, size: (u32, u32)) -> (u32, u32, u32, u32) {
    let px = |v: f32, max: u32| ((v * ppp).round().max(0.0) as u32).min(max);
    let (x0, y0) = (px(r.min.x, size.0), px(r.min.y, size.1));
    let (x1, y1) = (px(r.max.x, size.0), px(r.max.y, size.1));
    (
        x0.min(size.0.saturating_sub(1)),
        y0.min(size.1.saturating_sub(1)),
        x1.saturating_sub(x0).max(1),
        y1.saturating_sub(y0).max(1),
    )
}
