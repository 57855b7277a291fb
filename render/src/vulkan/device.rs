//! `GpuContext`: the chosen physical device, the logical device with its compute queue (and a
//! present queue when a window surface is given), the memory allocator and what the passes
//! need to know about the device. Destroyed on drop, children before parents.
//!
//! In detail:
//! `GpuContext`: device by best/index/name (with a window: one that presents to it), compute
//! queue (with a window: graphics + compute, and a present queue of another family if that one
//! cannot present: `choose_families`, unit-tested; the swapchain's images are then shared
//! concurrently), gpu-allocator shared as `Arc<Mutex<_>>` with the egui painter (freed before
//! the device on drop; leaked with a message if still shared), driver name, timestamp period,
//! the limits in force (`limits.rs`), pipeline statistics
//! (VK_KHR_pipeline_executable_properties) when the driver has them, a device without subgroup
//! basic/vote/ballot operations in compute is refused with a clear error (trace.comp needs
//! them), `shadow_queue` (float atomic adds: VK_EXT_shader_atomic_float enabled when present),
//! `Presentation` (surface, VK_KHR_swapchain, present queue); `ui_rendering`
//! (VK_KHR_dynamic_rendering on a Vulkan 1.2 instance) for a window or `draw_ui`. Fields drop
//! after the body: surface, then instance.

use super::instance::Instance;
use super::surface::{Surface, WindowHandles};
use super::{GpuError, vk_call};
use ash::vk;
use gpu_allocator::vulkan::Allocator;
use std::ffi::CStr;
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

/// Which device to use.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum DeviceChoice {
    /// A discrete GPU if there is one, else the first device.
    #[default]
    Best,
    /// The device at this index of the enumeration.
    Index(usize),
    /// The first device whose name contains this text (case-insensitive).
    Name(String),
}

/// How to create a context.
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Device choice.
    pub device: DeviceChoice,
    /// Enable the Khronos validation layer (with synchronization validation) and count its
    /// errors; also enabled by `VOXBRICK_VALIDATION=1`.
    pub validation: bool,
    /// A window to present to: the context then creates its surface, picks a device and
    /// queue that can present to it and enables swapchains and dynamic rendering.
    pub window: Option<WindowHandles>,
    /// Draw the editor's UI without a window (an offscreen target: headless measurement):
    /// a graphics + compute queue and dynamic rendering, as for a window.
    pub draw_ui: bool,
    /// Lower `maxStorageBufferRange` to this many bytes (as `VOXBRICK_MAX_STORAGE_RANGE`
    /// does; the smaller of the two holds).
    pub max_storage_range: Option<u64>,
    /// Lower `maxMemoryAllocationSize` to this many bytes (as `VOXBRICK_MAX_ALLOCATION`).
    pub max_allocation: Option<u64>,
}

/// What presenting to a window needs from the device.
pub struct Presentation {
    /// The window's surface.
    pub surface: Surface,
    /// VK_KHR_swapchain entry points.
    pub swapchain: ash::khr::swapchain::Device,
    /// The queue that presents (the compute queue when its family can).
    pub queue: vk::Queue,
    /// Its family.
    pub queue_family: u32,
}

/// A Vulkan context for compute, and for presentation when made for a window.
pub struct GpuContext {
    /// The physical device.
    pub physical: vk::PhysicalDevice,
    /// The logical device.
    pub device: ash::Device,
    /// The compute queue.
    pub queue: vk::Queue,
    /// Its family.
    pub queue_family: u32,
    /// Device memory sub-allocation (shared with the egui painter).
    pub allocator: ManuallyDrop<Arc<Mutex<Allocator>>>,
    /// Device name.
    pub name: String,
    /// Driver name and version, as the driver reports them.
    pub driver: String,
    /// Nanoseconds per timestamp tick (0 when the queue cannot time).
    pub timestamp_period: f32,
    /// The limits every buffer, binding and dispatch stays within (lowered by the caps of
    /// [`super::limits`]).
    pub limits: super::DeviceLimits,
    /// VK_KHR_pipeline_executable_properties, when the driver has it.
    pub pipeline_stats: Option<ash::khr::pipeline_executable_properties::Device>,
    /// Float atomic adds on storage buffers (VK_EXT_shader_atomic_float): what the path
    /// tracer's shadow-ray queue needs besides the subgroup operations every chosen device has.
    pub shadow_queue: bool,
    /// Presentation, for a context made with a window.
    pub presentation: Option<Presentation>,
    /// VK_KHR_dynamic_rendering entry points (egui draws with dynamic rendering), for a
    /// context made with a window or `draw_ui`.
    pub ui_rendering: Option<ash::khr::dynamic_rendering::Device>,
    /// Declared last: dropped after the device and the surface.
    pub instance: Instance,
}

/// Device extensions a window needs.
const PRESENT_EXTENSIONS: [&CStr; 2] =
    [ash::khr::swapchain::NAME, ash::khr::dynamic_rendering::NAME];
/// Device extensions drawing the UI offscreen needs.
const UI_EXTENSIONS: [&CStr; 1] = [ash::khr::dynamic_rendering::NAME];

impl GpuContext {
    /// Creates a context on the chosen device.
    pub fn new(options: &ContextOptions) -> Result<Self, GpuError> {
        let validation =
            options.validation || std::env::var("VOXBRICK_VALIDATION").is_ok_and(|v| v == "1");
        let surface_extensions = match options.window {
            Some(w) => Surface::required_extensions(w.display)?,
            None => &[],
        };
        let instance = Instance::new(validation, surface_extensions)?;
        let ui = options.window.is_some() || options.draw_ui;
        // SAFETY: the caller's window outlives the context (the editor drops it first).
        let surface = match options.window {
            Some(w) => Some(unsafe { Surface::new(&instance, w) }?),
            None => None,
        };
        let raw = &instance.raw;
        // SAFETY: plain queries on a live instance.
        let devices = vk_call("vkEnumeratePhysicalDevices", unsafe {
            raw.enumerate_physical_devices()
        })?;
        if devices.is_empty() {
            // A loader without any driver: the same as no Vulkan at all.
            return Err(GpuError::NoVulkan(
                "the Vulkan loader found no device (no driver installed)".into(),
            ));
        }
        let described: Vec<Candidate> = devices
            .iter()
            .map(|&d| Candidate::new(raw, d, surface.as_ref(), ui))
            .collect();
        let presentable = |c: &&Candidate| surface.is_none() || c.present_family.is_some();
        let chosen = match &options.device {
            DeviceChoice::Best => described
                .iter()
                .filter(presentable)
                .find(|d| d.kind == vk::PhysicalDeviceType::DISCRETE_GPU)
                .or(described.iter().find(presentable)),
            DeviceChoice::Index(i) => described.get(*i),
            DeviceChoice::Name(n) => described
                .iter()
                .find(|d| d.name.to_lowercase().contains(&n.to_lowercase())),
        };
        let Some(chosen) = chosen else {
            let names: Vec<&str> = described.iter().map(|d| d.name.as_str()).collect();
            let what = if surface.is_some() {
                " that can present to the window"
            } else {
                ""
            };
            return Err(GpuError::NoDevice(format!(
                "{:?}{what} (devices: {names:?})",
                options.device
            )));
        };
        let (physical, name) = (chosen.physical, chosen.name.clone());
        let queue_family = chosen
            .compute_family
            .ok_or_else(|| GpuError::NoDevice(format!("{name} has no compute queue")))?;
        let present_family = match &surface {
            Some(_) => Some(chosen.present_family.ok_or_else(|| {
                GpuError::NoDevice(format!("{name} cannot present to this window"))
            })?),
            None => None,
        };
        // SAFETY: plain query.
        let available =
            unsafe { raw.enumerate_device_extension_properties(physical) }.unwrap_or_default();
        let has = |name: &CStr| {
            available
                .iter()
                .any(|e| e.extension_name_as_c_str() == Ok(name))
        };
        let ui_extensions: &[&CStr] = match (surface.is_some(), ui) {
            (true, _) => &PRESENT_EXTENSIONS,
            (false, true) => &UI_EXTENSIONS,
            _ => &[],
        };
        if let Some(missing) = ui_extensions.iter().find(|e| !has(e)) {
            return Err(GpuError::NoDevice(format!(
                "{name} (it lacks {}, which the editor's window needs)",
                missing.to_string_lossy()
            )));
        }
        let has_stats = has(ash::khr::pipeline_executable_properties::NAME);
        // The shadow-ray queue: float atomic adds on buffers and subgroup ballots in compute.
        let mut atomic_float = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
        let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        // SAFETY: plain queries with valid output chains (Vulkan 1.1/1.2 core).
        unsafe {
            let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut atomic_float);
            raw.get_physical_device_features2(physical, &mut features);
            let mut props = vk::PhysicalDeviceProperties2::default()
                .push_next(&mut subgroup)
                .push_next(&mut driver);
            raw.get_physical_device_properties2(physical, &mut props);
        }
        let driver = format!(
            "{} {}",
            driver
                .driver_name_as_c_str()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            driver
                .driver_info_as_c_str()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        );
        // The path tracer's subgroup operations (every desktop driver and lavapipe have them).
        let needed = vk::SubgroupFeatureFlags::BASIC
            | vk::SubgroupFeatureFlags::VOTE
            | vk::SubgroupFeatureFlags::BALLOT;
        if !subgroup
            .supported_stages
            .contains(vk::ShaderStageFlags::COMPUTE)
            || !subgroup.supported_operations.contains(needed)
        {
            return Err(GpuError::NoDevice(format!(
                "{name} (it lacks subgroup basic, vote or ballot operations in compute shaders, which the path tracer needs)"
            )));
        }
        let shadow_queue = has(ash::ext::shader_atomic_float::NAME)
            && atomic_float.shader_buffer_float32_atomic_add == vk::TRUE;
        let mut extensions = Vec::new();
        if has_stats {
            extensions.push(ash::khr::pipeline_executable_properties::NAME.as_ptr());
        }
        if shadow_queue {
            extensions.push(ash::ext::shader_atomic_float::NAME.as_ptr());
        }
        extensions.extend(ui_extensions.iter().map(|e| e.as_ptr()));
        let priorities = [1.0];
        let mut queues = vec![
            vk::DeviceQueueCreateInfo::default()
                .queue_family_index(queue_family)
                .queue_priorities(&priorities),
        ];
        if let Some(p) = present_family.filter(|&p| p != queue_family) {
            queues.push(
                vk::DeviceQueueCreateInfo::default()
                    .queue_family_index(p)
                    .queue_priorities(&priorities),
            );
        }
        let mut stats_feature =
            vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default()
                .pipeline_executable_info(true);
        let mut float_feature = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default()
            .shader_buffer_float32_atomic_add(true);
        let mut rendering_feature =
            vk::PhysicalDeviceDynamicRenderingFeaturesKHR::default().dynamic_rendering(true);
        let mut info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&extensions);
        if has_stats {
            info = info.push_next(&mut stats_feature);
        }
        if shadow_queue {
            info = info.push_next(&mut float_feature);
        }
        if ui {
            info = info.push_next(&mut rendering_feature);
        }
        // SAFETY: the create info outlives the call.
        let device = vk_call("vkCreateDevice", unsafe {
            raw.create_device(physical, &info, None)
        })?;
        let pipeline_stats =
            has_stats.then(|| ash::khr::pipeline_executable_properties::Device::new(raw, &device));
        // SAFETY: family and index exist (we asked for one queue of this family).
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let presentation = surface.map(|surface| {
            let family = present_family.expect("a surface has a present family");
            Presentation {
                surface,
                swapchain: ash::khr::swapchain::Device::new(raw, &device),
                // SAFETY: as above, for the present family.
                queue: unsafe { device.get_device_queue(family, 0) },
                queue_family: family,
            }
        });
        let ui_rendering = ui.then(|| ash::khr::dynamic_rendering::Device::new(raw, &device));
        let allocator = Allocator::new(&gpu_allocator::vulkan::AllocatorCreateDesc {
            instance: raw.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        });
        let allocator = match allocator {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: nothing was created on the device yet.
                unsafe { device.destroy_device(None) };
                return Err(e.into());
            }
        };
        let device_limits = match super::DeviceLimits::read(raw, physical) {
            Ok(l) => l.capped_by(options.max_storage_range, options.max_allocation),
            Err(e) => {
                drop(allocator);
                // SAFETY: nothing else was created on the device yet.
                unsafe { device.destroy_device(None) };
                return Err(e);
            }
        };
        // SAFETY: plain queries.
        let limits = unsafe { raw.get_physical_device_properties(physical) }.limits;
        let families = unsafe { raw.get_physical_device_queue_family_properties(physical) };
        let timestamp_period = if families[queue_family as usize].timestamp_valid_bits > 0 {
            limits.timestamp_period
        } else {
            0.0
        };
        Ok(Self {
            physical,
            device,
            queue,
            queue_family,
            allocator: ManuallyDrop::new(Arc::new(Mutex::new(allocator))),
            name,
            driver,
            shadow_queue,
            timestamp_period,
            limits: device_limits,
            pipeline_stats,
            presentation,
            ui_rendering,
            instance,
        })
    }

    /// Validation errors reported so far (0 when validation is off).
    pub fn validation_errors(&self) -> u32 {
        self.instance.validation_errors()
    }

    /// Runs `record` in a one-time command buffer and waits for it.
    pub fn submit_and_wait(&self, record: impl FnOnce(vk::CommandBuffer)) -> Result<(), GpuError> {
        let d = &self.device;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(self.queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: every object created here is destroyed before returning; the fence wait
        // guarantees the GPU is done with them.
        unsafe {
            let pool = vk_call(
                "vkCreateCommandPool",
                d.create_command_pool(&pool_info, None),
            )?;
            let result = (|| {
                let alloc = vk::CommandBufferAllocateInfo::default()
                    .command_pool(pool)
                    .level(vk::CommandBufferLevel::PRIMARY)
                    .command_buffer_count(1);
                let cmd = vk_call(
                    "vkAllocateCommandBuffers",
                    d.allocate_command_buffers(&alloc),
                )?[0];
                let begin = vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
                vk_call("vkBeginCommandBuffer", d.begin_command_buffer(cmd, &begin))?;
                record(cmd);
                vk_call("vkEndCommandBuffer", d.end_command_buffer(cmd))?;
                let fence = vk_call(
                    "vkCreateFence",
                    d.create_fence(&vk::FenceCreateInfo::default(), None),
                )?;
                let cmds = [cmd];
                let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
                let waited = vk_call("vkQueueSubmit", d.queue_submit(self.queue, &submit, fence))
                    .and_then(|_| {
                        vk_call(
                            "vkWaitForFences",
                            d.wait_for_fences(&[fence], true, u64::MAX),
                        )
                    });
                d.destroy_fence(fence, None);
                waited
            })();
            d.destroy_command_pool(pool, None);
            result
        }
    }
}

/// A physical device as the choice sees it.
struct Candidate {
    physical: vk::PhysicalDevice,
    name: String,
    kind: vk::PhysicalDeviceType,
    compute_family: Option<u32>,
    /// A family that presents to the surface: the compute family when it can.
    present_family: Option<u32>,
}

impl Candidate {
    fn new(
        instance: &ash::Instance,
        physical: vk::PhysicalDevice,
        surface: Option<&Surface>,
        ui: bool,
    ) -> Self {
        // SAFETY: plain queries on a live instance.
        let (p, families) = unsafe {
            (
                instance.get_physical_device_properties(physical),
                instance.get_physical_device_queue_family_properties(physical),
            )
        };
        // A window's frames also draw egui: its queue needs graphics too.
        let flags = if ui {
            vk::QueueFlags::COMPUTE | vk::QueueFlags::GRAPHICS
        } else {
            vk::QueueFlags::COMPUTE
        };
        let flags_of: Vec<vk::QueueFlags> = families.iter().map(|f| f.queue_flags).collect();
        let (compute_family, present_family) = match surface {
            Some(s) => choose_families(&flags_of, flags, |f| s.supports(physical, f)),
            None => (choose_families(&flags_of, flags, |_| false).0, None),
        };
        Self {
            physical,
            name: p
                .device_name_as_c_str()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            kind: p.device_type,
            compute_family,
            present_family,
        }
    }
}

/// The queue families a context uses, from each family's flags: the first family with
/// `needed` (compute, plus graphics for a window's egui), and a family that presents
/// (`presents`): that same family when it can, else the first one that can (the swapchain's
/// images are then shared concurrently between the two). None where no family qualifies.
fn choose_families(
    families: &[vk::QueueFlags],
    needed: vk::QueueFlags,
    presents: impl Fn(u32) -> bool,
) -> (Option<u32>, Option<u32>) {
    let compute = families
        .iter()
        .position(|f| f.contains(needed))
        .map(|f| f as u32);
    let present = compute
        .filter(|&c| presents(c))
        .or_else(|| (0..families.len() as u32).find(|&f| presents(f)));
    (compute, present)
}

impl Drop for GpuContext {
    fn drop(&mut self) {
        // SAFETY: the device is idle after the wait; children go before parents (the
        // surface and the instance are fields dropped after this body).
        unsafe {
            let _ = self.device.device_wait_idle();
            // The allocator frees its memory blocks before the device goes; a renderer still
            // holding a clone would be a bug, and leaking beats freeing into a dead device.
            let allocator = ManuallyDrop::take(&mut self.allocator);
            if let Err(shared) = Arc::try_unwrap(allocator) {
                eprintln!("voxbrick: GPU allocator still shared at shutdown; leaking it");
                std::mem::forget(shared);
            }
            self.device.destroy_device(None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GC: vk::QueueFlags = vk::QueueFlags::from_raw(
        vk::QueueFlags::GRAPHICS.as_raw() | vk::QueueFlags::COMPUTE.as_raw(),
    );
    const C: vk::QueueFlags = vk::QueueFlags::COMPUTE;
    const T: vk::QueueFlags = vk::QueueFlags::TRANSFER;

    #[test]
    fn the_compute_queue_presents_when_it_can_else_another_family_does() {
        // One family that does everything (lavapipe, most desktop GPUs).
        assert_eq!(choose_families(&[GC], GC, |_| true), (Some(0), Some(0)));
        // Presenting from the compute family is preferred over an earlier one.
        assert_eq!(
            choose_families(&[T, GC, GC], GC, |f| f != 0),
            (Some(1), Some(1))
        );
        // The graphics + compute family cannot present: a separate present family.
        assert_eq!(
            choose_families(&[GC, C, T], GC, |f| f == 2),
            (Some(0), Some(2))
        );
        // Compute-only work takes the first compute family.
        assert_eq!(choose_families(&[T, C, GC], C, |_| false), (Some(1), None));
        // Nothing presents, or nothing computes: None, and the caller says so.
        assert_eq!(choose_families(&[GC], GC, |_| false), (Some(0), None));
        assert_eq!(choose_families(&[T], C, |_| true), (None, Some(0)));
    }
}
