//! Presentation: the viewport's display output copied into a window's swapchain image (or
//! an offscreen image of the window's size, for headless measurement), egui painted on top
//! with dynamic rendering, then presented. The frame loop's GPU half; it never blocks on the
//! GPU except when asked for a capture.

use crate::viewport::{FrameRequest, FrameStatus, Paced, TracedImage, Viewport};
use crate::vulkan::buffer::HostBuffer;
use crate::vulkan::frame::{FRAMES_IN_FLIGHT, FrameSlot};
use crate::vulkan::swapchain::{COLOUR, Swapchain, is_bgra};
use crate::vulkan::{GpuContext, GpuError, vk_call};
use ash::vk;
use brickmap::World;
use egui_ash_renderer::{DynamicRendering, Options, RenderMode, Renderer, allocator::GpuAllocator};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

mod target;
use target::{Offscreen, Target};

/// What egui drew this frame.
pub struct EguiFrame<'a> {
    /// Tessellated shapes.
    pub primitives: &'a [egui::ClippedPrimitive],
    /// Points to pixels.
    pub pixels_per_point: f32,
    /// Texture changes (applied before the frame; frees after its fence).
    pub textures: &'a egui::TexturesDelta,
}

/// What the display of a call to [`Presenter::frame`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Presented {
    /// A frame went to the screen.
    Shown,
    /// No display was asked for ([`Show::Skip`]).
    Skipped,
    /// Nothing was drawn: no frame slot or image was free yet (try again soon).
    NotReady,
    /// The swapchain was out of date and has been recreated; draw again.
    Recreated,
}

/// Whether a call to [`Presenter::frame`] displays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Show {
    /// Only the trace's pace: nothing on screen changed.
    Skip,
    /// The UI and the latest finished traced image.
    Show,
    /// The image of the job just submitted (waited for), captured.
    Capture,
}

/// What a call to [`Presenter::frame`] did.
pub struct Framed {
    /// The display.
    pub presented: Presented,
    /// The trace job submitted (None: the one in flight comes first, or nothing changed).
    pub traced: Option<FrameStatus>,
    /// Nothing would have changed the image: no job was needed.
    pub idle: bool,
    /// The traced image the display showed (None: none finished yet, or no display).
    pub image: Option<TracedImage>,
    /// The presented pixels ([`Show::Capture`]).
    pub capture: Option<Capture>,
}

/// A captured frame: RGB8 rows top to bottom, exactly what was presented.
pub struct Capture {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels.
    pub rgb: Vec<[u8; 3]>,
}

/// The window's presenter.
pub struct Presenter {
    target: Option<Target>,
    egui: Option<Renderer<GpuAllocator>>,
    upload_pool: vk::CommandPool,
    /// egui textures to free once the slot that last used them finished.
    to_free: [Vec<egui::TextureId>; FRAMES_IN_FLIGHT],
    /// The display's own frame slots (the viewport's are its trace jobs').
    slots: Vec<FrameSlot>,
    next: usize,
    /// Wait for each trace job before displaying ([`Presenter::set_synchronous`]).
    synchronous: bool,
    recreate: bool,
    size: (u32, u32),
    ctx: Arc<GpuContext>,
}

impl Presenter {
    /// A presenter for the context's window, `size` pixels.
    pub fn new(ctx: Arc<GpuContext>, size: (u32, u32)) -> Result<Self, GpuError> {
        let swapchain = Swapchain::new(ctx.clone(), size, None)?;
        Self::with_target(ctx, Target::Window(swapchain), size)
    }

    /// A presenter drawing into an offscreen image of `size` (B8G8R8A8_UNORM, like the
    /// window's) instead of a swapchain: the same frame as in the window, for measuring where
    /// there is no display. The context needs `draw_ui`.
    pub fn offscreen(ctx: Arc<GpuContext>, size: (u32, u32)) -> Result<Self, GpuError> {
        let image = Offscreen::new(ctx.clone(), size)?;
        Self::with_target(ctx, Target::Offscreen(image), size)
    }

    fn with_target(
        ctx: Arc<GpuContext>,
        target: Target,
        size: (u32, u32),
    ) -> Result<Self, GpuError> {
        let format = target.format();
        let egui = Renderer::with_gpu_allocator(
            Arc::clone(&ctx.allocator),
            ctx.device.clone(),
            RenderMode::DynamicRendering(DynamicRendering {
                color_attachment_format: format,
                depth_attachment_format: None,
                stencil_attachment_format: None,
            }),
            Options {
                in_flight_frames: FRAMES_IN_FLIGHT,
                srgb_framebuffer: matches!(
                    format,
                    vk::Format::B8G8R8A8_SRGB | vk::Format::R8G8B8A8_SRGB
                ),
                ..Default::default()
            },
        )
        .map_err(|e| GpuError::NoDevice(format!("egui painter: {e}")))?;
        // SAFETY: the create info outlives the call; the pool is destroyed in Drop.
        let upload_pool = vk_call("vkCreateCommandPool", unsafe {
            ctx.device.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(ctx.queue_family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )
        })?;
        Ok(Self {
            target: Some(target),
            egui: Some(egui),
            upload_pool,
            to_free: Default::default(),
            slots: Vec::new(),
            next: 0,
            synchronous: false,
            recreate: false,
            size,
            ctx,
        })
    }

    /// The window was resized (in physical pixels).
    pub fn resize(&mut self, size: (u32, u32)) {
        if size != self.size {
            self.size = size;
            self.recreate = true;
        }
    }

    fn recreate_now(&mut self, viewport: &Viewport) -> Result<(), GpuError> {
        viewport.wait_idle()?;
        // SAFETY: plain wait; the old swapchain's images must be idle before it goes.
        vk_call("vkDeviceWaitIdle", unsafe {
            self.ctx.device.device_wait_idle()
        })?;
        let next = match &self.target {
            Some(Target::Window(old)) => {
                Target::Window(Swapchain::new(self.ctx.clone(), self.size, Some(old))?)
            }
            _ => Target::Offscreen(Offscreen::new(self.ctx.clone(), self.size)?),
        };
        self.target = Some(next);
        self.recreate = false;
        Ok(())
    }

    /// Draws one frame: the viewport's next trace job when its pace allows
    /// ([`Viewport::trace_paced`]), then — unless `show` is [`Show::Skip`] — the display:
    /// the latest *finished* traced image in `area` (x, y, width, height in pixels, clamped
    /// to the image; None: the whole image) with the rest cleared to the panels' grey, egui
    /// on top, presented. Never waits for the trace, except for [`Show::Capture`] (the frame
    /// shows the job just submitted and returns the presented pixels) and a synchronous
    /// presenter ([`Presenter::set_synchronous`]).
    pub fn frame(
        &mut self,
        viewport: &mut Viewport,
        world: &World,
        req: &FrameRequest<'_>,
        area: Option<(u32, u32, u32, u32)>,
        ui: Option<EguiFrame<'_>>,
        show: Show,
    ) -> Result<Framed, GpuError> {
        let mut framed = Framed {
            presented: Presented::NotReady,
            traced: None,
            idle: false,
            image: None,
            capture: None,
        };
        if self.size.0 == 0 || self.size.1 == 0 {
            return Ok(framed);
        }
        if self.recreate {
            self.recreate_now(viewport)?;
            framed.presented = Presented::Recreated;
            return Ok(framed);
        }
        let target = self.target.as_ref().expect("made in new");
        let (extent, format) = (target.extent(), target.format());
        let area = clamp_area(area, extent);
        let req = FrameRequest {
            output: (area.extent.width, area.extent.height),
            bgra: is_bgra(format),
            ..*req
        };
        match viewport.trace_paced(world, &req)? {
            Paced::Traced(status) => framed.traced = Some(status),
            Paced::Idle => framed.idle = true,
            Paced::Busy => {}
        }
        let capture = show == Show::Capture;
        if capture || self.synchronous {
            viewport.wait_idle()?;
        }
        if show == Show::Skip {
            framed.presented = Presented::Skipped;
            return Ok(framed);
        }
        self.display(viewport, area, ui, capture, &mut framed)?;
        Ok(framed)
    }

    /// A synchronous presenter waits for each trace job before the frame that shows it
    /// (headless drivers and tests: each frame shows the state it was asked for).
    pub fn set_synchronous(&mut self, synchronous: bool) {
        self.synchronous = synchronous;
    }

    /// The display half of [`Presenter::frame`]: its own frame slot, so that it waits for
    /// nothing but the previous display of that slot.
    fn display(
        &mut self,
        viewport: &mut Viewport,
        area: vk::Rect2D,
        ui: Option<EguiFrame<'_>>,
        capture: bool,
        framed: &mut Framed,
    ) -> Result<(), GpuError> {
        let ctx = self.ctx.clone();
        let d = &ctx.device;
        while self.slots.len() < FRAMES_IN_FLIGHT {
            self.slots.push(FrameSlot::new(&ctx)?);
        }
        let slot_index = self.next;
        if !self.slots[slot_index].ready(&ctx)? {
            return Ok(());
        }
        let egui = self.egui.as_mut().expect("alive until drop");
        // The slot finished: textures freed by its last frame can go now.
        for id in self.to_free[slot_index].drain(..) {
            let _ = egui.free_texture(id);
        }
        let target = self.target.as_ref().expect("made in new");
        let acquired = self.slots[slot_index].acquired;
        let (index, suboptimal) = match target {
            Target::Window(swapchain) => match swapchain.acquire(acquired)? {
                Some(acquired) => acquired,
                None => {
                    self.recreate = true;
                    return Ok(());
                }
            },
            Target::Offscreen(_) => (0, false),
        };
        if let Some(ui) = &ui {
            for (id, deltas) in &ui.textures.set {
                for delta in deltas {
                    egui.set_texture(ctx.queue, self.upload_pool, *id, delta)
                        .map_err(|e| GpuError::NoDevice(format!("egui texture: {e}")))?;
                }
            }
        }
        let (extent, format) = (target.extent(), target.format());
        let shown = viewport.shown_image()?;
        framed.image = shown.map(|s| s.image);
        // The traced image fills the area when it was traced for it; otherwise (the first
        // frames, a resize) its part that fits, the rest grey.
        let fills = shown.is_some_and(|s| s.image.size == (area.extent.width, area.extent.height));
        let whole = area.extent == extent && fills;
        let (image, view) = target.image(index);
        let cmd = self.slots[slot_index].begin(&ctx)?;
        let capture_buffer = if capture {
            Some(HostBuffer::new(
                &ctx,
                "capture",
                extent.width as u64 * extent.height as u64 * 4,
                MemoryLocation::GpuToCpu,
            )?)
        } else {
            None
        };
        // SAFETY: recording into the slot's command buffer; every handle is alive until the
        // slot's fence signals (the capture buffer: until the wait below).
        unsafe {
            image_barrier(
                d,
                cmd,
                image,
                (
                    vk::ImageLayout::UNDEFINED,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                ),
                (vk::PipelineStageFlags::TRANSFER, vk::AccessFlags::empty()),
                (
                    vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::TRANSFER_WRITE,
                ),
            );
            if !whole {
                // Around the viewport's area: the panels' grey (egui's dark panel fill).
                let grey = 27.0 / 255.0;
                d.cmd_clear_color_image(
                    cmd,
                    image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &vk::ClearColorValue {
                        float32: [grey, grey, grey, 1.0],
                    },
                    &[vk::ImageSubresourceRange {
                        aspect_mask: vk::ImageAspectFlags::COLOR,
                        base_mip_level: 0,
                        level_count: 1,
                        base_array_layer: 0,
                        layer_count: 1,
                    }],
                );
                crate::vulkan::barrier::barrier(
                    &ctx,
                    cmd,
                    crate::vulkan::barrier::Scope::TRANSFER_WRITE,
                    crate::vulkan::barrier::Scope::TRANSFER_WRITE,
                );
            }
            if let Some(s) = shown {
                let mut copy = whole_image(vk::Extent2D {
                    width: s.image.size.0.min(area.extent.width),
                    height: s.image.size.1.min(area.extent.height),
                });
                copy.buffer_row_length = s.image.size.0;
                copy.image_offset = vk::Offset3D {
                    x: area.offset.x,
                    y: area.offset.y,
                    z: 0,
                };
                d.cmd_copy_buffer_to_image(
                    cmd,
                    s.buffer,
                    image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[copy],
                );
            }
            image_barrier(
                d,
                cmd,
                image,
                (
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                ),
                (
                    vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::TRANSFER_WRITE,
                ),
                (
                    vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                    vk::AccessFlags::COLOR_ATTACHMENT_READ
                        | vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
                ),
            );
            if let Some(ui) = &ui {
                let attachment = [vk::RenderingAttachmentInfo::default()
                    .image_view(view)
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(vk::AttachmentLoadOp::LOAD)
                    .store_op(vk::AttachmentStoreOp::STORE)];
                let info = vk::RenderingInfo::default()
                    .render_area(vk::Rect2D {
                        offset: vk::Offset2D::default(),
                        extent,
                    })
                    .layer_count(1)
                    .color_attachments(&attachment);
                let rendering = ctx
                    .ui_rendering
                    .as_ref()
                    .expect("made for a window or draw_ui");
                rendering.cmd_begin_rendering(cmd, &info);
                egui.cmd_draw(cmd, extent, ui.pixels_per_point, ui.primitives)
                    .map_err(|e| GpuError::NoDevice(format!("egui draw: {e}")))?;
                rendering.cmd_end_rendering(cmd);
            }
            let last = (
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            );
            // A window's image goes to the presentation engine; an offscreen one stays put.
            let final_layout = match target {
                Target::Window(_) => vk::ImageLayout::PRESENT_SRC_KHR,
                Target::Offscreen(_) => vk::ImageLayout::GENERAL,
            };
            if let Some(buf) = &capture_buffer {
                image_barrier(
                    d,
                    cmd,
                    image,
                    (
                        vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    ),
                    last,
                    (
                        vk::PipelineStageFlags::TRANSFER,
                        vk::AccessFlags::TRANSFER_READ,
                    ),
                );
                d.cmd_copy_image_to_buffer(
                    cmd,
                    image,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    buf.raw,
                    &[whole_image(extent)],
                );
                crate::vulkan::barrier::barrier(
                    &ctx,
                    cmd,
                    crate::vulkan::barrier::Scope::TRANSFER_WRITE,
                    crate::vulkan::barrier::Scope::HOST_READ,
                );
                image_barrier(
                    d,
                    cmd,
                    image,
                    (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, final_layout),
                    (vk::PipelineStageFlags::TRANSFER, vk::AccessFlags::empty()),
                    (
                        vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                        vk::AccessFlags::empty(),
                    ),
                );
            } else {
                image_barrier(
                    d,
                    cmd,
                    image,
                    (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, final_layout),
                    last,
                    (
                        vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                        vk::AccessFlags::empty(),
                    ),
                );
            }
        }
        let slot = &mut self.slots[slot_index];
        match target {
            Target::Window(swapchain) => {
                slot.submit(
                    &ctx,
                    &[(
                        acquired,
                        vk::PipelineStageFlags::TRANSFER
                            | vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                    )],
                    &[swapchain.render_finished[index as usize]],
                )?;
                if swapchain.present(index)? || suboptimal {
                    self.recreate = true;
                }
            }
            Target::Offscreen(_) => slot.submit(&ctx, &[], &[])?,
        }
        self.next = (slot_index + 1) % FRAMES_IN_FLIGHT;
        if let Some(ui) = &ui {
            self.to_free[slot_index].extend(ui.textures.free.iter().copied());
        }
        framed.presented = Presented::Shown;
        if let Some(buf) = capture_buffer {
            let waited = self.slots[slot_index].wait(&ctx);
            let bgra = is_bgra(format);
            let rgb = buf
                .read()
                .chunks_exact(4)
                .map(|p| {
                    if bgra {
                        [p[2], p[1], p[0]]
                    } else {
                        [p[0], p[1], p[2]]
                    }
                })
                .collect();
            buf.destroy(&ctx);
            waited?;
            framed.capture = Some(Capture {
                width: extent.width,
                height: extent.height,
                rgb,
            });
        }
        Ok(())
    }
}

/// A tightly packed copy of a whole image of `extent`.
/// The viewport's area inside an image of `extent`: at least one pixel, never past its edges.
fn clamp_area(area: Option<(u32, u32, u32, u32)>, extent: vk::Extent2D) -> vk::Rect2D {
    let (x, y, w, h) = area.unwrap_or((0, 0, extent.width, extent.height));
    let x = x.min(extent.width.saturating_sub(1));
    let y = y.min(extent.height.saturating_sub(1));
    vk::Rect2D {
        offset: vk::Offset2D {
            x: x as i32,
            y: y as i32,
        },
        extent: vk::Extent2D {
            width: w.clamp(1, extent.width - x),
            height: h.clamp(1, extent.height - y),
        },
    }
}

fn whole_image(extent: vk::Extent2D) -> vk::BufferImageCopy {
    vk::BufferImageCopy {
        buffer_offset: 0,
        buffer_row_length: 0,
        buffer_image_height: 0,
        image_subresource: LAYER,
        image_offset: vk::Offset3D::default(),
        image_extent: vk::Extent3D {
            width: extent.width,
            height: extent.height,
            depth: 1,
        },
    }
}

/// One colour layer.
const LAYER: vk::ImageSubresourceLayers = vk::ImageSubresourceLayers {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    mip_level: 0,
    base_array_layer: 0,
    layer_count: 1,
};

/// A layout transition of a whole colour image.
///
/// # Safety
/// `cmd` must be recording.
unsafe fn image_barrier(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    (old, new): (vk::ImageLayout, vk::ImageLayout),
    (src_stage, src_access): (vk::PipelineStageFlags, vk::AccessFlags),
    (dst_stage, dst_access): (vk::PipelineStageFlags, vk::AccessFlags),
) {
    let b = [vk::ImageMemoryBarrier::default()
        .old_layout(old)
        .new_layout(new)
        .src_access_mask(src_access)
        .dst_access_mask(dst_access)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(COLOUR)];
    // SAFETY: the caller guarantees `cmd` is recording.
    unsafe {
        d.cmd_pipeline_barrier(
            cmd,
            src_stage,
            dst_stage,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &b,
        )
    };
}

impl Drop for Presenter {
    fn drop(&mut self) {
        // SAFETY: the device is idle after the wait; egui's objects, then the pool, then the
        // target (its own Drop).
        unsafe {
            let _ = self.ctx.device.device_wait_idle();
            for s in self.slots.drain(..) {
                s.destroy(&self.ctx);
            }
            drop(self.egui.take());
            self.ctx.device.destroy_command_pool(self.upload_pool, None);
        }
        drop(self.target.take());
    }
}
