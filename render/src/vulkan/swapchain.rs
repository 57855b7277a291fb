//! The window's swapchain: B8G8R8A8_UNORM preferred (the display pass writes sRGB-encoded
//! bytes in that order, copied in raw), MAILBOX where offered (else FIFO), recreated by the
//! presenter on resize, suboptimal and out-of-date. One render-finished semaphore per image.
//!
//! In detail:
//! `Swapchain`: B8G8R8A8_UNORM preferred, then R8G8B8A8_UNORM, then the sRGB ones (raw
//! sRGB-encoded bytes are right for all four); MAILBOX else FIFO; min + 1 images; TRANSFER_DST
//! (copy in) + COLOR_ATTACHMENT (egui) + TRANSFER_SRC when offered (capture); one
//! render-finished semaphore per image; acquire with a 100 ms bound (out of date / timeout →
//! recreate / retry).

use super::{GpuContext, GpuError, vk_call};
use ash::vk;
use std::sync::Arc;

/// A swapchain and its image views; destroyed on drop (after the device is idle).
pub struct Swapchain {
    raw: vk::SwapchainKHR,
    /// The images (transfer destinations, colour attachments, transfer sources).
    pub images: Vec<vk::Image>,
    /// A view of each image (for egui's dynamic rendering).
    pub views: Vec<vk::ImageView>,
    /// Signalled when the frame drawn into image i may be presented.
    pub render_finished: Vec<vk::Semaphore>,
    /// The image format.
    pub format: vk::Format,
    /// The image size.
    pub extent: vk::Extent2D,
    /// The present mode chosen.
    pub present_mode: vk::PresentModeKHR,
    ctx: Arc<GpuContext>,
}

/// Formats in order of preference.
const FORMATS: [vk::Format; 4] = [
    vk::Format::B8G8R8A8_UNORM,
    vk::Format::R8G8B8A8_UNORM,
    vk::Format::B8G8R8A8_SRGB,
    vk::Format::R8G8B8A8_SRGB,
];

/// Whether a format stores blue first (the display pass then swaps red and blue).
pub fn is_bgra(format: vk::Format) -> bool {
    matches!(
        format,
        vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB
    )
}

impl Swapchain {
    /// A swapchain of about `size` pixels (the surface's current extent wins when fixed),
    /// replacing `old` (which the caller made idle).
    pub fn new(
        ctx: Arc<GpuContext>,
        size: (u32, u32),
        old: Option<&Swapchain>,
    ) -> Result<Self, GpuError> {
        let p = ctx
            .presentation
            .as_ref()
            .ok_or_else(|| GpuError::NoDevice("the context was made without a window".into()))?;
        let (s, physical) = (&p.surface, ctx.physical);
        // SAFETY: plain queries on live handles.
        let (caps, formats, modes) = unsafe {
            (
                vk_call(
                    "vkGetPhysicalDeviceSurfaceCapabilitiesKHR",
                    s.loader
                        .get_physical_device_surface_capabilities(physical, s.raw),
                )?,
                vk_call(
                    "vkGetPhysicalDeviceSurfaceFormatsKHR",
                    s.loader
                        .get_physical_device_surface_formats(physical, s.raw),
                )?,
                vk_call(
                    "vkGetPhysicalDeviceSurfacePresentModesKHR",
                    s.loader
                        .get_physical_device_surface_present_modes(physical, s.raw),
                )?,
            )
        };
        let format = FORMATS
            .iter()
            .find_map(|f| formats.iter().find(|s| s.format == *f))
            .ok_or_else(|| {
                GpuError::NoDevice(format!(
                    "the window offers no 8-bit RGBA format ({:?})",
                    formats.iter().map(|f| f.format).collect::<Vec<_>>()
                ))
            })?;
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: size
                    .0
                    .clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: size
                    .1
                    .clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        let present_mode = if modes.contains(&vk::PresentModeKHR::MAILBOX) {
            vk::PresentModeKHR::MAILBOX
        } else {
            vk::PresentModeKHR::FIFO
        };
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let mut usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_DST;
        if caps
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::TRANSFER_SRC)
        {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        }
        if !caps
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::TRANSFER_DST)
        {
            return Err(GpuError::NoDevice(
                "the window's images cannot be copied into (no TRANSFER_DST usage)".into(),
            ));
        }
        let families = [ctx.queue_family, p.queue_family];
        let mut info = vk::SwapchainCreateInfoKHR::default()
            .surface(s.raw)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(present_mode)
            .clipped(true)
            .old_swapchain(old.map_or(vk::SwapchainKHR::null(), |o| o.raw));
        info = if families[0] != families[1] {
            info.image_sharing_mode(vk::SharingMode::CONCURRENT)
                .queue_family_indices(&families)
        } else {
            info.image_sharing_mode(vk::SharingMode::EXCLUSIVE)
        };
        // SAFETY: the create info outlives the call; objects are destroyed in Drop.
        unsafe {
            let raw = vk_call(
                "vkCreateSwapchainKHR",
                p.swapchain.create_swapchain(&info, None),
            )?;
            let mut me = Self {
                raw,
                images: Vec::new(),
                views: Vec::new(),
                render_finished: Vec::new(),
                format: format.format,
                extent,
                present_mode,
                ctx: ctx.clone(),
            };
            me.images = vk_call(
                "vkGetSwapchainImagesKHR",
                p.swapchain.get_swapchain_images(raw),
            )?;
            for &image in &me.images {
                let view = vk::ImageViewCreateInfo::default()
                    .image(image)
                    .view_type(vk::ImageViewType::TYPE_2D)
                    .format(format.format)
                    .subresource_range(COLOUR);
                me.views.push(vk_call(
                    "vkCreateImageView",
                    ctx.device.create_image_view(&view, None),
                )?);
                me.render_finished.push(vk_call(
                    "vkCreateSemaphore",
                    ctx.device
                        .create_semaphore(&vk::SemaphoreCreateInfo::default(), None),
                )?);
            }
            Ok(me)
        }
    }

    /// Acquires the next image, signalling `semaphore`: `Ok(None)` when it is out of date
    /// (recreate) or none came within the wait; the flag says suboptimal.
    pub fn acquire(&self, semaphore: vk::Semaphore) -> Result<Option<(u32, bool)>, GpuError> {
        let p = self.ctx.presentation.as_ref().expect("made with a window");
        // SAFETY: live swapchain and semaphore (unsignalled: its last wait was submitted).
        match unsafe {
            p.swapchain
                .acquire_next_image(self.raw, 100_000_000, semaphore, vk::Fence::null())
        } {
            Ok((i, suboptimal)) => Ok(Some((i, suboptimal))),
            Err(
                vk::Result::ERROR_OUT_OF_DATE_KHR | vk::Result::TIMEOUT | vk::Result::NOT_READY,
            ) => Ok(None),
            Err(result) => Err(GpuError::Vk {
                call: "vkAcquireNextImageKHR",
                result,
            }),
        }
    }

    /// Presents image `index` once `render_finished[index]` is signalled; `Ok(true)` when the
    /// swapchain should be recreated (suboptimal or out of date).
    pub fn present(&self, index: u32) -> Result<bool, GpuError> {
        let p = self.ctx.presentation.as_ref().expect("made with a window");
        let waits = [self.render_finished[index as usize]];
        let chains = [self.raw];
        let indices = [index];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&waits)
            .swapchains(&chains)
            .image_indices(&indices);
        // SAFETY: the info outlives the call.
        match unsafe { p.swapchain.queue_present(p.queue, &info) } {
            Ok(suboptimal) => Ok(suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(true),
            Err(result) => Err(GpuError::Vk {
                call: "vkQueuePresentKHR",
                result,
            }),
        }
    }
}

/// The colour aspect, one mip level, one layer.
pub const COLOUR: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};

impl Drop for Swapchain {
    fn drop(&mut self) {
        let p = self.ctx.presentation.as_ref().expect("made with a window");
        // SAFETY: the device is idle after the wait; views before the swapchain.
        unsafe {
            let _ = self.ctx.device.device_wait_idle();
            for &v in &self.views {
                self.ctx.device.destroy_image_view(v, None);
            }
            for &s in &self.render_finished {
                self.ctx.device.destroy_semaphore(s, None);
            }
            p.swapchain.destroy_swapchain(self.raw, None);
        }
    }
}
