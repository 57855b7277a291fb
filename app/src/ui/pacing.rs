//! The trace's pace in the editor: what a frame asks the viewport to trace (the request, the
//! internal size, the samples-per-frame budget fed by each submitted job's GPU time), and the
//! pump between frames of the UI — the next trace job submitted when the one in flight
//! finished, and a frame asked for once a job's image is ready to show — so that the UI's
//! frames never wait for a trace ([`render::viewport::Viewport::trace_paced`]).

use super::Editor;
use super::screen::Gfx;
use anyhow::Result;
use render::present::{Framed, Show};
use render::viewport::FrameRequest;
use render::vulkan::trace::Dim;
use std::time::{Duration, Instant};

/// How often the loop looks whether the trace job in flight finished.
pub(super) const PUMP: Duration = Duration::from_millis(2);

/// The weight of what lies outside the edited object's box when the others are dimmed.
const DIM_FACTOR: f32 = 0.25;

/// The still and the traced internal size of a frame.
type Sizes = ((u32, u32), (u32, u32));

impl Editor {
    /// What the viewport is asked to trace: `internal` pixels shown at `shown`, up to
    /// `target_spp` samples.
    pub(super) fn request<'a>(
        &self,
        doc: &crate::editor::Document,
        params: &'a render::params::SceneParams,
        internal: (u32, u32),
        shown: (u32, u32),
        target_spp: u32,
    ) -> FrameRequest<'a> {
        FrameRequest {
            params,
            internal,
            output: shown,
            spp: self.screen.frames.budget.spp,
            target_spp,
            exposure: doc.scene.params.settings.exposure + self.settings.exposure,
            bgra: false,
            // A script run's capture is compared with headless renders: never denoised.
            denoise: self.settings.denoise && self.script.is_none(),
            reproject: self.settings.reproject,
            // Likewise never dimmed.
            dim: (self.settings.dim_others
                && self.script.is_none()
                && self.settings.brush.tool != super::tools::Tool::Arrange)
                .then(|| super::arranging::edited_box(&doc.scene))
                .flatten()
                .map(|(lo, hi)| Dim {
                    lo,
                    hi,
                    factor: DIM_FACTOR,
                }),
            grid: (self.settings.grid && self.script.is_none())
                .then_some(self.settings.grid_spacing as f32),
        }
    }

    /// What a frame's trace did: a submitted job's samples, the budget from the GPU time of
    /// the jobs before it (`sizes`: the still and the traced internal size), and which job
    /// first shows the last input or result.
    pub(super) fn traced(&mut self, gfx: &Gfx, framed: &Framed, (still, internal): Sizes) {
        if self.screen.frames.awaited {
            if framed.idle {
                // Nothing to trace: the image shown already shows it.
                self.screen.frames.awaited = false;
            } else if framed.traced.is_some() {
                self.screen.frames.input_job = Some(gfx.viewport.pending_image_job());
                self.screen.frames.awaited = false;
            }
        }
        let Some(status) = framed.traced else {
            return;
        };
        self.screen.frames.last_added = status.added;
        // The budget reasons about the still image: a moving frame's time is scaled by the
        // pixels it left out.
        let ratio = (f64::from(still.0) * f64::from(still.1))
            / (f64::from(internal.0) * f64::from(internal.1)).max(1.0);
        if status.added > 0 {
            self.adapt_samples(gfx.viewport.last_gpu_seconds().map(|t| t * ratio));
        }
    }

    /// Between frames of the UI: the next trace job when the one in flight finished (no UI
    /// is run or displayed), and a frame once a job's image is ready to be shown. Never
    /// waits for the GPU.
    pub(super) fn pump_trace(&mut self) -> Result<()> {
        self.screen.frames.pump_at = None;
        let gate = self.docs.edits.gate.clone();
        let Ok(_frame) = gate.try_lock() else {
            return Ok(());
        };
        let Some(mut gfx) = self.screen.gfx.take() else {
            return Ok(());
        };
        let result = self.pump_with(&mut gfx);
        self.screen.gfx = Some(gfx);
        result
    }

    fn pump_with(&mut self, gfx: &mut Gfx) -> Result<()> {
        let finished = gfx.viewport.shown_image()?.map(|s| s.image.job);
        if finished.is_some() && finished != self.screen.frames.shown_job {
            // A new image: a whole frame shows it (with the status line's new figures).
            gfx.host.request_redraw();
            return Ok(());
        }
        if gfx.generation != self.docs.generation() {
            gfx.host.request_redraw();
            return Ok(());
        }
        let (internal, target_spp) = self.screen.frames.asked;
        let area = self.viewing.area();
        let doc = self.docs.shared();
        let doc = doc.read().unwrap_or_else(|p| p.into_inner());
        if (doc.scene.epoch(), doc.scene.shifted()) != gfx.epoch {
            drop(doc);
            gfx.host.request_redraw();
            return Ok(());
        }
        let mut params = doc.scene.params.clone();
        params.camera = self.viewing.camera.camera.clone();
        let request = self.request(&doc, &params, internal, (area.2, area.3), target_spp);
        let framed = gfx.presenter.frame(
            &mut gfx.viewport,
            &doc.scene.world,
            &request,
            Some(area),
            None,
            Show::Skip,
        )?;
        drop(doc);
        let still = gfx
            .viewport
            .fit_internal(self.internal_size((area.2, area.3)));
        self.traced(gfx, &framed, (still, internal));
        if gfx.viewport.samples() < target_spp || gfx.viewport.in_flight()? > 0 {
            self.screen.frames.pump_at = Some(Instant::now() + PUMP);
        }
        Ok(())
    }

    /// The traced size for a viewport of `size`: the internal scale, then the budget's.
    pub(super) fn internal_size(&self, size: (u32, u32)) -> (u32, u32) {
        self.budgeted(scaled(size, self.settings.internal_scale))
    }

    /// `internal` scaled by the frame budget (not in a script run: its capture is compared
    /// with renders at the internal scale).
    pub(super) fn budgeted(&self, internal: (u32, u32)) -> (u32, u32) {
        if self.script.is_some() {
            internal
        } else {
            self.screen.frames.budget.apply(internal)
        }
    }

    /// Samples per frame and the traced resolution follow the GPU time ([`budget`]).
    pub(super) fn adapt_samples(&mut self, gpu: Option<f64>) {
        if let Some(t) = gpu {
            self.screen.frames.budget.update(t);
        }
    }
}

pub(super) fn scaled((w, h): (u32, u32), f: f32) -> (u32, u32) {
    let f = f.clamp(0.05, 1.0) as f64;
    (
        ((w as f64 * f).ceil() as u32).max(1),
        ((h as f64 * f).ceil() as u32).max(1),
    )
}
