//! The renderer: Vulkan compute path tracer over the brickmap and the CPU reference renderer
//! (their issue), and the scene parameters both consume.

pub mod params;

pub use params::{Camera, ParamError, RenderSettings, SceneParams, Sky, Sun};
