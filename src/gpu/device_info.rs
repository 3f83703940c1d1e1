//! What a Vulkan device is and what it allows: its kind, driver and the limits the renderer
//! plans against, read once when the devices are listed (context.rs).

use ash::vk;

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum DeviceType {
    // Declared in order of preference: a discrete GPU first, a CPU implementation (lavapipe) last.
    Discrete,
    Integrated,
    Virtual,
    Other,
    Cpu,
}

impl DeviceType {
    pub(super) fn from_vk(t: vk::PhysicalDeviceType) -> Self {
        match t {
            vk::PhysicalDeviceType::DISCRETE_GPU => Self::Discrete,
            vk::PhysicalDeviceType::INTEGRATED_GPU => Self::Integrated,
            vk::PhysicalDeviceType::VIRTUAL_GPU => Self::Virtual,
            vk::PhysicalDeviceType::CPU => Self::Cpu,
            _ => Self::Other,
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            Self::Discrete => "discrete GPU",
            Self::Integrated => "integrated GPU",
            Self::Virtual => "virtual GPU",
            Self::Other => "other",
            Self::Cpu => "CPU",
        }
    }
}

#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub index: usize,
    pub name: String,
    pub kind: DeviceType,
    pub api_version: String,
    /// The driver's version number as the device reports it (its encoding is the vendor's).
    pub driver: String,
    /// The driver's name and its own description of its version (VK_KHR_driver_properties, core in
    /// Vulkan 1.2), e.g. `llvmpipe` and `Mesa 25.0.7 (LLVM 19.1.7)`: which Mesa a lavapipe
    /// measurement ran on, which the device name does not say. Empty on devices below Vulkan 1.2.
    pub driver_name: String,
    pub driver_info: String,
    /// The driver's identity (VK_KHR_driver_properties; `None` below Vulkan 1.2), read through
    /// [`DeviceInfo::is_lavapipe`]: kernels that rely on how one driver runs them ask it.
    pub(super) driver_id: Option<vk::DriverId>,
    /// Bytes of shared memory a workgroup may use (`maxComputeSharedMemorySize`).
    pub max_compute_shared_memory_size: u32,
    /// Invocations in a subgroup (`subgroupSize`, Vulkan 1.1): lavapipe's SIMD width in lanes,
    /// NVIDIA's warp. 0 below Vulkan 1.1.
    pub subgroup_size: u32,
    /// `deviceUUID` (Vulkan 1.1): the same GPU has the same UUID in every process, whatever the
    /// loader's order; `--device` takes it (docs/farm.md, "Which GPU a task uses"), and CUDA and
    /// Open Image Denoise report it for the same GPU (the denoiser's device). None below 1.1.
    pub uuid: Option<[u8; 16]>,
    /// Bytes one storage-buffer binding can see (lowered by `ContextOptions::storage_binding_limit`).
    pub max_storage_buffer_range: u64,
    pub min_storage_buffer_offset_alignment: u64,
    pub max_storage_buffers_per_stage: u32,
    /// Texels one uniform texel buffer can see (`maxTexelBufferElements`, at most 2^31, which the
    /// kernel's `int` texel index reaches).
    pub max_texel_buffer_elements: u64,
    /// Bytes one texel buffer may see at most, whatever its texels' width:
    /// `ContextOptions::storage_binding_limit` (which lowers `max_storage_buffer_range` itself), or
    /// no bound.
    pub texel_binding_limit: u64,
    pub min_texel_buffer_offset_alignment: u64,
    /// Texel buffers count against the sampled images a stage may bind.
    pub max_texel_buffers_per_stage: u32,
    pub device_local_bytes: u64,
    pub(super) has_compute_queue: bool,
}

impl DeviceInfo {
    /// The UUID as text, lower-case hex grouped 8-4-4-4-12 (`nvidia-smi -L` prints NVIDIA's the
    /// same way after `GPU-`).
    pub fn uuid_text(&self) -> Option<String> {
        let hex: String = self.uuid?.iter().map(|b| format!("{b:02x}")).collect();
        Some(format!("{}-{}-{}-{}-{}", &hex[..8], &hex[8..12], &hex[12..16], &hex[16..20], &hex[20..]))
    }

    /// Mesa's lavapipe (llvmpipe's Vulkan driver): its kernels run on the CPU, a subgroup one SIMD
    /// loop, which several kernel choices are tuned for (render/walk_queue.rs, walk_records.rs).
    pub fn is_lavapipe(&self) -> bool {
        self.driver_id == Some(vk::DriverId::MESA_LLVMPIPE)
    }
}
