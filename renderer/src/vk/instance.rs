//! Instance creation with optional validation (including synchronization validation), and the
//! debug messenger that collects every warning and error so tests can fail on them.

use super::{VkError, VkResult};
use ash::vk;
use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

pub(super) struct InstanceParts {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
}

/// Messages of severity warning or error reported by the validation layers.
pub(super) type MessageLog = Arc<Mutex<Vec<String>>>;

pub(super) fn create(validation: bool, log: &MessageLog) -> VkResult<InstanceParts> {
    // SAFETY: loading the system Vulkan loader; its entry points are trusted from here on.
    let entry = unsafe { ash::Entry::load() }.map_err(|e| VkError::Loader(e.to_string()))?;
    if validation && !has_validation_layer(&entry)? {
        return Err(VkError::Invalid(
            "validation was requested but VK_LAYER_KHRONOS_validation is not installed; \
             install vulkan-validationlayers"
                .into(),
        ));
    }
    let app = vk::ApplicationInfo::default().application_name(c"relume").api_version(vk::API_VERSION_1_3);
    let layers = if validation { vec![VALIDATION_LAYER.as_ptr()] } else { vec![] };
    let extensions = if validation { vec![ash::ext::debug_utils::NAME.as_ptr()] } else { vec![] };
    let enabled_features = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled_features);
    let mut info =
        vk::InstanceCreateInfo::default().application_info(&app).enabled_layer_names(&layers).enabled_extension_names(&extensions);
    if validation {
        info = info.push_next(&mut features);
    }
    // SAFETY: every pointer in `info` refers to locals that outlive the call.
    let instance = unsafe { entry.create_instance(&info, None) }?;
    let debug = if validation {
        match create_messenger(&entry, &instance, log) {
            Ok(debug) => Some(debug),
            Err(e) => {
                // SAFETY: the instance was created above and nothing uses it yet.
                unsafe { instance.destroy_instance(None) };
                return Err(e);
            }
        }
    } else {
        None
    };
    Ok(InstanceParts { entry, instance, debug })
}

fn has_validation_layer(entry: &ash::Entry) -> VkResult<bool> {
    // SAFETY: a plain query of the loader.
    let layers = unsafe { entry.enumerate_instance_layer_properties() }?;
    Ok(layers.iter().any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER)))
}

fn create_messenger(
    entry: &ash::Entry,
    instance: &ash::Instance,
    log: &MessageLog,
) -> VkResult<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)> {
    let loader = ash::ext::debug_utils::Instance::new(entry, instance);
    let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(on_message))
        .user_data(Arc::as_ptr(log) as *mut c_void);
    // SAFETY: the callback's user data points into `log`, which the Context keeps alive
    // until after the messenger is destroyed.
    let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }?;
    Ok((loader, messenger))
}

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes valid callback data; user_data is the Mutex set above.
    let (message, log) = unsafe {
        let text = (*data).message_as_c_str().map(|m| m.to_string_lossy().into_owned());
        (text.unwrap_or_default(), &*(user_data as *const Mutex<Vec<String>>))
    };
    // Logged, not printed: the library never writes to stderr; callers report the messages.
    if let Ok(mut messages) = log.lock() {
        messages.push(format!("[{severity:?}] {message}"));
    }
    vk::FALSE
}
