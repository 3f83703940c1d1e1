//! Driving the kernel: GPU struct layouts, scene flattening, the kernel source, progressive passes.

mod kernel;
pub mod layout;
mod renderer;
mod scene_data;

pub use kernel::{kernel_source, kernel_spirv};
pub use renderer::{frame_params, Renderer};
pub use scene_data::SceneData;
