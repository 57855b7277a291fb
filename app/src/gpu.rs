//! Opening the GPU session for a device named on the command line ("gpu" = the best one, or
//! part of a device's name): the one place the CLI, replay scripts and benchmarks get a
//! [`Viewport`] from.

use anyhow::{Context, Result};
use render::viewport::Viewport;
use render::vulkan::{ContextOptions, DeviceChoice, GpuContext};
use std::sync::Arc;

/// The device choice for a `--device` argument other than "cpu".
pub fn device_choice(device: &str) -> DeviceChoice {
    if device == "gpu" {
        DeviceChoice::Best
    } else {
        DeviceChoice::Name(device.to_string())
    }
}

/// A headless context on `device` (several sessions may share it), with the validation layer
/// when asked.
pub fn context(device: &str, validation: bool) -> Result<Arc<GpuContext>> {
    let ctx = GpuContext::new(&ContextOptions {
        device: device_choice(device),
        validation,
        ..Default::default()
    })
    .context("no usable Vulkan device")?;
    Ok(Arc::new(ctx))
}

/// A headless GPU session on `device` with the world of `view` uploaded.
pub fn session(device: &str, view: &brickmap::WorldView<'_>) -> Result<Viewport> {
    session_with(device, view, false)
}

/// [`session`] on a context that can also draw the editor's UI offscreen (`draw_ui`).
pub fn session_with(
    device: &str,
    view: &brickmap::WorldView<'_>,
    draw_ui: bool,
) -> Result<Viewport> {
    let ctx = GpuContext::new(&ContextOptions {
        device: device_choice(device),
        draw_ui,
        ..Default::default()
    })
    .context("no usable Vulkan device (the CPU reference renderer runs with --device cpu)")?;
    Ok(Viewport::new(Arc::new(ctx), view)?)
}
