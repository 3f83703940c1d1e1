//! All Vulkan lives here: instance and device selection, buffers, the compute pipeline and shader
//! compilation. Nothing outside this module touches `ash` types.

mod buffer;
mod compute;
mod context;
mod failure;
mod loop_limit;
mod shader;
mod validation;

pub use buffer::{Buffer, BufferKind};
pub use compute::{Binding, ComputeKernel};
pub use context::{list_devices, ContextOptions, DeviceInfo, DeviceType, GpuContext};
pub use failure::{DeviceFailure, VulkanError};
pub use shader::{assemble_source, compile_compute, ShaderSources};
