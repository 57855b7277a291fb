//! Where the presenter's frames go: a window's swapchain, or a device-local image of the
//! window's size and format for headless frames and measurement.

use crate::vulkan::swapchain::{COLOUR, Swapchain};
use crate::vulkan::{GpuContext, GpuError, vk_call};
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// Where frames go: a window's swapchain or an offscreen image.
pub(super) enum Target {
    Window(Swapchain),
    Offscreen(Offscreen),
}

impl Target {
    pub(super) fn format(&self) -> vk::Format {
        match self {
            Target::Window(s) => s.format,
            Target::Offscreen(o) => o.format,
        }
    }

    pub(super) fn extent(&self) -> vk::Extent2D {
        match self {
            Target::Window(s) => s.extent,
            Target::Offscreen(o) => o.extent,
        }
    }

    /// Image `index` and its view.
    pub(super) fn image(&self, index: u32) -> (vk::Image, vk::ImageView) {
        match self {
            Target::Window(s) => (s.images[index as usize], s.views[index as usize]),
            Target::Offscreen(o) => (o.image, o.view),
        }
    }
}

/// A device-local image of the window's size and format, for headless frames.
pub(super) struct Offscreen {
    pub(super) image: vk::Image,
    pub(super) view: vk::ImageView,
    allocation: Option<gpu_allocator::vulkan::Allocation>,
    pub(super) extent: vk::Extent2D,
    pub(super) format: vk::Format,
    ctx: Arc<GpuContext>,
}

impl Offscreen {
    pub(super) fn new(ctx: Arc<GpuContext>, (w, h): (u32, u32)) -> Result<Self, GpuError> {
        let format = vk::Format::B8G8R8A8_UNORM;
        let extent = vk::Extent2D {
            width: w.max(1),
            height: h.max(1),
        };
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D {
                width: extent.width,
                height: extent.height,
                depth: 1,
            })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(
                vk::ImageUsageFlags::COLOR_ATTACHMENT
                    | vk::ImageUsageFlags::TRANSFER_DST
                    | vk::ImageUsageFlags::TRANSFER_SRC,
            )
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: the create info outlives the call; destroyed in Drop.
        let image = vk_call("vkCreateImage", unsafe {
            ctx.device.create_image(&info, None)
        })?;
        let mut me = Self {
            image,
            view: vk::ImageView::null(),
            allocation: None,
            extent,
            format,
            ctx: ctx.clone(),
        };
        // SAFETY: plain query on a live image.
        let requirements = unsafe { ctx.device.get_image_memory_requirements(image) };
        let allocation = ctx.allocator.lock().expect("allocator lock").allocate(
            &gpu_allocator::vulkan::AllocationCreateDesc {
                name: "offscreen target",
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: gpu_allocator::vulkan::AllocationScheme::GpuAllocatorManaged,
            },
        )?;
        // SAFETY: the allocation satisfies the image's requirements.
        let bound = unsafe {
            ctx.device
                .bind_image_memory(image, allocation.memory(), allocation.offset())
        };
        me.allocation = Some(allocation);
        vk_call("vkBindImageMemory", bound)?;
        let view = vk::ImageViewCreateInfo::default()
            .image(image)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(COLOUR);
        // SAFETY: as above.
        me.view = vk_call("vkCreateImageView", unsafe {
            ctx.device.create_image_view(&view, None)
        })?;
        Ok(me)
    }
}

impl Drop for Offscreen {
    fn drop(&mut self) {
        // SAFETY: the device is idle after the wait; view, image, then its memory.
        unsafe {
            let _ = self.ctx.device.device_wait_idle();
            if self.view != vk::ImageView::null() {
                self.ctx.device.destroy_image_view(self.view, None);
            }
            self.ctx.device.destroy_image(self.image, None);
        }
        if let Some(a) = self.allocation.take()
            && let Ok(mut allocator) = self.ctx.allocator.lock()
        {
            let _ = allocator.free(a);
        }
    }
}
