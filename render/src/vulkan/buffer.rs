//! Storage buffers (host-visible ones the CPU writes and reads back, device-local ones that
//! copies fill), bindings of buffer ranges, and reading a device-local range back.

use super::barrier::{Scope, barrier, before_transfer};
use super::{GpuContext, GpuError, vk_call};
use ash::vk;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};

/// A byte range of a buffer bound to one storage-buffer binding.
#[derive(Clone, Copy, Debug)]
pub struct Binding {
    /// The buffer.
    pub buffer: vk::Buffer,
    /// Offset in bytes (a multiple of `minStorageBufferOffsetAlignment`).
    pub offset: u64,
    /// Length in bytes.
    pub range: u64,
}

/// A storage buffer in host-visible memory.
pub struct HostBuffer {
    /// The Vulkan buffer.
    pub raw: vk::Buffer,
    allocation: Option<Allocation>,
    /// Size in bytes.
    pub size: u64,
}

impl HostBuffer {
    /// A buffer of `size` bytes (at least 4) at `location` (CpuToGpu, GpuToCpu, or GpuOnly for
    /// device-local memory, which copies fill).
    pub fn new(
        ctx: &GpuContext,
        name: &str,
        size: u64,
        location: MemoryLocation,
    ) -> Result<Self, GpuError> {
        let size = size.max(4);
        ctx.limits.check_allocation(name, size)?;
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(
                vk::BufferUsageFlags::STORAGE_BUFFER
                    | vk::BufferUsageFlags::TRANSFER_SRC
                    | vk::BufferUsageFlags::TRANSFER_DST
                    | vk::BufferUsageFlags::INDIRECT_BUFFER,
            )
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: the create info outlives the call; the buffer is destroyed in `destroy`.
        let raw = vk_call("vkCreateBuffer", unsafe {
            ctx.device.create_buffer(&info, None)
        })?;
        // SAFETY: plain query on a live buffer.
        let requirements = unsafe { ctx.device.get_buffer_memory_requirements(raw) };
        let mut allocator = ctx.allocator.lock().expect("allocator lock");
        let allocation = match allocator.allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        }) {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: the buffer was never bound or used.
                unsafe { ctx.device.destroy_buffer(raw, None) };
                return Err(e.into());
            }
        };
        // SAFETY: the allocation satisfies the buffer's requirements.
        if let Err(result) = unsafe {
            ctx.device
                .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
        } {
            let _ = allocator.free(allocation);
            unsafe { ctx.device.destroy_buffer(raw, None) };
            return Err(GpuError::Vk {
                call: "vkBindBufferMemory",
                result,
            });
        }
        Ok(Self {
            raw,
            allocation: Some(allocation),
            size,
        })
    }

    /// The whole buffer as a binding.
    pub fn binding(&self) -> Binding {
        Binding {
            buffer: self.raw,
            offset: 0,
            range: self.size,
        }
    }

    /// Copies bytes into the start of the buffer.
    pub fn write(&mut self, bytes: &[u8]) {
        self.write_at(0, bytes);
    }

    /// Copies bytes into the buffer at byte `offset`.
    pub fn write_at(&mut self, offset: usize, bytes: &[u8]) {
        let slice = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .expect("host-visible buffers are mapped");
        slice[offset..offset + bytes.len()].copy_from_slice(bytes);
    }

    /// The buffer's bytes (after the GPU finished writing them).
    pub fn read(&self) -> &[u8] {
        let slice = self
            .allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .expect("host-visible buffers are mapped");
        &slice[..self.size as usize]
    }

    /// Frees the buffer (the GPU must be done with it).
    pub fn destroy(mut self, ctx: &GpuContext) {
        if let Some(a) = self.allocation.take()
            && let Ok(mut allocator) = ctx.allocator.lock()
        {
            let _ = allocator.free(a);
        }
        // SAFETY: the caller guarantees the GPU no longer uses the buffer.
        unsafe { ctx.device.destroy_buffer(self.raw, None) };
    }
}

/// Copies a (device-local) buffer range into host memory and returns its bytes; earlier
/// shader writes and copies are made visible first.
pub fn read_device(ctx: &GpuContext, src: Binding) -> Result<Vec<u8>, GpuError> {
    let out = HostBuffer::new(ctx, "read back", src.range, MemoryLocation::GpuToCpu)?;
    let dst = out.raw;
    let copied = ctx.submit_and_wait(|cmd| {
        // SAFETY: both buffers live until after the wait inside submit_and_wait.
        unsafe {
            before_transfer(ctx, cmd);
            if src.range > 0 {
                ctx.device.cmd_copy_buffer(
                    cmd,
                    src.buffer,
                    dst,
                    &[vk::BufferCopy {
                        src_offset: src.offset,
                        dst_offset: 0,
                        size: src.range,
                    }],
                );
            }
            barrier(ctx, cmd, Scope::TRANSFER_WRITE, Scope::HOST_READ);
        }
    });
    let bytes = copied.map(|_| out.read()[..src.range as usize].to_vec());
    out.destroy(ctx);
    bytes
}
