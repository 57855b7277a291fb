//! The display pass on the GPU: linear HDR → exposure → ACES fitted → sRGB 8-bit
//! (`shaders/tonemap.comp`), the same curve as `Image::to_srgb8` on the CPU.

use super::buffer::HostBuffer;
use super::{GpuContext, GpuError, vk_call};
use crate::image::Image;
use ash::vk;
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

/// The compiled pipeline, created once per context.
pub struct ToneMapper {
    module: vk::ShaderModule,
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    pool: vk::DescriptorPool,
}

impl ToneMapper {
    /// Builds the pipeline.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let d = &ctx.device;
        let words: Vec<u32> = SPIRV
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        let binding = |b: u32| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(b)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(1)
                .stage_flags(vk::ShaderStageFlags::COMPUTE)
        };
        let bindings = [binding(0), binding(1)];
        let push = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .size(8)];
        let sizes = [vk::DescriptorPoolSize::default()
            .ty(vk::DescriptorType::STORAGE_BUFFER)
            .descriptor_count(2)];
        // SAFETY: create infos outlive each call; objects are destroyed in `destroy`.
        unsafe {
            let module = vk_call(
                "vkCreateShaderModule",
                d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None),
            )?;
            let set_layout = vk_call(
                "vkCreateDescriptorSetLayout",
                d.create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                    None,
                ),
            )?;
            let set_layouts = [set_layout];
            let layout = vk_call(
                "vkCreatePipelineLayout",
                d.create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::default()
                        .set_layouts(&set_layouts)
                        .push_constant_ranges(&push),
                    None,
                ),
            )?;
            let stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module)
                .name(c"main");
            let info = [vk::ComputePipelineCreateInfo::default()
                .stage(stage)
                .layout(layout)];
            let pipeline = d
                .create_compute_pipelines(vk::PipelineCache::null(), &info, None)
                .map_err(|(_, result)| GpuError::Vk {
                    call: "vkCreateComputePipelines",
                    result,
                })?[0];
            let pool = vk_call(
                "vkCreateDescriptorPool",
                d.create_descriptor_pool(
                    &vk::DescriptorPoolCreateInfo::default()
                        .max_sets(1)
                        .pool_sizes(&sizes)
                        .flags(vk::DescriptorPoolCreateFlags::FREE_DESCRIPTOR_SET),
                    None,
                ),
            )?;
            Ok(Self {
                module,
                set_layout,
                layout,
                pipeline,
                pool,
            })
        }
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
        let result = self.dispatch(
            ctx,
            &hdr,
            &ldr,
            Push {
                pixels,
                scale: 2f32.powf(exposure),
            },
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

    fn dispatch(
        &self,
        ctx: &GpuContext,
        hdr: &HostBuffer,
        ldr: &HostBuffer,
        push: Push,
    ) -> Result<(), GpuError> {
        let d = &ctx.device;
        let layouts = [self.set_layout];
        // SAFETY: the set is written before use and freed after the fence wait.
        unsafe {
            let set = vk_call(
                "vkAllocateDescriptorSets",
                d.allocate_descriptor_sets(
                    &vk::DescriptorSetAllocateInfo::default()
                        .descriptor_pool(self.pool)
                        .set_layouts(&layouts),
                ),
            )?[0];
            let infos = [
                [vk::DescriptorBufferInfo::default()
                    .buffer(hdr.raw)
                    .range(vk::WHOLE_SIZE)],
                [vk::DescriptorBufferInfo::default()
                    .buffer(ldr.raw)
                    .range(vk::WHOLE_SIZE)],
            ];
            let writes: Vec<vk::WriteDescriptorSet> = infos
                .iter()
                .enumerate()
                .map(|(b, info)| {
                    vk::WriteDescriptorSet::default()
                        .dst_set(set)
                        .dst_binding(b as u32)
                        .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                        .buffer_info(info)
                })
                .collect();
            d.update_descriptor_sets(&writes, &[]);
            let result = ctx.submit_and_wait(|cmd| {
                d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline);
                d.cmd_bind_descriptor_sets(
                    cmd,
                    vk::PipelineBindPoint::COMPUTE,
                    self.layout,
                    0,
                    &[set],
                    &[],
                );
                d.cmd_push_constants(
                    cmd,
                    self.layout,
                    vk::ShaderStageFlags::COMPUTE,
                    0,
                    bytemuck::bytes_of(&push),
                );
                d.cmd_dispatch(cmd, push.pixels.div_ceil(GROUP), 1, 1);
                // Make the shader's writes visible to the host read after the fence.
                let barrier = [vk::MemoryBarrier::default()
                    .src_access_mask(vk::AccessFlags::SHADER_WRITE)
                    .dst_access_mask(vk::AccessFlags::HOST_READ)];
                d.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::PipelineStageFlags::HOST,
                    vk::DependencyFlags::empty(),
                    &barrier,
                    &[],
                    &[],
                );
            });
            let _ = d.free_descriptor_sets(self.pool, &[set]);
            result
        }
    }

    /// Destroys the pipeline's objects.
    pub fn destroy(self, ctx: &GpuContext) {
        let d = &ctx.device;
        // SAFETY: no submission using them is pending (every run waits for its fence).
        unsafe {
            d.destroy_descriptor_pool(self.pool, None);
            d.destroy_pipeline(self.pipeline, None);
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
            d.destroy_shader_module(self.module, None);
        }
    }
}
