//! Driving the kernel: GPU struct layouts, the table of its bindings, scene flattening, the kernel
//! source, progressive passes, AOVs.

mod acceleration;
mod aov;
pub mod bindings;
mod bvh_width;
mod chunks;
mod env_sampling;
mod features;
mod frame;
mod glsl_block;
mod group_order;
mod interface;
mod kernel;
mod kernel_options;
mod kernel_setup;
pub mod layout;
mod light_selection;
pub mod light_tree;
pub mod light_tree_index;
mod media;
mod ray_query_scene;
mod renderer;
mod scene_data;
mod shadow_walk;
#[cfg(test)]
mod spirv_reflect;
mod textured_emission;
mod tile_taking;
mod variant;
mod walk_queue;
mod walk_records;
mod wavefront;
mod workgroup;

pub use acceleration::{Acceleration, AccelerationStats};
pub use aov::{AovSet, AovSums};
pub use bvh_width::BvhWidth;
pub use chunks::UNSPLIT;
pub use features::{FewShapes, SceneFeatures, ALPHA_DELTA, FEW_PRIMITIVES};
pub use frame::{frame_params, TEXTURE_BUDGET_BYTES};
pub use group_order::GroupOrder;
pub use kernel::{assemble_with_kernel_files, kernel_source, kernel_spirv, shader_file, SHADER_DIR_VAR};
pub use kernel_options::{
    help as kernel_options_help, DeviceClass, KernelChoices, KernelOption, KernelOptions, OPTIONS as KERNEL_OPTIONS,
    TAKE_TILES_VAR, WALK_QUEUE_VAR, WALK_RECORDS_VAR, WAVEFRONT_VAR, WORKGROUP_VAR,
};
pub use renderer::{GeometryReport, LightTreeReport, Renderer, MAX_SAMPLES_PER_PIXEL};
pub use scene_data::SceneData;
pub use shadow_walk::ShadowWalk;
pub use variant::{KernelChoice, KernelVariant};
pub use walk_queue::{QueueRequest, WalkQueue};
pub use walk_records::WalkRecords;
pub use wavefront::WavefrontStage;
pub use workgroup::Workgroup;

/// Rec. 709 luminance of linear RGB (the first three values): what light and environment sampling
/// make their distributions proportional to (lights.glsl evaluates the same weights in the kernel).
fn luminance(rgb: &[f32]) -> f64 {
    0.2126 * rgb[0] as f64 + 0.7152 * rgb[1] as f64 + 0.0722 * rgb[2] as f64
}
