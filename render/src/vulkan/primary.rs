//! The world on the GPU and first-hit traversal of rays (`shaders/primary.comp`): the
//! brickmap's GPU buffers uploaded as they are, and the same DDA as `brickmap::raycast` in f32.
//! Buffers are host-visible for now; device-local buffers fed by a staging ring come next.

use super::buffer::HostBuffer;
use super::pass::ComputePass;
use super::world::GpuWorld;
use super::{GpuContext, GpuError};
use glam::{IVec3, Vec3};
use gpu_allocator::MemoryLocation;

const SPIRV: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/primary.comp.spv"));
const GROUP: u32 = 64;

/// Push constants. Keep in sync with `Push` in shaders/primary.comp (std430: uvec3 then three
/// uints).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    dims: [u32; 3],
    count: u32,
    words_per_column: u32,
    /// The medium the rays travel in: material + 1, 0 for air.
    medium: u32,
}
const _: () = assert!(std::mem::size_of::<Push>() == 24);

/// The first hit of a ray on the GPU.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuHit {
    /// The voxel.
    pub voxel: IVec3,
    /// Ray parameter.
    pub t: f32,
}

/// The traversal pipeline.
pub struct PrimaryTracer(ComputePass);

impl PrimaryTracer {
    /// Builds the pipeline.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self(ComputePass::new(
            ctx,
            SPIRV,
            7,
            std::mem::size_of::<Push>() as u32,
        )?))
    }

    /// The first interaction along each ray (origin, direction), or None: in air (`medium`
    /// None) the first solid voxel, inside a dielectric material the first voxel that is not it.
    pub fn trace(
        &self,
        ctx: &GpuContext,
        world: &GpuWorld,
        rays: &[(Vec3, Vec3)],
        medium: Option<u8>,
    ) -> Result<Vec<Option<GpuHit>>, GpuError> {
        let packed: Vec<[f32; 4]> = rays
            .iter()
            .flat_map(|(o, d)| [o.extend(0.0).to_array(), d.extend(0.0).to_array()])
            .collect();
        let mut input = HostBuffer::new(
            ctx,
            "rays",
            packed.len() as u64 * 16,
            MemoryLocation::CpuToGpu,
        )?;
        let output = match HostBuffer::new(
            ctx,
            "hits",
            rays.len() as u64 * 16,
            MemoryLocation::GpuToCpu,
        ) {
            Ok(b) => b,
            Err(e) => {
                input.destroy(ctx);
                return Err(e);
            }
        };
        input.write(bytemuck::cast_slice(&packed));
        let push = Push {
            dims: world.dims(),
            count: rays.len() as u32,
            words_per_column: world.words_per_column(),
            medium: medium.map_or(0, |m| u32::from(m) + 1),
        };
        let mut bound = world.bindings();
        bound.extend([input.binding(), output.binding()]);
        let result = self.0.run(
            ctx,
            &bound,
            bytemuck::bytes_of(&push),
            [(rays.len() as u32).div_ceil(GROUP), 1],
        );
        let hits = result.map(|_| {
            let raw: &[[f32; 4]] = bytemuck::cast_slice(&output.read()[..rays.len() * 16]);
            raw.iter()
                .map(|h| {
                    (h[0] >= 0.0).then(|| GpuHit {
                        voxel: IVec3::new(h[0] as i32, h[1] as i32, h[2] as i32),
                        t: h[3],
                    })
                })
                .collect()
        });
        input.destroy(ctx);
        output.destroy(ctx);
        hits
    }

    /// Destroys the pipeline.
    pub fn destroy(self, ctx: &GpuContext) {
        self.0.destroy(ctx);
    }
}
