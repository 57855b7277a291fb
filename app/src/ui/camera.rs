//! The editor's view camera: view state, not history. It wraps the renderer's pinhole
//! [`Camera`] (so a scene camera is shown exactly) plus the distance to the pivot it orbits;
//! orbit keeps the pivot and its distance, pan keeps the orientation, zoom keeps the point
//! under the cursor where it is on screen, fly moves eye and pivot together.

use glam::DVec3;
use render::Camera;

/// The pitch limit (the renderer's camera takes −89..=89 degrees).
const PITCH_LIMIT: f64 = 89.0;
/// Nearest the eye gets to the pivot, in voxels.
const MIN_DISTANCE: f64 = 0.5;

/// A camera orbiting a pivot.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewCamera {
    /// The pinhole camera the renderer gets.
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
        // is 2·dy in v and 2·dx/aspect in u, at the pivot's distance.
        self.camera.position -= (right * (2.0 * dx / aspect) + up * (2.0 * dy)) * self.distance;
    }

    /// Zooms by `factor` (< 1 nearer) towards `target`, a point on the ray through the
    /// cursor (the surface hit, or the pivot plane): eye and pivot scale about it, so it
    /// stays under the cursor and the orientation is kept.
    pub fn zoom_towards(&mut self, target: DVec3, factor: f64) {
        let factor = factor.clamp(1e-3, 1e3);
        let new_distance = (self.distance * factor).max(MIN_DISTANCE);
        let factor = new_distance / self.distance;
        self.camera.position = target + (self.camera.position - target) * factor;
        self.distance = new_distance;
    }

    /// The direction of the ray through normalized device coordinates (u, v) ∈ [−1, 1]²
    /// (v up), as the renderers compute it.
    pub fn ray(&self, u: f64, v: f64, aspect: f64) -> DVec3 {
        let (f, r, up) = self.camera.basis(aspect);
        (f + r * u + up * v).normalize()
    }

    /// Where the cursor's ray meets the plane through the pivot facing the camera.
    pub fn pivot_plane_point(&self, u: f64, v: f64, aspect: f64) -> DVec3 {
        let (f, r, up) = self.camera.basis(aspect);
        // The unnormalized ray has unit length along `forward`.
        self.camera.position + (f + r * u + up * v) * self.distance
    }

    /// Flies: moves eye and pivot by `local` (right, up, forward) in voxels.
    pub fn fly(&mut self, local: DVec3) {
        let f = self.camera.forward();
        let right = f.cross(DVec3::Y).normalize_or(DVec3::X);
        self.camera.position += right * local.x + DVec3::Y * local.y + f * local.z;
    }

    /// Frames a box: keeps the orientation, pivots on its centre and backs off until its
    /// bounding sphere fits the vertical field of view.
    pub fn frame(&mut self, min: DVec3, max: DVec3) {
        let (camera, distance) = self.camera.framing(min, max);
        *self = Self::from_camera(camera, distance);
    }

    /// Where a world point appears, in normalized device coordinates (None behind the eye).
    pub fn project(&self, p: DVec3, aspect: f64) -> Option<(f64, f64)> {
        let (f, r, up) = self.camera.basis(aspect);
        let d = p - self.camera.position;
        let z = d.dot(f);
        (z > 1e-9).then(|| {
            (
                d.dot(r) / r.length_squared() / z,
                d.dot(up) / up.length_squared() / z,
            )
        })
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
        let hit = v.camera.position + v.ray(0.4, 0.1, aspect) * 12.0;
        let before = v.project(hit, aspect).unwrap();
        v.zoom_towards(hit, 0.7);
        let after = v.project(hit, aspect).unwrap();
        assert!((before.0 - after.0).abs() < 1e-9 && (before.1 - after.1).abs() < 1e-9);
    }

    #[test]
    fn framing_puts_the_box_in_view() {
        let mut v = view();
        let (min, max) = (DVec3::ZERO, DVec3::new(96.0, 48.0, 96.0));
        v.frame(min, max);
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
}
