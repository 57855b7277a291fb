//! The Vulkan instance: the runtime-loaded library, the validation layer (with synchronization
//! validation) and a debug-utils messenger that counts its errors, plus whatever instance
//! extensions a window surface needs.

use super::{GpuError, vk_call};
use ash::vk;
use std::ffi::{CStr, c_char, c_void};
use std::sync::atomic::{AtomicU32, Ordering};

const VALIDATION: &CStr = c"VK_LAYER_KHRONOS_validation";

/// A debug messenger and its loader.
type Messenger = (ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT);

/// The loaded library, the instance and the error-counting messenger (destroyed on drop).
pub struct Instance {
    /// The loader's entry points.
    pub entry: ash::Entry,
    /// The instance.
    pub raw: ash::Instance,
    debug: Option<Messenger>,
    errors: Box<AtomicU32>,
}

unsafe extern "system" fn count_errors(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        // SAFETY: user data is the instance's boxed counter, alive as long as the messenger.
        unsafe { &*(user as *const AtomicU32) }.fetch_add(1, Ordering::Relaxed);
    }
    // SAFETY: the layer passes a valid callback-data pointer with a NUL-terminated message.
    let message = unsafe {
        data.as_ref()
            .and_then(|d| d.message_as_c_str())
            .map(|m| m.to_string_lossy().into_owned())
    };
    eprintln!("vulkan {severity:?}: {}", message.unwrap_or_default());
    // Where the call came from (debugging a validation message: VOXBRICK_VALIDATION_BACKTRACE=1).
    if std::env::var("VOXBRICK_VALIDATION_BACKTRACE").is_ok_and(|v| v == "1") {
        eprintln!("{}", std::backtrace::Backtrace::force_capture());
    }
    vk::FALSE
}

impl Instance {
    /// Loads Vulkan and creates an instance with `extensions` (a surface's, for a window);
    /// with `validation`, the Khronos layer and a messenger counting its errors.
    pub fn new(validation: bool, extensions: &[*const c_char]) -> Result<Self, GpuError> {
        // SAFETY: loading the Vulkan library runs its initialisation; nothing else is shared.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| GpuError::NoVulkan(e.to_string()))?;
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
        let mut ext_names = extensions.to_vec();
        if validation {
            ext_names.extend([
                ash::ext::debug_utils::NAME.as_ptr(),
                ash::ext::validation_features::NAME.as_ptr(),
            ]);
        }
        let sync = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&sync);
        let mut info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_extension_names(&ext_names);
        if validation {
            info = info
                .enabled_layer_names(&layer_names)
                .push_next(&mut features);
        }
        // SAFETY: the create info and everything it points to outlive the call.
        let raw = unsafe { entry.create_instance(&info, None) }
            .map_err(|e| GpuError::NoVulkan(format!("vkCreateInstance: {e}")))?;
        let mut instance = Self {
            entry,
            raw,
            debug: None,
            errors: Box::new(AtomicU32::new(0)),
        };
        if validation {
            let utils = ash::ext::debug_utils::Instance::new(&instance.entry, &instance.raw);
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
                .user_data(&*instance.errors as *const AtomicU32 as *mut c_void);
            // SAFETY: the counter is boxed and outlives the messenger (destroyed in Drop first).
            let messenger = vk_call("vkCreateDebugUtilsMessengerEXT", unsafe {
                utils.create_debug_utils_messenger(&info, None)
            })?;
            instance.debug = Some((utils, messenger));
        }
        Ok(instance)
    }

    /// Validation errors reported so far (0 when validation is off).
    pub fn validation_errors(&self) -> u32 {
        self.errors.load(Ordering::Relaxed)
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        // SAFETY: every child of the instance (device, surface) was destroyed before this.
        unsafe {
            if let Some((utils, m)) = self.debug.take() {
                utils.destroy_debug_utils_messenger(m, None);
            }
            self.raw.destroy_instance(None);
        }
    }
}
