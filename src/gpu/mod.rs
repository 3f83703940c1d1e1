//! All Vulkan lives here: instance and device selection, buffers, the compute pipeline and shader
//! compilation, and the window's swapchain with the viewer's frames. Nothing outside this module touches `ash` types.

mod acceleration_structure;
mod buffer;
mod compute;
mod context;
mod device_info;
mod failure;
mod loop_limit;
mod overlay_pass;
mod pipeline_statistics;
mod presenter;
mod shader;
mod swapchain;
mod traversal;
mod validation;

pub use acceleration_structure::{BottomGeometry, Placement, SceneStructure, MAX_CUSTOM_INDEX};
pub use buffer::{Buffer, BufferKind};
pub use compute::{Binding, ComputeKernel, TexelWords};
pub use context::{list_devices, ContextOptions, GpuContext};
pub use device_info::{DeviceInfo, DeviceType};
pub use failure::{DeviceFailure, VulkanError};
pub use overlay_pass::OverlayDraw;
pub use pipeline_statistics::KernelStatistic;
pub use presenter::{Frame, Picture, Presented, Presenter, Screen};
pub use shader::{assemble_source, compile_compute, ShaderSources};
pub use swapchain::ChannelOrder;
pub use traversal::{Traversal, TraversalRequest};
