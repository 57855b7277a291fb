//! The path tracer on the GPU (`shaders/trace.comp`): the CPU reference integrator ported
//! to a compute shader, one invocation per pixel, in pipeline variants specialised to what a
//! scene needs ([`Variant`], built on first use and cached). With the sun, shadow rays are
//! queued and traced by a second pass (`shaders/shadow.comp`, one invocation per ray) where
//! the device can (float atomic adds, subgroup ballots).
//!
//! In detail:
//! `TraceParams` (mirrors `Params` in trace.comp), `Variant` (specialization constants:
//! material kinds from the table, sun, gradient sky, bounce count, ray counting, experiments,
//! `lights`: light sampling of emissive voxels, on when the world has light faces; `Variant {
//! lights: false, .. }` is the BSDF-only estimator) with a per-tracer pipeline cache (the
//! one-shot `PathTracer::render` is in `progressive.rs`). A dispatch runs `image[2]` samples
//! per invocation in `slices` invocations per pixel (workgroup z): an image below
//! `FULL_DISPATCH` (1.2 Mpixel) is split up to `MAX_SLICES` = 8 ways with `SLICED_SAMPLES` = 4
//! each, by trace.comp's second module (`SAMPLE_SLICES` defined by build.rs: its invocations
//! add to the accumulation with float atomics, zeroed by `vkCmdFillBuffer` when an accumulation
//! starts; sample index = first + slice · per-invocation + s, so the samples are the unsplit
//! ones); otherwise 8 per invocation from `LARGE_IMAGE` pixels, else 4, and at most 4 for a
//! `lights` variant (`samples_per_dispatch_for`; `set_samples_per_dispatch`,
//! `set_sample_slices`; measurements at `SAMPLES_PER_DISPATCH` and `FULL_DISPATCH`). Devices
//! without float atomics never split. With the sun or light faces and a capable device a frame
//! is two passes: trace.comp queues shadow rays (48 B each, the light slot of a light face's
//! ray in `light.w`, `NO_LIGHT` for the sun's; header reset by `vkCmdUpdateBuffer`, slots
//! reserved with one atomic per subgroup, capacity one ray per sample within 2¹⁶..2²¹, with
//! light faces one per vertex up to 2²³; overflow traced in place), then shadow.comp traces
//! them one per invocation by an indirect dispatch and adds unblocked light with float atomics
//! (a light face's ray may end in its light's voxel, found from the slot). A vertex may hold
//! two pending shadow rays (the sun's and a light face's) only in `lights` variants; without
//! them the code is the sun-only code (measured: thesis complexities unchanged).
//! `set_deferred_shadows`/`set_queue_limit` for benchmarks and tests. With experiment bit 18,
//! light-sampling variants run the light visibility cache's pass before the trace
//! (`light_cache.rs`; binding 11). A dispatch is planned
//! once (`plan`: pipelines, queue, bindings) and recorded by `record_plan`, either in a waited
//! submission (`dispatch_repeated`) or into a frame's command buffer with cached sets
//! (`record`). The queue holds at most `queue_fit` rays (the device's limits); a larger queue
//! replaces the old one only after a device wait (the other frame in flight may still trace
//! with it).

use super::barrier::{Scope, barrier};
use super::buffer::{Binding, HostBuffer};
use super::pass::{ComputePass, Dispatch, SetCache, run_batch};
use super::world::GpuWorld;
use super::{GpuContext, GpuError, vk_call};
use crate::cpu::RenderJob;
use crate::params::{SceneParams, Sequence, Sky};
use ash::vk;
use brickmap::{MaterialKind, MaterialTable, WorldView};
use glam::DVec3;
use gpu_allocator::MemoryLocation;
use std::collections::HashMap;

mod light_cache;
mod params;
mod variant;
use light_cache::LightCache;
pub use light_cache::{EXPERIMENT_LIGHT_CACHE, LIGHT_CACHE_ENTRIES};
pub use params::{Dim, TraceParams, Window};
pub use variant::Variant;

const SPIRV: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/trace.comp.spv"));
const SHADOW_SPIRV: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/shadow.comp.spv"));
/// trace.comp with SAMPLE_SLICES: a pixel's samples split among several invocations, added
/// with float atomics (render/build.rs).
const SLICED_SPIRV: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/trace.comp.SAMPLE_SLICES.spv"));

/// Storage bindings of the three passes: the world (0..4), parameters, accumulation, counters,
/// shadow rays, queue header, light faces (10), the light visibility cache (11).
const BINDINGS: u32 = 12;
/// Bytes per queued shadow ray (`ShadowRay` in shaders/shadow_queue.glsl).
const SHADOW_RAY_BYTES: u64 = 48;
/// Queue capacity bounds, in rays: enough for one shadow ray per sample of a dispatch,
/// within these; rays that do not fit are traced in place (correct, slower).
const QUEUE_MIN: u64 = 1 << 16;
const QUEUE_MAX: u64 = 1 << 21;
/// With light faces every vertex of a path may queue a shadow ray (two with the sun too), so
/// those variants ask for one per vertex, up to 2²³ rays (384 MiB): a queue of one per
/// sample overflowed at 1024 × 576, and rays traced in place cost several times a queued one.
const QUEUE_MAX_LIGHTS: u64 = 1 << 23;
/// The most shadow rays a queue may hold on a device: its buffer within the storage range and
/// the allocation size, and its pass (`shadow.comp`, 64 rays per workgroup, one dimension)
/// within the workgroup count. Rays past it are traced in place, so a device with small limits
/// (2²⁷ bytes on lavapipe and many drivers: 2.8 M rays) renders the same image.
pub fn queue_fit(limits: &super::DeviceLimits) -> u64 {
    limits
        .elements(SHADOW_RAY_BYTES)
        .min(u64::from(limits.groups[0]) * 64)
        .max(1)
}
/// The queue header before a trace dispatch: no groups, y = z = 1, no rays.
const QUEUE_RESET: [u32; 4] = [0, 1, 1, 0];

/// Samples per pixel one dispatch computes by default: few, since an invocation starts its
/// next sample as soon as a path ends, so over many samples the lanes of a warp drift apart
/// and trace unrelated rays (incoherent memory access); but each dispatch ends in a tail
/// where the GPU drains. Measured on the H100 (thesis scene, 64 spp, `render`): at
/// 1024 × 576, 2 / 4 / 6 / 8 per dispatch took 53.6 / 50.7 / 49.4 / 48.7 ms (16: 76 ms, in
/// an earlier build); at 512 × 288, 1 / 2 / 4 / 8 took 30.1 / 28.0 / 28.3 / 29.5 ms. So 8
/// from [`LARGE_IMAGE`] pixels on, else 4. With the faster traversal of the fifth session:
/// 4 / 8 / 16 = 39.4 / 38.0 / 67.4 ms at 1024 × 576, 4 / 8 = 22.0 / 22.8 ms at 512 × 288.
pub const SAMPLES_PER_DISPATCH: [u32; 2] = [4, 8];
/// Pixels from which an image takes the larger number of samples per dispatch.
pub const LARGE_IMAGE: u64 = 1024 * 576 / 2;
/// The most samples per pixel one dispatch may take (long-running invocations lose samples on
/// lavapipe; see [`PathTracer::render`]).
pub const MAX_SAMPLES_PER_DISPATCH: u32 = 16;
/// Invocations a dispatch should have at least: an image with fewer pixels splits each
/// pixel's samples among up to [`MAX_SLICES`] invocations (where the device has float
/// atomics), [`SLICED_SAMPLES`] each, so the GPU is full. Measured on the H100 (thesis scene,
/// `render` 64 spp, slices × samples per invocation; BENCHMARKS.md): at 1024 × 576 1 × 8 /
/// 2 × 4 / 4 × 2 / 8 × 1 = 38.1 / 35.5 / 35.3 / 38.9 ms; at 512 × 288 1 × 4 / 4 × 4 / 8 × 1 /
/// 8 × 2 / 8 × 4 = 22.0 / 11.2 / 10.4 / 9.8 / 9.6 ms; at 256 × 144 1 × 4 / 8 × 2..8 = 19.0 /
/// 4.0 ms. 16 samples per dispatch at 1024 × 576 overflow the shadow queue (60–64 ms).
pub const FULL_DISPATCH: u64 = 2 * 1024 * 576;
/// The most invocations one pixel's samples are split among in a dispatch.
pub const MAX_SLICES: u32 = 8;
/// Samples per invocation when a pixel's samples are split.
pub const SLICED_SAMPLES: u32 = 4;

/// The ray counters (trace.comp's `counters`), and their bytes.
const COUNTERS: usize = 11;
const COUNTERS_BYTES: u64 = 4 * COUNTERS as u64;

/// Rays a render traced, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Camera rays.
    pub primary: u64,
    /// Continuation rays after a scattering vertex.
    pub secondary: u64,
    /// Shadow rays towards the sun.
    pub shadow: u64,
    /// Traversal steps of camera, continuation and shadow rays.
    pub steps: [u64; 3],
    /// The most steps one camera or continuation ray took, and one shadow ray.
    pub max_steps: [u64; 2],
    /// Iteration caps hit in the traversal (a step budget or `cell_at`'s corrections run
    /// out); expected zero.
    pub capped: u64,
    /// The trace pass's traversal steps (shadow rays traced by the shadow pass excluded),
    /// and the lane steps its subgroups paid for them (per traversal, the slowest lane's
    /// steps times the subgroup size): their ratio is the share of lanes kept busy.
    pub lane_steps: [u64; 2],
}

impl RayCounts {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.primary + self.secondary + self.shadow
    }
}

/// The shadow-ray queue: rays and the header (also the shadow pass's indirect dispatch).
struct ShadowQueue {
    rays: HostBuffer,
    header: HostBuffer,
    capacity: u64,
}

/// Which part of an image's rows one dispatch traces: band `index` of `count` equal bands of
/// workgroup rows (count 1: the whole image). A sample pass in bands adds the same samples
/// as one dispatch; it only lets each band be its own submission.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Band {
    /// This band (0..count).
    pub index: u32,
    /// Bands in the pass.
    pub count: u32,
}

impl Band {
    /// The whole image in one dispatch.
    pub const WHOLE: Band = Band { index: 0, count: 1 };

    /// Whether this is the pass's last band (its samples are then complete).
    pub fn is_last(&self) -> bool {
        self.index + 1 >= self.count
    }

    /// This band's workgroup rows of `rows`.
    pub fn rows(&self, rows: u32) -> (u32, u32) {
        let count = self.count.max(1) as u64;
        let at = |k: u64| (k * rows as u64 / count) as u32;
        (at(self.index as u64), at(self.index as u64 + 1))
    }
}

/// A dispatch ready to record: which pipelines, what they bind, how many groups.
struct Plan {
    pass: (Variant, bool, bool),
    shadow: Option<(bool, u32, bool)>,
    bound: Vec<Binding>,
    groups: Dispatch,
    zero: Option<Binding>,
    header: Option<Binding>,
    /// The light visibility cache's pass first, and whether it drops the counts.
    cache: Option<bool>,
}

/// The path-tracing pipelines, one per variant in use.
pub struct PathTracer {
    /// Trace pipelines by variant, shadow queue and sample slicing.
    passes: HashMap<(Variant, bool, bool), ComputePass>,
    /// The shadow pass, by ray counting and experiment.
    shadow_passes: HashMap<(bool, u32, bool), ComputePass>,
    queue: Option<ShadowQueue>,
    queue_limit: u64,
    deferred_shadows: bool,
    samples_per_dispatch: Option<u32>,
    sample_slices: Option<u32>,
    /// Whether the device can split samples (float atomic adds).
    can_slice: bool,
    counters: HostBuffer,
    /// The light visibility cache, made with the first light-sampling dispatch.
    cache: Option<LightCache>,
}

impl PathTracer {
    /// Creates the tracer; pipelines are built when a variant is first used. Shadow rays are
    /// queued for a second pass when the device can ([`GpuContext::shadow_queue`]).
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self {
            passes: HashMap::new(),
            shadow_passes: HashMap::new(),
            queue: None,
            queue_limit: QUEUE_MAX_LIGHTS,
            deferred_shadows: ctx.shadow_queue,
            samples_per_dispatch: None,
            sample_slices: None,
            can_slice: ctx.shadow_queue,
            counters: HostBuffer::new(
                ctx,
                "ray counters",
                COUNTERS_BYTES,
                MemoryLocation::GpuToCpu,
            )?,
            cache: None,
        })
    }

    /// Whether shadow rays are queued for the shadow pass (else traced where they start).
    pub fn deferred_shadows(&self) -> bool {
        self.deferred_shadows
    }

    /// Queue shadow rays (where the device can) or trace them in place: the images are the
    /// same up to float rounding; benchmarks compare the two.
    pub fn set_deferred_shadows(&mut self, ctx: &GpuContext, on: bool) {
        self.deferred_shadows = on && ctx.shadow_queue;
    }

    /// The most shadow rays one dispatch queues (at most 2²¹ = 96 MiB of queue, 2²³ with
    /// light faces); the rest are traced in place. Tests use small limits to exercise overflow.
    pub fn set_queue_limit(&mut self, rays: u64) {
        self.queue_limit = rays.clamp(1, QUEUE_MAX_LIGHTS);
    }

    /// Samples per pixel in one dispatch: `Some(n)` fixes it (1..=16), `None` chooses from
    /// the image size ([`SAMPLES_PER_DISPATCH`]).
    pub fn set_samples_per_dispatch(&mut self, samples: Option<u32>) {
        self.samples_per_dispatch = samples.map(|n| n.clamp(1, MAX_SAMPLES_PER_DISPATCH));
    }

    /// Samples per pixel and invocation one dispatch of an image of `pixels` takes:
    /// [`SLICED_SAMPLES`] when the pixel's samples are split, else [`SAMPLES_PER_DISPATCH`].
    pub fn samples_per_dispatch(&self, pixels: u64) -> u32 {
        self.samples_per_dispatch
            .unwrap_or(if self.sample_slices(pixels) > 1 {
                SLICED_SAMPLES
            } else {
                SAMPLES_PER_DISPATCH[usize::from(pixels >= LARGE_IMAGE)]
            })
    }

    /// [`PathTracer::samples_per_dispatch`] for a variant: with light faces never more than
    /// the smaller default (every vertex may queue a shadow ray; at 8 per dispatch the queue
    /// of a 1024 × 576 image overflowed and the overflow, traced in place, cost 9 % of the
    /// frame on the H200).
    pub fn samples_per_dispatch_for(&self, pixels: u64, variant: Variant) -> u32 {
        let n = self.samples_per_dispatch(pixels);
        if variant.lights && self.samples_per_dispatch.is_none() {
            n.min(SAMPLES_PER_DISPATCH[0])
        } else {
            n
        }
    }

    /// Invocations a pixel's samples are split among: `Some(n)` fixes it (1..=[`MAX_SLICES`];
    /// 1 on a device without float atomic adds), `None` chooses from the image size.
    pub fn set_sample_slices(&mut self, slices: Option<u32>) {
        self.sample_slices = slices.map(|n| n.clamp(1, MAX_SLICES));
    }

    /// Invocations per pixel in a dispatch of an image of `pixels`: enough for
    /// [`FULL_DISPATCH`] invocations, at most [`MAX_SLICES`].
    pub fn sample_slices(&self, pixels: u64) -> u32 {
        if !self.can_slice {
            return 1;
        }
        self.sample_slices.unwrap_or_else(|| {
            FULL_DISPATCH
                .div_ceil(pixels.max(1))
                .clamp(1, u64::from(MAX_SLICES)) as u32
        })
    }

    fn queued(&self, variant: Variant) -> bool {
        self.deferred_shadows && (variant.sun || variant.lights)
    }

    /// Builds a variant's pipelines now (they are cached), sliced or not.
    pub fn prepare(
        &mut self,
        ctx: &GpuContext,
        variant: Variant,
        sliced: bool,
    ) -> Result<(), GpuError> {
        let queued = self.queued(variant);
        if let std::collections::hash_map::Entry::Vacant(slot) =
            self.passes.entry((variant, queued, sliced))
        {
            slot.insert(ComputePass::specialized(
                ctx,
                if sliced { SLICED_SPIRV } else { SPIRV },
                BINDINGS,
                0,
                &variant.constants(queued),
            )?);
        }
        let key = (variant.count_rays, variant.experiment, variant.lights);
        if queued && !self.shadow_passes.contains_key(&key) {
            let pass = ComputePass::specialized(
                ctx,
                SHADOW_SPIRV,
                BINDINGS,
                0,
                &[
                    variant.count_rays as u32,
                    variant.experiment,
                    variant.lights as u32,
                ],
            )?;
            self.shadow_passes.insert(key, pass);
        }
        Ok(())
    }

    /// A queue of at least `rays` capacity (within the bounds and the limit): kept while it
    /// is large enough (a smaller batch does not reallocate it), replaced when too small or
    /// above a lowered limit.
    fn ensure_queue(&mut self, ctx: &GpuContext, rays: u64, max: u64) -> Result<(), GpuError> {
        let capacity = rays
            .clamp(QUEUE_MIN, max)
            .min(self.queue_limit)
            .min(queue_fit(&ctx.limits));
        if self
            .queue
            .as_ref()
            .is_some_and(|q| q.capacity >= capacity && q.capacity <= self.queue_limit)
        {
            return Ok(());
        }
        if let Some(old) = self.queue.take() {
            // The viewport's other frame in flight may still trace with the old queue (found
            // by the soak test: more samples per frame, more bounces or a first lamp ask for a
            // larger queue while a frame runs); growing is rare, so wait for the device rather
            // than track retirees.
            // SAFETY: no command buffer of this thread is being submitted meanwhile.
            vk_call("vkDeviceWaitIdle", unsafe { ctx.device.device_wait_idle() })?;
            old.rays.destroy(ctx);
            old.header.destroy(ctx);
        }
        let rays = HostBuffer::new(
            ctx,
            "shadow rays",
            capacity * SHADOW_RAY_BYTES,
            MemoryLocation::GpuOnly,
        )?;
        let header = match HostBuffer::new(ctx, "shadow queue", 16, MemoryLocation::GpuOnly) {
            Ok(h) => h,
            Err(e) => {
                rays.destroy(ctx);
                return Err(e);
            }
        };
        self.queue = Some(ShadowQueue {
            rays,
            header,
            capacity,
        });
        Ok(())
    }

    /// The driver's statistics of a variant's pipeline (built if needed).
    pub fn statistics(
        &mut self,
        ctx: &GpuContext,
        variant: Variant,
    ) -> Result<Vec<(String, String)>, GpuError> {
        self.prepare(ctx, variant, false)?;
        let mut stats = self.passes[&(variant, self.queued(variant), false)].statistics(ctx);
        if let Some(shadow) = self
            .shadow_passes
            .get(&(variant.count_rays, variant.experiment, variant.lights))
            .filter(|_| self.queued(variant))
        {
            stats.extend(
                shadow
                    .statistics(ctx)
                    .into_iter()
                    .map(|(k, v)| (format!("shadow pass {k}"), v)),
            );
        }
        Ok(stats)
    }

    /// Variants built so far.
    pub fn variants(&self) -> usize {
        self.passes.len()
    }

    /// One dispatch of `p` (its batch of samples, `p.image[2]` per invocation) into `accum`
    /// (one vec4 per pixel: radiance sum and sample count), each pixel's samples split among
    /// `slices` invocations (1 unless [`PathTracer::sample_slices`] allows more); returns its
    /// GPU time when `time` is set and the queue can time.
    #[allow(clippy::too_many_arguments)]
    pub fn dispatch(
        &mut self,
        ctx: &GpuContext,
        world: &GpuWorld,
        variant: Variant,
        p: &TraceParams,
        slices: u32,
        uniforms: &mut HostBuffer,
        accum: Binding,
        time: bool,
    ) -> Result<Option<f64>, GpuError> {
        self.dispatch_repeated(ctx, world, variant, p, slices, uniforms, accum, 1, time)
            .map(|t| t.first().copied())
    }

    /// [`PathTracer::dispatch`] `count` times back to back in one submission (benchmarks:
    /// the GPU stays busy, so its clocks stay up); the GPU time of each when `time` is set.
    #[allow(clippy::too_many_arguments)]
    pub fn dispatch_repeated(
        &mut self,
        ctx: &GpuContext,
        world: &GpuWorld,
        variant: Variant,
        p: &TraceParams,
        slices: u32,
        uniforms: &mut HostBuffer,
        accum: Binding,
        count: u32,
        time: bool,
    ) -> Result<Vec<f64>, GpuError> {
        let plan = self.plan(ctx, world, variant, p, slices, uniforms, accum)?;
        let (trace, shadow) = self.passes_of(&plan);
        let cache = self.cache_pass(&plan);
        let mut sets = Vec::new();
        for pass in std::iter::once(trace).chain(shadow).chain(cache) {
            match pass.allocate_set(ctx, &plan.bound) {
                Ok(set) => sets.push((pass, set)),
                Err(e) => {
                    for (pass, set) in sets {
                        pass.free_set(ctx, set);
                    }
                    return Err(e);
                }
            }
        }
        let set_of = |k: usize| sets.get(k).map(|s| s.1);
        let shadow_set = shadow.and(set_of(1));
        let cache_set = cache.and(set_of(1 + shadow.is_some() as usize));
        let first = std::cell::Cell::new(true);
        let result = run_batch(ctx, count, time, |cmd| {
            // Only the batch's first dispatch may drop the cache's counts.
            let cache = plan.cache.map(|reset| reset && first.replace(false));
            let cache = cache.zip(cache_set);
            self.record_plan(ctx, cmd, &plan, cache, sets[0].1, shadow_set)
        });
        for (pass, set) in sets {
            pass.free_set(ctx, set);
        }
        result
    }

    /// Records one dispatch of `p` into `cmd` without submitting (the interactive frame):
    /// like [`PathTracer::dispatch`], with descriptor sets from `sets` (made once per
    /// binding set and kept). The caller orders it after earlier writes to the buffers.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        cmd: vk::CommandBuffer,
        world: &GpuWorld,
        variant: Variant,
        p: &TraceParams,
        slices: u32,
        uniforms: &mut HostBuffer,
        accum: Binding,
        sets: &mut SetCache,
        band: Band,
    ) -> Result<(), GpuError> {
        let mut plan = self.plan(ctx, world, variant, p, slices, uniforms, accum)?;
        if band.count > 1 {
            let Dispatch::Groups(x, y, z) = plan.groups else {
                unreachable!("a plan dispatches groups")
            };
            plan.groups = Dispatch::Rows(x, band.rows(y), z);
            // The sliced shader's zeroing of a new accumulation, and the cache's factors: once,
            // before the first band (the pass's bands sample as its one dispatch would).
            if band.index > 0 {
                plan.zero = None;
                plan.cache = None;
            }
        }
        let (trace, shadow) = self.passes_of(&plan);
        let trace_set = sets.get(ctx, trace, &plan.bound)?;
        let shadow_set = shadow.map(|s| sets.get(ctx, s, &plan.bound)).transpose()?;
        let cache_set = self
            .cache_pass(&plan)
            .map(|c| sets.get(ctx, c, &plan.bound))
            .transpose()?;
        let cache = plan.cache.zip(cache_set);
        self.record_plan(ctx, cmd, &plan, cache, trace_set, shadow_set);
        Ok(())
    }

    /// Builds what a dispatch needs (pipelines, queue) and writes its parameters.
    #[allow(clippy::too_many_arguments)]
    fn plan(
        &mut self,
        ctx: &GpuContext,
        world: &GpuWorld,
        variant: Variant,
        p: &TraceParams,
        slices: u32,
        uniforms: &mut HostBuffer,
        accum: Binding,
    ) -> Result<Plan, GpuError> {
        let slices = if self.can_slice {
            slices.clamp(1, MAX_SLICES)
        } else {
            1
        };
        let sliced = slices > 1;
        self.prepare(ctx, variant, sliced)?;
        let queued = self.queued(variant);
        if queued {
            let samples = p.image[0] as u64 * p.image[1] as u64 * p.image[2] as u64 * slices as u64;
            let (per_sample, max) = if variant.lights {
                let per_vertex = 1 + variant.sun as u64;
                (
                    per_vertex * variant.max_bounces.min(4) as u64,
                    QUEUE_MAX_LIGHTS,
                )
            } else {
                (1, QUEUE_MAX)
            };
            self.ensure_queue(ctx, samples * per_sample, max)?;
        }
        let cached = variant.lights && variant.experiment & EXPERIMENT_LIGHT_CACHE != 0;
        if cached && self.cache.is_none() {
            self.cache = Some(LightCache::new(ctx, BINDINGS)?);
        }
        uniforms.write(bytemuck::bytes_of(p));
        let mut bound = world.bindings();
        bound.extend([uniforms.binding(), accum, self.counters.binding()]);
        let queue = self.queue.as_ref().filter(|_| queued);
        match queue {
            Some(q) => bound.extend([q.rays.binding(), q.header.binding()]),
            // Unused without the queue (SHADOW_QUEUE is false): any valid buffer.
            None => bound.extend([self.counters.binding(), self.counters.binding()]),
        }
        bound.push(world.light_binding());
        // Unused without the cache: any valid buffer.
        bound.push(match &self.cache {
            Some(cache) => cache.binding(),
            None => self.counters.binding(),
        });
        // The counts outlive an accumulation (a camera move keeps what the cells learnt) but
        // not a change of the world's voxels or lights: then they start again from none, so
        // the same world and dispatches give the same images.
        let cache = match &mut self.cache {
            Some(c) if cached => Some(c.reset_for(world)),
            _ => None,
        };
        Ok(Plan {
            pass: (variant, queued, sliced),
            shadow: queued.then_some((variant.count_rays, variant.experiment, variant.lights)),
            bound,
            groups: Dispatch::Groups(p.image[0].div_ceil(8), p.image[1].div_ceil(8), slices),
            // The sliced shader only adds: a new accumulation starts from zero.
            zero: (sliced && p.seed[3] == 0).then_some(accum),
            header: queue.map(|q| q.header.binding()),
            cache,
        })
    }

    fn cache_pass(&self, plan: &Plan) -> Option<&ComputePass> {
        plan.cache.and(self.cache.as_ref()).map(LightCache::pass)
    }

    /// The light visibility cache's buffer (tests read it back), once a light-sampling
    /// dispatch has made it.
    pub fn light_cache(&self) -> Option<Binding> {
        self.cache.as_ref().map(LightCache::binding)
    }

    fn passes_of(&self, plan: &Plan) -> (&ComputePass, Option<&ComputePass>) {
        (
            &self.passes[&plan.pass],
            plan.shadow.map(|k| &self.shadow_passes[&k]),
        )
    }

    /// Records a planned dispatch: zeroing and queue reset, the light visibility cache's pass
    /// (`cache`: whether it drops the counts, and its set), the trace pass, the shadow pass.
    fn record_plan(
        &self,
        ctx: &GpuContext,
        cmd: vk::CommandBuffer,
        plan: &Plan,
        cache: Option<(bool, vk::DescriptorSet)>,
        trace_set: vk::DescriptorSet,
        shadow_set: Option<vk::DescriptorSet>,
    ) {
        let (trace, shadow) = self.passes_of(plan);
        // SAFETY: recording; the accumulation range and the 16-byte queue header are
        // transfer destinations.
        unsafe {
            if let Some(a) = plan.zero {
                ctx.device
                    .cmd_fill_buffer(cmd, a.buffer, a.offset, a.range, 0);
            }
            if let Some(h) = plan.header {
                ctx.device.cmd_update_buffer(
                    cmd,
                    h.buffer,
                    h.offset,
                    bytemuck::cast_slice(&QUEUE_RESET),
                );
            }
            if plan.zero.is_some() || plan.header.is_some() {
                barrier(ctx, cmd, Scope::TRANSFER_WRITE, Scope::SHADER_RW);
            }
        }
        if let (Some((reset, set)), Some(c)) = (cache, &self.cache) {
            c.record(ctx, cmd, set, reset);
        }
        trace.record(ctx, cmd, trace_set, &[], plan.groups);
        if let (Some(h), Some(shadow), Some(set)) = (plan.header, shadow, shadow_set) {
            // SAFETY: recording.
            unsafe {
                barrier(ctx, cmd, Scope::SHADER_WRITE, Scope::SHADER_RW_INDIRECT);
            }
            shadow.record(ctx, cmd, set, &[], Dispatch::Indirect(h.buffer, h.offset));
        }
    }

    /// Zeroes the ray counters (before a counted render).
    pub(crate) fn reset_counters(&mut self) {
        self.counters.write(&[0; COUNTERS_BYTES as usize]);
    }

    /// The ray counters after a counted render.
    pub(crate) fn read_counters(&self) -> RayCounts {
        let c: [u32; COUNTERS] =
            bytemuck::pod_read_unaligned(&self.counters.read()[..COUNTERS_BYTES as usize]);
        RayCounts {
            primary: c[0] as u64,
            secondary: c[1] as u64,
            shadow: c[2] as u64,
            steps: [c[3] as u64, c[4] as u64, c[5] as u64],
            max_steps: [c[6] as u64, c[7] as u64],
            capped: c[8] as u64,
            lane_steps: [c[9] as u64, c[10] as u64],
        }
    }

    /// Destroys the pipelines.
    pub fn destroy(self, ctx: &GpuContext) {
        for (_, pass) in self.passes {
            pass.destroy(ctx);
        }
        for (_, pass) in self.shadow_passes {
            pass.destroy(ctx);
        }
        if let Some(q) = self.queue {
            q.rays.destroy(ctx);
            q.header.destroy(ctx);
        }
        self.counters.destroy(ctx);
        if let Some(cache) = self.cache {
            cache.destroy(ctx);
        }
    }
}
