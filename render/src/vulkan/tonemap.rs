//! The display pass on the GPU: linear HDR → exposure → ACES fitted → sRGB 8-bit
//! (`shaders/tonemap.comp`), the same curve as `Image::to_srgb8` on the CPU.

use super::buffer::HostBuffer;
use super::pass::ComputePass;
use super::{GpuContext, GpuError};
use crate::image::Image;
use gpu_allocator::MemoryLocation;

const SPIRV: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/tonemap.comp.spv"));
const GROUP: u32 = 64;

/// Push constants. Keep in sync with `Push` in shaders/tonemap.comp.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    pixels: u32,
    scale: f32,
}
const _: () = assert!(std::mem::size_of::<Push>() == 8);

/// The tone-map pipeline.
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

    /// Tone-maps an image on the GPU; returns sRGB 8-bit pixels.
    pub fn run(
        &self,
        ctx: &GpuContext,
        image: &Image,
        exposure: f32,
    ) -> Result<Vec<[u8; 3]>, GpuError> {
        let pixels = image.pixels.len() as u32;
        let mut hdr = HostBuffer::new(ctx, "hdr", pixels as u64 * 12, MemoryLocation::CpuToGpu)?;
        let ldr = match HostBuffer::new(ctx, "ldr", pixels as u64 * 4, MemoryLocation::GpuToCpu) {
            Ok(b) => b,
            Err(e) => {
                hdr.destroy(ctx);
                return Err(e);
            }
        };
        hdr.write(bytemuck::cast_slice(&image.pixels));
        let push = Push {
            pixels,
            scale: 2f32.powf(exposure),
        };
        let result = self.0.run(
            ctx,
            &[hdr.binding(), ldr.binding()],
            bytemuck::bytes_of(&push),
            [pixels.div_ceil(GROUP), 1],
        );
        let out = result.map(|_| {
            ldr.read()[..pixels as usize * 4]
                .chunks_exact(4)
                .map(|p| [p[0], p[1], p[2]])
                .collect()
        });
        hdr.destroy(ctx);
        ldr.destroy(ctx);
        out
    }

    /// Destroys the pipeline.
    pub fn destroy(self, ctx: &GpuContext) {
        self.0.destroy(ctx);
    }
}
