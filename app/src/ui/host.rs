//! Where the editor's frames go and its egui input comes from: a winit window (egui-winit
//! turns its events into egui's), or a headless stand-in of a given size that takes the
//! editor's own [`Input`] events (the soak test drives the editor so, through the same
//! handlers as a window's events, with frames drawn offscreen).

use super::event::{Input, egui_modifiers};
use super::input::Mods;
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::window::Window;

/// The editor's window, or none.
pub(super) enum Host {
    /// A real window.
    Window {
        egui_state: Box<egui_winit::State>,
        window: Arc<Window>,
        clock: InputClock,
    },
    /// No window: a size, egui's pending events, and whether a frame was asked for.
    Headless(Headless),
}

/// egui's clock for a window: wall time that stops while a frame blocks the event loop
/// for longer than [`FRAME_ALLOWANCE`]. egui tells a click from a held press by the time
/// between the passes that see the press and the release; on wall time, a quick click whose
/// press and release were read after two slow frames (the path tracer at 1–3 s a frame on a
/// CPU driver) read as a held press and did nothing — a menu that did not open, a swatch that
/// needed two clicks. Input queued while the loop was blocked is dated, on this clock, to
/// when the loop stopped reading: what the user did in a frozen window counts as done at once.
pub(super) struct InputClock {
    start: Instant,
    /// Time the clock stood still (the blocked part of slow frames).
    stood: Duration,
    last: f64,
}

/// How long a frame may block the loop before the clock stops for the rest of it.
const FRAME_ALLOWANCE: Duration = Duration::from_millis(50);

impl InputClock {
    pub fn new() -> Self {
        Self {
            start: Instant::now(),
            stood: Duration::ZERO,
            last: 0.0,
        }
    }

    /// A frame ran from `began` until now.
    pub fn frame_ran(&mut self, began: Instant) {
        self.stood += began.elapsed().saturating_sub(FRAME_ALLOWANCE);
    }

    /// The next pass's time in seconds (never earlier than the last).
    fn pass_time(&mut self) -> f64 {
        let t = self.start.elapsed().saturating_sub(self.stood);
        self.last = t.as_secs_f64().max(self.last);
        self.last
    }
}

/// The headless stand-in for a window.
pub(super) struct Headless {
    pub size: (u32, u32),
    events: Vec<egui::Event>,
    cursor: (f64, f64),
    /// A frame was asked for since the last one (what `request_redraw` would do).
    pub redraw: bool,
    pub title: String,
    /// Frames drawn: egui's clock runs at 60 per second of them, so a headless session is a
    /// function of its input, not of the machine's speed.
    frames: u64,
    /// The last frame's widgets that have a label, with their rectangles in points (from
    /// egui's accessibility tree): how tests find a button by what it says.
    pub widgets: Vec<(String, egui::Rect)>,
}

impl Headless {
    pub fn new(size: (u32, u32)) -> Self {
        Self {
            size,
            events: Vec::new(),
            cursor: (0.0, 0.0),
            redraw: true,
            title: String::new(),
            frames: 0,
            widgets: Vec::new(),
        }
    }

    /// An input event for egui's next frame.
    pub fn push(&mut self, input: &Input, mods: Mods) {
        match input {
            Input::Moved { x, y } => self.cursor = (*x, *y),
            Input::Modifiers(m) => self
                .events
                .push(egui::Event::ModifiersChanged(egui_modifiers(*m))),
            Input::Resized(w, h) => self.size = (*w, *h),
            _ => {}
        }
        self.events.extend(input.to_egui(self.cursor, mods));
    }
}

impl Host {
    pub fn request_redraw(&mut self) {
        match self {
            Host::Window { window, .. } => window.request_redraw(),
            Host::Headless(h) => h.redraw = true,
        }
    }

    pub fn set_title(&mut self, title: &str) {
        match self {
            Host::Window { window, .. } => window.set_title(title),
            Host::Headless(h) => h.title = title.to_string(),
        }
    }

    /// The inner size in physical pixels.
    pub fn inner_size(&self) -> (u32, u32) {
        match self {
            Host::Window { window, .. } => {
                let s = window.inner_size();
                (s.width, s.height)
            }
            Host::Headless(h) => h.size,
        }
    }

    /// egui's input for the next frame.
    pub fn take_egui_input(&mut self) -> egui::RawInput {
        match self {
            Host::Window {
                egui_state,
                window,
                clock,
            } => {
                let mut raw = egui_state.take_egui_input(window);
                raw.time = Some(clock.pass_time());
                raw
            }
            Host::Headless(h) => {
                h.frames += 1;
                egui::RawInput {
                    screen_rect: Some(egui::Rect::from_min_size(
                        egui::Pos2::ZERO,
                        egui::vec2(h.size.0 as f32, h.size.1 as f32),
                    )),
                    time: Some(h.frames as f64 / 60.0),
                    events: std::mem::take(&mut h.events),
                    focused: true,
                    ..Default::default()
                }
            }
        }
    }

    /// What egui asks of the platform (cursor icon, clipboard, links): a window's only.
    pub fn handle_platform_output(&mut self, output: egui::PlatformOutput) {
        match self {
            Host::Window {
                egui_state, window, ..
            } => egui_state.handle_platform_output(window, output),
            Host::Headless(h) => {
                if let Some(update) = &output.accesskit_update {
                    h.widgets = labelled_widgets(update);
                }
            }
        }
    }
}

/// The widgets of an accessibility update that have a label (or a value), with their
/// rectangles in points, in the update's order.
pub fn labelled_widgets(update: &egui::accesskit::TreeUpdate) -> Vec<(String, egui::Rect)> {
    update
        .nodes
        .iter()
        .filter_map(|(_, node)| {
            let label = node.label().or(node.value())?;
            let b = node.bounds()?;
            let rect = egui::Rect::from_min_max(
                egui::pos2(b.x0 as f32, b.y0 as f32),
                egui::pos2(b.x1 as f32, b.y1 as f32),
            );
            Some((label.to_string(), rect))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_clock_stands_still_while_a_slow_frame_blocks_the_loop() {
        let mut clock = InputClock::new();
        let press_pass = clock.pass_time();
        // A slow frame (1 s) runs; the release, queued meanwhile, is seen by the next pass.
        let began = Instant::now();
        std::thread::sleep(Duration::from_millis(1000));
        clock.frame_ran(began);
        let release_pass = clock.pass_time();
        assert!(
            release_pass - press_pass < 0.8,
            "press at {press_pass} s, release at {release_pass} s: egui would not see a click"
        );
        assert!(release_pass - press_pass >= 0.049, "the allowance counts");
        // Between frames the clock runs; it never goes back.
        std::thread::sleep(Duration::from_millis(40));
        let later = clock.pass_time();
        assert!(later >= release_pass + 0.039, "{later} s");
        let fast = Instant::now();
        clock.frame_ran(fast);
        assert!(clock.pass_time() >= later);
    }
}
