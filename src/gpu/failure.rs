//! Vulkan failures kept typed, so that callers can tell a device that can go on no longer (lost, or
//! out of memory) from other errors, and save what was rendered before exiting.

use ash::vk;

/// A failed Vulkan call, described for people; the result code stays available to [`DeviceFailure`].
#[derive(Debug, thiserror::Error)]
#[error("{}", describe(*.0))]
pub struct VulkanError(pub(super) vk::Result);

fn describe(e: vk::Result) -> String {
    match e {
        vk::Result::ERROR_DEVICE_LOST => {
            "the GPU was lost (VK_ERROR_DEVICE_LOST): the driver reset it, or a dispatch ran too long".into()
        }
        vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => "the GPU ran out of memory (VK_ERROR_OUT_OF_DEVICE_MEMORY)".into(),
        vk::Result::ERROR_OUT_OF_HOST_MEMORY => "out of host memory (VK_ERROR_OUT_OF_HOST_MEMORY)".into(),
        other => format!("Vulkan error {other}"),
    }
}

/// Why the device cannot be used any more.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceFailure {
    /// VK_ERROR_DEVICE_LOST.
    Lost,
    /// VK_ERROR_OUT_OF_DEVICE_MEMORY or VK_ERROR_OUT_OF_HOST_MEMORY.
    OutOfMemory,
}

impl DeviceFailure {
    /// The failure behind `error`, when one of its causes is a lost device or exhausted memory.
    pub fn of(error: &anyhow::Error) -> Option<Self> {
        error.chain().find_map(|cause| {
            // Calls outside submit-and-wait pass the bare `vk::Result` up with `?`.
            let code = cause
                .downcast_ref::<VulkanError>()
                .map(|v| v.0)
                .or_else(|| cause.downcast_ref::<vk::Result>().copied())?;
            match code {
                vk::Result::ERROR_DEVICE_LOST => Some(Self::Lost),
                vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
                    Some(Self::OutOfMemory)
                }
                _ => None,
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::Context as _;

    fn failed(code: vk::Result) -> anyhow::Error {
        Err::<(), _>(VulkanError(code)).context("dispatching pass 3").unwrap_err()
    }

    #[test]
    fn lost_device_and_out_of_memory_are_recognised_through_context() {
        assert_eq!(DeviceFailure::of(&failed(vk::Result::ERROR_DEVICE_LOST)), Some(DeviceFailure::Lost));
        assert_eq!(
            DeviceFailure::of(&failed(vk::Result::ERROR_OUT_OF_DEVICE_MEMORY)),
            Some(DeviceFailure::OutOfMemory)
        );
        assert_eq!(DeviceFailure::of(&failed(vk::Result::ERROR_OUT_OF_HOST_MEMORY)), Some(DeviceFailure::OutOfMemory));
        let bare = anyhow::Error::new(vk::Result::ERROR_DEVICE_LOST).context("allocating a command buffer");
        assert_eq!(DeviceFailure::of(&bare), Some(DeviceFailure::Lost));
    }

    #[test]
    fn other_errors_are_not_device_failures() {
        assert_eq!(DeviceFailure::of(&failed(vk::Result::ERROR_INITIALIZATION_FAILED)), None);
        assert_eq!(DeviceFailure::of(&anyhow::anyhow!("the GPU was lost")), None);
    }

    #[test]
    fn messages_name_the_vulkan_error() {
        assert!(format!("{:#}", failed(vk::Result::ERROR_DEVICE_LOST))
            .ends_with("(VK_ERROR_DEVICE_LOST): the driver reset it, or a dispatch ran too long"));
        assert!(failed(vk::Result::ERROR_OUT_OF_DEVICE_MEMORY)
            .root_cause()
            .to_string()
            .contains("VK_ERROR_OUT_OF_DEVICE_MEMORY"));
    }
}
