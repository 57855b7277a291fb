//! The view in motion: for a while after a camera move or a stroke the viewport traces at
//! the moving scale (each change shows in the next, cheaper frame), and the time from a
//! move's input to the first frame that shows it is kept for the status line
//! (input to photon).

use std::time::{Duration, Instant};

/// How long after the last move the moving scale lasts.
pub(super) const SETTLE: Duration = Duration::from_millis(150);

/// Motion and its latency.
pub(super) struct Motion {
    until: Instant,
    pending: Option<Instant>,
    latency: Option<Duration>,
}

impl Motion {
    /// Still, nothing measured.
    pub(super) fn new() -> Self {
        Self {
            until: Instant::now(),
            pending: None,
            latency: None,
        }
    }

    /// The camera moved (the first move since the last frame shown starts the clock).
    pub(super) fn moved(&mut self) {
        self.settling();
        self.pending.get_or_insert_with(Instant::now);
    }

    /// Something else changed the view (a stroke ended): the moving scale a while longer.
    pub(super) fn settling(&mut self) {
        self.until = Instant::now() + SETTLE;
    }

    /// Whether the view is still moving.
    pub(super) fn is_moving(&self) -> bool {
        Instant::now() < self.until
    }

    /// A frame was shown: the pending move, if any, is on screen now.
    pub(super) fn shown(&mut self) {
        if let Some(t) = self.pending.take() {
            self.latency = Some(t.elapsed());
        }
    }

    /// Input to photon of the latest move shown.
    pub(super) fn latency(&self) -> Option<Duration> {
        self.latency
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_move_is_motion_until_it_settles_and_its_latency_is_taken_when_shown() {
        let mut m = Motion::new();
        assert!(!m.is_moving() && m.latency().is_none());
        m.moved();
        assert!(m.is_moving());
        m.shown();
        assert!(m.latency().is_some());
        let first = m.latency();
        m.shown();
        assert_eq!(m.latency(), first, "no move pending: unchanged");
        std::thread::sleep(SETTLE + Duration::from_millis(20));
        assert!(!m.is_moving());
    }
}
