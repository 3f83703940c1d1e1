//! Vulkan instance, physical-device choice, logical device, queue and memory allocator.

use super::device_info::{DeviceInfo, DeviceType};
use super::failure::VulkanError;
use super::traversal::{self, Traversal, TraversalRequest};
use super::validation::{self, ValidationLog};
use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use raw_window_handle::{HasDisplayHandle, HasWindowHandle, RawDisplayHandle, RawWindowHandle};
use std::mem::ManuallyDrop;
use std::sync::{Mutex, OnceLock};

#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Case-insensitive substring of a device name, or a device index from `caustica devices`.
    pub device: Option<String>,
    /// Enable the Khronos validation layer (when installed) and record its messages.
    pub validation: bool,
    /// Act as if one storage or texel-buffer binding could see at most this many bytes (tests of the splitting of
    /// large arrays, and of the refusal of scenes too large, on any device).
    pub storage_binding_limit: Option<u64>,
    /// Which traversal the kernel runs (traversal.rs); ray queries enable their extensions.
    pub traversal: TraversalRequest,
}

pub struct GpuContext {
    _entry: ash::Entry,
    pub(super) instance: ash::Instance,
    pub(super) physical_device: vk::PhysicalDevice,
    /// The window surface and the loaders of the surface and swapchain extensions, when this
    /// context was made for a window ([`GpuContext::for_window`]).
    pub(super) presentation: Option<Presentation>,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    // Boxed so the pointer handed to the validation callback stays put.
    validation_log: Box<ValidationLog>,
    pub(super) device: ash::Device,
    pub(super) queue: vk::Queue,
    pub(super) command_pool: vk::CommandPool,
    pub(super) allocator: ManuallyDrop<Mutex<Allocator>>,
    pub info: DeviceInfo,
    /// Nanoseconds per timestamp tick where the compute queue records timestamps, else `None`.
    pub timestamp_period_ns: Option<f64>,
    /// See [`GpuContext::loop_limit`] (loop_limit.rs); probed on first use.
    pub(super) loop_limit: OnceLock<Option<u32>>,
    /// Reads what the driver says of each compiled kernel, where the device can
    /// (pipeline_statistics.rs).
    pub(super) pipeline_statistics: Option<ash::khr::pipeline_executable_properties::Device>,
    /// The traversal the kernel runs on this device (what `ContextOptions::traversal` resolved to).
    pub traversal: Traversal,
    /// Builds acceleration structures where the traversal is ray queries
    /// (acceleration_structure.rs), with the device's alignment of their scratch memory.
    pub(super) acceleration_structures: Option<(ash::khr::acceleration_structure::Device, u64)>,
}

/// What presenting to a window needs beside the device: its surface and the extensions' loaders.
pub(super) struct Presentation {
    pub(super) surface_loader: ash::khr::surface::Instance,
    pub(super) surface: vk::SurfaceKHR,
    pub(super) swapchain_loader: ash::khr::swapchain::Device,
}

/// A window's raw handles, taken from a winit (or any raw-window-handle) window.
#[derive(Clone, Copy)]
struct WindowHandles {
    display: RawDisplayHandle,
    window: RawWindowHandle,
}

fn load_entry() -> Result<ash::Entry> {
    // SAFETY: loading libvulkan runs its initialisers; ash::Entry keeps the library loaded for as long as the entry
    // (and every instance made from it: GpuContext holds `_entry`) lives.
    unsafe { ash::Entry::load() }.map_err(|e| {
        anyhow!(
            "cannot load the Vulkan loader (libvulkan.so.1): {e}. Install it, e.g. `apt-get install libvulkan1 mesa-vulkan-drivers`"
        )
    })
}

fn create_instance(
    entry: &ash::Entry,
    validation: bool,
    window_extensions: &[*const std::ffi::c_char],
) -> Result<(ash::Instance, bool)> {
    let app = vk::ApplicationInfo::default()
        .application_name(c"caustica")
        .engine_name(c"caustica")
        .api_version(vk::API_VERSION_1_2);
    // SAFETY: a global command on a loaded entry; it takes no handles and fills a Vec it allocates.
    let layer_available = validation
        && unsafe { entry.enumerate_instance_layer_properties() }
            .unwrap_or_default()
            .iter()
            .any(|l| l.layer_name_as_c_str().ok() == Some(validation::LAYER_NAME));
    if validation && !layer_available {
        log::warn!(
            "caustica: validation requested but {:?} is not installed; running without it",
            validation::LAYER_NAME
        );
    }
    let layers = if layer_available { vec![validation::LAYER_NAME.as_ptr()] } else { vec![] };
    let mut extensions = window_extensions.to_vec();
    if layer_available {
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    let info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&extensions);
    // SAFETY: `info` borrows `app`, `layers` and `extensions`, locals alive until the call returns; their pointers
    // are to static C strings (the layer's and extensions' names, the window extensions ash_window returns as
    // 'static).
    let instance = unsafe { entry.create_instance(&info, None) }
        .map_err(|e| anyhow!("vkCreateInstance failed: {e} (is a Vulkan driver installed? try mesa-vulkan-drivers)"))?;
    Ok((instance, layer_available))
}

fn describe(instance: &ash::Instance, pd: vk::PhysicalDevice, index: usize) -> DeviceInfo {
    // SAFETY: `pd` was enumerated from this live `instance`, and these queries only fill structures they return.
    let props = unsafe { instance.get_physical_device_properties(pd) };
    let memory = unsafe { instance.get_physical_device_memory_properties(pd) };
    let queues = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let device_local_bytes = memory.memory_heaps[..memory.memory_heap_count as usize]
        .iter()
        .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
        .map(|h| h.size)
        .max()
        .unwrap_or(0);
    let v = props.api_version;
    let (driver_name, driver_info, driver_id) = driver_properties(instance, pd, v);
    DeviceInfo {
        index,
        name: props.device_name_as_c_str().map(|c| c.to_string_lossy().into_owned()).unwrap_or_default(),
        kind: DeviceType::from_vk(props.device_type),
        api_version: format!("{}.{}.{}", vk::api_version_major(v), vk::api_version_minor(v), vk::api_version_patch(v)),
        driver: format!("{:#x}", props.driver_version),
        driver_name,
        driver_info,
        driver_id,
        max_compute_shared_memory_size: props.limits.max_compute_shared_memory_size,
        subgroup_size: subgroup_size(instance, pd, v),
        uuid: device_uuid(instance, pd, v),
        max_storage_buffer_range: props.limits.max_storage_buffer_range as u64,
        min_storage_buffer_offset_alignment: props.limits.min_storage_buffer_offset_alignment,
        max_storage_buffers_per_stage: props.limits.max_per_stage_descriptor_storage_buffers,
        max_texel_buffer_elements: (props.limits.max_texel_buffer_elements as u64).min(1 << 31),
        texel_binding_limit: u64::MAX,
        min_texel_buffer_offset_alignment: props.limits.min_texel_buffer_offset_alignment,
        max_texel_buffers_per_stage: props.limits.max_per_stage_descriptor_sampled_images,
        device_local_bytes,
        has_compute_queue: queues.iter().any(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE)),
    }
}

/// The driver's name, version text and identity; chained only where the device supports Vulkan
/// 1.2, which made the structure core (the instance is created for 1.2).
fn driver_properties(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    api_version: u32,
) -> (String, String, Option<vk::DriverId>) {
    if api_version < vk::API_VERSION_1_2 {
        return (String::new(), String::new(), None);
    }
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut props = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
    // SAFETY: `pd` belongs to the live `instance`, which was created for Vulkan 1.2, and the device reports 1.2
    // (checked above), so the chained PhysicalDeviceDriverProperties is a structure it knows; `driver` is a local
    // that outlives the call.
    unsafe { instance.get_physical_device_properties2(pd, &mut props) };
    let text = |c: Result<&std::ffi::CStr, _>| c.map(|c| c.to_string_lossy().into_owned()).unwrap_or_default();
    (text(driver.driver_name_as_c_str()), text(driver.driver_info_as_c_str()), Some(driver.driver_id))
}

/// The device's UUID (`VkPhysicalDeviceIDProperties::deviceUUID`), or None below Vulkan 1.1,
/// which made the structure core. The same physical GPU reports the same UUID to every process
/// (NVIDIA's equals the `GPU-…` UUID of nvidia-smi), unlike the device index, which follows the
/// loader's order.
fn device_uuid(instance: &ash::Instance, pd: vk::PhysicalDevice, api_version: u32) -> Option<[u8; 16]> {
    if api_version < vk::API_VERSION_1_1 {
        return None;
    }
    let mut id = vk::PhysicalDeviceIDProperties::default();
    let mut props = vk::PhysicalDeviceProperties2::default().push_next(&mut id);
    // SAFETY: `pd` belongs to the live `instance` and the device reports Vulkan 1.1 or newer (checked above), where
    // PhysicalDeviceIDProperties is core; `id` is a local that outlives the call.
    unsafe { instance.get_physical_device_properties2(pd, &mut props) };
    Some(id.device_uuid)
}

/// The device's subgroup size, or 0 below Vulkan 1.1, which made the structure core.
fn subgroup_size(instance: &ash::Instance, pd: vk::PhysicalDevice, api_version: u32) -> u32 {
    if api_version < vk::API_VERSION_1_1 {
        return 0;
    }
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut props = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
    // SAFETY: `pd` belongs to the live `instance` and the device reports Vulkan 1.1 or newer (checked above), where
    // PhysicalDeviceSubgroupProperties is core; `subgroup` is a local that outlives the call.
    unsafe { instance.get_physical_device_properties2(pd, &mut props) };
    subgroup.subgroup_size
}

fn enumerate(instance: &ash::Instance) -> Result<Vec<(vk::PhysicalDevice, DeviceInfo)>> {
    // SAFETY: `instance` is alive (the caller's); the call fills a Vec it allocates.
    let devices = unsafe { instance.enumerate_physical_devices() }.context("vkEnumeratePhysicalDevices failed")?;
    Ok(devices.into_iter().enumerate().map(|(i, pd)| (pd, describe(instance, pd, i))).collect())
}

/// Every Vulkan device the loader sees, in the loader's order.
pub fn list_devices() -> Result<Vec<DeviceInfo>> {
    let entry = load_entry()?;
    let (instance, _) = create_instance(&entry, false, &[])?;
    let devices = enumerate(&instance);
    // SAFETY: the instance was made above for this listing alone; nothing was created from it (no device, surface
    // or messenger), and `devices` holds only copied-out information.
    unsafe { instance.destroy_instance(None) };
    Ok(devices?.into_iter().map(|(_, info)| info).collect())
}

/// The requested device, or the most preferred kind (discrete GPU first, CPU last).
fn choose(
    devices: Vec<(vk::PhysicalDevice, DeviceInfo)>,
    wanted: Option<&str>,
) -> Result<(vk::PhysicalDevice, DeviceInfo)> {
    let names = devices.iter().map(|(_, d)| format!("{}: {}", d.index, d.name)).collect::<Vec<_>>().join(", ");
    let usable = devices.into_iter().filter(|(_, d)| d.has_compute_queue);
    match wanted {
        Some(w) => {
            let w_lower = w.to_lowercase();
            usable
                .filter(|(_, d)| {
                    d.index.to_string() == w
                        || d.uuid_text().is_some_and(|u| u == w_lower)
                        || d.name.to_lowercase().contains(&w_lower)
                })
                .min_by_key(|(_, d)| d.index)
                .ok_or_else(|| anyhow!("no Vulkan device matches --device '{w}' (devices: {names})"))
        }
        None => usable
            .min_by_key(|(_, d)| (d.kind, d.index))
            .ok_or_else(|| anyhow!("no Vulkan device with a compute queue was found (devices: [{names}])")),
    }
}

/// A queue family of `pd` that can compute, draw (the viewer's overlay) and present to `surface`.
fn presenting_family(
    instance: &ash::Instance,
    loader: &ash::khr::surface::Instance,
    pd: vk::PhysicalDevice,
    surface: vk::SurfaceKHR,
) -> Option<u32> {
    // SAFETY: `pd` was enumerated from the caller's live `instance`; the query fills a Vec it returns.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let wanted = vk::QueueFlags::COMPUTE | vk::QueueFlags::GRAPHICS;
    (0..families.len() as u32).find(|&f| {
        // SAFETY: `pd` and `surface` belong to the live `instance` (the caller's), and `f` is an index below
        // the family count just queried.
        families[f as usize].queue_flags.contains(wanted)
            && unsafe { loader.get_physical_device_surface_support(pd, f, surface) }.unwrap_or(false)
    })
}

impl GpuContext {
    pub fn new(options: &ContextOptions) -> Result<Self> {
        Self::create(options, None)
    }

    /// A context whose device can also present to `window` (through a swapchain, see
    /// [`super::Presenter`]): the device chosen as [`Self::new`] chooses among those that can.
    /// The window must outlive the context, which holds a surface of it.
    pub fn for_window(options: &ContextOptions, window: &(impl HasDisplayHandle + HasWindowHandle)) -> Result<Self> {
        let display = window.display_handle().map_err(|e| anyhow!("the window's display handle: {e}"))?.as_raw();
        let window = window.window_handle().map_err(|e| anyhow!("the window's handle: {e}"))?.as_raw();
        Self::create(options, Some(WindowHandles { display, window }))
    }

    fn create(options: &ContextOptions, window: Option<WindowHandles>) -> Result<Self> {
        let entry = load_entry()?;
        let window_extensions = match window {
            Some(w) => ash_window::enumerate_required_extensions(w.display)
                .context("the Vulkan extensions this kind of window needs")?
                .to_vec(),
            None => vec![],
        };
        let (instance, validating) = create_instance(&entry, options.validation, &window_extensions)?;
        let surface = match window {
            // SAFETY: the raw handles come from a live window that, as for_window's contract says, outlives this
            // context, whose surface is destroyed before the instance (Drop); `instance` was created with the
            // extensions ash_window asked for.
            Some(w) => match unsafe { ash_window::create_surface(&entry, &instance, w.display, w.window, None) } {
                Ok(surface) => Some((ash::khr::surface::Instance::new(&entry, &instance), surface)),
                Err(e) => {
                    // SAFETY: the instance was created above and nothing has been created from it yet (the surface
                    // failed), so it can be destroyed before returning the error.
                    unsafe { instance.destroy_instance(None) };
                    bail!("creating a Vulkan surface for the window: {e}");
                }
            },
            None => None,
        };
        let validation_log = Box::<ValidationLog>::default();
        let debug = if validating {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let messenger =
                // SAFETY: the create-info points at `validation_log`, a Box whose heap place never moves and
                // which the context owns until Drop destroys the messenger, before the log; the instance was
                // created with VK_EXT_debug_utils enabled.
                unsafe { loader.create_debug_utils_messenger(&validation::messenger_info(&validation_log), None) }
                    .context("creating the validation messenger")?;
            Some((loader, messenger))
        } else {
            None
        };
        let mut devices = enumerate(&instance)?;
        if let Some((loader, surface)) = &surface {
            let all = devices.iter().map(|(_, d)| d.name.clone()).collect::<Vec<_>>().join(", ");
            devices.retain(|(pd, _)| presenting_family(&instance, loader, *pd, *surface).is_some());
            if devices.is_empty() {
                bail!("no Vulkan device can present to the window (devices: [{all}])");
            }
        }
        let (physical, mut info) = choose(devices, options.device.as_deref())?;
        log::debug!("caustica: device {} ({}, {})", info.name, info.kind.label(), info.driver_name);
        if let Some(limit) = options.storage_binding_limit {
            info.max_storage_buffer_range = info.max_storage_buffer_range.min(limit);
            info.texel_binding_limit = limit;
        }
        // SAFETY: `physical` was enumerated from the live `instance`; the queries fill structures they return.
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let family = match &surface {
            Some((loader, surface)) => presenting_family(&instance, loader, physical, *surface)
                .expect("devices that cannot present were left out"),
            None => families
                .iter()
                .position(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE))
                .ok_or_else(|| anyhow!("{} has no compute queue", info.name))? as u32,
        };
        // SAFETY: `physical` belongs to the live `instance`; the query fills a structure it returns.
        let timestamp_period = unsafe { instance.get_physical_device_properties(physical) }.limits.timestamp_period;
        let timestamp_period_ns = (families[family as usize].timestamp_valid_bits > 0 && timestamp_period > 0.0)
            .then_some(timestamp_period as f64);
        let priorities = [1.0f32];
        let queue_info =
            [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
        let mut device_extensions = if surface.is_some() { vec![ash::khr::swapchain::NAME.as_ptr()] } else { vec![] };
        let statistics = super::pipeline_statistics::supported(&instance, physical);
        if statistics {
            device_extensions.push(ash::khr::pipeline_executable_properties::NAME.as_ptr());
        }
        let mut statistics_feature =
            vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default().pipeline_executable_info(statistics);
        // SAFETY: `physical` was enumerated from this live instance.
        let api_version = unsafe { instance.get_physical_device_properties(physical) }.api_version;
        let traversal = Traversal::resolve(
            options.traversal,
            &info,
            &traversal::missing_for_ray_query(&instance, physical, api_version),
        )?;
        let ray_query = traversal == Traversal::RayQuery;
        if ray_query {
            device_extensions.extend(traversal::RAY_QUERY_EXTENSIONS.iter().map(|name| name.as_ptr()));
        }
        let mut structures_feature =
            vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default().acceleration_structure(true);
        let mut query_feature = vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true);
        let mut address_feature = vk::PhysicalDeviceBufferDeviceAddressFeatures::default().buffer_device_address(true);
        let mut device_info =
            vk::DeviceCreateInfo::default().queue_create_infos(&queue_info).enabled_extension_names(&device_extensions);
        if statistics {
            device_info = device_info.push_next(&mut statistics_feature);
        }
        if ray_query {
            device_info = device_info
                .push_next(&mut structures_feature)
                .push_next(&mut query_feature)
                .push_next(&mut address_feature);
        }
        // SAFETY: `device_info` borrows `queue_info`, `priorities`, `device_extensions`, `statistics_feature` and the ray-query
        // feature structs,
        // locals alive until the call returns; `family` is a queue family of `physical` that computes (and
        // presents, for a window); the extensions are supported (swapchain for a surface, statistics by supported()).
        let device = unsafe { instance.create_device(physical, &device_info, None) }
            .with_context(|| format!("creating a logical device on {}", info.name))?;
        // SAFETY: the device was just created with one queue of `family`.
        let queue = unsafe { device.get_device_queue(family, 0) };
        // SAFETY: a create-info without borrowed arrays for a queue family the device was created with; the pool is
        // destroyed in Drop, before the device.
        let command_pool = unsafe {
            device.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )
        }?;
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: ray_query,
            allocation_sizes: Default::default(),
        })
        .context("creating the GPU memory allocator")?;
        let pipeline_statistics =
            statistics.then(|| ash::khr::pipeline_executable_properties::Device::new(&instance, &device));
        let acceleration_structures = ray_query.then(|| {
            let mut properties = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
            let mut all = vk::PhysicalDeviceProperties2::default().push_next(&mut properties);
            // SAFETY: `all` borrows `properties`, a local alive until the call returns; `physical`
            // was enumerated from this live instance.
            unsafe { instance.get_physical_device_properties2(physical, &mut all) };
            let scratch_alignment = u64::from(properties.min_acceleration_structure_scratch_offset_alignment).max(1);
            (ash::khr::acceleration_structure::Device::new(&instance, &device), scratch_alignment)
        });
        let presentation = surface.map(|(surface_loader, surface)| Presentation {
            surface_loader,
            surface,
            swapchain_loader: ash::khr::swapchain::Device::new(&instance, &device),
        });
        Ok(Self {
            _entry: entry,
            instance,
            physical_device: physical,
            presentation,
            debug,
            validation_log,
            device,
            queue,
            command_pool,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            info,
            timestamp_period_ns,
            loop_limit: OnceLock::new(),
            pipeline_statistics,
            traversal,
            acceleration_structures,
        })
    }

    /// Waits until the device has finished everything submitted (before freeing what it uses).
    pub fn wait_idle(&self) {
        // SAFETY: the device is alive as long as `self`; waiting for idle needs no other handles.
        let _ = unsafe { self.device.device_wait_idle() };
    }

    /// Validation messages recorded since the last call (empty when validation is off).
    fn take_validation_messages(&self) -> Vec<String> {
        self.validation_log.take()
    }

    pub fn validating(&self) -> bool {
        self.debug.is_some()
    }

    /// Fails when the validation layer reported anything: the results can no longer be trusted.
    pub fn check_validation(&self) -> Result<()> {
        let messages = self.take_validation_messages();
        if messages.is_empty() {
            return Ok(());
        }
        bail!("the Vulkan validation layer reported {} message(s); first: {}", messages.len(), messages[0])
    }

    pub(super) fn allocator(&self) -> std::sync::MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Records commands into a one-off command buffer, submits it and waits for it to finish.
    pub(super) fn submit_and_wait(&self, record: impl FnOnce(&ash::Device, vk::CommandBuffer)) -> Result<()> {
        let device = &self.device;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool is the context's, created with RESET_COMMAND_BUFFER for this queue family, and the
        // context is used from one thread (nothing in caustica shares a context across threads), which is the
        // external synchronisation the pool and the queue need.
        let cb = unsafe { device.allocate_command_buffers(&alloc) }?[0];
        // SAFETY: a create-info without borrowed arrays on the live device; the fence is destroyed below.
        let fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }?;
        let result = (|| -> Result<()> {
            // SAFETY: `cb` was just allocated and is recorded once (ONE_TIME_SUBMIT); `record` gets the device and
            // the recording buffer only; `cbs` and `submit` are locals alive until the submission call returns, and
            // the wait for `fence` means the commands have finished before the buffer is freed below.
            unsafe {
                device.begin_command_buffer(
                    cb,
                    &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                )?;
                record(device, cb);
                device.end_command_buffer(cb)?;
                let cbs = [cb];
                let submit = [vk::SubmitInfo::default().command_buffers(&cbs)];
                device.queue_submit(self.queue, &submit, fence).map_err(VulkanError)?;
                device.wait_for_fences(&[fence], true, u64::MAX).map_err(VulkanError)?;
            }
            Ok(())
        })();
        // SAFETY: the fence was waited for, or the submission never happened (an error before it), so neither the
        // fence nor the command buffer is in use; a failed wait means a lost device, whose objects may be destroyed.
        unsafe {
            device.destroy_fence(fence, None);
            device.free_command_buffers(self.command_pool, &[cb]);
        }
        result
    }
}

impl Drop for GpuContext {
    fn drop(&mut self) {
        // SAFETY: the device is waited idle first, so nothing in flight uses what is destroyed; the order is
        // children before parents: the allocator's memory and the command pool before the device, the surface and
        // the validation messenger before the instance. `self` is being dropped, so each handle is destroyed once.
        unsafe {
            let _ = self.device.device_wait_idle();
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_command_pool(self.command_pool, None);
            self.device.destroy_device(None);
            if let Some(p) = self.presentation.take() {
                p.surface_loader.destroy_surface(p.surface, None);
            }
            if let Some((loader, messenger)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}
