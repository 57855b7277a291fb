//! The Vulkan layer: a headless context (instance, device, compute queue, allocator) with
//! the validation layer and a debug-utils messenger that counts errors when asked, host-visible
//! buffers, and compute passes. Vulkan is loaded at run time (`ash` feature `loaded`): a machine
//! without a driver gets [`GpuError::NoVulkan`], not a link failure.

pub mod barrier;
pub mod buffer;
pub mod denoise;
pub mod device;
pub mod frame;
pub mod instance;
pub mod limits;
pub mod pass;
pub mod primary;
pub mod progressive;
pub mod staging;
pub mod surface;
pub mod swapchain;
pub mod temporal;
pub mod tonemap;
pub mod trace;
pub mod world;

use ash::vk;

pub use device::{ContextOptions, DeviceChoice, GpuContext, Presentation};
pub use limits::DeviceLimits;
pub use surface::WindowHandles;

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
    /// A buffer, binding or dispatch would pass one of the device's limits (or a cap set by
    /// `VOXBRICK_MAX_STORAGE_RANGE` / `VOXBRICK_MAX_ALLOCATION`).
    #[error("{what} needs {bytes} where this device's {limit} is {max}")]
    Limit {
        /// What would pass the limit.
        what: String,
        /// How much it needs (bytes, or workgroups).
        bytes: u64,
        /// The Vulkan limit's name.
        limit: &'static str,
        /// Its value in force.
        max: u64,
    },
    /// A setting (an environment variable) is malformed.
    #[error("{0}")]
    BadSetting(String),
    /// The allocator refused.
    #[error("GPU memory: {0}")]
    Memory(#[from] gpu_allocator::AllocationError),
}

/// Shorthand for mapping a Vulkan result.
pub(crate) fn vk_call<T>(call: &'static str, r: Result<T, vk::Result>) -> Result<T, GpuError> {
    r.map_err(|result| GpuError::Vk { call, result })
}
