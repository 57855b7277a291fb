//! The light visibility cache of the light-sampling variants (shaders/lights.glsl
//! `LightCache`, shaders/light_cache.comp; docs/DESIGN.md "The GPU's light visibility cache"):
//! an experiment (trace.comp's experiment bit 18, [`EXPERIMENT_LIGHT_CACHE`]), off by default:
//! per 8³-voxel cell (hashed into at most [`LIGHT_CACHE_ENTRIES`] entries: fewer where the
//! device's limits do not fit them), how often shadow rays from there
//! reached the lights under each node of the light tree's cached level, and the factors the
//! descent weighs those nodes by. The trace and shadow passes add to the counts; this pass,
//! recorded before each trace dispatch, turns them into factors. The counts are kept while the
//! world's [`GpuWorld::state`] is (a camera move keeps them) and dropped when it changes.

use super::super::barrier::{Scope, barrier};
use super::super::buffer::{Binding, HostBuffer};
use super::super::pass::{ComputePass, Dispatch};
use super::super::world::GpuWorld;
use super::super::{GpuContext, GpuError};
use ash::vk;
use gpu_allocator::MemoryLocation;

const SPIRV: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/light_cache.comp.spv"));

/// The most entries of the cache, 256 words each (lights.glsl `CACHE_WORDS`).
pub const LIGHT_CACHE_ENTRIES: u32 = 8192;
const ENTRY_BYTES: u64 = 256 * 4;
/// trace.comp's experiment bit that turns the cache on (lights.glsl `LIGHT_CACHE_ON`): an
/// experiment, off in every real render — it learns between dispatches, so an image would
/// depend on where dispatches end and on the renders before (tiles, bands of another shape,
/// the one-shot and the interactive accumulation would differ).
pub const EXPERIMENT_LIGHT_CACHE: u32 = 1 << 18;

/// The cache's buffer and pass, and the world state its counts were gathered in.
pub(super) struct LightCache {
    buffer: HostBuffer,
    pass: ComputePass,
    world: Option<(u64, u64)>,
    entries: u32,
}

impl LightCache {
    /// A cache with no counts yet (its first pass zeroes the buffer); `bindings` is the
    /// tracer's binding count, which the pass shares.
    pub(super) fn new(ctx: &GpuContext, bindings: u32) -> Result<Self, GpuError> {
        // The most that fits the storage range, the allocation size and the pass's groups, as a
        // power of two (the shader masks its hash with it).
        let fit = ctx
            .limits
            .elements(ENTRY_BYTES)
            .min(u64::from(LIGHT_CACHE_ENTRIES))
            .min(u64::from(ctx.limits.groups[0]))
            .max(1);
        let entries = 1u32 << fit.ilog2();
        let bytes = u64::from(entries) * ENTRY_BYTES;
        let buffer = HostBuffer::new(
            ctx,
            "light visibility cache",
            bytes,
            MemoryLocation::GpuOnly,
        )?;
        match ComputePass::new(ctx, SPIRV, bindings, 4) {
            Ok(pass) => Ok(Self {
                buffer,
                pass,
                world: None,
                entries,
            }),
            Err(e) => {
                buffer.destroy(ctx);
                Err(e)
            }
        }
    }

    pub(super) fn binding(&self) -> Binding {
        self.buffer.binding()
    }

    pub(super) fn pass(&self) -> &ComputePass {
        &self.pass
    }

    /// Whether a dispatch on `world` must drop the counts (the world changed since they were
    /// gathered, or there are none yet); remembers its state.
    pub(super) fn reset_for(&mut self, world: &GpuWorld) -> bool {
        let state = Some(world.state());
        std::mem::replace(&mut self.world, state) != state
    }

    /// Records the pass (dropping the counts first when `reset`) between the last dispatch's
    /// shadow rays and this one's trace.
    pub(super) fn record(
        &self,
        ctx: &GpuContext,
        cmd: vk::CommandBuffer,
        set: vk::DescriptorSet,
        reset: bool,
    ) {
        // SAFETY: recording.
        unsafe { barrier(ctx, cmd, Scope::SHADER_WRITE, Scope::SHADER_RW) };
        let push = u32::from(reset).to_ne_bytes();
        self.pass
            .record(ctx, cmd, set, &push, Dispatch::Groups(self.entries, 1, 1));
        // SAFETY: recording.
        unsafe { barrier(ctx, cmd, Scope::SHADER_WRITE, Scope::SHADER_RW) };
    }

    pub(super) fn destroy(self, ctx: &GpuContext) {
        self.buffer.destroy(ctx);
        self.pass.destroy(ctx);
    }
}
