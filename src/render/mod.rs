//! Driving the kernel: GPU struct layouts, scene flattening, the kernel source, progressive passes.

mod acceleration;
mod env_sampling;
mod kernel;
pub mod layout;
mod light_selection;
mod renderer;
mod scene_data;

pub use kernel::{kernel_source, kernel_spirv};
pub use acceleration::{Acceleration, AccelerationStats};
pub use renderer::{frame_params, mean_image, GeometryReport, Renderer, TEXTURE_BUDGET_BYTES};
pub use scene_data::SceneData;
