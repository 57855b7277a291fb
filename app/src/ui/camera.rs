//! The editor's view camera: view state, not history. It wraps the renderer's [`Camera`]
//! (so a scene camera is shown exactly) plus the distance to the pivot it orbits; orbit
//! keeps the pivot and its distance, pan keeps the orientation, zoom keeps the point under
//! the cursor where it is on screen, fly moves eye and pivot together, and the projection
//! toggle keeps the pivot and the size things have on the pivot plane.
//!
//! In detail:
//! `ViewCamera`: the scene's `Camera` plus the pivot distance; orbit (keeps pivot and
//! distance), pan (keeps orientation, scene follows the cursor), zoom towards the point under
//! the cursor (exact CPU cast hit, else the pivot plane; keeps its pixel; orthographic: the
//! height scales and the image plane stays), fly, frame a box, the perspective / orthographic
//! toggle (O, Numpad 5: keeps the pivot and the pivot plane's scale; going orthographic, the
//! eye backs off until the grid is in front of the image plane). View state, never history;
//! "use this view as the scene camera" is `SetCamera`.

use glam::DVec3;
use render::{Camera, Projection};

/// The pitch limit (the renderer's camera takes −89..=89 degrees).
const PITCH_LIMIT: f64 = 89.0;
/// Nearest the eye gets to the pivot, in voxels.
const MIN_DISTANCE: f64 = 0.5;

/// A camera orbiting a pivot.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewCamera {
    /// The camera the renderer gets.
    pub camera: Camera,
    /// Distance from the eye to the pivot along the view direction.
    pub distance: f64,
}

impl ViewCamera {
    /// The view of a scene camera, orbiting the point `distance` ahead of it.
    pub fn from_camera(camera: Camera, distance: f64) -> Self {
        Self {
            camera,
            distance: distance.max(MIN_DISTANCE),
        }
    }

    /// A scene camera viewed as it is, orbiting the point of the view axis nearest to
    /// `centre` (at least a voxel ahead).
    pub fn for_scene(camera: Camera, centre: DVec3) -> Self {
        let ahead = (centre - camera.position).dot(camera.forward());
        Self::from_camera(camera, ahead.max(1.0))
    }

    /// The point the camera orbits.
    pub fn pivot(&self) -> DVec3 {
        self.camera.position + self.camera.forward() * self.distance
    }

    /// Rotates about the pivot by yaw and pitch increments in degrees.
    pub fn orbit(&mut self, yaw_deg: f64, pitch_deg: f64) {
        let pivot = self.pivot();
        let c = &mut self.camera;
        c.yaw_deg = (c.yaw_deg + yaw_deg).rem_euclid(360.0);
        c.pitch_deg = (c.pitch_deg + pitch_deg).clamp(-PITCH_LIMIT, PITCH_LIMIT);
        c.position = pivot - c.forward() * self.distance;
    }

    /// Moves eye and pivot in the view plane by a fraction of the view's height (`dx`
    /// right, `dy` up), so the scene follows the cursor.
    pub fn pan(&mut self, dx: f64, dy: f64, aspect: f64) {
        let aspect = aspect.max(1e-9);
        let (_, right, up) = self.camera.basis(aspect);
        // Normalized device coordinates span 2 over the image: a drag of `dy` of the height
        // is 2·dy in v and 2·dx/aspect in u, at the pivot's distance (orthographic: the basis
        // is already in voxels at every distance).
        let scale = if self.camera.is_orthographic() {
            1.0
        } else {
            self.distance
        };
        self.camera.position -= (right * (2.0 * dx / aspect) + up * (2.0 * dy)) * scale;
    }

    /// Zooms by `factor` (< 1 nearer) towards `target`, a point on the ray through the
    /// cursor (the surface hit, or the pivot plane): eye and pivot scale about it, so it
    /// stays under the cursor and the orientation is kept.
    /// Orthographic: the view's height scales instead and the eye moves only in its plane
    /// (the plane does not move into the scene).
    pub fn zoom_towards(&mut self, target: DVec3, factor: f64) {
        let factor = factor.clamp(1e-3, 1e3);
        if let Projection::Orthographic { height } = &mut self.camera.projection {
            let new_height = (*height * factor).clamp(MIN_DISTANCE, 1e8);
            let factor = new_height / *height;
            *height = new_height;
            let f = self.camera.forward();
            let offset = self.camera.position - target;
            let along = f * offset.dot(f);
            self.camera.position = target + along + (offset - along) * factor;
            return;
        }
        let new_distance = (self.distance * factor).max(MIN_DISTANCE);
        let factor = new_distance / self.distance;
        self.camera.position = target + (self.camera.position - target) * factor;
        self.distance = new_distance;
    }

    /// The ray (origin, unit direction) through normalized device coordinates
    /// (u, v) ∈ [−1, 1]² (v up), as the renderers compute it.
    pub fn ray(&self, u: f64, v: f64, aspect: f64) -> (DVec3, DVec3) {
        self.camera.ray(u, v, aspect)
    }

    /// Where the cursor's ray meets the plane through the pivot facing the camera.
    pub fn pivot_plane_point(&self, u: f64, v: f64, aspect: f64) -> DVec3 {
        let (origin, dir) = self.ray(u, v, aspect);
        let along = (origin - self.camera.position).dot(self.camera.forward());
        origin + dir * ((self.distance - along) / dir.dot(self.camera.forward()))
    }

    /// Switches between perspective and orthographic about the pivot, so that the pivot
    /// plane keeps its size on screen. Going orthographic, the eye backs off (keeping the
    /// pivot) until the box [`min`, `max`) — the scene — is in front of the image plane.
    pub fn toggle_projection(&mut self, min: DVec3, max: DVec3) {
        let pivot = self.pivot();
        let f = self.camera.forward();
        let height = self.camera.view_height_at(self.distance);
        match self.camera.projection {
            Projection::Perspective => {
                let behind = (0..8)
                    .map(|i| {
                        let c = DVec3::new(
                            if i & 1 == 0 { min.x } else { max.x },
                            if i & 2 == 0 { min.y } else { max.y },
                            if i & 4 == 0 { min.z } else { max.z },
                        );
                        (pivot - c).dot(f)
                    })
                    .fold(0.0, f64::max);
                self.distance = self.distance.max(behind + 1.0);
                self.camera.projection = Projection::Orthographic {
                    height: height.clamp(MIN_DISTANCE, 1e8),
                };
            }
            Projection::Orthographic { .. } => {
                self.camera.projection = Projection::Perspective;
                let tan = (self.camera.fov_y_deg.to_radians() * 0.5).tan();
                self.distance = (height / (2.0 * tan)).max(MIN_DISTANCE);
            }
        }
        self.camera.position = pivot - f * self.distance;
    }

    /// Flies: moves eye and pivot by `local` (right, up, forward) in voxels.
    pub fn fly(&mut self, local: DVec3) {
        let f = self.camera.forward();
        let right = f.cross(DVec3::Y).normalize_or(DVec3::X);
        self.camera.position += right * local.x + DVec3::Y * local.y + f * local.z;
    }

    /// Frames a box in a view of `aspect` (width / height): keeps the orientation, pivots
    /// on its centre and backs off until its bounding sphere fits the narrower field of view
    /// (orthographic: the view's narrower side).
    pub fn frame(&mut self, min: DVec3, max: DVec3, aspect: f64) {
        let (camera, distance) = self.camera.framing_in(min, max, aspect);
        *self = Self::from_camera(camera, distance);
    }

    /// Where a world point appears, in normalized device coordinates (None behind the eye,
    /// or behind the image plane of an orthographic view).
    pub fn project(&self, p: DVec3, aspect: f64) -> Option<(f64, f64)> {
        self.camera.project(p, aspect)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> ViewCamera {
        ViewCamera::for_scene(
            Camera::looking_at(
                DVec3::new(10.0, 40.0, 90.0),
                DVec3::new(48.0, 10.0, 30.0),
                50.0,
            ),
            DVec3::new(48.0, 10.0, 30.0),
        )
    }

    fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
        (a - b).length() < tol
    }

    #[test]
    fn a_scene_camera_is_viewed_exactly_and_orbits_its_target() {
        let v = view();
        assert_eq!(v.camera.position, DVec3::new(10.0, 40.0, 90.0));
        assert!(close(v.pivot(), DVec3::new(48.0, 10.0, 30.0), 1e-9));
    }

    #[test]
    fn orbit_keeps_the_pivot_and_its_distance() {
        let mut v = view();
        let (pivot, distance) = (v.pivot(), v.distance);
        for (yaw, pitch) in [(30.0, 10.0), (-170.0, 60.0), (45.0, -200.0), (720.5, 3.0)] {
            v.orbit(yaw, pitch);
            assert!(close(v.pivot(), pivot, 1e-9), "{:?}", v.pivot());
            assert!(((v.camera.position - pivot).length() - distance).abs() < 1e-9);
            assert!(v.camera.pitch_deg.abs() <= PITCH_LIMIT);
            assert!(v.camera.validate().is_ok());
        }
    }

    #[test]
    fn pan_keeps_the_orientation_and_moves_the_scene_with_the_cursor() {
        let mut v = view();
        let before = v.clone();
        let aspect = 16.0 / 9.0;
        let point = v.pivot();
        v.pan(0.1, 0.05, aspect);
        assert_eq!(v.camera.yaw_deg, before.camera.yaw_deg);
        assert_eq!(v.camera.pitch_deg, before.camera.pitch_deg);
        assert_eq!(v.distance, before.distance);
        // The old pivot moved right and up on screen, by the dragged fraction of the height.
        let (u, w) = v.project(point, aspect).unwrap();
        assert!((u - 0.2 / aspect).abs() < 1e-9, "{u}");
        assert!((w - 0.1).abs() < 1e-9, "{w}");
    }

    #[test]
    fn zoom_to_the_cursor_keeps_the_point_under_it() {
        let aspect = 1.5;
        for (u, w, factor) in [(0.3, -0.2, 0.8), (-0.9, 0.7, 1.25), (0.0, 0.0, 0.5)] {
            let mut v = view();
            let target = v.pivot_plane_point(u, w, aspect);
            let (pu, pw) = v.project(target, aspect).unwrap();
            assert!((pu - u).abs() < 1e-9 && (pw - w).abs() < 1e-9);
            let (yaw, pitch, d) = (v.camera.yaw_deg, v.camera.pitch_deg, v.distance);
            v.zoom_towards(target, factor);
            let (qu, qw) = v.project(target, aspect).unwrap();
            assert!((qu - u).abs() < 1e-9 && (qw - w).abs() < 1e-9, "{qu} {qw}");
            assert!((v.distance - d * factor).abs() < 1e-9);
            assert_eq!((v.camera.yaw_deg, v.camera.pitch_deg), (yaw, pitch));
        }
        // A surface point nearer than the pivot plane stays put too.
        let mut v = view();
        let (origin, dir) = v.ray(0.4, 0.1, aspect);
        let hit = origin + dir * 12.0;
        let before = v.project(hit, aspect).unwrap();
        v.zoom_towards(hit, 0.7);
        let after = v.project(hit, aspect).unwrap();
        assert!((before.0 - after.0).abs() < 1e-9 && (before.1 - after.1).abs() < 1e-9);
    }

    #[test]
    fn framing_puts_the_box_in_view() {
        let mut v = view();
        let (min, max) = (DVec3::ZERO, DVec3::new(96.0, 48.0, 96.0));
        v.frame(min, max, 1.6);
        assert!(close(v.pivot(), (min + max) * 0.5, 1e-9));
        for corner in 0..8 {
            let p = DVec3::new(
                if corner & 1 == 0 { min.x } else { max.x },
                if corner & 2 == 0 { min.y } else { max.y },
                if corner & 4 == 0 { min.z } else { max.z },
            );
            let (_, w) = v.project(p, 1.0).unwrap();
            assert!(w.abs() <= 1.0, "corner {corner} at {w}");
        }
    }

    #[test]
    fn fly_moves_eye_and_pivot_together() {
        let mut v = view();
        let (pivot, eye, forward) = (v.pivot(), v.camera.position, v.camera.forward());
        v.fly(DVec3::new(1.0, 2.0, 3.0));
        let moved = v.camera.position - eye;
        assert!(close(v.pivot() - pivot, moved, 1e-9));
        // Forward along the view, up along world y, right level with the ground.
        let right = forward.cross(DVec3::Y).normalize();
        assert!(
            close(moved, right + DVec3::Y * 2.0 + forward * 3.0, 1e-9),
            "{moved}"
        );
        assert!(right.y.abs() < 1e-12);
    }

    fn ortho() -> ViewCamera {
        let mut v = view();
        v.toggle_projection(DVec3::ZERO, DVec3::new(96.0, 48.0, 96.0));
        v
    }

    #[test]
    fn the_projection_toggle_keeps_the_pivot_and_the_pivot_planes_scale() {
        let aspect = 1.5;
        let mut v = view();
        let (pivot, yaw, pitch) = (v.pivot(), v.camera.yaw_deg, v.camera.pitch_deg);
        let points: Vec<DVec3> = [(0.5, -0.3), (-0.8, 0.6)]
            .iter()
            .map(|&(u, w)| v.pivot_plane_point(u, w, aspect))
            .collect();
        let before: Vec<_> = points
            .iter()
            .map(|p| v.project(*p, aspect).unwrap())
            .collect();
        v.toggle_projection(DVec3::ZERO, DVec3::new(96.0, 48.0, 96.0));
        assert!(v.camera.is_orthographic());
        v.camera.validate().unwrap();
        assert!(close(v.pivot(), pivot, 1e-9));
        assert_eq!((v.camera.yaw_deg, v.camera.pitch_deg), (yaw, pitch));
        for (p, b) in points.iter().zip(&before) {
            let a = v.project(*p, aspect).unwrap();
            assert!(
                (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-9,
                "{a:?} vs {b:?}"
            );
        }
        // The whole box is in front of the image plane (nothing of the scene is cut off).
        let f = v.camera.forward();
        for corner in 0..8 {
            let c = DVec3::new(
                if corner & 1 == 0 { 0.0 } else { 96.0 },
                if corner & 2 == 0 { 0.0 } else { 48.0 },
                if corner & 4 == 0 { 0.0 } else { 96.0 },
            );
            assert!((c - v.camera.position).dot(f) > 0.0, "corner {corner}");
        }
        // And back: perspective again, same pivot, same scale on the pivot plane.
        v.toggle_projection(DVec3::ZERO, DVec3::new(96.0, 48.0, 96.0));
        assert!(!v.camera.is_orthographic());
        assert!(close(v.pivot(), pivot, 1e-9));
        for (p, b) in points.iter().zip(&before) {
            let a = v.project(*p, aspect).unwrap();
            assert!(
                (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-9,
                "{a:?} vs {b:?}"
            );
        }
    }

    #[test]
    fn orthographic_rays_are_parallel_and_start_on_the_image_plane() {
        let v = ortho();
        let f = v.camera.forward();
        for (u, w) in [(0.0, 0.0), (1.0, -1.0), (-0.4, 0.9)] {
            let (origin, dir) = v.ray(u, w, 1.5);
            assert!(close(dir, f, 1e-12));
            assert!((origin - v.camera.position).dot(f).abs() < 1e-9);
            let (pu, pw) = v.project(origin + dir * 30.0, 1.5).unwrap();
            assert!((pu - u).abs() < 1e-9 && (pw - w).abs() < 1e-9);
        }
    }

    #[test]
    fn orthographic_pan_and_zoom_keep_their_promises() {
        let aspect = 16.0 / 9.0;
        let mut v = ortho();
        let point = v.pivot();
        v.pan(0.1, 0.05, aspect);
        let (u, w) = v.project(point, aspect).unwrap();
        assert!(
            (u - 0.2 / aspect).abs() < 1e-9 && (w - 0.1).abs() < 1e-9,
            "{u} {w}"
        );
        for (u, w, factor) in [(0.3, -0.2, 0.8), (-0.9, 0.7, 1.25)] {
            let mut v = ortho();
            let plane = (v.camera.position - DVec3::ZERO).dot(v.camera.forward());
            let target = v.pivot_plane_point(u, w, aspect);
            let height = v.camera.view_height_at(1.0);
            v.zoom_towards(target, factor);
            let (qu, qw) = v.project(target, aspect).unwrap();
            assert!((qu - u).abs() < 1e-9 && (qw - w).abs() < 1e-9, "{qu} {qw}");
            assert!((v.camera.view_height_at(1.0) - height * factor).abs() < 1e-9);
            // The image plane stays where it was (zoom never cuts into the scene).
            let now = (v.camera.position - DVec3::ZERO).dot(v.camera.forward());
            assert!((now - plane).abs() < 1e-9);
        }
    }

    #[test]
    fn orthographic_framing_puts_the_box_in_view_in_front_of_the_plane() {
        let mut v = ortho();
        let (min, max) = (DVec3::new(10.0, 0.0, 20.0), DVec3::new(40.0, 30.0, 50.0));
        v.frame(min, max, 1.6);
        assert!(v.camera.is_orthographic());
        for corner in 0..8 {
            let p = DVec3::new(
                if corner & 1 == 0 { min.x } else { max.x },
                if corner & 2 == 0 { min.y } else { max.y },
                if corner & 4 == 0 { min.z } else { max.z },
            );
            let (u, w) = v.project(p, 1.0).expect("in front of the image plane");
            assert!(
                u.abs() <= 1.0 && w.abs() <= 1.0,
                "corner {corner} at {u} {w}"
            );
        }
    }
}
