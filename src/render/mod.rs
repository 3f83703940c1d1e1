//! Driving the kernel: GPU struct layouts, scene flattening, the kernel source, progressive passes,
//! AOVs.

mod acceleration;
mod aov;
mod chunks;
mod env_sampling;
mod kernel;
pub mod layout;
mod light_selection;
mod renderer;
mod scene_data;

pub use kernel::{kernel_source, kernel_spirv, UNSPLIT};
pub use acceleration::{Acceleration, AccelerationStats};
pub use aov::{AovSet, AovSums};
pub use renderer::{frame_params, mean_image, GeometryReport, Renderer, TEXTURE_BUDGET_BYTES};
pub use scene_data::SceneData;
