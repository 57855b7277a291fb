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
    /// The outward normal of the face the ray entered through (the face behind the origin
    /// for a ray starting inside the voxel).
    pub normal: IVec3,
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
        Ok(self.trace_counted(ctx, world, rays, medium)?.0)
    }

    /// [`PrimaryTracer::trace`], also returning the iteration caps the traversals hit (a
    /// step budget or a cell correction loop run out; expected zero).
    pub fn trace_counted(
        &self,
        ctx: &GpuContext,
        world: &GpuWorld,
        rays: &[(Vec3, Vec3)],
        medium: Option<u8>,
    ) -> Result<(Vec<Option<GpuHit>>, u64), GpuError> {
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
            rays.len() as u64 * 32,
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
            let raw: &[[[f32; 4]; 2]] = bytemuck::cast_slice(&output.read()[..rays.len() * 32]);
            let capped = raw.iter().map(|[_, n]| n[3] as u64).sum();
            let hits = raw
                .iter()
                .map(|[h, n]| {
                    (h[0] >= 0.0).then(|| GpuHit {
                        voxel: IVec3::new(h[0] as i32, h[1] as i32, h[2] as i32),
                        t: h[3],
                        normal: IVec3::new(n[0] as i32, n[1] as i32, n[2] as i32),
                    })
                })
                .collect();
            (hits, capped)
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
