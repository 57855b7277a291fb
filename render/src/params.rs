//! What the renderer needs besides the voxel world: camera, sun, sky and render settings.
//! Plain data with serde, so scene files carry them as readable RON; `validate` says what is
//! out of range instead of letting a bad file reach the GPU.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A value outside its valid range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{what} = {value} is outside {range}")]
pub struct ParamError {
    /// Which parameter.
    pub what: &'static str,
    /// Its value, printed.
    pub value: String,
    /// The valid range, in words.
    pub range: &'static str,
}

fn check(
    ok: bool,
    what: &'static str,
    value: impl std::fmt::Debug,
    range: &'static str,
) -> Result<(), ParamError> {
    if ok {
        Ok(())
    } else {
        Err(ParamError {
            what,
            value: format!("{value:?}"),
            range,
        })
    }
}

fn finite3(v: DVec3) -> bool {
    v.is_finite()
}

fn colour_ok(c: [f32; 3]) -> bool {
    c.iter().all(|v| v.is_finite() && *v >= 0.0)
}

/// How camera rays leave the image plane.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum Projection {
    /// A pinhole at the camera's position with its vertical field of view.
    #[default]
    Perspective,
    /// Parallel rays along the view direction from the plane through the camera's position
    /// (nothing behind that plane is seen); the image is `height` voxels tall.
    Orthographic {
        /// Height of the view in voxels, > 0.
        height: f64,
    },
}

impl Projection {
    fn is_perspective(&self) -> bool {
        *self == Projection::Perspective
    }
}

/// A camera: position, orientation as yaw and pitch, vertical field of view, projection.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Eye position, in voxel units.
    pub position: DVec3,
    /// Rotation about +y in degrees; 0 looks along −z, 90 along −x.
    pub yaw_deg: f64,
    /// Elevation in degrees, −89..=89; positive looks up.
    pub pitch_deg: f64,
    /// Vertical field of view in degrees, in (0, 180) (kept while orthographic, for
    /// switching back).
    pub fov_y_deg: f64,
    /// Perspective (the default; files without the field are perspective, and a perspective
    /// camera is written without it) or orthographic.
    #[serde(default, skip_serializing_if = "Projection::is_perspective")]
    pub projection: Projection,
}

impl Camera {
    /// Unit view direction.
    pub fn forward(&self) -> DVec3 {
        let (yaw, pitch) = (self.yaw_deg.to_radians(), self.pitch_deg.to_radians());
        DVec3::new(
            -yaw.sin() * pitch.cos(),
            pitch.sin(),
            -yaw.cos() * pitch.cos(),
        )
    }
    /// The image-plane basis for an aspect ratio (width / height): (forward, right, up), with
    /// right and up scaled so that image position (u, v) in [−1, 1]² (v up) looks along
    /// forward + right·u + up·v from the eye (perspective: scaled by tan(fov/2)), or along
    /// forward from position + right·u + up·v (orthographic: scaled by height/2). Both
    /// renderers derive camera rays from this ([`Camera::ray`]).
    pub fn basis(&self, aspect: f64) -> (DVec3, DVec3, DVec3) {
        let forward = self.forward();
        let right = forward.cross(DVec3::Y).normalize();
        let up = right.cross(forward);
        let half = match self.projection {
            Projection::Perspective => (self.fov_y_deg.to_radians() * 0.5).tan(),
            Projection::Orthographic { height } => height * 0.5,
        };
        (forward, right * half * aspect, up * half)
    }

    /// Whether camera rays are parallel.
    pub fn is_orthographic(&self) -> bool {
        matches!(self.projection, Projection::Orthographic { .. })
    }

    /// The camera ray (origin, unit direction) through image position (u, v) ∈ [−1, 1]²,
    /// v up: what the CPU reference traces and trace.comp's `begin_path` computes in f32.
    pub fn ray(&self, u: f64, v: f64, aspect: f64) -> (DVec3, DVec3) {
        let (forward, right, up) = self.basis(aspect);
        match self.projection {
            Projection::Perspective => (self.position, (forward + right * u + up * v).normalize()),
            Projection::Orthographic { .. } => (self.position + right * u + up * v, forward),
        }
    }

    /// Where a world point appears, as the (u, v) of [`Camera::ray`] (None behind the eye, or
    /// behind the image plane of an orthographic view): the ray through it passes through
    /// the point.
    pub fn project(&self, p: DVec3, aspect: f64) -> Option<(f64, f64)> {
        let (f, r, up) = self.basis(aspect);
        let d = p - self.position;
        let z = d.dot(f);
        let depth = if self.is_orthographic() { 1.0 } else { z };
        (z > 1e-9).then(|| {
            (
                d.dot(r) / r.length_squared() / depth,
                d.dot(up) / up.length_squared() / depth,
            )
        })
    }

    /// The view height at `distance` ahead: what a perspective view shows there, and an
    /// orthographic one everywhere.
    pub fn view_height_at(&self, distance: f64) -> f64 {
        match self.projection {
            Projection::Perspective => 2.0 * distance * (self.fov_y_deg.to_radians() * 0.5).tan(),
            Projection::Orthographic { height } => height,
        }
    }

    /// The same orientation, moved back from the centre of the box [`min`, `max`) until the
    /// box's bounding sphere fits the vertical field of view (orthographic: the view is the
    /// sphere's diameter tall and its plane behind the sphere); also returns the distance
    /// from the eye to that centre. The editor's "frame the scene" and a `.vox` import's
    /// camera.
    pub fn framing(&self, min: DVec3, max: DVec3) -> (Camera, f64) {
        self.framing_in(min, max, 1.0)
    }

    /// [`Camera::framing`] for an image of `aspect` (width / height): the sphere fits the
    /// narrower of the two fields of view (the vertical one for an image at least as wide
    /// as tall, as in `framing`).
    pub fn framing_in(&self, min: DVec3, max: DVec3, aspect: f64) -> (Camera, f64) {
        let centre = (min + max) * 0.5;
        let radius = ((max - min).length() * 0.5).max(1.0);
        let aspect = if aspect.is_finite() {
            aspect.clamp(1e-3, 1.0)
        } else {
            1.0
        };
        let half_v = self.fov_y_deg.to_radians() * 0.5;
        let half_h = (half_v.tan() * aspect).atan();
        let half = half_h.sin().max(1e-3);
        let distance = radius / half;
        let projection = match self.projection {
            Projection::Perspective => Projection::Perspective,
            Projection::Orthographic { .. } => Projection::Orthographic {
                height: 2.0 * radius / aspect,
            },
        };
        let camera = Camera {
            position: centre - self.forward() * distance,
            projection,
            ..self.clone()
        };
        (camera, distance)
    }

    /// A camera at `position` looking at `target`, refusing a target that gives no direction
    /// (at the eye, or within 10⁻⁶ voxels of it) and non-finite points: what every target a
    /// user types goes through.
    pub fn aimed(position: DVec3, target: DVec3, fov_y_deg: f64) -> Result<Self, ParamError> {
        check(finite3(position), "camera eye", position, "finite numbers")?;
        check(finite3(target), "camera target", target, "finite numbers")?;
        check(
            position.distance(target) > 1e-6,
            "camera target",
            target,
            "the points away from the eye (this one is the eye: the view would have no direction)",
        )?;
        let camera = Self::looking_at(position, target, fov_y_deg);
        camera.validate()?;
        Ok(camera)
    }

    /// A camera at `position` looking at `target` (a target at the eye looks along −z; user
    /// input goes through [`Camera::aimed`], which refuses it).
    pub fn looking_at(position: DVec3, target: DVec3, fov_y_deg: f64) -> Self {
        let d = (target - position).normalize_or(DVec3::NEG_Z);
        let pitch = d.y.clamp(-1.0, 1.0).asin().to_degrees().clamp(-89.0, 89.0);
        let yaw = (-d.x).atan2(-d.z).to_degrees();
        Self {
            position,
            yaw_deg: yaw,
            pitch_deg: pitch,
            fov_y_deg,
            projection: Projection::Perspective,
        }
    }
    /// Checks every field.
    pub fn validate(&self) -> Result<(), ParamError> {
        check(
            finite3(self.position),
            "camera position",
            self.position,
            "finite numbers",
        )?;
        check(
            self.yaw_deg.is_finite(),
            "camera yaw",
            self.yaw_deg,
            "finite degrees",
        )?;
        check(
            (-89.0..=89.0).contains(&self.pitch_deg),
            "camera pitch",
            self.pitch_deg,
            "[-89, 89] degrees",
        )?;
        check(
            self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0,
            "camera fov",
            self.fov_y_deg,
            "(0, 180) degrees",
        )?;
        match self.projection {
            Projection::Perspective => Ok(()),
            Projection::Orthographic { height } => check(
                height.is_finite() && height > 0.0 && height < 1e9,
                "camera orthographic height",
                height,
                "(0, 1e9) voxels",
            ),
        }
    }
}

/// The sun: a one-sided disc facing the grid centre.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sun {
    /// Whether it lights the scene.
    pub enabled: bool,
    /// Disc centre, in voxel units.
    pub position: DVec3,
    /// Disc radius, > 0.
    pub radius: f64,
    /// Linear RGB colour.
    pub colour: [f32; 3],
    /// Radiance scale, ≥ 0.
    pub intensity: f32,
    /// Whether the sun circles the scene.
    pub animate: bool,
    /// Animation speed in degrees per second.
    pub speed_deg_per_s: f64,
}

/// The sun as both renderers sample it: a one-sided disc facing the grid centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunDisc {
    /// Disc centre.
    pub centre: DVec3,
    /// Unit normal of the emitting face (towards the grid centre).
    pub normal: DVec3,
    /// Unit vectors spanning the disc.
    pub e1: DVec3,
    /// See `e1`.
    pub e2: DVec3,
    /// Radius.
    pub radius: f64,
    /// Emitted radiance (colour × intensity).
    pub radiance: DVec3,
}

impl Sun {
    /// The disc facing `grid_centre`, or None when the sun is off, dark, or at the centre.
    pub fn disc(&self, grid_centre: DVec3) -> Option<SunDisc> {
        if !self.enabled || self.intensity <= 0.0 || self.position == grid_centre {
            return None;
        }
        let normal = (grid_centre - self.position).normalize();
        let helper = if normal.x.abs() < 0.9 {
            DVec3::X
        } else {
            DVec3::Y
        };
        let e1 = normal.cross(helper).normalize();
        let c = self.colour;
        Some(SunDisc {
            centre: self.position,
            normal,
            e1,
            e2: normal.cross(e1),
            radius: self.radius,
            radiance: DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * self.intensity as f64,
        })
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), ParamError> {
        check(
            finite3(self.position),
            "sun position",
            self.position,
            "finite numbers",
        )?;
        check(
            self.radius > 0.0 && self.radius.is_finite(),
            "sun radius",
            self.radius,
            "(0, ∞)",
        )?;
        check(
            colour_ok(self.colour),
            "sun colour",
            self.colour,
            "finite, ≥ 0",
        )?;
        check(
            self.intensity.is_finite() && self.intensity >= 0.0,
            "sun intensity",
            self.intensity,
            "[0, ∞)",
        )?;
        check(
            self.speed_deg_per_s.is_finite(),
            "sun speed",
            self.speed_deg_per_s,
            "finite",
        )
    }
}

/// Radiance arriving from directions that hit nothing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Sky {
    /// The same radiance from every direction.
    Uniform {
        /// Linear RGB radiance.
        colour: [f32; 3],
    },
    /// L(d) = (1 − t)·horizon + t·zenith with t = clamp(d.y, 0, 1).
    Gradient {
        /// Radiance at and below the horizon.
        horizon: [f32; 3],
        /// Radiance straight up.
        zenith: [f32; 3],
    },
}

impl Sky {
    /// Checks every colour.
    pub fn validate(&self) -> Result<(), ParamError> {
        match self {
            Sky::Uniform { colour } => {
                check(colour_ok(*colour), "sky colour", colour, "finite, ≥ 0")
            }
            Sky::Gradient { horizon, zenith } => {
                check(colour_ok(*horizon), "sky horizon", horizon, "finite, ≥ 0")?;
                check(colour_ok(*zenith), "sky zenith", zenith, "finite, ≥ 0")
            }
        }
    }
}

/// How the image is computed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderSettings {
    /// Samples per pixel per frame, 1..=1024.
    pub samples_per_pixel: u32,
    /// Scattering vertices per path, 1..=64 (docs/DESIGN.md's B).
    pub max_bounces: u32,
    /// Internal resolution (width, height), each 1..=16384.
    pub internal_resolution: (u32, u32),
    /// Exposure in stops.
    pub exposure: f32,
    /// The numbers the samples are made from (projects from before it: independent).
    #[serde(default)]
    pub sequence: Sequence,
}

/// The numbers a path's random decisions are made from (`voxbrick bench-error` measures
/// both; Sobol reaches equal error in 1.6–3.2× less GPU time on the H200, so it is the default,
/// also for projects saved before the choice existed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Sequence {
    /// Independent uniform numbers (a hash chain per pixel and sample).
    Independent,
    /// Owen-scrambled Sobol points, padded in pairs of dimensions (Burley 2020): stratified
    /// over a pixel's samples, still unbiased (each render's scrambling is random). The CPU
    /// reference always uses independent numbers.
    #[default]
    Sobol,
}

impl RenderSettings {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), ParamError> {
        check(
            (1..=1024).contains(&self.samples_per_pixel),
            "samples per pixel",
            self.samples_per_pixel,
            "1..=1024",
        )?;
        check(
            (1..=64).contains(&self.max_bounces),
            "max bounces",
            self.max_bounces,
            "1..=64",
        )?;
        let (w, h) = self.internal_resolution;
        check(
            (1..=16384).contains(&w) && (1..=16384).contains(&h),
            "internal resolution",
            (w, h),
            "1..=16384 each",
        )?;
        check(
            self.exposure.is_finite() && self.exposure.abs() <= 32.0,
            "exposure",
            self.exposure,
            "[-32, 32] stops",
        )
    }
}

/// Everything but the voxels: what a scene file carries besides the world.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneParams {
    /// The camera.
    pub camera: Camera,
    /// The sun.
    pub sun: Sun,
    /// The sky.
    pub sky: Sky,
    /// Render settings.
    pub settings: RenderSettings,
}

impl SceneParams {
    /// Defaults framing a grid of `size` voxels: camera above a corner looking at the
    /// centre, sun high over the opposite side, a blue gradient sky.
    pub fn framing(size: DVec3) -> Self {
        let centre = size * 0.5;
        let eye = DVec3::new(-0.15 * size.x, size.y * 0.9 + 0.2 * size.x, -0.15 * size.z);
        Self {
            camera: Camera::looking_at(eye, centre, 50.0),
            sun: Sun {
                enabled: true,
                position: centre + DVec3::new(0.6, 1.0, 0.3).normalize() * size.max_element() * 2.0,
                radius: size.max_element() * 0.05,
                colour: [1.0, 0.95, 0.85],
                intensity: 40.0,
                animate: false,
                speed_deg_per_s: 10.0,
            },
            sky: Sky::Gradient {
                horizon: [0.85, 0.9, 1.0],
                zenith: [0.25, 0.45, 0.9],
            },
            settings: RenderSettings {
                samples_per_pixel: 1,
                max_bounces: 3,
                internal_resolution: (1024, 576),
                exposure: 0.0,
                sequence: Sequence::default(),
            },
        }
    }
    /// Checks every part.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.camera.validate()?;
        self.sun.validate()?;
        self.sky.validate()?;
        self.settings.validate()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn looking_at_points_at_the_target() {
        let c = Camera::looking_at(DVec3::new(1.0, 5.0, 2.0), DVec3::new(10.0, 0.0, -7.0), 45.0);
        let want = (DVec3::new(10.0, 0.0, -7.0) - DVec3::new(1.0, 5.0, 2.0)).normalize();
        assert!((c.forward() - want).length() < 1e-12);
        c.validate().unwrap();
    }

    #[test]
    fn a_target_at_the_eye_is_refused() {
        let eye = DVec3::new(3.0, 4.0, 5.0);
        let e = Camera::aimed(eye, eye, 45.0).unwrap_err();
        assert_eq!(e.what, "camera target");
        assert!(e.to_string().contains("no direction"), "{e}");
        assert!(Camera::aimed(eye, eye + DVec3::splat(1e-9), 45.0).is_err());
        assert!(Camera::aimed(eye, DVec3::new(f64::NAN, 0.0, 0.0), 45.0).is_err());
        assert!(Camera::aimed(DVec3::INFINITY, eye, 45.0).is_err());
        let c = Camera::aimed(eye, eye + DVec3::X, 45.0).unwrap();
        assert!((c.forward() - DVec3::X).length() < 1e-12);
    }

    #[test]
    fn validation_names_the_field() {
        let mut p = SceneParams::framing(DVec3::splat(64.0));
        p.validate().unwrap();
        p.settings.max_bounces = 0;
        assert_eq!(p.validate().unwrap_err().what, "max bounces");
        p.settings.max_bounces = 3;
        p.sun.radius = f64::NAN;
        assert_eq!(p.validate().unwrap_err().what, "sun radius");
    }
}
