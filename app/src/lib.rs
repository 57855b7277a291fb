//! voxbrick's application library: the scene and its document engine (commands, history,
//! scripts), the built-in scenes, the file formats, the interactive editor (`ui`), the soak test and the GPU
//! session opener. The `voxbrick` binary (`main.rs`, its subcommands in `cli/`) is built on it.

pub mod atomic;
pub mod builtin;
pub mod camera_path;
pub mod editor;
pub mod formats;
pub mod gpu;
pub mod picture;
pub mod rect_select;
pub mod scene;
#[cfg(any(test, feature = "test-hooks"))]
pub mod scratch;
pub mod selection;
pub mod selection_scale;
pub mod selection_transform;
pub mod soak;
pub mod ui;
pub mod wand;

pub use scene::Scene;
