//! The renderer: the scene parameters, the CPU reference path tracer (`cpu`) and images;
//! the Vulkan compute path tracer arrives with the rest of its issue.

pub mod convergence;
pub mod cpu;
pub mod image;
pub mod params;
pub mod vulkan;

pub use image::Image;
pub use params::{Camera, ParamError, RenderSettings, SceneParams, Sky, Sun, SunDisc};
