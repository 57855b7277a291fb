//! Frames in flight: each slot has its command buffer, a fence (signalled when the slot's
//! last submission finished), a semaphore for the swapchain image it acquires, its own
//! parameter buffer and display output (the host writes them while the other slot runs),
//! descriptor sets made once and kept, and two timestamps around its GPU work.

use super::buffer::HostBuffer;
use super::pass::SetCache;
use super::trace::TraceParams;
use super::{GpuContext, GpuError, vk_call};
use ash::vk;
use gpu_allocator::MemoryLocation;

/// Frames the interactive loop keeps in flight.
pub const FRAMES_IN_FLIGHT: usize = 2;

/// One frame's resources.
pub struct FrameSlot {
    pool: vk::CommandPool,
    /// The slot's command buffer.
    pub cmd: vk::CommandBuffer,
    /// Signalled when the slot's last submission finished (created signalled).
    pub fence: vk::Fence,
    /// Signalled by the swapchain when the image this frame acquired is ready.
    pub acquired: vk::Semaphore,
    /// Trace parameters of this frame's dispatch.
    pub uniforms: HostBuffer,
    /// The display output (packed 8-bit pixels at the output size).
    pub ldr: Option<HostBuffer>,
    /// Descriptor sets bound by this slot.
    pub sets: SetCache,
    queries: Option<vk::QueryPool>,
    /// The two timestamps, copied here by the GPU at the end of the frame (reading the query
    /// pool from the host blocks on lavapipe even after the fence; a buffer read never does).
    times: HostBuffer,
    /// Whether the timestamps were written by the last submission.
    timed: bool,
}

impl FrameSlot {
    /// A slot whose fence starts signalled.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let d = &ctx.device;
        // SAFETY: create infos outlive the calls; everything is destroyed in `destroy`.
        unsafe {
            let pool = vk_call(
                "vkCreateCommandPool",
                d.create_command_pool(
                    &vk::CommandPoolCreateInfo::default()
                        .queue_family_index(ctx.queue_family)
                        .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                    None,
                ),
            )?;
            let cmd = vk_call(
                "vkAllocateCommandBuffers",
                d.allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(pool)
                        .level(vk::CommandBufferLevel::PRIMARY)
                        .command_buffer_count(1),
                ),
            )?[0];
            let fence = vk_call(
                "vkCreateFence",
                d.create_fence(
                    &vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED),
                    None,
                ),
            )?;
            let acquired = vk_call(
                "vkCreateSemaphore",
                d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None),
            )?;
            let queries = if ctx.timestamp_period > 0.0 {
                let info = vk::QueryPoolCreateInfo::default()
                    .query_type(vk::QueryType::TIMESTAMP)
                    .query_count(2);
                Some(vk_call(
                    "vkCreateQueryPool",
                    d.create_query_pool(&info, None),
                )?)
            } else {
                None
            };
            Ok(Self {
                pool,
                cmd,
                fence,
                acquired,
                uniforms: HostBuffer::new(
                    ctx,
                    "frame trace params",
                    std::mem::size_of::<TraceParams>() as u64,
                    MemoryLocation::CpuToGpu,
                )?,
                ldr: None,
                times: HostBuffer::new(ctx, "frame timestamps", 16, MemoryLocation::GpuToCpu)?,
                sets: SetCache::new(ctx)?,
                queries,
                timed: false,
            })
        }
    }

    /// Whether the slot's last submission finished (never blocks).
    pub fn ready(&self, ctx: &GpuContext) -> Result<bool, GpuError> {
        // SAFETY: plain query on a live fence.
        vk_call("vkGetFenceStatus", unsafe {
            ctx.device.get_fence_status(self.fence)
        })
    }

    /// Blocks until the slot's last submission finished (shutdown, capture, resize).
    pub fn wait(&self, ctx: &GpuContext) -> Result<(), GpuError> {
        // SAFETY: plain wait on a live fence.
        vk_call("vkWaitForFences", unsafe {
            ctx.device.wait_for_fences(&[self.fence], true, u64::MAX)
        })
    }

    /// GPU time of the slot's last submission (call once it is ready).
    pub fn gpu_seconds(&self, ctx: &GpuContext) -> Option<f64> {
        self.queries.filter(|_| self.timed)?;
        // The fence signalled, so the copy of both timestamps is done and visible.
        let ticks: [u64; 2] = bytemuck::pod_read_unaligned(&self.times.read()[..16]);
        Some(ticks[1].wrapping_sub(ticks[0]) as f64 * ctx.timestamp_period as f64 * 1e-9)
    }

    /// Starts recording (the slot must be ready); the first timestamp is written.
    pub fn begin(&mut self, ctx: &GpuContext) -> Result<vk::CommandBuffer, GpuError> {
        self.sets.trim(ctx);
        let d = &ctx.device;
        // SAFETY: the slot's previous submission finished (the caller checked `ready`).
        unsafe {
            vk_call(
                "vkResetCommandBuffer",
                d.reset_command_buffer(self.cmd, vk::CommandBufferResetFlags::empty()),
            )?;
            vk_call(
                "vkBeginCommandBuffer",
                d.begin_command_buffer(
                    self.cmd,
                    &vk::CommandBufferBeginInfo::default()
                        .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                ),
            )?;
            if let Some(q) = self.queries {
                d.cmd_reset_query_pool(self.cmd, q, 0, 2);
                d.cmd_write_timestamp(self.cmd, vk::PipelineStageFlags::TOP_OF_PIPE, q, 0);
            }
        }
        self.timed = false;
        Ok(self.cmd)
    }

    /// A display output of at least `bytes`, kept while large enough.
    pub fn ensure_ldr(&mut self, ctx: &GpuContext, bytes: u64) -> Result<(), GpuError> {
        if self.ldr.as_ref().is_some_and(|b| b.size >= bytes) {
            return Ok(());
        }
        if let Some(old) = self.ldr.take() {
            // The slot is ready, so its sets no longer matter; drop those naming the buffer.
            self.sets.clear(ctx);
            old.destroy(ctx);
        }
        self.ldr = Some(HostBuffer::new(
            ctx,
            "display output",
            bytes,
            MemoryLocation::GpuOnly,
        )?);
        Ok(())
    }

    /// Ends recording (second timestamp) and submits, waiting on `waits` and signalling
    /// `signals` and the fence. Never waits on the host.
    pub fn submit(
        &mut self,
        ctx: &GpuContext,
        waits: &[(vk::Semaphore, vk::PipelineStageFlags)],
        signals: &[vk::Semaphore],
    ) -> Result<(), GpuError> {
        let d = &ctx.device;
        // SAFETY: the command buffer is recording; the fence is signalled (slot ready).
        unsafe {
            if let Some(q) = self.queries {
                d.cmd_write_timestamp(self.cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, q, 1);
                d.cmd_copy_query_pool_results(
                    self.cmd,
                    q,
                    0,
                    2,
                    self.times.raw,
                    0,
                    8,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                );
                super::barrier::barrier(
                    ctx,
                    self.cmd,
                    crate::vulkan::barrier::Scope::TRANSFER_WRITE,
                    crate::vulkan::barrier::Scope::HOST_READ,
                );
                self.timed = true;
            }
            vk_call("vkEndCommandBuffer", d.end_command_buffer(self.cmd))?;
            let (sems, stages): (Vec<_>, Vec<_>) = waits.iter().copied().unzip();
            let cmds = [self.cmd];
            let submit = [vk::SubmitInfo::default()
                .wait_semaphores(&sems)
                .wait_dst_stage_mask(&stages)
                .command_buffers(&cmds)
                .signal_semaphores(signals)];
            vk_call("vkResetFences", d.reset_fences(&[self.fence]))?;
            vk_call(
                "vkQueueSubmit",
                d.queue_submit(ctx.queue, &submit, self.fence),
            )
        }
    }

    /// Destroys the slot (after its last submission finished).
    pub fn destroy(self, ctx: &GpuContext) {
        let _ = self.wait(ctx);
        let d = &ctx.device;
        // SAFETY: the fence wait above: nothing of the slot is in use.
        unsafe {
            if let Some(q) = self.queries {
                d.destroy_query_pool(q, None);
            }
            d.destroy_semaphore(self.acquired, None);
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
        }
        self.sets.destroy(ctx);
        self.times.destroy(ctx);
        self.uniforms.destroy(ctx);
        if let Some(l) = self.ldr {
            l.destroy(ctx);
        }
    }
}
