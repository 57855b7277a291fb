//! A compute pass: one SPIR-V module, N storage buffers in set 0 (bindings 0..N), push
//! constants, dispatched synchronously with the results made visible to the host.
//!
//! In detail:
//! `ComputePass`: one SPIR-V module, N storage bindings, push constants, specialization
//! constants; `allocate_set` / `record` (direct or indirect dispatch) for multi-pass frames,
//! `run`/`run_repeated` for one pass; `SetCache`: descriptor sets made once per (layout,
//! bindings) and kept by a frame slot, trimmed only at a frame's start (its fence signalled).
//! `run_batch`: records a frame N times back to back in one submission (barriers between
//! repetitions), timestamps around each, waits; results visible to the host, later passes and
//! copies. Benchmarks repeat frames so the GPU never idles (an idle-looking GPU drops its
//! clocks). `statistics()`.

use super::barrier::{Scope, after_earlier_passes, barrier};
use super::buffer::Binding;
use super::{GpuContext, GpuError, vk_call};
use ash::vk;

/// How many workgroups a recorded dispatch runs.
#[derive(Clone, Copy, Debug)]
pub enum Dispatch {
    /// x × y × z groups.
    Groups(u32, u32, u32),
    /// The rows of groups `y0..y1` of an x × (rows) × z dispatch (its group IDs as in the
    /// whole one: a band of the image, so that a long dispatch can be submitted in parts).
    Rows(u32, (u32, u32), u32),
    /// Read by the device from a buffer (three u32 at the offset).
    Indirect(vk::Buffer, u64),
}

/// Records `record` `count` times back to back in one submission (each repetition after the
/// previous one's shader and transfer writes), then waits; afterwards shader writes are
/// visible to the host, later passes and copies. With `time`, the GPU time of each
/// repetition from timestamp queries (empty when the queue cannot time). Benchmarks use
/// repetitions: a GPU kept busy keeps its clocks up, while one dispatch per submission with
/// host work in between lets the driver lower them (seen on the H100: 1980 → 405 MHz in the
/// middle of a benchmark).
pub fn run_batch(
    ctx: &GpuContext,
    count: u32,
    time: bool,
    record: impl Fn(vk::CommandBuffer),
) -> Result<Vec<f64>, GpuError> {
    let d = &ctx.device;
    // SAFETY: the query pool is destroyed after the fence wait; commands are recorded into a
    // buffer that is recording.
    unsafe {
        let queries = if time && ctx.timestamp_period > 0.0 {
            let info = vk::QueryPoolCreateInfo::default()
                .query_type(vk::QueryType::TIMESTAMP)
                .query_count(2 * count);
            Some(vk_call(
                "vkCreateQueryPool",
                d.create_query_pool(&info, None),
            )?)
        } else {
            None
        };
        let result = ctx.submit_and_wait(|cmd| {
            // Host writes before the submit are visible to the device (submission order).
            if let Some(q) = queries {
                d.cmd_reset_query_pool(cmd, q, 0, 2 * count);
            }
            for k in 0..count {
                if k > 0 {
                    // The previous repetition's writes come first (same buffers).
                    after_earlier_passes(ctx, cmd);
                }
                // Start: once everything before has completed; end: once this has.
                if let Some(q) = queries {
                    d.cmd_write_timestamp(cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, q, 2 * k);
                }
                record(cmd);
                if let Some(q) = queries {
                    d.cmd_write_timestamp(
                        cmd,
                        vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                        q,
                        2 * k + 1,
                    );
                }
            }
            // Results are visible to the host and to later passes and copies.
            barrier(ctx, cmd, Scope::SHADER_WRITE, Scope::RESULTS_READ);
        });
        let mut elapsed = Vec::new();
        if let Some(q) = queries {
            let mut ticks = vec![0u64; 2 * count as usize];
            if result.is_ok()
                && d.get_query_pool_results(
                    q,
                    0,
                    &mut ticks,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                )
                .is_ok()
            {
                elapsed = ticks
                    .chunks_exact(2)
                    .map(|t| t[1].wrapping_sub(t[0]) as f64 * ctx.timestamp_period as f64 * 1e-9)
                    .collect();
            }
            d.destroy_query_pool(q, None);
        }
        result.map(|_| elapsed)
    }
}

/// A compute pipeline and what it needs to be bound.
pub struct ComputePass {
    module: vk::ShaderModule,
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    pool: vk::DescriptorPool,
    buffers: u32,
}

impl ComputePass {
    /// Builds the pipeline for SPIR-V bytes with `buffers` storage buffers and `push` bytes
    /// of push constants.
    pub fn new(ctx: &GpuContext, spirv: &[u8], buffers: u32, push: u32) -> Result<Self, GpuError> {
        Self::specialized(ctx, spirv, buffers, push, &[])
    }

    /// [`ComputePass::new`] with specialization constants: `constants[i]` is the 32-bit
    /// value of `constant_id = i` (booleans as 0 or 1).
    pub fn specialized(
        ctx: &GpuContext,
        spirv: &[u8],
        buffers: u32,
        push: u32,
        constants: &[u32],
    ) -> Result<Self, GpuError> {
        let d = &ctx.device;
        let entries: Vec<vk::SpecializationMapEntry> = (0..constants.len() as u32)
            .map(|i| vk::SpecializationMapEntry {
                constant_id: i,
                offset: 4 * i,
                size: 4,
            })
            .collect();
        let spec_data: &[u8] = bytemuck::cast_slice(constants);
        let spec = vk::SpecializationInfo::default()
            .map_entries(&entries)
            .data(spec_data);
        let words: Vec<u32> = spirv
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        let bindings: Vec<_> = (0..buffers)
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .size(push)];
        let sizes = [vk::DescriptorPoolSize::default()
            .ty(vk::DescriptorType::STORAGE_BUFFER)
            .descriptor_count(buffers)];
        // SAFETY: create infos outlive each call; objects are destroyed in `destroy`.
        unsafe {
            let module = vk_call(
                "vkCreateShaderModule",
                d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None),
            )?;
            let set_layout = vk_call(
                "vkCreateDescriptorSetLayout",
                d.create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                    None,
                ),
            )?;
            let set_layouts = [set_layout];
            let info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
            let info = if push > 0 {
                info.push_constant_ranges(&ranges)
            } else {
                info
            };
            let layout = vk_call(
                "vkCreatePipelineLayout",
                d.create_pipeline_layout(&info, None),
            )?;
            let stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module)
                .name(c"main");
            let stage = if constants.is_empty() {
                stage
            } else {
                stage.specialization_info(&spec)
            };
            // Any pass may be dispatched in bands of rows (`Dispatch::Rows`).
            let flags = if ctx.pipeline_stats.is_some() {
                vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR
            } else {
                vk::PipelineCreateFlags::empty()
            } | vk::PipelineCreateFlags::DISPATCH_BASE;
            let info = [vk::ComputePipelineCreateInfo::default()
                .flags(flags)
                .stage(stage)
                .layout(layout)];
            let pipeline = d
                .create_compute_pipelines(vk::PipelineCache::null(), &info, None)
                .map_err(|(_, result)| GpuError::Vk {
                    call: "vkCreateComputePipelines",
                    result,
                })?[0];
            let pool_info = vk::DescriptorPoolCreateInfo::default()
                .max_sets(1)
                .pool_sizes(&sizes)
                .flags(vk::DescriptorPoolCreateFlags::FREE_DESCRIPTOR_SET);
            let pool = vk_call(
                "vkCreateDescriptorPool",
                d.create_descriptor_pool(&pool_info, None),
            )?;
            Ok(Self {
                module,
                set_layout,
                layout,
                pipeline,
                pool,
                buffers,
            })
        }
    }

    /// Binds `buffers` to bindings 0.., pushes `push`, dispatches `groups` and waits; shader
    /// writes are visible to the host afterwards.
    pub fn run(
        &self,
        ctx: &GpuContext,
        buffers: &[Binding],
        push: &[u8],
        groups: [u32; 2],
    ) -> Result<(), GpuError> {
        self.run_repeated(ctx, buffers, push, groups, 1, false)
            .map(|_| ())
    }

    /// `count` identical dispatches back to back in one submission (each after the previous
    /// one's writes), then waits; with `time`, the GPU time of each (empty when the queue
    /// cannot time).
    pub fn run_repeated(
        &self,
        ctx: &GpuContext,
        buffers: &[Binding],
        push: &[u8],
        groups: [u32; 2],
        count: u32,
        time: bool,
    ) -> Result<Vec<f64>, GpuError> {
        ctx.limits
            .check_groups("a compute dispatch", [groups[0], groups[1], 1])?;
        let set = self.allocate_set(ctx, buffers)?;
        let result = run_batch(ctx, count, time, |cmd| {
            self.record(
                ctx,
                cmd,
                set,
                push,
                Dispatch::Groups(groups[0], groups[1], 1),
            )
        });
        self.free_set(ctx, set);
        result
    }

    /// A descriptor set binding `buffers` to bindings 0.. (one set per pass may be live).
    pub fn allocate_set(
        &self,
        ctx: &GpuContext,
        buffers: &[Binding],
    ) -> Result<vk::DescriptorSet, GpuError> {
        assert_eq!(buffers.len() as u32, self.buffers, "one buffer per binding");
        check_bindings(ctx, buffers)?;
        let d = &ctx.device;
        let layouts = [self.set_layout];
        // SAFETY: the pool and layout are alive; the writes' infos outlive the update.
        unsafe {
            let set = vk_call(
                "vkAllocateDescriptorSets",
                d.allocate_descriptor_sets(
                    &vk::DescriptorSetAllocateInfo::default()
                        .descriptor_pool(self.pool)
                        .set_layouts(&layouts),
                ),
            )?[0];
            write_set(ctx, set, buffers);
            Ok(set)
        }
    }

    /// Frees a set from [`ComputePass::allocate_set`] once no pending submission uses it.
    pub fn free_set(&self, ctx: &GpuContext, set: vk::DescriptorSet) {
        // SAFETY: the caller waited for every submission using the set.
        let _ = unsafe { ctx.device.free_descriptor_sets(self.pool, &[set]) };
    }

    /// Records one dispatch with `set` bound.
    pub fn record(
        &self,
        ctx: &GpuContext,
        cmd: vk::CommandBuffer,
        set: vk::DescriptorSet,
        push: &[u8],
        dispatch: Dispatch,
    ) {
        let d = &ctx.device;
        // SAFETY: the command buffer is recording; the set matches the layout.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                self.layout,
                0,
                &[set],
                &[],
            );
            if !push.is_empty() {
                d.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            }
            match dispatch {
                Dispatch::Groups(x, y, z) => d.cmd_dispatch(cmd, x, y, z),
                Dispatch::Rows(x, (y0, y1), z) => {
                    d.cmd_dispatch_base(cmd, 0, y0, 0, x, y1.saturating_sub(y0), z)
                }
                Dispatch::Indirect(buffer, offset) => d.cmd_dispatch_indirect(cmd, buffer, offset),
            }
        }
    }

    /// The driver's statistics of the compiled pipeline (name, value), e.g. register count
    /// and spills on NVIDIA; empty without VK_KHR_pipeline_executable_properties.
    pub fn statistics(&self, ctx: &GpuContext) -> Vec<(String, String)> {
        let Some(ext) = &ctx.pipeline_stats else {
            return Vec::new();
        };
        let mut out = Vec::new();
        // SAFETY: queries on a live pipeline created with CAPTURE_STATISTICS_KHR.
        unsafe {
            let info = vk::PipelineInfoKHR::default().pipeline(self.pipeline);
            let count = ext
                .get_pipeline_executable_properties(&info)
                .map_or(0, |p| p.len());
            for index in 0..count as u32 {
                let exec = vk::PipelineExecutableInfoKHR::default()
                    .pipeline(self.pipeline)
                    .executable_index(index);
                for st in ext
                    .get_pipeline_executable_statistics(&exec)
                    .unwrap_or_default()
                {
                    let name = st
                        .name_as_c_str()
                        .map(|n| n.to_string_lossy().into_owned())
                        .unwrap_or_default();
                    let value = match st.format {
                        vk::PipelineExecutableStatisticFormatKHR::BOOL32 => {
                            (st.value.b32 != 0).to_string()
                        }
                        vk::PipelineExecutableStatisticFormatKHR::INT64 => st.value.i64.to_string(),
                        vk::PipelineExecutableStatisticFormatKHR::UINT64 => {
                            st.value.u64.to_string()
                        }
                        _ => format!("{:.3}", st.value.f64),
                    };
                    out.push((name, value));
                }
            }
        }
        out
    }

    /// Destroys the pipeline's objects.
    pub fn destroy(self, ctx: &GpuContext) {
        let d = &ctx.device;
        // SAFETY: no submission using them is pending (every run waits for its fence).
        unsafe {
            d.destroy_descriptor_pool(self.pool, None);
            d.destroy_pipeline(self.pipeline, None);
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
            d.destroy_shader_module(self.module, None);
        }
    }
}

/// Refuses bindings whose range passes the device's `maxStorageBufferRange`: nothing is ever
/// bound past it (see [`super::limits`]).
fn check_bindings(ctx: &GpuContext, buffers: &[Binding]) -> Result<(), GpuError> {
    for (i, b) in buffers.iter().enumerate() {
        ctx.limits
            .check_binding(&format!("storage binding {i}"), b.range)?;
    }
    Ok(())
}

/// Points `set`'s bindings 0.. at `buffers`.
fn write_set(ctx: &GpuContext, set: vk::DescriptorSet, buffers: &[Binding]) {
    let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
        .iter()
        .map(|b| {
            [vk::DescriptorBufferInfo::default()
                .buffer(b.buffer)
                .offset(b.offset)
                .range(b.range)]
        })
        .collect();
    let writes: Vec<vk::WriteDescriptorSet> = infos
        .iter()
        .enumerate()
        .map(|(b, info)| {
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(b as u32)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(info)
        })
        .collect();
    // SAFETY: the set is not in use by a pending submission (fresh from its pool).
    unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };
}

/// Descriptor sets made once per (pass, buffers) and kept: what one frame slot of the
/// interactive loop binds. When the buffers change (a grown world, a resized image) new sets
/// are made; [`SetCache::clear`] drops them all once the slot's submission is done.
pub struct SetCache {
    pool: vk::DescriptorPool,
    sets: std::collections::HashMap<SetKey, vk::DescriptorSet>,
}

/// A set's identity: its layout and the (buffer, offset, range) of each binding.
type SetKey = (vk::DescriptorSetLayout, Vec<(vk::Buffer, u64, u64)>);

/// Sets a cache holds before it starts over.
const CACHED_SETS: u32 = 40;
/// New sets one frame may make: trace, shadow, denoiser, temporal and display passes, with
/// room to spare.
pub const SET_HEADROOM: u32 = 10;
/// Storage buffers per cached set at most.
const CACHED_BUFFERS: u32 = 16;

impl SetCache {
    /// An empty cache with its own pool.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let sizes = [vk::DescriptorPoolSize::default()
            .ty(vk::DescriptorType::STORAGE_BUFFER)
            .descriptor_count(CACHED_SETS * CACHED_BUFFERS)];
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(CACHED_SETS)
            .pool_sizes(&sizes);
        // SAFETY: the create info outlives the call; the pool is destroyed in `destroy`.
        let pool = vk_call("vkCreateDescriptorPool", unsafe {
            ctx.device.create_descriptor_pool(&info, None)
        })?;
        Ok(Self {
            pool,
            sets: Default::default(),
        })
    }

    /// The set binding `buffers` for `pass`, made on first use (at most [`SET_HEADROOM`]
    /// new ones per frame after [`SetCache::trim`]).
    pub fn get(
        &mut self,
        ctx: &GpuContext,
        pass: &ComputePass,
        buffers: &[Binding],
    ) -> Result<vk::DescriptorSet, GpuError> {
        assert_eq!(buffers.len() as u32, pass.buffers, "one buffer per binding");
        let key = (
            pass.set_layout,
            buffers
                .iter()
                .map(|b| (b.buffer, b.offset, b.range))
                .collect(),
        );
        if let Some(&set) = self.sets.get(&key) {
            return Ok(set);
        }
        check_bindings(ctx, buffers)?;
        let layouts = [pass.set_layout];
        // SAFETY: pool and layout are alive.
        let set = vk_call("vkAllocateDescriptorSets", unsafe {
            ctx.device.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(self.pool)
                    .set_layouts(&layouts),
            )
        })?[0];
        write_set(ctx, set, buffers);
        self.sets.insert(key, set);
        Ok(set)
    }

    /// At the start of a frame, once the slot's previous submission finished: starts over
    /// when fewer than [`SET_HEADROOM`] sets are left.
    pub fn trim(&mut self, ctx: &GpuContext) {
        if self.sets.len() as u32 + SET_HEADROOM > CACHED_SETS {
            self.clear(ctx);
        }
    }

    /// Drops every set (no pending submission may use them).
    pub fn clear(&mut self, ctx: &GpuContext) {
        self.sets.clear();
        // SAFETY: the caller guarantees no pending submission uses the sets.
        let _ = unsafe {
            ctx.device
                .reset_descriptor_pool(self.pool, vk::DescriptorPoolResetFlags::empty())
        };
    }

    /// Destroys the pool (no pending submission may use its sets).
    pub fn destroy(self, ctx: &GpuContext) {
        // SAFETY: as above.
        unsafe { ctx.device.destroy_descriptor_pool(self.pool, None) };
    }
}
