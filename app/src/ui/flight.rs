//! Fly keys held (W A S D, Q / E) and their clock: the camera moves by the time since the
//! last tick (a key's press, a frame, a release), so a second of holding goes as far at any
//! frame rate. Without a window a tick is a fixed 1/60 s, so that a headless session is a
//! function of its input.

use super::input;
use glam::DVec3;
use std::collections::HashSet;
use std::time::Instant;
use winit::keyboard::KeyCode;

/// The fly keys held and the time of the last tick.
pub(super) struct Flight {
    keys: HashSet<KeyCode>,
    last_tick: Instant,
    fixed_step: bool,
}

impl Flight {
    /// No key held; `fixed_step`: every tick is 1/60 s (headless).
    pub(super) fn new(fixed_step: bool) -> Self {
        Self {
            keys: HashSet::new(),
            last_tick: Instant::now(),
            fixed_step,
        }
    }

    /// Ticks measure the time that passed, also without a window.
    pub(super) fn in_real_time(&mut self) {
        self.fixed_step = false;
    }

    /// Whether any fly key is held.
    pub(super) fn is_flying(&self) -> bool {
        !self.keys.is_empty()
    }

    /// Whether `code` is held as a fly key.
    pub(super) fn holds(&self, code: KeyCode) -> bool {
        self.keys.contains(&code)
    }

    /// A fly key went down (tick first when others are held: they fly until now in their
    /// old direction); the first key starts the clock.
    pub(super) fn press(&mut self, code: KeyCode) {
        if self.keys.is_empty() {
            self.last_tick = Instant::now();
        }
        self.keys.insert(code);
    }

    /// A fly key went up (tick first: the flight lasts until the release).
    pub(super) fn release(&mut self, code: KeyCode) {
        self.keys.remove(&code);
    }

    /// The move since the last tick at `speed` voxels per second, in the camera's axes
    /// (right, up, forward); None when no key is held. Restarts the clock either way.
    pub(super) fn step(&mut self, speed: f64) -> Option<DVec3> {
        let now = Instant::now();
        let dt = if self.fixed_step {
            1.0 / 60.0
        } else {
            (now - self.last_tick).as_secs_f64()
        };
        self.last_tick = now;
        if self.keys.is_empty() {
            return None;
        }
        let dir: DVec3 = self.keys.iter().filter_map(|k| input::fly_axis(*k)).sum();
        Some(dir * speed * dt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fixed_step_flight_moves_a_sixtieth_of_a_second_per_tick() {
        let mut f = Flight::new(true);
        assert!(f.step(60.0).is_none(), "nothing held");
        f.press(KeyCode::KeyW);
        assert!(f.is_flying() && f.holds(KeyCode::KeyW));
        assert_eq!(f.step(60.0), Some(DVec3::Z));
        f.press(KeyCode::KeyD);
        assert_eq!(f.step(60.0), Some(DVec3::new(1.0, 0.0, 1.0)));
        f.release(KeyCode::KeyW);
        f.release(KeyCode::KeyD);
        assert!(!f.is_flying());
        assert!(f.step(60.0).is_none());
    }

    #[test]
    fn a_real_time_flight_moves_by_the_time_that_passed() {
        let mut f = Flight::new(true);
        f.in_real_time();
        f.press(KeyCode::KeyE);
        std::thread::sleep(std::time::Duration::from_millis(20));
        let up = f.step(10.0).unwrap();
        assert!(up.x == 0.0 && up.z == 0.0 && up.y >= 0.2, "{up}");
    }
}
