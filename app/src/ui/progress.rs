//! A long job's progress as the editor shows it (File → Render image…, File → Export mesh):
//! the part done, shared with the job's thread, the time left at the pace so far, and a Cancel
//! the job polls; and the window that shows them.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

/// Shared between a job's thread (which sets the part done and polls `cancelled`) and the UI.
pub struct TaskProgress {
    done: AtomicU64,
    cancel: AtomicBool,
    started: Instant,
    /// Wakes an idle editor (the frame loop draws on events, not on a timer).
    wake: Option<Arc<dyn Fn() + Send + Sync>>,
}

impl Default for TaskProgress {
    fn default() -> Self {
        Self {
            done: AtomicU64::new(0f64.to_bits()),
            cancel: AtomicBool::new(false),
            started: Instant::now(),
            wake: None,
        }
    }
}

impl TaskProgress {
    /// Progress that wakes the editor with `wake` whenever the shown percentage changes.
    pub fn waking(wake: Arc<dyn Fn() + Send + Sync>) -> Self {
        Self {
            wake: Some(wake),
            ..Self::default()
        }
    }

    /// Wakes the editor (its job ended, or the shown percentage changed).
    pub fn wake(&self) {
        if let Some(w) = &self.wake {
            w();
        }
    }

    /// Sets the part done (0..=1); returns false once a cancel was asked.
    pub fn set(&self, done: f64) -> bool {
        let done = done.clamp(0.0, 1.0);
        let before = self.done.swap(done.to_bits(), Ordering::Relaxed);
        if (f64::from_bits(before) * 100.0).floor() != (done * 100.0).floor() {
            self.wake();
        }
        !self.cancelled()
    }

    /// The part done.
    pub fn done(&self) -> f64 {
        f64::from_bits(self.done.load(Ordering::Relaxed))
    }

    /// Asks the job to stop.
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    /// Seconds since the job started.
    pub fn elapsed(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }

    /// Whether a cancel was asked.
    pub fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// Seconds left at the pace so far (None until something is done).
    pub fn remaining(&self) -> Option<f64> {
        let done = self.done();
        (done > 0.0).then(|| self.started.elapsed().as_secs_f64() * (1.0 - done) / done)
    }
}

/// The progress window: `what` under the title, the bar, the time left and Cancel.
pub fn window(ctx: &egui::Context, title: &str, what: &str, p: &TaskProgress) {
    egui::Window::new(title)
        .collapsible(false)
        .resizable(false)
        .show(ctx, |ui| {
            ui.label(what);
            ui.add(egui::ProgressBar::new(p.done() as f32).show_percentage());
            let left = match (p.cancelled(), p.remaining()) {
                (true, _) => "stopping…".to_string(),
                (false, None) => "estimating the time left…".to_string(),
                (false, Some(s)) => format!("about {} left", seconds(s)),
            };
            ui.label(left);
            if ui
                .add_enabled(!p.cancelled(), egui::Button::new("Cancel"))
                .clicked()
            {
                p.cancel();
            }
        });
}

/// Seconds as `1 h 2 min`, `3 min 4 s` or `5 s`.
pub fn seconds(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    match s {
        0..60 => format!("{s} s"),
        60..3600 => format!("{} min {} s", s / 60, s % 60),
        _ => format!("{} h {} min", s / 3600, s % 3600 / 60),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn progress_counts_down_and_a_cancel_is_seen() {
        let p = TaskProgress::default();
        assert_eq!(p.remaining(), None);
        std::thread::sleep(std::time::Duration::from_millis(20));
        assert!(p.set(0.25));
        let left = p.remaining().unwrap();
        assert!(left > 0.0 && left < 10.0, "{left}");
        p.cancel();
        assert!(!p.set(0.5));
        assert_eq!(p.done(), 0.5);
        assert_eq!(seconds(3725.0), "1 h 2 min");
        assert_eq!(seconds(64.0), "1 min 4 s");
    }
}
