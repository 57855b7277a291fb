//! The editor's frames-and-GPU part: the GPU session and its host (a window, or the headless
//! stand-in) once they exist, the frames' state (counts, budget, pacing), egui's context, and
//! whether the editor has a window at all.

use super::budget;
use super::host::Host;
use render::present::Presenter;
use render::viewport::Viewport;
use std::time::Instant;

/// What the GPU and the window are, once the window exists (or its headless stand-in).
/// Field order is drop order: the presenter and the session go before the window their
/// surface belongs to.
pub(super) struct Gfx {
    pub(super) presenter: Presenter,
    pub(super) viewport: Viewport,
    pub(super) host: Host,
    /// The document generation whose world the viewport holds.
    pub(super) generation: u64,
    /// The scene's world (its epoch) the viewport holds, and how far the scene had moved
    /// then (a regrid makes a new world and moves the scene).
    pub(super) epoch: (u64, glam::IVec3),
    /// The window title last set.
    title: String,
}

impl Gfx {
    /// The session for `host`, holding the world of document `generation` at `epoch`.
    pub(super) fn new(
        presenter: Presenter,
        viewport: Viewport,
        host: Host,
        generation: u64,
        epoch: (u64, glam::IVec3),
    ) -> Self {
        Self {
            presenter,
            viewport,
            host,
            generation,
            epoch,
            title: String::new(),
        }
    }

    /// Sets the window's title when it changed (each set is a round trip to the window
    /// system).
    pub(super) fn set_title(&mut self, title: String) {
        if title != self.title {
            self.host.set_title(&title);
            self.title = title;
        }
    }
}

/// The frames' own state.
pub(super) struct Frames {
    /// Frames drawn.
    pub(super) count: u64,
    /// Samples per pixel the last shown frame added (0 once converged).
    pub(super) last_added: u32,
    /// Samples per frame and the traced resolution's scale, from the GPU time per frame.
    pub(super) budget: budget::FrameBudget,
    /// egui's texture changes, kept until a frame with the UI applies them.
    pub(super) textures: egui::TexturesDelta,
    /// The trace job whose image the last frame showed.
    pub(super) shown_job: Option<u64>,
    /// When to look for the trace job's end again ([`Editor::pump_trace`]).
    pub(super) pump_at: Option<Instant>,
    /// The internal size and target samples the last frame asked for (pumped jobs ask
    /// the same).
    pub(super) asked: ((u32, u32), u32),
    /// An input or a result (edit, file) came since the last trace job: the next job's
    /// image is the first to show it.
    pub(super) awaited: bool,
    /// The trace job whose image first shows the last input or result.
    pub(super) input_job: Option<u64>,
    /// Tests only: the frame that fails as if the device were lost
    /// (`VOXBRICK_TEST_GPU_FAILURE_AT_FRAME`), to check nothing is lost when the GPU fails.
    #[cfg(feature = "test-hooks")]
    pub(super) fail_at: Option<u64>,
}

impl Frames {
    pub(super) fn new() -> Self {
        Self {
            count: 0,
            last_added: 0,
            budget: Default::default(),
            textures: Default::default(),
            shown_job: None,
            pump_at: None,
            asked: ((1, 1), 1),
            awaited: false,
            input_job: None,
            #[cfg(feature = "test-hooks")]
            fail_at: std::env::var("VOXBRICK_TEST_GPU_FAILURE_AT_FRAME")
                .ok()
                .and_then(|v| v.parse().ok()),
        }
    }
}

/// The GPU session, the frames and the UI's context.
pub(super) struct Screen {
    /// None until the window (or its stand-in) exists, and after the session ended.
    pub(super) gfx: Option<Gfx>,
    /// Frames drawn, the samples-per-frame budget, textures waiting for a frame.
    pub(super) frames: Frames,
    pub(super) egui: egui::Context,
    /// No window: frames are drawn offscreen, no native dialog is shown, fly keys move the
    /// camera a fixed 1/60 s per frame (a headless session is a function of its input).
    headless: bool,
}

impl Screen {
    /// No session yet. egui without fades or slides: its clock stands still while a slow
    /// frame blocks the loop (`host::InputClock`), so on a slow device a 0.1 s fade took
    /// seconds and dialogs appeared as ghosts (seen at 1280 × 720 on lavapipe).
    pub(super) fn new(headless: bool) -> Self {
        let egui = egui::Context::default();
        egui.all_styles_mut(|s| s.animation_time = 0.0);
        Self {
            gfx: None,
            frames: Frames::new(),
            egui,
            headless,
        }
    }

    /// Whether the editor runs without a window.
    pub(super) fn headless(&self) -> bool {
        self.headless
    }

    /// Asks the host for a frame (nothing before the session exists).
    pub(super) fn request_redraw(&mut self) {
        if let Some(g) = &mut self.gfx {
            g.host.request_redraw();
        }
    }

    /// Validation messages the session has seen (0 without one).
    pub(super) fn validation_errors(&self) -> u32 {
        self.gfx
            .as_ref()
            .map_or(0, |g| g.viewport.ctx().validation_errors())
    }

    /// Ends the GPU session (before the window its surface belongs to) and drops the
    /// texture changes no frame will apply.
    pub(super) fn release(&mut self) {
        self.gfx = None;
        self.frames.textures.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_a_session_nothing_is_drawn_and_release_drops_waiting_textures() {
        let mut s = Screen::new(true);
        assert!(s.headless() && s.gfx.is_none());
        s.request_redraw();
        assert_eq!(s.validation_errors(), 0);
        s.frames.textures.free.insert(egui::TextureId::Managed(7));
        assert!(!s.frames.textures.is_empty());
        s.release();
        assert!(s.frames.textures.is_empty() && s.gfx.is_none());
        // egui draws no animation (a slow frame would stretch it).
        assert_eq!(s.egui.style_of(egui::Theme::Dark).animation_time, 0.0);
        assert_eq!(s.egui.style_of(egui::Theme::Light).animation_time, 0.0);
    }
}
