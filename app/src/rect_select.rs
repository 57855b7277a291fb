//! Selection by a rectangle dragged on the screen: every solid voxel whose centre shows inside
//! it, through all depth — or only the visible ones: the voxel each pixel of the rectangle
//! sees first (one exact ray cast per pixel centre, the pixels of the viewport the rectangle
//! was dragged in).
//!
//! The rectangle is kept with the camera, the aspect and the pixel count it was dragged
//! with (`ScreenRect`), so a script replays it to the same voxels whatever the window.
//! Through all depth it works a brick at a time: a brick in front of the eye whose eight
//! corners all show inside is taken whole, one whose corners all lie beyond one side is
//! skipped (a box's picture lies within its corners' hull), any other is tested voxel by
//! voxel.

use brickmap::{Mask, Ray, VoxelSet, WorldView};
use glam::{DVec3, IVec3};
use render::Camera;
use serde::{Deserialize, Serialize};

/// The most rays a visible-only rectangle casts (a larger one samples every k-th pixel).
pub const MAX_RAYS: u64 = 4 << 20;

/// A rectangle on the screen and the view it was dragged in.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScreenRect {
    /// The camera.
    pub camera: Camera,
    /// The viewport's width / height.
    pub aspect: f64,
    /// The viewport's pixels (width, height): the visible-only mode's rays.
    pub pixels: (u32, u32),
    /// One corner, as the (u, v) of [`Camera::ray`] (each in −1..=1, v up).
    pub a: (f64, f64),
    /// The opposite corner.
    pub b: (f64, f64),
    /// Only the voxels a pixel sees first.
    pub visible_only: bool,
}

impl ScreenRect {
    fn lo_hi(&self) -> ((f64, f64), (f64, f64)) {
        (
            (self.a.0.min(self.b.0), self.a.1.min(self.b.1)),
            (self.a.0.max(self.b.0), self.a.1.max(self.b.1)),
        )
    }

    /// Whether the point shows inside the rectangle.
    fn shows(&self, p: DVec3) -> bool {
        let (lo, hi) = self.lo_hi();
        self.camera
            .project(p, self.aspect)
            .is_some_and(|(u, v)| u >= lo.0 && u <= hi.0 && v >= lo.1 && v <= hi.1)
    }
}

/// The voxels the rectangle selects in `view`.
pub fn rect_set(view: &WorldView<'_>, rect: &ScreenRect) -> VoxelSet {
    if !(rect.aspect.is_finite() && rect.aspect > 0.0) {
        return VoxelSet::new();
    }
    if rect.visible_only {
        visible(view, rect)
    } else {
        through(view, rect)
    }
}

/// Every solid voxel whose centre shows inside.
fn through(view: &WorldView<'_>, rect: &ScreenRect) -> VoxelSet {
    let (lo, hi) = rect.lo_hi();
    let mut set = VoxelSet::new();
    view.for_each_brick(|b, solid, _| {
        let min = b.as_ivec3() * 8;
        // The brick's voxel centres span min + 0.5 ..= min + 7.5.
        let corners: Vec<Option<(f64, f64)>> = (0..8)
            .map(|k| {
                let c = DVec3::new(
                    if k & 1 == 0 { 0.5 } else { 7.5 },
                    if k & 2 == 0 { 0.5 } else { 7.5 },
                    if k & 4 == 0 { 0.5 } else { 7.5 },
                );
                rect.camera.project(min.as_dvec3() + c, rect.aspect)
            })
            .collect();
        if corners.iter().all(Option::is_some) {
            let c: Vec<(f64, f64)> = corners.into_iter().flatten().collect();
            let beyond = c.iter().all(|p| p.0 < lo.0)
                || c.iter().all(|p| p.0 > hi.0)
                || c.iter().all(|p| p.1 < lo.1)
                || c.iter().all(|p| p.1 > hi.1);
            if beyond {
                return;
            }
            let within = c
                .iter()
                .all(|p| p.0 >= lo.0 && p.0 <= hi.0 && p.1 >= lo.1 && p.1 <= hi.1);
            if within {
                set.set_brick(b, *solid);
                return;
            }
        }
        let mut m = Mask::EMPTY;
        for bit in solid.ones() {
            let l = IVec3::new(bit as i32 & 7, (bit as i32 >> 3) & 7, bit as i32 >> 6);
            if rect.shows((min + l).as_dvec3() + 0.5) {
                m.set(bit);
            }
        }
        set.set_brick(b, m);
    });
    set
}

/// The voxel each pixel centre of the rectangle sees first.
fn visible(view: &WorldView<'_>, rect: &ScreenRect) -> VoxelSet {
    let (lo, hi) = rect.lo_hi();
    let (w, h) = (rect.pixels.0.max(1) as f64, rect.pixels.1.max(1) as f64);
    // Pixel columns and rows whose centres lie inside: u = (x + 0.5) / w · 2 − 1.
    let range = |l: f64, h_: f64, n: f64| {
        let first = (((l + 1.0) * 0.5 * n) - 0.5).ceil().max(0.0) as i64;
        let last = (((h_ + 1.0) * 0.5 * n) - 0.5).floor().min(n - 1.0) as i64;
        (first, last)
    };
    let (x0, x1) = range(lo.0, hi.0, w);
    let (y0, y1) = range(lo.1, hi.1, h);
    let mut set = VoxelSet::new();
    if x1 < x0 || y1 < y0 {
        return set;
    }
    let n = ((x1 - x0 + 1) * (y1 - y0 + 1)) as u64;
    let step = ((n as f64 / MAX_RAYS as f64).sqrt().ceil() as i64).max(1);
    for y in (y0..=y1).step_by(step as usize) {
        for x in (x0..=x1).step_by(step as usize) {
            let u = (x as f64 + 0.5) / w * 2.0 - 1.0;
            let v = (y as f64 + 0.5) / h * 2.0 - 1.0;
            let (origin, dir) = rect.camera.ray(u, v, rect.aspect);
            if let Ok(Some((hit, _))) = view.ray_cast(&Ray { origin, dir }, f64::INFINITY) {
                set.insert(hit.voxel);
            }
        }
    }
    set
}
