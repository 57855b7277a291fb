//! Camera paths for the benchmark (`voxbrick bench`): keyframes of position and orientation
//! in a RON file, interpolated by time (Catmull-Rom cubics over the keyframe times, yaw
//! unwrapped to the nearer turn), so where the camera is at a time does not depend on the
//! frame rate; the sun circles the scene at the path's rate.
//!
//! In detail:
//! `CameraPath`: keyframes (time, position, yaw, pitch) from RON
//! (`assets/bench/thesis_path.ron` built in), checked (≥ 2, times from 0 increasing, pitch
//! within ±89), yaw unwrapped to the nearer turn, Catmull-Rom cubics over the keyframe times
//! (`camera_at(t)`: the path does not depend on the frame rate), `sun_at(t)`: the sun turned
//! about the vertical axis through the grid centre; `PathError`.

use glam::DVec3;
use render::{Camera, Projection, Sun};
use serde::Deserialize;
use std::path::Path;

/// The thesis scene's path, built in (`assets/bench/thesis_path.ron`).
pub const THESIS_PATH: &str = include_str!("../../assets/bench/thesis_path.ron");

/// Why a path cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum PathError {
    /// The file could not be read.
    #[error("reading {path}: {source}")]
    Read {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// Not a path file.
    #[error("not a camera path: {0}")]
    Parse(String),
    /// A field is out of range.
    #[error("camera path: {0}")]
    Invalid(String),
}

/// One keyframe.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
pub struct Keyframe {
    /// Seconds from the start (0 for the first, strictly increasing).
    pub time_s: f64,
    /// Eye position, in voxels.
    pub position: (f64, f64, f64),
    /// Rotation about +y in degrees (0 looks along −z).
    pub yaw_deg: f64,
    /// Elevation in degrees, within ±89.
    pub pitch_deg: f64,
}

/// A camera path.
#[derive(Clone, Debug, Deserialize, PartialEq)]
pub struct CameraPath {
    /// The sun's rotation about the vertical axis through the grid centre, in degrees per
    /// second of path time.
    pub sun_deg_per_s: f64,
    /// At least two keyframes.
    pub keyframes: Vec<Keyframe>,
}

/// Catmull-Rom (cubic Hermite with finite-difference tangents over non-uniform times).
fn hermite(t: f64, t0: f64, t1: f64, p0: f64, p1: f64, m0: f64, m1: f64) -> f64 {
    let h = t1 - t0;
    let s = (t - t0) / h;
    let (s2, s3) = (s * s, s * s * s);
    (2.0 * s3 - 3.0 * s2 + 1.0) * p0
        + (s3 - 2.0 * s2 + s) * h * m0
        + (-2.0 * s3 + 3.0 * s2) * p1
        + (s3 - s2) * h * m1
}

impl CameraPath {
    /// Parses and checks a path.
    pub fn parse(text: &str) -> Result<Self, PathError> {
        let mut path: CameraPath =
            ron::from_str(text).map_err(|e| PathError::Parse(e.to_string()))?;
        path.validate()?;
        // Yaw unwrapped: each keyframe's within 180° of the previous one's.
        for i in 1..path.keyframes.len() {
            let prev = path.keyframes[i - 1].yaw_deg;
            let y = &mut path.keyframes[i].yaw_deg;
            *y = prev + (*y - prev + 180.0).rem_euclid(360.0) - 180.0;
        }
        Ok(path)
    }

    /// Reads a path file.
    pub fn load(path: &Path) -> Result<Self, PathError> {
        let text = std::fs::read_to_string(path).map_err(|source| PathError::Read {
            path: path.display().to_string(),
            source,
        })?;
        Self::parse(&text)
    }

    /// The built-in thesis path.
    pub fn thesis() -> Self {
        Self::parse(THESIS_PATH).expect("the built-in path is valid")
    }

    fn validate(&self) -> Result<(), PathError> {
        let bad = |m: String| Err(PathError::Invalid(m));
        if !self.sun_deg_per_s.is_finite() {
            return bad("sun_deg_per_s is not finite".into());
        }
        if self.keyframes.len() < 2 {
            return bad(format!("{} keyframes (at least 2)", self.keyframes.len()));
        }
        if self.keyframes[0].time_s != 0.0 {
            return bad("the first keyframe's time_s must be 0".into());
        }
        for (i, k) in self.keyframes.iter().enumerate() {
            let p = DVec3::from(k.position);
            if !p.is_finite() || !k.yaw_deg.is_finite() || !k.pitch_deg.is_finite() {
                return bad(format!("keyframe {i}: a value is not finite"));
            }
            if k.pitch_deg.abs() > 89.0 {
                return bad(format!("keyframe {i}: pitch {} outside ±89", k.pitch_deg));
            }
            if i > 0 && k.time_s <= self.keyframes[i - 1].time_s {
                return bad(format!("keyframe {i}: time_s must increase"));
            }
        }
        Ok(())
    }

    /// The path's length in seconds.
    pub fn duration(&self) -> f64 {
        self.keyframes.last().map_or(0.0, |k| k.time_s)
    }

    /// The camera at `t` seconds (clamped to the path), with `fov_y_deg`.
    pub fn camera_at(&self, t: f64, fov_y_deg: f64) -> Camera {
        let k = &self.keyframes;
        let t = t.clamp(0.0, self.duration());
        let i = k
            .windows(2)
            .position(|w| t <= w[1].time_s)
            .unwrap_or(k.len() - 2);
        let value = |f: &dyn Fn(&Keyframe) -> f64| {
            let slope = |a: usize, b: usize| (f(&k[b]) - f(&k[a])) / (k[b].time_s - k[a].time_s);
            let tangent = |j: usize| {
                if j == 0 {
                    slope(0, 1)
                } else if j == k.len() - 1 {
                    slope(j - 1, j)
                } else {
                    slope(j - 1, j + 1)
                }
            };
            hermite(
                t,
                k[i].time_s,
                k[i + 1].time_s,
                f(&k[i]),
                f(&k[i + 1]),
                tangent(i),
                tangent(i + 1),
            )
        };
        Camera {
            position: DVec3::new(
                value(&|k| k.position.0),
                value(&|k| k.position.1),
                value(&|k| k.position.2),
            ),
            yaw_deg: value(&|k| k.yaw_deg).rem_euclid(360.0),
            pitch_deg: value(&|k| k.pitch_deg).clamp(-89.0, 89.0),
            fov_y_deg,
            projection: Projection::Perspective,
        }
    }

    /// `sun` at `t` seconds: turned about the vertical axis through `grid_centre` by
    /// `sun_deg_per_s · t` (its height and distance kept).
    pub fn sun_at(&self, sun: &Sun, t: f64, grid_centre: DVec3) -> Sun {
        let a = (self.sun_deg_per_s * t).to_radians();
        let r = sun.position - grid_centre;
        let (s, c) = a.sin_cos();
        Sun {
            position: grid_centre + DVec3::new(c * r.x + s * r.z, r.y, -s * r.x + c * r.z),
            ..sun.clone()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_path_passes_through_its_keyframes_and_is_smooth() {
        let p = CameraPath::thesis();
        assert_eq!(p.duration(), 20.0);
        for k in &p.keyframes {
            let c = p.camera_at(k.time_s, 60.0);
            assert!(
                (c.position - DVec3::from(k.position)).length() < 1e-9,
                "{k:?}"
            );
            let dy = (c.yaw_deg - k.yaw_deg).rem_euclid(360.0);
            assert!(!(1e-9..=360.0 - 1e-9).contains(&dy), "{k:?}: {}", c.yaw_deg);
            assert!((c.pitch_deg - k.pitch_deg).abs() < 1e-9);
        }
        // Continuous: small time steps make small moves, and yaw never jumps a whole turn
        // (150° follows −160°: 50° the short way).
        let mut prev = p.camera_at(0.0, 60.0);
        for i in 1..=2000 {
            let c = p.camera_at(i as f64 * 0.01, 60.0);
            assert!((c.position - prev.position).length() < 1.5, "at {i}");
            let dy = (c.yaw_deg - prev.yaw_deg + 180.0).rem_euclid(360.0) - 180.0;
            assert!(
                dy.abs() < 1.0,
                "yaw at {i}: {} → {}",
                prev.yaw_deg,
                c.yaw_deg
            );
            prev = c;
        }
        // Between −160° (t = 3) and 150° (t = 6) the yaw passes 180°, not 0°.
        let mid = p.camera_at(4.5, 60.0).yaw_deg;
        assert!((150.0..=210.0).contains(&mid), "{mid}");
        // Past the end: the last keyframe.
        assert_eq!(
            p.camera_at(99.0, 60.0).position,
            p.camera_at(20.0, 60.0).position
        );
    }

    #[test]
    fn the_sun_circles_the_centre() {
        let p = CameraPath::thesis();
        let sun = Sun {
            enabled: true,
            position: DVec3::new(356.0, 400.0, 256.0),
            radius: 20.0,
            colour: [1.0; 3],
            intensity: 10.0,
            animate: true,
            speed_deg_per_s: 0.0,
        };
        let centre = DVec3::new(256.0, 128.0, 256.0);
        let s = p.sun_at(&sun, 10.0, centre); // 90°
        assert!(
            (s.position - DVec3::new(256.0, 400.0, 156.0)).length() < 1e-9,
            "{}",
            s.position
        );
        assert_eq!(p.sun_at(&sun, 0.0, centre).position, sun.position);
    }

    #[test]
    fn bad_paths_are_refused_with_the_reason() {
        let one = "(sun_deg_per_s: 1.0, keyframes: [(time_s: 0.0, position: (0.0, 0.0, 0.0), yaw_deg: 0.0, pitch_deg: 0.0)])";
        assert!(
            CameraPath::parse(one)
                .unwrap_err()
                .to_string()
                .contains("at least 2")
        );
        let back = one.replace(
            ")])",
            "), (time_s: 0.0, position: (1.0, 0.0, 0.0), yaw_deg: 0.0, pitch_deg: 0.0)])",
        );
        assert!(
            CameraPath::parse(&back)
                .unwrap_err()
                .to_string()
                .contains("increase")
        );
        let steep = back
            .replace("time_s: 0.0, position: (1.0", "time_s: 1.0, position: (1.0")
            .replace("pitch_deg: 0.0)])", "pitch_deg: 90.0)])");
        assert!(
            CameraPath::parse(&steep)
                .unwrap_err()
                .to_string()
                .contains("±89")
        );
        assert!(matches!(
            CameraPath::parse("[1, 2]"),
            Err(PathError::Parse(_))
        ));
        assert!(matches!(
            CameraPath::load(Path::new("/no/such/path.ron")),
            Err(PathError::Read { .. })
        ));
    }
}
