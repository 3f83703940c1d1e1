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

/// The layer's callback: records the message in the [`ValidationLog`] that `user` points at.
///
/// # Safety
/// Called by the validation layer only, as registered by [`messenger_info`]: `data` is null or
/// points to the layer's message for the duration of the call, and `user` is null or the
/// `ValidationLog` given there, which the context keeps alive (boxed) until the messenger is gone.
unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if data.is_null() || user.is_null() {
        return vk::FALSE;
    }
    // SAFETY: `data` is not null (checked above) and the layer keeps it and its message valid
    // during the call; message_as_c_str reads up to the message's terminating NUL.
    let text = unsafe { (*data).message_as_c_str() }.map(|m| m.to_string_lossy().into_owned()).unwrap_or_default();
    // SAFETY: `user` is not null (checked above), and the only user data registered with this
    // callback is the context's boxed ValidationLog, alive until after the messenger is destroyed;
    // only a shared reference is made, and the log's Mutex orders concurrent calls.
    let log = unsafe { &*(user as *const ValidationLog) };
    let line = format!("[{severity:?}] {text}");
    log::warn!("vulkan validation: {line}");
    log.messages.lock().unwrap_or_else(|e| e.into_inner()).push(line);
    vk::FALSE
}
