//! The renderer: the scene parameters, the CPU reference path tracer (`cpu`) and images;
//! the Vulkan layer (`vulkan`), the GPU session every caller uses (`viewport`) and the
//! window presenter with egui painting (`present`).

pub mod convergence;
pub mod cpu;
pub mod finished;
pub mod image;
pub mod params;
pub mod present;
pub mod stress;
pub mod viewport;
pub mod vulkan;

pub use image::Image;
pub use params::{
    Camera, ParamError, Projection, RenderSettings, SceneParams, Sequence, Sky, Sun, SunDisc,
};
