//! The editor's input-and-tools part: the key map, the pointer (modifiers, cursor, the
//! gesture in progress), what a click would change under the cursor, the fly keys, the view
//! in motion, input that waits for an edit to free the frame gate, and when the UI was last
//! used (for [`UI_FIRST`] after it, refinement waits and frames are the UI's).

use super::event::Input;
use super::{flight, keymap, motion, pointer, preview};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How long after pointer or key input on the UI refinement waits (frames are the UI's).
pub(super) const UI_FIRST: Duration = Duration::from_millis(350);

/// What the UI's last use asks of the event loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum UiWait {
    /// The UI was not used lately.
    None,
    /// Refinement waits until then.
    Until(Instant),
    /// The wait just ended: refinement resumes (draw a frame).
    Ended,
}

/// Input, and the tools' state between inputs.
pub(super) struct Controls {
    /// Which keys do what (keys.ron).
    pub(super) keymap: keymap::KeyMap,
    /// The modifiers, the cursor and the gesture in progress.
    pub(super) pointer: pointer::Pointer,
    /// What a click would change, under the cursor.
    pub(super) preview: preview::Preview,
    /// Fly keys held and their clock.
    pub(super) flight: flight::Flight,
    /// The view in motion (the moving scale) and input to photon.
    pub(super) motion: motion::Motion,
    /// Input that arrived while an edit held the frame gate (and whether egui kept it),
    /// handled in order once it is free: a keystroke during a long undo is late, never lost.
    backlog: Vec<(Input, bool)>,
    /// When pointer or key input last went to the UI (a panel, a menu, a window).
    ui_touched: Option<Instant>,
}

impl Controls {
    /// No input yet; `fixed_step`: fly keys move a fixed 1/60 s a frame (headless);
    /// `wake` wakes the event loop when a preview is ready.
    pub(super) fn new(fixed_step: bool, wake: Arc<dyn Fn() + Send + Sync>) -> Self {
        Self {
            keymap: Default::default(),
            pointer: Default::default(),
            preview: preview::Preview::new(wake),
            flight: flight::Flight::new(fixed_step),
            motion: motion::Motion::new(),
            backlog: Vec::new(),
            ui_touched: None,
        }
    }

    /// Input to handle once the frame gate is free, after what waits already.
    pub(super) fn defer(&mut self, input: Input, consumed: bool) {
        self.backlog.push((input, consumed));
    }

    /// The input that waited, in arrival order (the backlog is then empty).
    pub(super) fn take_backlog(&mut self) -> Vec<(Input, bool)> {
        std::mem::take(&mut self.backlog)
    }

    /// No input waits.
    pub(super) fn backlog_empty(&self) -> bool {
        self.backlog.is_empty()
    }

    /// Input went to the UI at `now`.
    pub(super) fn touch_ui(&mut self, now: Instant) {
        self.ui_touched = Some(now);
    }

    /// Whether the UI was used within [`UI_FIRST`] before `now` (frames are the UI's).
    pub(super) fn ui_first(&self, now: Instant) -> bool {
        self.ui_touched
            .is_some_and(|t| now.saturating_duration_since(t) < UI_FIRST)
    }

    /// Whether a wait for the UI is still to be ended (the loop should wake for it).
    pub(super) fn ui_waiting(&self) -> bool {
        self.ui_touched.is_some()
    }

    /// What the UI's last use asks of the loop at `now`; once its wait is over, says so
    /// once and forgets it.
    pub(super) fn ui_wait(&mut self, now: Instant) -> UiWait {
        match self.ui_touched {
            None => UiWait::None,
            Some(t) if t + UI_FIRST > now => UiWait::Until(t + UI_FIRST),
            Some(_) => {
                self.ui_touched = None;
                UiWait::Ended
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn controls() -> Controls {
        Controls::new(true, Arc::new(|| {}))
    }

    #[test]
    fn input_that_waited_comes_back_in_order_once() {
        let mut c = controls();
        assert!(c.backlog_empty());
        c.defer(Input::Text("a".into()), false);
        c.defer(Input::Text("b".into()), true);
        assert!(!c.backlog_empty());
        assert_eq!(
            c.take_backlog(),
            vec![
                (Input::Text("a".into()), false),
                (Input::Text("b".into()), true)
            ]
        );
        assert!(c.backlog_empty() && c.take_backlog().is_empty());
    }

    #[test]
    fn the_ui_keeps_its_frames_for_ui_first_then_refinement_resumes_once() {
        let mut c = controls();
        let t = Instant::now();
        assert_eq!(c.ui_wait(t), UiWait::None);
        assert!(!c.ui_first(t) && !c.ui_waiting());
        c.touch_ui(t);
        assert!(c.ui_first(t + UI_FIRST / 2));
        assert_eq!(c.ui_wait(t + UI_FIRST / 2), UiWait::Until(t + UI_FIRST));
        assert!(!c.ui_first(t + UI_FIRST));
        assert_eq!(c.ui_wait(t + UI_FIRST), UiWait::Ended);
        assert_eq!(c.ui_wait(t + UI_FIRST), UiWait::None, "said once");
        assert!(!c.ui_waiting());
    }
}
