//! Memory barriers, named by their access pair: a [`Scope`] is the stages and accesses on one
//! side, `barrier(ctx, cmd, from, to)` orders `to` after `from`. Every pass and copy uses
//! these names instead of spelling masks out at its call site.

use super::GpuContext;
use ash::vk;

/// One side of a barrier: pipeline stages and the memory accesses they make there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Scope {
    stage: vk::PipelineStageFlags,
    access: vk::AccessFlags,
}

const COMPUTE: vk::PipelineStageFlags = vk::PipelineStageFlags::COMPUTE_SHADER;
const TRANSFER: vk::PipelineStageFlags = vk::PipelineStageFlags::TRANSFER;
const HOST: vk::PipelineStageFlags = vk::PipelineStageFlags::HOST;
const INDIRECT: vk::PipelineStageFlags = vk::PipelineStageFlags::DRAW_INDIRECT;
const SHADER_RW: vk::AccessFlags = vk::AccessFlags::from_raw(
    vk::AccessFlags::SHADER_READ.as_raw() | vk::AccessFlags::SHADER_WRITE.as_raw(),
);
const TRANSFER_RW: vk::AccessFlags = vk::AccessFlags::from_raw(
    vk::AccessFlags::TRANSFER_READ.as_raw() | vk::AccessFlags::TRANSFER_WRITE.as_raw(),
);

const fn or_s(a: vk::PipelineStageFlags, b: vk::PipelineStageFlags) -> vk::PipelineStageFlags {
    vk::PipelineStageFlags::from_raw(a.as_raw() | b.as_raw())
}
const fn or_a(a: vk::AccessFlags, b: vk::AccessFlags) -> vk::AccessFlags {
    vk::AccessFlags::from_raw(a.as_raw() | b.as_raw())
}

impl Scope {
    /// Copies and fills writing.
    pub(crate) const TRANSFER_WRITE: Scope = Scope {
        stage: TRANSFER,
        access: vk::AccessFlags::TRANSFER_WRITE,
    };
    /// Copies reading.
    pub(crate) const TRANSFER_READ: Scope = Scope {
        stage: TRANSFER,
        access: vk::AccessFlags::TRANSFER_READ,
    };
    /// Copies and fills reading and writing.
    pub(crate) const TRANSFER_RW: Scope = Scope {
        stage: TRANSFER,
        access: TRANSFER_RW,
    };
    /// Compute shaders writing.
    pub(crate) const SHADER_WRITE: Scope = Scope {
        stage: COMPUTE,
        access: vk::AccessFlags::SHADER_WRITE,
    };
    /// Compute shaders reading and writing.
    pub(crate) const SHADER_RW: Scope = Scope {
        stage: COMPUTE,
        access: SHADER_RW,
    };
    /// Compute shaders reading and writing, and indirect dispatch arguments read.
    pub(crate) const SHADER_RW_INDIRECT: Scope = Scope {
        stage: or_s(COMPUTE, INDIRECT),
        access: or_a(SHADER_RW, vk::AccessFlags::INDIRECT_COMMAND_READ),
    };
    /// The host reading (after a fence).
    pub(crate) const HOST_READ: Scope = Scope {
        stage: HOST,
        access: vk::AccessFlags::HOST_READ,
    };
    /// Shaders and copies writing.
    pub(crate) const ANY_WRITE: Scope = Scope {
        stage: or_s(COMPUTE, TRANSFER),
        access: or_a(
            vk::AccessFlags::SHADER_WRITE,
            vk::AccessFlags::TRANSFER_WRITE,
        ),
    };
    /// Shaders and copies writing, with indirect dispatches among the stages.
    pub(crate) const ANY_WRITE_INDIRECT: Scope = Scope {
        stage: or_s(or_s(COMPUTE, TRANSFER), INDIRECT),
        access: or_a(
            vk::AccessFlags::SHADER_WRITE,
            vk::AccessFlags::TRANSFER_WRITE,
        ),
    };
    /// Shaders reading, copies reading and writing.
    pub(crate) const SHADER_READ_TRANSFER_RW: Scope = Scope {
        stage: or_s(COMPUTE, TRANSFER),
        access: or_a(vk::AccessFlags::SHADER_READ, TRANSFER_RW),
    };
    /// Everything later on the queue: shaders, copies and indirect arguments, reading and
    /// writing.
    pub(crate) const ANY_ACCESS: Scope = Scope {
        stage: or_s(or_s(COMPUTE, TRANSFER), INDIRECT),
        access: or_a(
            or_a(SHADER_RW, TRANSFER_RW),
            vk::AccessFlags::INDIRECT_COMMAND_READ,
        ),
    };
    /// Results read by the host, later shaders and copies.
    pub(crate) const RESULTS_READ: Scope = Scope {
        stage: or_s(or_s(HOST, COMPUTE), TRANSFER),
        access: or_a(or_a(vk::AccessFlags::HOST_READ, SHADER_RW), TRANSFER_RW),
    };
}

/// A global memory barrier: `to` waits for `from` and sees its writes.
///
/// # Safety
/// `cmd` must be recording.
pub(crate) unsafe fn barrier(ctx: &GpuContext, cmd: vk::CommandBuffer, from: Scope, to: Scope) {
    let b = [vk::MemoryBarrier::default()
        .src_access_mask(from.access)
        .dst_access_mask(to.access)];
    // SAFETY: the caller guarantees `cmd` is recording.
    unsafe {
        ctx.device.cmd_pipeline_barrier(
            cmd,
            from.stage,
            to.stage,
            vk::DependencyFlags::empty(),
            &b,
            &[],
            &[],
        )
    };
}

/// Orders transfers after earlier shader and transfer writes and reads (WAR and WAW).
///
/// # Safety
/// `cmd` must be recording.
pub(crate) unsafe fn before_transfer(ctx: &GpuContext, cmd: vk::CommandBuffer) {
    // SAFETY: forwarded from the caller.
    unsafe { barrier(ctx, cmd, Scope::ANY_WRITE, Scope::TRANSFER_RW) }
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
            Scope::TRANSFER_WRITE,
            Scope::SHADER_READ_TRANSFER_RW,
        )
    }
}

/// Orders one compute pass's writes before the next compute pass's reads and writes.
///
/// # Safety
/// `cmd` must be recording.
pub(crate) unsafe fn between_passes(ctx: &GpuContext, cmd: vk::CommandBuffer) {
    // SAFETY: forwarded from the caller.
    unsafe { barrier(ctx, cmd, Scope::SHADER_WRITE, Scope::SHADER_RW) }
}

/// Orders a frame's (or a repetition's) passes after the shader, transfer and indirect
/// writes of everything earlier on the queue, which they read and write again.
///
/// # Safety
/// `cmd` must be recording.
pub(crate) unsafe fn after_earlier_passes(ctx: &GpuContext, cmd: vk::CommandBuffer) {
    // SAFETY: forwarded from the caller.
    unsafe { barrier(ctx, cmd, Scope::ANY_WRITE_INDIRECT, Scope::ANY_ACCESS) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_scopes_are_the_masks_they_name() {
        assert_eq!(
            Scope::ANY_ACCESS.access,
            vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::SHADER_WRITE
                | vk::AccessFlags::TRANSFER_READ
                | vk::AccessFlags::TRANSFER_WRITE
                | vk::AccessFlags::INDIRECT_COMMAND_READ
        );
        assert_eq!(
            Scope::RESULTS_READ.stage,
            vk::PipelineStageFlags::HOST
                | vk::PipelineStageFlags::COMPUTE_SHADER
                | vk::PipelineStageFlags::TRANSFER
        );
        assert_eq!(
            Scope::SHADER_RW_INDIRECT.stage,
            vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::DRAW_INDIRECT
        );
    }
}
