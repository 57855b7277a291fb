//! The staging ring: N host-visible staging buffers, each with its command buffer and fence.
//! A flush packs queued uploads into the next free slot (waiting for that slot's previous
//! copy only), records one `vkCmdCopyBuffer` with as few regions as the destinations allow,
//! and submits without waiting. What does not fit stays queued for the next flush: queued
//! uploads own their bytes (copied when they were queued), so a deferred upload never reads
//! world data that may have changed since.

use super::barrier::{Scope, after_transfer, barrier, before_transfer};
use super::buffer::HostBuffer;
use super::{GpuContext, GpuError, vk_call};
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::collections::VecDeque;

/// Bytes waiting to be copied to `offset` of a destination the caller resolves at flush time
/// (`region` picks it, so a destination that moved — a grown buffer — is still right).
#[derive(Clone, Debug)]
pub struct Upload {
    /// Which destination region (the caller's numbering).
    pub region: usize,
    /// Byte offset inside the region.
    pub offset: u64,
    /// The bytes, owned.
    pub bytes: Vec<u8>,
    /// Bytes already copied by earlier flushes.
    pub done: usize,
}

/// What one flush did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Flushed {
    /// Bytes copied.
    pub bytes: u64,
    /// Copy regions recorded.
    pub regions: u32,
}

struct Slot {
    buffer: HostBuffer,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    in_flight: bool,
}

/// N staging buffers used round-robin.
pub struct StagingRing {
    pool: vk::CommandPool,
    slots: Vec<Slot>,
    next: usize,
    slot_size: u64,
}

impl StagingRing {
    /// A ring of `slots` staging buffers of `slot_size` bytes each (at most the device's
    /// allocation size: uploads larger than a slot span several flushes).
    pub fn new(ctx: &GpuContext, slots: usize, slot_size: u64) -> Result<Self, GpuError> {
        let slot_size = slot_size.min(ctx.limits.allocation & !3).max(4);
        let d = &ctx.device;
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: the pool is destroyed in `destroy` (or below on failure).
        let pool = vk_call("vkCreateCommandPool", unsafe {
            d.create_command_pool(&info, None)
        })?;
        let mut ring = Self {
            pool,
            slots: Vec::new(),
            next: 0,
            slot_size,
        };
        for _ in 0..slots.max(1) {
            match ring.make_slot(ctx) {
                Ok(slot) => ring.slots.push(slot),
                Err(e) => {
                    ring.destroy(ctx);
                    return Err(e);
                }
            }
        }
        Ok(ring)
    }

    fn make_slot(&self, ctx: &GpuContext) -> Result<Slot, GpuError> {
        let d = &ctx.device;
        let buffer = HostBuffer::new(
            ctx,
            "staging ring",
            self.slot_size,
            MemoryLocation::CpuToGpu,
        )?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: objects are owned by the slot and destroyed in `destroy`.
        let made = unsafe {
            vk_call(
                "vkAllocateCommandBuffers",
                d.allocate_command_buffers(&alloc),
            )
            .and_then(|cmd| {
                vk_call(
                    "vkCreateFence",
                    d.create_fence(&vk::FenceCreateInfo::default(), None),
                )
                .map(|fence| (cmd[0], fence))
            })
        };
        match made {
            Ok((cmd, fence)) => Ok(Slot {
                buffer,
                cmd,
                fence,
                in_flight: false,
            }),
            Err(e) => {
                buffer.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Bytes one flush can carry.
    pub fn slot_size(&self) -> u64 {
        self.slot_size
    }

    /// Copies as much of `queue` as fits in one slot to the destinations `resolve` gives for
    /// each region (buffer, base offset), and submits; the copies are ordered after earlier
    /// shader reads and made visible to later compute shaders and transfers.
    pub fn flush(
        &mut self,
        ctx: &GpuContext,
        queue: &mut VecDeque<Upload>,
        resolve: impl Fn(usize) -> (vk::Buffer, u64),
    ) -> Result<Flushed, GpuError> {
        if queue.is_empty() {
            return Ok(Flushed::default());
        }
        let d = &ctx.device;
        let slot_index = self.next;
        self.wait_slot(ctx, slot_index)?;
        let slot = &mut self.slots[slot_index];
        // Pack: per destination buffer, regions in queue order (later bytes overwrite earlier
        // ones in submission order, which vkCmdCopyBuffer regions must not overlap within
        // one command, so overlapping uploads are split into separate copy commands).
        let mut commands: Vec<(vk::Buffer, Vec<vk::BufferCopy>)> = Vec::new();
        let mut cursor = 0u64;
        while let Some(front) = queue.front_mut() {
            let room = self.slot_size - cursor;
            let left = (front.bytes.len() - front.done) as u64;
            let n = left.min(room);
            if n == 0 {
                break;
            }
            let (dst, base) = resolve(front.region);
            let copy = vk::BufferCopy {
                src_offset: cursor,
                dst_offset: base + front.offset + front.done as u64,
                size: n,
            };
            let staged_bytes = &front.bytes[front.done..front.done + n as usize];
            slot.buffer.write_at(cursor as usize, staged_bytes);
            push_copy(&mut commands, dst, copy);
            cursor += n;
            front.done += n as usize;
            if front.done == front.bytes.len() {
                queue.pop_front();
            }
        }
        let regions = commands.iter().map(|(_, r)| r.len() as u32).sum();
        let src = slot.buffer.raw;
        // SAFETY: the slot's previous submission finished (wait_slot); the staging buffer and
        // destinations outlive the submission (destinations are only destroyed after
        // `wait_idle`).
        unsafe {
            vk_call(
                "vkResetCommandBuffer",
                d.reset_command_buffer(slot.cmd, vk::CommandBufferResetFlags::empty()),
            )?;
            vk_call(
                "vkBeginCommandBuffer",
                d.begin_command_buffer(
                    slot.cmd,
                    &vk::CommandBufferBeginInfo::default()
                        .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                ),
            )?;
            before_transfer(ctx, slot.cmd);
            for (i, (dst, copies)) in commands.iter().enumerate() {
                if i > 0 {
                    barrier(ctx, slot.cmd, Scope::TRANSFER_WRITE, Scope::TRANSFER_WRITE);
                }
                d.cmd_copy_buffer(slot.cmd, src, *dst, copies);
            }
            after_transfer(ctx, slot.cmd);
            vk_call("vkEndCommandBuffer", d.end_command_buffer(slot.cmd))?;
            let cmds = [slot.cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            vk_call(
                "vkQueueSubmit",
                d.queue_submit(ctx.queue, &submit, slot.fence),
            )?;
        }
        slot.in_flight = true;
        self.next = (self.next + 1) % self.slots.len();
        Ok(Flushed {
            bytes: cursor,
            regions,
        })
    }

    fn wait_slot(&mut self, ctx: &GpuContext, i: usize) -> Result<(), GpuError> {
        let slot = &mut self.slots[i];
        if slot.in_flight {
            // SAFETY: the fence belongs to this device and was submitted.
            unsafe {
                vk_call(
                    "vkWaitForFences",
                    ctx.device.wait_for_fences(&[slot.fence], true, u64::MAX),
                )?;
                vk_call("vkResetFences", ctx.device.reset_fences(&[slot.fence]))?;
            }
            slot.in_flight = false;
        }
        Ok(())
    }

    /// Waits until every submitted copy finished.
    pub fn wait_idle(&mut self, ctx: &GpuContext) -> Result<(), GpuError> {
        (0..self.slots.len()).try_for_each(|i| self.wait_slot(ctx, i))
    }

    /// Frees the ring, after waiting for its copies.
    pub fn destroy(mut self, ctx: &GpuContext) {
        let _ = self.wait_idle(ctx);
        for slot in self.slots.drain(..) {
            // SAFETY: the slot's work finished (wait_idle) or it was never submitted.
            unsafe { ctx.device.destroy_fence(slot.fence, None) };
            slot.buffer.destroy(ctx);
        }
        // SAFETY: freeing the pool frees its command buffers, none of which is pending.
        unsafe { ctx.device.destroy_command_pool(self.pool, None) };
    }
}

/// Appends a copy, merging it into the previous region when both source and destination
/// continue it; starts a new copy command when its destination does not lie after the
/// previous region's (regions of one command must not overlap).
fn push_copy(
    commands: &mut Vec<(vk::Buffer, Vec<vk::BufferCopy>)>,
    dst: vk::Buffer,
    c: vk::BufferCopy,
) {
    if let Some((buffer, copies)) = commands.last_mut()
        && *buffer == dst
    {
        if let Some(last) = copies.last_mut()
            && last.src_offset + last.size == c.src_offset
            && last.dst_offset + last.size == c.dst_offset
        {
            last.size += c.size;
            return;
        }
        // Destinations ascending within a command cannot overlap; checking the last region
        // keeps this O(1) per upload (a frame's uploads are queued in ascending order, so
        // only deferred leftovers followed by newer bytes start a new command).
        if copies
            .last()
            .is_none_or(|last| c.dst_offset >= last.dst_offset + last.size)
        {
            copies.push(c);
            return;
        }
    }
    commands.push((dst, vec![c]));
}
