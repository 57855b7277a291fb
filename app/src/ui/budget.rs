//! The frame budget: how much tracing one frame may do, from the GPU time the last frames
//! took. Samples per frame follow it first (about 16 ms of tracing a frame, 1 to 16
//! samples); when even one sample per pixel takes longer than [`BUDGET`], the traced
//! resolution shrinks, down to [`FLOOR`] of the internal size, so that the panels, menus
//! and the cursor keep a usable rate on any device (lavapipe on two loaded cores took 1–3 s
//! a frame at 960 × 540). It grows back when frames are fast again. Hysteresis keeps a
//! still camera's accumulation from restarting: the scale changes only when the time is
//! well outside the budget.

/// The longest a frame's tracing should take, in seconds: ten frames a second for the UI.
/// (Tighter budgets only hit the floor on lavapipe, where the passes at the output size
/// cost ~50 ms whatever is traced.)
pub const BUDGET: f64 = 0.1;
/// The smallest scale of the internal size the budget may pick.
pub const FLOOR: f32 = 0.125;

/// Samples per frame and the resolution scale the budget allows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameBudget {
    /// Samples per pixel a frame adds at most.
    pub spp: u32,
    /// Scale of the internal resolution (1: as set; down to [`FLOOR`]).
    pub scale: f32,
    /// The last frame measured at a scale the budget picked: (fraction of the pixels, its
    /// time). Two sizes give the part of a frame's time that does not shrink with the
    /// pixels (display, denoiser, dispatch).
    seen: Option<(f64, f64)>,
    /// Measurements still to pass over after a change of scale or samples: a frame's GPU
    /// time is read back when its slot comes round, so the next ones are of frames made
    /// before the change.
    skip: u8,
}

/// Frames whose time is still the old size's after a change of scale (the frames in
/// flight, and one more).
const LAG: u8 = 3;

impl Default for FrameBudget {
    fn default() -> Self {
        Self {
            spp: 1,
            scale: 1.0,
            seen: None,
            skip: 0,
        }
    }
}

impl FrameBudget {
    /// The next frame's budget after one whose tracing took `gpu` seconds.
    pub fn update(&mut self, gpu: f64) {
        if !gpu.is_finite() || gpu < 0.0 {
            return;
        }
        if self.skip > 0 {
            self.skip -= 1;
            return;
        }
        if gpu < 0.008 && self.spp < 16 && self.scale >= 1.0 {
            self.spp *= 2;
            self.skip = LAG;
        } else if gpu > 0.033 && self.spp > 1 {
            self.spp /= 2;
            self.skip = LAG;
        } else if self.spp == 1 && gpu > BUDGET * 1.5 {
            self.shrink(gpu);
        } else if self.scale < 1.0 && gpu < BUDGET / 3.0 {
            self.seen = Some((f64::from(self.scale).powi(2), gpu));
            self.scale = (self.scale * 1.25).min(1.0);
            self.skip = LAG;
        }
    }

    /// A frame over budget at one sample: the scale whose pixels fit 80 % of the budget
    /// beside the fixed part; where the fixed part alone is over it, the scale at which
    /// tracing costs as much as the fixed part (smaller would blur the image and gain
    /// little). Changes under 10 % are not made (each restarts the accumulation).
    fn shrink(&mut self, gpu: f64) {
        let q = f64::from(self.scale).powi(2);
        let (fixed, per_q) = match self.seen {
            Some((q0, t0)) if (q0 - q).abs() > 0.2 * q0.max(q) => {
                let per_q = ((t0 - gpu) / (q0 - q)).max(1e-9);
                // This size becomes the pair's other end.
                self.seen = Some((q, gpu));
                ((gpu - per_q * q).max(0.0), per_q)
            }
            // The same size again: the pair stays (a second look at one size says nothing
            // about the fixed part) — unless the time moved by half (a heavier scene, a
            // busier machine): then it starts again from this frame.
            Some((_, t0)) if (gpu - t0).abs() <= 0.5 * t0 => return,
            _ => {
                self.seen = Some((q, gpu));
                (0.0, gpu / q)
            }
        };
        let want = 0.8 * BUDGET - fixed;
        let q_new = if want > 0.0 {
            want / per_q
        } else {
            fixed / per_q
        };
        let to = (q_new.sqrt() as f32).clamp(FLOOR, 1.0);
        if (to - self.scale).abs() > 0.1 * self.scale {
            self.scale = to;
            self.skip = LAG;
        }
    }

    /// `internal` scaled by the budget (at least one pixel each way).
    pub fn apply(&self, (w, h): (u32, u32)) -> (u32, u32) {
        let f = f64::from(self.scale);
        (
            ((f64::from(w) * f).round() as u32).max(1),
            ((f64::from(h) * f).round() as u32).max(1),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A device whose tracing time is `per_pixel` seconds per traced pixel and sample.
    fn run(b: &mut FrameBudget, per_pixel: f64, frames: usize) -> Vec<FrameBudget> {
        run_with(b, 0.0, per_pixel, frames)
    }

    /// The same with `fixed` seconds a frame whatever is traced; as in the editor, the time
    /// a frame learns is the one of the frame two before (read back when its slot is reused).
    fn run_with(
        b: &mut FrameBudget,
        fixed: f64,
        per_pixel: f64,
        frames: usize,
    ) -> Vec<FrameBudget> {
        let internal = (480u32, 480u32);
        let mut in_flight = std::collections::VecDeque::new();
        (0..frames)
            .map(|_| {
                let (w, h) = b.apply(internal);
                in_flight.push_back(fixed + per_pixel * f64::from(w * h) * f64::from(b.spp));
                if in_flight.len() > 2 {
                    b.update(in_flight.pop_front().unwrap());
                }
                *b
            })
            .collect()
    }

    #[test]
    fn a_fixed_cost_per_frame_settles_above_the_floor() {
        // lavapipe as measured: ~1 s at 488 × 494, of which ~55 ms does not shrink.
        let per_pixel = 0.95 / (488.0 * 494.0);
        let mut b = FrameBudget::default();
        let steps = run_with(&mut b, 0.055, per_pixel, 60);
        assert!(b.scale > FLOOR, "{b:?}");
        let (w, h) = b.apply((480, 480));
        assert!(0.055 + per_pixel * f64::from(w * h) <= BUDGET * 1.5);
        assert!(steps[40..].windows(2).all(|p| p[0] == p[1]), "{steps:?}");
        // A fixed part over the budget on its own: no shrinking to the floor for nothing.
        let mut b = FrameBudget::default();
        let steps = run_with(&mut b, 0.13, per_pixel, 60);
        assert!(b.scale > 0.3, "{b:?}");
        assert!(
            steps[15..].windows(2).all(|p| p[0].scale == p[1].scale),
            "{steps:?}"
        );
    }

    #[test]
    fn a_slow_device_traces_fewer_pixels_until_a_frame_fits_the_budget() {
        // lavapipe-like: one sample of 480 × 480 takes 1.2 s.
        let per_pixel = 1.2 / (480.0 * 480.0);
        let mut b = FrameBudget::default();
        let steps = run(&mut b, per_pixel, 40);
        let (w, h) = b.apply((480, 480));
        let t = per_pixel * f64::from(w * h);
        assert!(t <= BUDGET * 1.5, "{t} s a frame at {b:?}");
        assert_eq!(b.spp, 1);
        // Settled: the last frames keep one scale (a still view's accumulation goes on).
        assert!(steps[25..].windows(2).all(|p| p[0] == p[1]), "{steps:?}");
    }

    #[test]
    fn the_floor_holds_on_a_hopeless_device_and_a_fast_one_gets_back_to_full_size() {
        let mut b = FrameBudget::default();
        run(&mut b, 100.0 / (480.0 * 480.0), 40);
        assert_eq!(b.scale, FLOOR);
        run(&mut b, 1e-9, 80);
        assert_eq!(b.scale, 1.0);
        assert_eq!(b.spp, 16, "fast frames add samples once at full size");
    }

    #[test]
    fn a_fast_device_is_never_scaled_down() {
        let mut b = FrameBudget::default();
        let steps = run(&mut b, 0.004 / (480.0 * 480.0), 30);
        assert!(steps.iter().all(|s| s.scale == 1.0));
        assert_eq!(b.spp, 2, "4 ms a sample: two a frame (8 ms)");
    }
}
