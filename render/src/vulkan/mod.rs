//! The Vulkan layer: a headless context (instance, device, compute queue, allocator) with
//! the validation layer and a debug-utils messenger that counts errors when asked, host-visible
//! buffers, and compute passes. Vulkan is loaded at run time (`ash` feature `loaded`): a machine
//! without a driver gets [`GpuError::NoVulkan`], not a link failure.

pub mod buffer;
pub mod pass;
pub mod primary;
pub mod progressive;
pub mod staging;
pub mod tonemap;
pub mod trace;
pub mod world;

use ash::vk;
use std::ffi::{CStr, c_void};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU32, Ordering};

/// Everything that can go wrong on the GPU side.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No Vulkan loader or no driver on this machine.
    #[error("no usable Vulkan: {0}")]
    NoVulkan(String),
    /// No device matches the choice.
    #[error("no Vulkan device matches {0}")]
    NoDevice(String),
    /// The validation layer was asked for and is not installed.
    #[error("the Khronos validation layer is not installed (package vulkan-validationlayers)")]
    NoValidationLayer,
    /// A Vulkan call failed.
    #[error("Vulkan call {call} failed: {result}")]
    Vk {
        /// Which call.
        call: &'static str,
        /// Its result code.
        result: vk::Result,
    },
    /// The allocator refused.
    #[error("GPU memory: {0}")]
    Memory(#[from] gpu_allocator::AllocationError),
}

/// Shorthand for mapping a Vulkan result.
pub(crate) fn vk_call<T>(call: &'static str, r: Result<T, vk::Result>) -> Result<T, GpuError> {
    r.map_err(|result| GpuError::Vk { call, result })
}

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
}

/// A headless Vulkan context for compute.
pub struct GpuContext {
    _entry: ash::Entry,
    instance: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    errors: Box<AtomicU32>,
    /// The physical device.
    pub physical: vk::PhysicalDevice,
    /// The logical device.
    pub device: ash::Device,
    /// The compute queue.
    pub queue: vk::Queue,
    /// Its family.
    pub queue_family: u32,
    /// Device memory sub-allocation.
    pub allocator: Mutex<Option<gpu_allocator::vulkan::Allocator>>,
    /// Device name.
    pub name: String,
    /// Nanoseconds per timestamp tick (0 when the queue cannot time).
    pub timestamp_period: f32,
    /// `minStorageBufferOffsetAlignment`: storage bindings start at multiples of it.
    pub storage_alignment: u64,
    /// VK_KHR_pipeline_executable_properties, when the driver has it.
    pub pipeline_stats: Option<ash::khr::pipeline_executable_properties::Device>,
    /// Float atomic adds on storage buffers (VK_EXT_shader_atomic_float): what the path
    /// tracer's shadow-ray queue needs besides the subgroup operations every chosen device has.
    pub shadow_queue: bool,
}

unsafe extern "system" fn count_errors(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        // SAFETY: user data is the context's boxed counter, alive as long as the messenger.
        unsafe { &*(user as *const AtomicU32) }.fetch_add(1, Ordering::Relaxed);
    }
    // SAFETY: the layer passes a valid callback-data pointer with a NUL-terminated message.
    let message = unsafe {
        data.as_ref()
            .and_then(|d| d.message_as_c_str())
            .map(|m| m.to_string_lossy().into_owned())
    };
    eprintln!("vulkan {severity:?}: {}", message.unwrap_or_default());
    vk::FALSE
}

const VALIDATION: &CStr = c"VK_LAYER_KHRONOS_validation";

impl GpuContext {
    /// Creates a context on the chosen device.
    pub fn new(options: &ContextOptions) -> Result<Self, GpuError> {
        // SAFETY: loading the Vulkan library runs its initialisation; nothing else is shared.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| GpuError::NoVulkan(e.to_string()))?;
        let validation =
            options.validation || std::env::var("VOXBRICK_VALIDATION").is_ok_and(|v| v == "1");
        if validation {
            // SAFETY: plain query.
            let layers = vk_call("vkEnumerateInstanceLayerProperties", unsafe {
                entry.enumerate_instance_layer_properties()
            })?;
            if !layers
                .iter()
                .any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == VALIDATION))
            {
                return Err(GpuError::NoValidationLayer);
            }
        }
        let app = vk::ApplicationInfo::default()
            .application_name(c"voxbrick")
            .api_version(vk::API_VERSION_1_2);
        let layer_names = [VALIDATION.as_ptr()];
        let ext_names = [
            ash::ext::debug_utils::NAME.as_ptr(),
            ash::ext::validation_features::NAME.as_ptr(),
        ];
        let sync = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&sync);
        let mut info = vk::InstanceCreateInfo::default().application_info(&app);
        if validation {
            info = info
                .enabled_layer_names(&layer_names)
                .enabled_extension_names(&ext_names)
                .push_next(&mut features);
        }
        // SAFETY: the create info and everything it points to outlive the call.
        let instance = unsafe { entry.create_instance(&info, None) }
            .map_err(|e| GpuError::NoVulkan(format!("vkCreateInstance: {e}")))?;
        let errors = Box::new(AtomicU32::new(0));
        let debug = if validation {
            let utils = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                        | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(count_errors))
                .user_data(&*errors as *const AtomicU32 as *mut c_void);
            // SAFETY: the counter is boxed and outlives the messenger (destroyed in Drop first).
            let messenger = vk_call("vkCreateDebugUtilsMessengerEXT", unsafe {
                utils.create_debug_utils_messenger(&info, None)
            })?;
            Some((utils, messenger))
        } else {
            None
        };
        let mut partial = Partial {
            instance: Some(instance),
            debug,
        };
        let instance = partial.instance.as_ref().expect("set above");
        // SAFETY: plain queries on a live instance.
        let devices = vk_call("vkEnumeratePhysicalDevices", unsafe {
            instance.enumerate_physical_devices()
        })?;
        if devices.is_empty() {
            // A loader without any driver: the same as no Vulkan at all.
            return Err(GpuError::NoVulkan(
                "the Vulkan loader found no device (no driver installed)".into(),
            ));
        }
        let described: Vec<(vk::PhysicalDevice, String, vk::PhysicalDeviceType)> = devices
            .iter()
            .map(|&d| {
                let p = unsafe { instance.get_physical_device_properties(d) };
                (
                    d,
                    p.device_name_as_c_str()
                        .map(|n| n.to_string_lossy().into_owned())
                        .unwrap_or_default(),
                    p.device_type,
                )
            })
            .collect();
        let chosen = match &options.device {
            DeviceChoice::Best => described
                .iter()
                .find(|d| d.2 == vk::PhysicalDeviceType::DISCRETE_GPU)
                .or(described.first()),
            DeviceChoice::Index(i) => described.get(*i),
            DeviceChoice::Name(n) => described
                .iter()
                .find(|d| d.1.to_lowercase().contains(&n.to_lowercase())),
        };
        let Some((physical, name, _)) = chosen.cloned() else {
            let names: Vec<&str> = described.iter().map(|d| d.1.as_str()).collect();
            return Err(GpuError::NoDevice(format!(
                "{:?} (devices: {names:?})",
                options.device
            )));
        };
        // SAFETY: plain query.
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let queue_family = families
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
            .ok_or_else(|| GpuError::NoDevice(format!("{name} has no compute queue")))?
            as u32;
        let priorities = [1.0];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        // Pipeline statistics (registers, spills, instructions per shader) when the driver
        // offers them: benchmarks print them next to the timings.
        // SAFETY: plain query.
        let available =
            unsafe { instance.enumerate_device_extension_properties(physical) }.unwrap_or_default();
        let has = |name: &CStr| {
            available
                .iter()
                .any(|e| e.extension_name_as_c_str() == Ok(name))
        };
        let has_stats = has(ash::khr::pipeline_executable_properties::NAME);
        // The shadow-ray queue: float atomic adds on buffers and subgroup ballots in compute.
        let mut atomic_float = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
        let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
        // SAFETY: plain queries with valid output chains (Vulkan 1.1 core).
        unsafe {
            let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut atomic_float);
            instance.get_physical_device_features2(physical, &mut features);
            let mut props = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
            instance.get_physical_device_properties2(physical, &mut props);
        }
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
        let mut stats_feature =
            vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default()
                .pipeline_executable_info(true);
        let mut float_feature = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default()
            .shader_buffer_float32_atomic_add(true);
        let mut info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&extensions);
        if has_stats {
            info = info.push_next(&mut stats_feature);
        }
        if shadow_queue {
            info = info.push_next(&mut float_feature);
        }
        // SAFETY: the create info outlives the call.
        let device = vk_call("vkCreateDevice", unsafe {
            instance.create_device(physical, &info, None)
        })?;
        let pipeline_stats = has_stats
            .then(|| ash::khr::pipeline_executable_properties::Device::new(instance, &device));
        // SAFETY: family and index exist (we asked for one queue of this family).
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let allocator =
            gpu_allocator::vulkan::Allocator::new(&gpu_allocator::vulkan::AllocatorCreateDesc {
                instance: instance.clone(),
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
        // SAFETY: plain query.
        let limits = unsafe { instance.get_physical_device_properties(physical) }.limits;
        let timestamp_period = if families[queue_family as usize].timestamp_valid_bits > 0 {
            limits.timestamp_period
        } else {
            0.0
        };
        let (instance, debug) = partial.take();
        Ok(Self {
            _entry: entry,
            instance,
            debug,
            errors,
            physical,
            device,
            queue,
            queue_family,
            allocator: Mutex::new(Some(allocator)),
            name,
            shadow_queue,
            timestamp_period,
            storage_alignment: limits.min_storage_buffer_offset_alignment.max(4),
            pipeline_stats,
        })
    }

    /// Validation errors reported so far (0 when validation is off).
    pub fn validation_errors(&self) -> u32 {
        self.errors.load(Ordering::Relaxed)
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

/// Owns what `GpuContext::new` created until the context is complete, so an early return
/// cleans up.
struct Partial {
    instance: Option<ash::Instance>,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
}

impl Partial {
    fn take(
        &mut self,
    ) -> (
        ash::Instance,
        Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    ) {
        (self.instance.take().expect("taken once"), self.debug.take())
    }
}

impl Drop for Partial {
    fn drop(&mut self) {
        // SAFETY: objects are destroyed in reverse creation order; only reached on errors.
        unsafe {
            if let Some((utils, m)) = self.debug.take() {
                utils.destroy_debug_utils_messenger(m, None);
            }
            if let Some(i) = self.instance.take() {
                i.destroy_instance(None);
            }
        }
    }
}

impl Drop for GpuContext {
    fn drop(&mut self) {
        // SAFETY: the device is idle after the wait; children go before parents.
        unsafe {
            let _ = self.device.device_wait_idle();
            drop(self.allocator.lock().map(|mut a| a.take()));
            self.device.destroy_device(None);
            if let Some((utils, m)) = self.debug.take() {
                utils.destroy_debug_utils_messenger(m, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}
