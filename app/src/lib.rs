//! voxbrick's application library: the scene document, file formats and CLI commands that
//! the `voxbrick` binary and the editor use.

pub mod atomic;
pub mod camera_path;
pub mod editor;
pub mod formats;
pub mod gpu;
pub mod scene;
pub mod selection;
pub mod soak;
pub mod ui;

pub use scene::Scene;
