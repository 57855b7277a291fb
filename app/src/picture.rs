//! Finished renders as the CLI (`voxbrick render`) and the editor (File → Render image…)
//! make them: the camera presets (the scene's camera, isometric and orthographic views
//! framing the content), turntables and camera-path sequences as lists of shots, and the
//! loop that renders each shot on a GPU session (`render::finished`) and writes its file
//! (`formats::picture`).

use crate::camera_path::CameraPath;
use crate::formats::picture::{PictureFormat, numbered, write_picture};
use glam::{DQuat, DVec3};
use render::finished::{Finish, Picture, PictureError, Progress};
use render::viewport::Viewport;
use render::{Camera, Projection, SceneParams};
use std::path::{Path, PathBuf};

/// Where a finished render's camera comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Preset {
    /// The scene's camera.
    Scene,
    /// Orthographic, isometric (yaw 45°, pitch −35.26°: the three axes equally short),
    /// framing the content.
    Isometric,
    /// Orthographic, looking along −z, framing the content.
    Front,
    /// Orthographic, looking along −x, framing the content.
    Side,
    /// Orthographic, looking down, framing the content.
    Top,
}

impl Preset {
    /// Every preset, for menus.
    pub const ALL: [Preset; 5] = [
        Self::Scene,
        Self::Isometric,
        Self::Front,
        Self::Side,
        Self::Top,
    ];

    /// Its name on the command line and in menus.
    pub fn name(self) -> &'static str {
        match self {
            Self::Scene => "scene",
            Self::Isometric => "iso",
            Self::Front => "front",
            Self::Side => "side",
            Self::Top => "top",
        }
    }

    /// The preset `name` names.
    pub fn parse(name: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == name)
            .ok_or_else(|| format!("{name:?} is not a view: scene, iso, front, side or top"))
    }

    /// The camera of this preset for an image of `aspect`, framing `bounds` (the content's
    /// box, voxels) where it is not the scene's.
    pub fn camera(self, scene: &Camera, bounds: (DVec3, DVec3), aspect: f64) -> Camera {
        let (yaw, pitch) = match self {
            Self::Scene => return scene.clone(),
            Self::Isometric => (45.0, -(1.0f64 / 2f64.sqrt()).atan().to_degrees()),
            Self::Front => (0.0, 0.0),
            Self::Side => (90.0, 0.0),
            Self::Top => (0.0, -89.0),
        };
        let oriented = Camera {
            yaw_deg: yaw,
            pitch_deg: pitch,
            projection: Projection::Orthographic { height: 1.0 },
            ..scene.clone()
        };
        oriented.framing_in(bounds.0, bounds.1, aspect).0
    }
}

/// The content's box in voxels (the world's when empty).
pub fn content_bounds(view: &brickmap::WorldView<'_>) -> (DVec3, DVec3) {
    match view.occupied_bounds() {
        Some((lo, hi)) => (lo.as_dvec3(), hi.as_dvec3()),
        None => (DVec3::ZERO, view.dims().voxels().as_dvec3()),
    }
}

/// One picture to render: the scene's parameters with its camera (and sun), and its file.
#[derive(Clone, Debug)]
pub struct Shot {
    /// The parameters it is rendered with.
    pub params: SceneParams,
    /// The file it is written to.
    pub out: PathBuf,
}

/// `frames` shots turning the camera once about the vertical axis through `pivot` (its
/// distance, height and the angle it looks down at kept), files numbered from `out`.
pub fn turntable(params: &SceneParams, pivot: DVec3, frames: usize, out: &Path) -> Vec<Shot> {
    let c = &params.camera;
    (0..frames)
        .map(|k| {
            let turn = DQuat::from_rotation_y(std::f64::consts::TAU * k as f64 / frames as f64);
            let position = pivot + turn * (c.position - pivot);
            let forward = turn * c.forward();
            let camera = Camera {
                projection: c.projection,
                ..Camera::looking_at(position, position + forward, c.fov_y_deg)
            };
            Shot {
                params: SceneParams {
                    camera,
                    ..params.clone()
                },
                out: numbered(out, k, frames),
            }
        })
        .collect()
}

/// The shots of `path` at `fps` frames per second (from 0 to its end), the sun turning as
/// the benchmark turns it, files numbered from `out`.
pub fn along_path(
    params: &SceneParams,
    path: &CameraPath,
    fps: f64,
    grid_centre: DVec3,
    out: &Path,
) -> Vec<Shot> {
    let frames = (path.duration() * fps).floor() as usize + 1;
    (0..frames)
        .map(|k| {
            let t = k as f64 / fps;
            Shot {
                params: SceneParams {
                    camera: path.camera_at(t, params.camera.fov_y_deg),
                    sun: path.sun_at(&params.sun, t, grid_centre),
                    ..params.clone()
                },
                out: numbered(out, k, frames),
            }
        })
        .collect()
}

/// What rendering the shots gave: per shot the picture's samples, noise and GPU time.
#[derive(Clone, Debug, PartialEq)]
pub struct Rendered {
    /// The file written.
    pub out: PathBuf,
    /// The fewest and most samples per pixel a tile took.
    pub samples: (u32, u32),
    /// The worst tile's relative noise (noise targets only).
    pub noise: Option<f64>,
    /// Tiles.
    pub tiles: usize,
    /// GPU seconds (timestamp queries).
    pub gpu_seconds: Option<f64>,
}

/// Why shots were not all rendered and written.
#[derive(Debug, thiserror::Error)]
pub enum ShotError {
    /// The render failed or was cancelled.
    #[error(transparent)]
    Render(#[from] PictureError),
    /// A file could not be written (the files before it were).
    #[error("writing {path}: {error}")]
    Write {
        /// The file.
        path: String,
        /// Why.
        error: std::io::Error,
    },
}

/// Renders every shot on `vp` and writes it as `format`, calling `progress` with the part
/// of all shots done (false: stop; the shot under way is not written, those before are).
pub fn render_shots(
    vp: &mut Viewport,
    view: &brickmap::WorldView<'_>,
    shots: &[Shot],
    finish: &Finish,
    format: PictureFormat,
    progress: &mut dyn FnMut(Progress) -> bool,
) -> Result<Vec<Rendered>, ShotError> {
    let mut done = Vec::new();
    let started = std::time::Instant::now();
    for (k, shot) in shots.iter().enumerate() {
        let n = shots.len() as f64;
        let mut each = |p: Progress| {
            progress(Progress {
                done: (k as f64 + p.done) / n,
                elapsed: started.elapsed().as_secs_f64(),
                ..p
            })
        };
        let picture: Picture = vp.render_picture(view, &shot.params, finish, &mut each)?;
        write_picture(&shot.out, &picture, format, shot.params.settings.exposure).map_err(
            |error| ShotError::Write {
                path: shot.out.display().to_string(),
                error,
            },
        )?;
        done.push(Rendered {
            out: shot.out.clone(),
            samples: picture.samples,
            noise: picture.noise,
            tiles: picture.tiles,
            gpu_seconds: picture.gpu_seconds,
        });
    }
    Ok(done)
}
