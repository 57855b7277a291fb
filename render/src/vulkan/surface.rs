//! A window's presentation surface (created through ash-window from raw window handles) and
//! the queries a swapchain is built from.

use super::instance::Instance;
use super::{GpuError, vk_call};
use ash::vk;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};

/// The raw handles of the window to present to (from winit's `HasWindowHandle` /
/// `HasDisplayHandle`); only used while the context is created.
#[derive(Clone, Copy, Debug)]
pub struct WindowHandles {
    /// The display connection (X11, Wayland…).
    pub display: RawDisplayHandle,
    /// The window.
    pub window: RawWindowHandle,
}

/// A surface and its loader; destroyed on drop (after the swapchains made from it).
pub struct Surface {
    /// VK_KHR_surface entry points.
    pub loader: ash::khr::surface::Instance,
    /// The surface.
    pub raw: vk::SurfaceKHR,
}

impl Surface {
    /// The instance extensions a surface for `display` needs.
    pub fn required_extensions(
        display: RawDisplayHandle,
    ) -> Result<&'static [*const std::ffi::c_char], GpuError> {
        vk_call(
            "vkEnumerateInstanceExtensionProperties (surface)",
            ash_window::enumerate_required_extensions(display),
        )
    }

    /// Creates the surface of a window.
    ///
    /// # Safety
    /// The window must outlive the surface.
    pub unsafe fn new(instance: &Instance, handles: WindowHandles) -> Result<Self, GpuError> {
        // SAFETY: the caller keeps the window alive; the instance has the extensions.
        let raw = vk_call("vkCreate*SurfaceKHR", unsafe {
            ash_window::create_surface(
                &instance.entry,
                &instance.raw,
                handles.display,
                handles.window,
                None,
            )
        })?;
        Ok(Self {
            loader: ash::khr::surface::Instance::new(&instance.entry, &instance.raw),
            raw,
        })
    }

    /// Whether queue family `family` of `physical` can present to this surface.
    pub fn supports(&self, physical: vk::PhysicalDevice, family: u32) -> bool {
        // SAFETY: plain query on live handles.
        unsafe {
            self.loader
                .get_physical_device_surface_support(physical, family, self.raw)
        }
        .unwrap_or(false)
    }
}

impl Drop for Surface {
    fn drop(&mut self) {
        // SAFETY: the swapchains made from the surface are gone (they hold the context).
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}
