//! `TraceParams`: the path tracer's per-dispatch parameters, laid out as `Params` in
//! shaders/trace.comp (std430) and filled from the scene's camera, sun, sky and settings.

use super::*;

/// A box of the world shown at full weight, the rest of what camera rays hit weighted by
/// `factor` (the editor's dimming of the objects it is not editing).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dim {
    /// The box's low corner (voxels).
    pub lo: glam::IVec3,
    /// Its high corner (exclusive).
    pub hi: glam::IVec3,
    /// The weight of camera hits outside it (0..1).
    pub factor: f32,
}

/// The ground grid's lines: their width in pixels and their radiance (a grey that reads on
/// the default sky and on dark floors alike).
const GRID_LINE_PIXELS: f32 = 1.5;
const GRID_RADIANCE: f32 = 0.35;

/// Where an image lies in a larger picture: a tile of a tiled render. Its pixels are the
/// picture's pixels there, random numbers included (shaders/scene.glsl `picture_index`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Window {
    /// The image's top left pixel in the picture.
    pub origin: (u32, u32),
    /// The whole picture's width and height.
    pub picture: (u32, u32),
}

impl Window {
    /// The whole picture of `size`.
    pub fn whole(size: (u32, u32)) -> Self {
        Self {
            origin: (0, 0),
            picture: size,
        }
    }
}

/// Keep in sync with `Params` in shaders/scene.glsl (std430: eleven vec4, three uvec4, three
/// vec4, one uvec4).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable, Default)]
pub struct TraceParams {
    cam_pos: [f32; 4],
    cam_forward: [f32; 4],
    cam_right: [f32; 4],
    cam_up: [f32; 4],
    sun_centre: [f32; 4],
    sun_normal: [f32; 4],
    sun_e1: [f32; 4],
    sun_e2: [f32; 4],
    sun_radiance: [f32; 4],
    sky_horizon: [f32; 4],
    sky_zenith: [f32; 4],
    grid: [u32; 4],
    pub(super) image: [u32; 4],
    pub(super) seed: [u32; 4],
    dim_lo: [f32; 4],
    dim_hi: [f32; 4],
    ground: [f32; 4],
    window: [u32; 4],
}
const _: () = assert!(std::mem::size_of::<TraceParams>() == 288);

fn v4(v: DVec3, w: f32) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w]
}

impl TraceParams {
    /// The camera as shaders read it (position with w = 1 when orthographic, forward, and
    /// right and up scaled by the half-extents): what temporal reprojection projects with.
    pub fn camera(&self) -> [[f32; 4]; 4] {
        [self.cam_pos, self.cam_forward, self.cam_right, self.cam_up]
    }

    /// A hash of everything but the camera, the image's size and place and the batch's
    /// samples and seed: equal keys mean only the camera (or the size) changed.
    pub fn scene_key(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut rest = *self;
        rest.cam_pos = [0.0; 4];
        rest.cam_forward = [0.0; 4];
        rest.cam_right = [0.0; 4];
        rest.cam_up = [0.0; 4];
        rest.image = [0, 0, 0, self.image[3]];
        rest.seed = [0; 4];
        rest.window = [0; 4];
        let mut h = std::collections::hash_map::DefaultHasher::new();
        bytemuck::bytes_of(&rest).hash(&mut h);
        h.finish()
    }

    /// The parameters of a render, derived exactly as `CpuScene::new` derives them.
    pub fn new(view: &WorldView<'_>, params: &SceneParams, job: &RenderJob) -> Self {
        Self::in_window(view, params, job, Window::whole((job.width, job.height)))
    }

    /// The parameters of `job`'s image as the part `window` of a larger picture (the
    /// camera frames the picture; the image is `job.width` × `job.height` of it).
    pub fn in_window(
        view: &WorldView<'_>,
        params: &SceneParams,
        job: &RenderJob,
        window: Window,
    ) -> Self {
        let c = &params.camera;
        let (forward, right, up) = c.basis(window.picture.0 as f64 / window.picture.1 as f64);
        let dims = view.dims();
        let centre = dims.voxels().as_dvec3() * 0.5;
        let mut p = TraceParams {
            // w: 1 for an orthographic camera (rays from the image plane; trace.comp then
            // finds each ray's medium itself).
            cam_pos: v4(c.position, if c.is_orthographic() { 1.0 } else { 0.0 }),
            cam_forward: v4(forward, 0.0),
            cam_right: v4(right, 0.0),
            cam_up: v4(up, 0.0),
            grid: [
                dims.bricks().x,
                dims.bricks().y,
                dims.bricks().z,
                dims.coarse_words_per_column() as u32,
            ],
            image: [job.width, job.height, job.spp, params.settings.max_bounces],
            window: [
                window.origin.0,
                window.origin.1,
                window.picture.0,
                window.picture.1,
            ],
            ..Default::default()
        };
        if let Some(sun) = params.sun.disc(centre) {
            p.sun_centre = v4(sun.centre, sun.radius as f32);
            p.sun_normal = v4(sun.normal, 1.0);
            p.sun_e1 = v4(sun.e1, 0.0);
            p.sun_e2 = v4(sun.e2, 0.0);
            p.sun_radiance = v4(sun.radiance, 0.0);
        }
        match &params.sky {
            Sky::Uniform { colour } => p.sky_horizon = [colour[0], colour[1], colour[2], 0.0],
            Sky::Gradient { horizon, zenith } => {
                p.sky_horizon = [horizon[0], horizon[1], horizon[2], 0.0];
                p.sky_zenith = [zenith[0], zenith[1], zenith[2], 1.0];
            }
        }
        let medium = (!c.is_orthographic())
            .then(|| view.voxel(c.position.floor().as_ivec3()).ok().flatten())
            .flatten()
            .filter(|&m| {
                view.materials()
                    .get(m)
                    .is_ok_and(|mat| mat.kind == MaterialKind::Dielectric)
            });
        p.seed = [
            job.seed as u32 ^ (job.seed >> 32) as u32,
            medium.map_or(0, |m| m as u32 + 1),
            0,
            0,
        ];
        p
    }

    /// The same parameters with `samples` samples per pixel starting at sample `first`,
    /// added to the accumulation when `add`.
    pub fn batch(mut self, samples: u32, first: u32, add: bool) -> Self {
        self.image[2] = samples;
        self.seed[2] = first;
        self.seed[3] = u32::from(add);
        self
    }

    /// The same parameters with the seed of accumulation number `epoch` of a session (0: the
    /// job's own seed, unchanged): each epoch's numbers are independent of the others'.
    pub fn reseeded(mut self, epoch: u32) -> Self {
        if epoch > 0 {
            let mut x = epoch.wrapping_mul(0x9e37_79b9) ^ 0x85eb_ca6b;
            x ^= x >> 16;
            x = x.wrapping_mul(0x7feb_352d);
            x ^= x >> 15;
            self.seed[0] ^= x;
        }
        self
    }

    /// The same parameters with camera hits outside `dim`'s box weighted by its factor (read
    /// by [`Variant::dim`] variants only).
    pub fn dimmed(mut self, dim: Option<Dim>) -> Self {
        if let Some(d) = dim {
            let f = |v: glam::IVec3, w: f32| [v.x as f32, v.y as f32, v.z as f32, w];
            self.dim_lo = f(d.lo, d.factor);
            self.dim_hi = f(d.hi, 0.0);
        } else {
            self.dim_lo = [0.0; 4];
            self.dim_hi = [0.0; 4];
        }
        self
    }

    /// The same parameters with a ground grid of lines `spacing` voxels apart on the plane
    /// y = 0, reaching half the world's larger side past its sides, in whole spacings (read by
    /// [`Variant::grid`] variants only).
    pub fn with_grid(mut self, spacing: Option<f32>) -> Self {
        self.ground = match spacing {
            Some(s) => {
                let s = s.max(1.0);
                let side = (self.grid[0].max(self.grid[2]) * 8) as f32;
                let margin = (0.5 * side / s).ceil() * s;
                [s, margin, GRID_LINE_PIXELS, GRID_RADIANCE]
            }
            None => [0.0; 4],
        };
        self
    }

    /// Everything that changes the converged image (not the seed, the batch or the sample
    /// index), as bytes: two renders with equal keys converge to the same image.
    pub fn image_key(&self) -> Vec<u8> {
        let mut k = *self;
        k.seed = [0, self.seed[1], 0, 0];
        k.image[2] = 0;
        bytemuck::bytes_of(&k).to_vec()
    }
}
