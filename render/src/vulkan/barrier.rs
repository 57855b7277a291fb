//! Memory barriers shared by every pass: a global barrier, and the pair that orders transfers
//! against shader work.

use super::GpuContext;
use ash::vk;

/// Orders transfers after earlier shader and transfer writes and reads (WAR and WAW).
///
/// # Safety
/// `cmd` must be recording.
pub(crate) unsafe fn before_transfer(ctx: &GpuContext, cmd: vk::CommandBuffer) {
    // SAFETY: forwarded from the caller.
    unsafe {
        barrier(
            ctx,
            cmd,
            vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
            vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE,
            vk::PipelineStageFlags::TRANSFER,
            vk::AccessFlags::TRANSFER_READ | vk::AccessFlags::TRANSFER_WRITE,
        )
    }
}

/// Makes transfer writes visible to later compute shaders and transfers.
///
/// # Safety
/// `cmd` must be recording.
pub(crate) unsafe fn after_transfer(ctx: &GpuContext, cmd: vk::CommandBuffer) {
    // SAFETY: forwarded from the caller.
    unsafe {
        barrier(
            ctx,
            cmd,
            vk::PipelineStageFlags::TRANSFER,
            vk::AccessFlags::TRANSFER_WRITE,
            vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
            vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::TRANSFER_READ
                | vk::AccessFlags::TRANSFER_WRITE,
        )
    }
}

/// Orders one compute pass's writes before the next compute pass's reads and writes.
///
/// # Safety
/// `cmd` must be recording.
pub(crate) unsafe fn between_passes(ctx: &GpuContext, cmd: vk::CommandBuffer) {
    // SAFETY: forwarded from the caller.
    unsafe {
        barrier(
            ctx,
            cmd,
            vk::PipelineStageFlags::COMPUTE_SHADER,
            vk::AccessFlags::SHADER_WRITE,
            vk::PipelineStageFlags::COMPUTE_SHADER,
            vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE,
        )
    }
}

/// A global memory barrier.
///
/// # Safety
/// `cmd` must be recording.
pub(crate) unsafe fn barrier(
    ctx: &GpuContext,
    cmd: vk::CommandBuffer,
    src_stage: vk::PipelineStageFlags,
    src_access: vk::AccessFlags,
    dst_stage: vk::PipelineStageFlags,
    dst_access: vk::AccessFlags,
) {
    let b = [vk::MemoryBarrier::default()
        .src_access_mask(src_access)
        .dst_access_mask(dst_access)];
    // SAFETY: the caller guarantees `cmd` is recording.
    unsafe {
        ctx.device.cmd_pipeline_barrier(
            cmd,
            src_stage,
            dst_stage,
            vk::DependencyFlags::empty(),
            &b,
            &[],
            &[],
        )
    };
}

/// Orders a frame's (or a repetition's) passes after the shader, transfer and indirect
/// writes of everything earlier on the queue, which they read and write again.
///
/// # Safety
/// `cmd` must be recording.
pub(crate) unsafe fn after_earlier_passes(ctx: &GpuContext, cmd: vk::CommandBuffer) {
    let stages = vk::PipelineStageFlags::COMPUTE_SHADER
        | vk::PipelineStageFlags::TRANSFER
        | vk::PipelineStageFlags::DRAW_INDIRECT;
    // SAFETY: forwarded from the caller.
    unsafe {
        barrier(
            ctx,
            cmd,
            stages,
            vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE,
            stages,
            vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::SHADER_WRITE
                | vk::AccessFlags::TRANSFER_READ
                | vk::AccessFlags::TRANSFER_WRITE
                | vk::AccessFlags::INDIRECT_COMMAND_READ,
        )
    }
}
