//! Khronos validation layer hook-up: every warning or error it reports is recorded, so callers (and
//! the test suite) can fail on them. After a validation error lavapipe may corrupt its heap, so these
//! messages are never just logged.

use ash::vk;
use std::ffi::{c_void, CStr};
use std::sync::Mutex;

pub const LAYER_NAME: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Messages reported by the layer, shared with the callback through its user-data pointer.
#[derive(Default)]
pub struct ValidationLog {
    messages: Mutex<Vec<String>>,
}

impl ValidationLog {
    pub fn take(&self) -> Vec<String> {
        std::mem::take(&mut *self.messages.lock().unwrap_or_else(|e| e.into_inner()))
    }
}

pub fn messenger_info(log: &ValidationLog) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(on_message))
        .user_data(log as *const ValidationLog as *mut c_void)
}

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if data.is_null() || user.is_null() {
        return vk::FALSE;
    }
    let text = unsafe { (*data).message_as_c_str() }.map(|m| m.to_string_lossy().into_owned()).unwrap_or_default();
    let log = unsafe { &*(user as *const ValidationLog) };
    let line = format!("[{severity:?}] {text}");
    log::warn!("vulkan validation: {line}");
    log.messages.lock().unwrap_or_else(|e| e.into_inner()).push(line);
    vk::FALSE
}
