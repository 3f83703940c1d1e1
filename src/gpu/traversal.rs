//! How the kernel finds what a ray hits: its own compute walk of caustica's BVH (shaders/bvh.glsl),
//! or the device's ray queries over Vulkan acceleration structures (VK_KHR_acceleration_structure
//! and VK_KHR_ray_query, shaders/ray_query.glsl). The choice is made once, when the device is
//! opened, since the ray queries need extensions and features enabled on the logical device.

use super::device_info::{DeviceInfo, DeviceType};
use anyhow::{bail, Result};
use ash::vk;
use std::ffi::CStr;

/// What the user asked for (`--traversal`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TraversalRequest {
    /// Ray queries on a GPU that has them, the compute walk elsewhere ([`Traversal::auto_for`]).
    #[default]
    Auto,
    Compute,
    RayQuery,
}

impl TraversalRequest {
    /// The names `--traversal` takes.
    pub const NAMES: [&'static str; 3] = ["auto", "compute", "ray-query"];

    pub fn parse(name: &str) -> Result<Self> {
        Ok(match name {
            "auto" => Self::Auto,
            "compute" => Self::Compute,
            "ray-query" => Self::RayQuery,
            other => bail!("unknown traversal '{other}': expected auto, compute or ray-query"),
        })
    }
}

/// The traversal a device runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Traversal {
    /// caustica's own walk of its wide BVH, in the kernel.
    #[default]
    Compute,
    /// rayQueryEXT over one bottom-level structure a mesh and a top-level one over the placements.
    RayQuery,
}

impl Traversal {
    /// Its name, as `--traversal` and `bench --json` spell it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Compute => "compute",
            Self::RayQuery => "ray-query",
        }
    }

    /// What `auto` picks on a device, given whether it has the ray-query extensions.
    ///
    /// A GPU that exposes them has ray-tracing hardware (NVIDIA exposes them on its RTX products
    /// alone; AMD from RDNA2, Intel from Arc): ray queries there. Their speed on such a GPU is not
    /// measured (none was available; docs/benchmarks.md). On a CPU device (lavapipe) the faster
    /// traversal measured there: the compute walk, whose samples per CPU second on the six mesh
    /// scenes of `bench --suite` were 1.33-3.21x lavapipe's ray queries' (Mesa 25.0.7, 2-core AMD
    /// EPYC Zen 4; docs/benchmarks.md, 2026-12-07).
    pub fn auto_for(info: &DeviceInfo, has_ray_query: bool) -> Self {
        if has_ray_query && info.kind != DeviceType::Cpu {
            Self::RayQuery
        } else {
            Self::Compute
        }
    }

    /// What `request` resolves to on a device that lacks `missing` of what ray queries need
    /// (nothing: it has them); a request for ray queries on a device without them is an error
    /// naming the device and what it lacks.
    pub fn resolve(request: TraversalRequest, info: &DeviceInfo, missing: &[String]) -> Result<Self> {
        let has_ray_query = missing.is_empty();
        match request {
            TraversalRequest::Auto => Ok(Self::auto_for(info, has_ray_query)),
            TraversalRequest::Compute => Ok(Self::Compute),
            TraversalRequest::RayQuery if has_ray_query => Ok(Self::RayQuery),
            TraversalRequest::RayQuery => bail!(
                "--traversal ray-query: {} ({}) does not support ray queries: it lacks {}; use --traversal compute or auto",
                info.name,
                if info.driver_info.is_empty() { format!("Vulkan {}", info.api_version) } else { info.driver_info.clone() },
                missing.join(", ")
            ),
        }
    }
}

/// The device extensions ray queries need beyond Vulkan 1.2 (which has buffer device addresses,
/// descriptor indexing and SPIR-V 1.4 in its core): the acceleration structures, their deferred
/// host operations (a dependency of the first), and the queries.
pub(super) const RAY_QUERY_EXTENSIONS: [&CStr; 3] =
    [ash::khr::acceleration_structure::NAME, ash::khr::ray_query::NAME, ash::khr::deferred_host_operations::NAME];

/// What `pd` lacks of what ray queries need (empty: it can run them): Vulkan 1.2, the
/// extensions, and the accelerationStructure, rayQuery and bufferDeviceAddress features.
pub(super) fn missing_for_ray_query(instance: &ash::Instance, pd: vk::PhysicalDevice, api_version: u32) -> Vec<String> {
    if api_version < vk::API_VERSION_1_2 {
        return vec!["Vulkan 1.2".into()];
    }
    // SAFETY: `pd` was enumerated from this live instance.
    let available = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    let has = |name: &CStr| available.iter().any(|e| e.extension_name_as_c_str().ok() == Some(name));
    let missing: Vec<String> =
        RAY_QUERY_EXTENSIONS.iter().filter(|name| !has(name)).map(|name| name.to_string_lossy().into_owned()).collect();
    if !missing.is_empty() {
        return missing;
    }
    let mut structures = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
    let mut queries = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
    let mut addresses = vk::PhysicalDeviceBufferDeviceAddressFeatures::default();
    let mut features = vk::PhysicalDeviceFeatures2::default()
        .push_next(&mut structures)
        .push_next(&mut queries)
        .push_next(&mut addresses);
    // SAFETY: `features` borrows the three feature structs, locals alive until the call returns;
    // `pd` was enumerated from this live instance.
    unsafe { instance.get_physical_device_features2(pd, &mut features) };
    [
        (structures.acceleration_structure, "the accelerationStructure feature"),
        (queries.ray_query, "the rayQuery feature"),
        (addresses.buffer_device_address, "the bufferDeviceAddress feature"),
    ]
    .into_iter()
    .filter(|&(on, _)| on != vk::TRUE)
    .map(|(_, what)| what.to_owned())
    .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_parses_and_others_are_refused() {
        for name in TraversalRequest::NAMES {
            TraversalRequest::parse(name).expect("a listed name");
        }
        let refused = TraversalRequest::parse("rtx").unwrap_err().to_string();
        assert!(refused.contains("'rtx'") && refused.contains("ray-query"), "{refused}");
        assert_eq!(Traversal::RayQuery.name(), "ray-query");
    }
}
