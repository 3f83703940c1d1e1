//! What the driver says of a compiled kernel (`VK_KHR_pipeline_executable_properties`): on a GPU,
//! its registers per invocation, spills and shared memory, which decide how many invocations a
//! multiprocessor keeps in flight; on lavapipe, what gallivm reports. `caustica bench` prints them,
//! so a device session that cannot run a profiler still learns why one kernel outruns another.

use ash::vk;

/// Whether `pd` offers the extension and its `pipelineExecutableInfo` feature.
pub(super) fn supported(instance: &ash::Instance, pd: vk::PhysicalDevice) -> bool {
    // SAFETY: `pd` was enumerated from the caller's live `instance`; the query fills a Vec it returns.
    let extensions = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    let named = extensions
        .iter()
        .any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == ash::khr::pipeline_executable_properties::NAME));
    if !named {
        return false;
    }
    let mut feature = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default();
    let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut feature);
    // SAFETY: `pd` belongs to the live `instance`, which is created for Vulkan 1.2 (where PhysicalDeviceFeatures2
    // is core), and the device offers the extension whose feature structure is chained; `feature` is a local that
    // outlives the call.
    unsafe { instance.get_physical_device_features2(pd, &mut features) };
    feature.pipeline_executable_info == vk::TRUE
}

/// One figure the driver gives of a kernel, e.g. ("Register Count", "128").
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct KernelStatistic {
    pub name: String,
    pub value: String,
}

/// The statistics of every executable of `pipeline` (a compute pipeline has one; where a driver
/// gives several, each name is prefixed by its executable's). Empty where the driver gives none.
pub(super) fn read(
    loader: &ash::khr::pipeline_executable_properties::Device,
    pipeline: vk::Pipeline,
) -> Vec<KernelStatistic> {
    let info = vk::PipelineInfoKHR::default().pipeline(pipeline);
    // SAFETY: the loader exists only where the device was created with the extension and its pipelineExecutableInfo
    // feature (GpuContext::create), and `pipeline` is a live pipeline created with CAPTURE_STATISTICS_KHR
    // (ComputeKernel::new sets it whenever the loader exists).
    let Ok(executables) = (unsafe { loader.get_pipeline_executable_properties(&info) }) else {
        return Vec::new();
    };
    let several = executables.len() > 1;
    let mut statistics = Vec::new();
    for (index, executable) in executables.iter().enumerate() {
        let info = vk::PipelineExecutableInfoKHR::default().pipeline(pipeline).executable_index(index as u32);
        // SAFETY: as above; `index` is below the executable count the driver just gave.
        let Ok(figures) = (unsafe { loader.get_pipeline_executable_statistics(&info) }) else {
            continue;
        };
        let prefix = if several { format!("{}: ", text(executable.name_as_c_str())) } else { String::new() };
        statistics.extend(figures.iter().map(|figure| KernelStatistic {
            name: format!("{prefix}{}", text(figure.name_as_c_str())),
            value: value_text(figure),
        }));
    }
    statistics
}

fn text(c: Result<&std::ffi::CStr, std::ffi::FromBytesUntilNulError>) -> String {
    c.map(|c| c.to_string_lossy().into_owned()).unwrap_or_default()
}

/// The figure as the driver typed it.
fn value_text(figure: &vk::PipelineExecutableStatisticKHR) -> String {
    // SAFETY: `format` says which member of the union the driver wrote.
    unsafe {
        match figure.format {
            vk::PipelineExecutableStatisticFormatKHR::BOOL32 => (figure.value.b32 == vk::TRUE).to_string(),
            vk::PipelineExecutableStatisticFormatKHR::INT64 => figure.value.i64.to_string(),
            vk::PipelineExecutableStatisticFormatKHR::UINT64 => figure.value.u64.to_string(),
            vk::PipelineExecutableStatisticFormatKHR::FLOAT64 => figure.value.f64.to_string(),
            _ => "?".to_owned(),
        }
    }
}
