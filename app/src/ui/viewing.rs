//! The view and where it shows: the camera the viewport looks through, the nine stored
//! views (Ctrl + 1–9 store, 1–9 recall), the window's size and the viewport's area in it
//! (what the bars and docked panels leave, as last drawn). The geometry input and frames
//! ask of it: the aspect, a window point's normalized coordinates and ray, where a world
//! point shows.

use super::camera::ViewCamera;
use glam::DVec3;

/// The view camera, the stored views, the window and the viewport's area.
#[derive(Debug)]
pub(super) struct Viewing {
    /// The camera looked through (orbit, pan, zoom, fly, frame).
    pub camera: ViewCamera,
    slots: [Option<ViewCamera>; 9],
    window: (u32, u32),
    area: (u32, u32, u32, u32),
}

impl Viewing {
    /// A view through `camera` of a window not drawn yet.
    pub fn new(camera: ViewCamera) -> Self {
        Self {
            camera,
            slots: Default::default(),
            window: (16, 9),
            area: (0, 0, 16, 9),
        }
    }

    /// Stores the view in slot `n` (1–9).
    pub fn store(&mut self, n: u8) {
        if let Some(s) = self.slots.get_mut(usize::from(n).wrapping_sub(1)) {
            *s = Some(self.camera.clone());
        }
    }

    /// Moves the view and every stored view by `d` (the scene moved into a larger grid:
    /// what was in view stays in view).
    pub fn shift(&mut self, d: DVec3) {
        for c in std::iter::once(&mut self.camera).chain(self.slots.iter_mut().flatten()) {
            c.camera.position += d;
        }
    }

    /// The view stored in slot `n` (1–9), if any.
    pub fn stored(&self, n: u8) -> Option<ViewCamera> {
        self.slots
            .get(usize::from(n).wrapping_sub(1))
            .cloned()
            .flatten()
    }

    /// The window's size in physical pixels.
    pub fn window(&self) -> (u32, u32) {
        self.window
    }

    /// The window was resized.
    pub fn set_window(&mut self, size: (u32, u32)) {
        self.window = size;
    }

    /// Where the viewport shows (x, y, width, height in pixels).
    pub fn area(&self) -> (u32, u32, u32, u32) {
        self.area
    }

    /// The viewport's area as drawn this frame; true when it changed.
    pub fn set_area(&mut self, area: (u32, u32, u32, u32)) -> bool {
        std::mem::replace(&mut self.area, area) != area
    }

    /// The viewport's width over its height.
    pub fn aspect(&self) -> f64 {
        let (_, _, w, h) = self.area;
        w.max(1) as f64 / h.max(1) as f64
    }

    /// Normalized device coordinates of a window point in the viewport (v up).
    pub fn ndc(&self, (x, y): (f64, f64)) -> (f64, f64) {
        let (x0, y0, w, h) = self.area;
        (
            2.0 * (x - f64::from(x0)) / w.max(1) as f64 - 1.0,
            1.0 - 2.0 * (y - f64::from(y0)) / h.max(1) as f64,
        )
    }

    /// The view's ray through a window point.
    pub fn ray_at(&self, p: (f64, f64)) -> (DVec3, DVec3) {
        let (u, v) = self.ndc(p);
        self.camera.ray(u, v, self.aspect())
    }

    /// Where world point `p` shows in the window, in pixels (None behind the eye).
    pub fn window_point(&self, p: DVec3) -> Option<(f64, f64)> {
        let (u, v) = self.camera.project(p, self.aspect())?;
        let (x0, y0, w, h) = self.area;
        Some((
            f64::from(x0) + (u + 1.0) * 0.5 * f64::from(w),
            f64::from(y0) + (1.0 - v) * 0.5 * f64::from(h),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_window_point_and_its_ray_agree_and_slots_keep_views() {
        let camera = render::SceneParams::framing(DVec3::splat(64.0)).camera;
        let mut v = Viewing::new(ViewCamera::for_scene(camera, DVec3::splat(32.0)));
        assert!(v.set_area((100, 20, 800, 400)));
        assert!(!v.set_area((100, 20, 800, 400)));
        assert_eq!(v.aspect(), 2.0);
        assert_eq!(v.ndc((500.0, 220.0)), (0.0, 0.0));
        let p = DVec3::new(30.0, 10.0, 35.0);
        let at = v.window_point(p).expect("in front of the camera");
        let (o, d) = v.ray_at(at);
        let along = (p - o).dot(d);
        assert!(
            (o + d * along - p).length() < 1e-6,
            "the ray through the point meets it"
        );
        assert_eq!(v.stored(3), None);
        v.store(3);
        let before = v.camera.clone();
        v.camera.orbit(40.0, 10.0);
        assert_eq!(v.stored(3), Some(before));
        v.store(0);
        v.store(10);
        assert_eq!(v.stored(0), None, "slots are 1–9");
    }
}
