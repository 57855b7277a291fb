//! The path tracer on the GPU (`shaders/trace.comp`): the CPU reference integrator ported
//! to a compute shader, one invocation per pixel.

use super::buffer::HostBuffer;
use super::pass::ComputePass;
use super::world::GpuWorld;
use super::{GpuContext, GpuError};
use crate::cpu::RenderJob;
use crate::image::Image;
use crate::params::{SceneParams, Sky};
use brickmap::{MaterialKind, WorldView};
use glam::DVec3;
use gpu_allocator::MemoryLocation;

const SPIRV: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/trace.comp.spv"));

/// Samples per pixel one dispatch computes at most.
pub const SAMPLES_PER_DISPATCH: u32 = 16;

/// Keep in sync with `Params` in shaders/trace.comp (std430: eleven vec4, three uvec4).
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
    image: [u32; 4],
    seed: [u32; 4],
}
const _: () = assert!(std::mem::size_of::<TraceParams>() == 224);

fn v4(v: DVec3, w: f32) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w]
}

impl TraceParams {
    /// The parameters of a render, derived exactly as `CpuScene::new` derives them.
    pub fn new(view: &WorldView<'_>, params: &SceneParams, job: &RenderJob) -> Self {
        let c = &params.camera;
        let (forward, right, up) = c.basis(job.width as f64 / job.height as f64);
        let dims = view.dims();
        let centre = dims.voxels().as_dvec3() * 0.5;
        let mut p = TraceParams {
            cam_pos: v4(c.position, 0.0),
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
        let medium = view
            .voxel(c.position.floor().as_ivec3())
            .ok()
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
}

/// The parameter buffer and the accumulation buffer of a frame of `pixels` pixels.
fn frame_buffers(ctx: &GpuContext, pixels: u64) -> Result<(HostBuffer, HostBuffer), GpuError> {
    let uniforms = HostBuffer::new(
        ctx,
        "trace params",
        std::mem::size_of::<TraceParams>() as u64,
        MemoryLocation::CpuToGpu,
    )?;
    match HostBuffer::new(ctx, "accumulation", pixels * 16, MemoryLocation::GpuToCpu) {
        Ok(accum) => Ok((uniforms, accum)),
        Err(e) => {
            uniforms.destroy(ctx);
            Err(e)
        }
    }
}

/// The path-tracing pipeline.
pub struct PathTracer(ComputePass);

impl PathTracer {
    /// Builds the pipeline.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self(ComputePass::new(ctx, SPIRV, 7, 0)?))
    }

    /// Renders `job.spp` samples per pixel; returns the linear image and the GPU time spent
    /// (timestamp queries summed over the dispatches; None when the queue cannot time). Samples go in batches
    /// of at most [`SAMPLES_PER_DISPATCH`] per dispatch (averaged on the host): long-running
    /// invocations lose samples on lavapipe (measured: 256 samples per invocation came out 9%
    /// dark there, exact on the H100), and short dispatches are what a viewport does anyway.
    pub fn render(
        &self,
        ctx: &GpuContext,
        world: &GpuWorld,
        view: &WorldView<'_>,
        params: &SceneParams,
        job: &RenderJob,
    ) -> Result<(Image, Option<f64>), GpuError> {
        let pixels = job.width as u64 * job.height as u64;
        let (mut uniforms, accum) = frame_buffers(ctx, pixels)?;
        let base = TraceParams::new(view, params, job);
        let mut sum = vec![[0f64; 3]; pixels as usize];
        let mut result = Ok(());
        let mut done = 0;
        let mut gpu_seconds = Some(0.0);
        while done < job.spp && result.is_ok() {
            let batch = (job.spp - done).min(SAMPLES_PER_DISPATCH);
            let mut p = base;
            p.image[2] = batch;
            p.seed[2] = done;
            uniforms.write(bytemuck::bytes_of(&p));
            let mut bound = world.bindings();
            bound.extend([uniforms.binding(), accum.binding()]);
            result = self
                .0
                .run_timed(
                    ctx,
                    &bound,
                    &[],
                    [job.width.div_ceil(8), job.height.div_ceil(8)],
                    true,
                )
                .map(|t| gpu_seconds = gpu_seconds.zip(t).map(|(a, b)| a + b));
            if result.is_ok() {
                let raw: &[[f32; 4]] = bytemuck::cast_slice(&accum.read()[..pixels as usize * 16]);
                for (s, px) in sum.iter_mut().zip(raw) {
                    for k in 0..3 {
                        s[k] += px[k] as f64 * batch as f64;
                    }
                }
            }
            done += batch;
        }
        let n = job.spp.max(1) as f64;
        let image = result.map(|_| {
            (
                Image {
                    width: job.width,
                    height: job.height,
                    pixels: sum
                        .iter()
                        .map(|s| [(s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32])
                        .collect(),
                },
                gpu_seconds,
            )
        });
        uniforms.destroy(ctx);
        accum.destroy(ctx);
        image
    }

    /// Destroys the pipeline.
    pub fn destroy(self, ctx: &GpuContext) {
        self.0.destroy(ctx);
    }
}
