//! The display pass on the GPU (`shaders/tonemap.comp`): accumulated HDR (radiance sum and
//! sample count per pixel) → mean → bilinear upscale from the internal to the output
//! resolution → exposure → ACES fitted → sRGB 8-bit; the same arithmetic as
//! `Image::resized_bilinear` and `Image::to_srgb8` on the CPU.

use super::buffer::{Binding, HostBuffer};
use super::pass::{ComputePass, Dispatch, SetCache};
use super::{GpuContext, GpuError};
use crate::image::Image;
use ash::vk;
use gpu_allocator::MemoryLocation;

const SPIRV: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/tonemap.comp.spv"));

/// Push constants. Keep in sync with `Push` in shaders/tonemap.comp.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    src: [u32; 2],
    dst: [u32; 2],
    scale: f32,
    bgra: u32,
}
const _: () = assert!(std::mem::size_of::<Push>() == 24);

impl Push {
    fn new(src: (u32, u32), dst: (u32, u32), exposure: f32, bgra: bool) -> Self {
        Self {
            src: [src.0, src.1],
            dst: [dst.0, dst.1],
            scale: 2f32.powf(exposure),
            bgra: bgra as u32,
        }
    }
}

/// The display pipeline.
pub struct ToneMapper(ComputePass);

impl ToneMapper {
    /// Builds the pipeline.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self(ComputePass::new(
            ctx,
            SPIRV,
            2,
            std::mem::size_of::<Push>() as u32,
        )?))
    }

    /// Displays `hdr` (vec4 per pixel: radiance sum, sample count) of size `src` at size
    /// `dst`; returns sRGB 8-bit pixels, rows top to bottom.
    pub fn display(
        &self,
        ctx: &GpuContext,
        hdr: Binding,
        src: (u32, u32),
        dst: (u32, u32),
        exposure: f32,
    ) -> Result<Vec<[u8; 3]>, GpuError> {
        let pixels = dst.0 as u64 * dst.1 as u64;
        let ldr = HostBuffer::new(ctx, "ldr", pixels * 4, MemoryLocation::GpuToCpu)?;
        let push = Push::new(src, dst, exposure, false);
        let result = self.0.run(
            ctx,
            &[hdr, ldr.binding()],
            bytemuck::bytes_of(&push),
            [dst.0.div_ceil(8), dst.1.div_ceil(8)],
        );
        let out = result.map(|_| {
            ldr.read()[..pixels as usize * 4]
                .chunks_exact(4)
                .map(|p| [p[0], p[1], p[2]])
                .collect()
        });
        ldr.destroy(ctx);
        out
    }

    /// Records the display of `hdr` (size `src`) into `ldr` (packed 8-bit, size `dst`,
    /// in B, G, R, A byte order when `bgra`) without submitting; the set comes from `sets`.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &GpuContext,
        cmd: vk::CommandBuffer,
        sets: &mut SetCache,
        hdr: Binding,
        ldr: Binding,
        (src, dst): ((u32, u32), (u32, u32)),
        exposure: f32,
        bgra: bool,
    ) -> Result<(), GpuError> {
        let push = Push::new(src, dst, exposure, bgra);
        let set = sets.get(ctx, &self.0, &[hdr, ldr])?;
        self.0.record(
            ctx,
            cmd,
            set,
            bytemuck::bytes_of(&push),
            Dispatch::Groups(dst.0.div_ceil(8), dst.1.div_ceil(8), 1),
        );
        Ok(())
    }

    /// Tone-maps a linear image on the GPU at its own size; returns sRGB 8-bit pixels.
    pub fn run(
        &self,
        ctx: &GpuContext,
        image: &Image,
        exposure: f32,
    ) -> Result<Vec<[u8; 3]>, GpuError> {
        let size = (image.width, image.height);
        self.upscale(ctx, image, size, exposure)
    }

    /// Displays a linear image at size `dst` (bilinear upscale, then the curve).
    pub fn upscale(
        &self,
        ctx: &GpuContext,
        image: &Image,
        dst: (u32, u32),
        exposure: f32,
    ) -> Result<Vec<[u8; 3]>, GpuError> {
        let packed: Vec<[f32; 4]> = image
            .pixels
            .iter()
            .map(|p| [p[0], p[1], p[2], 1.0])
            .collect();
        let mut hdr = HostBuffer::new(
            ctx,
            "hdr",
            packed.len() as u64 * 16,
            MemoryLocation::CpuToGpu,
        )?;
        hdr.write(bytemuck::cast_slice(&packed));
        let out = self.display(
            ctx,
            hdr.binding(),
            (image.width, image.height),
            dst,
            exposure,
        );
        hdr.destroy(ctx);
        out
    }

    /// Destroys the pipeline.
    pub fn destroy(self, ctx: &GpuContext) {
        self.0.destroy(ctx);
    }
}
