//! The viewer's own Vulkan instance, surface and device, as an engine makes them: the
//! window system's surface extensions, the swapchain extension, and what relume documents it
//! needs (`Context::from_existing`). relume is handed the device and never owns it; the viewer
//! destroys it after relume is gone. With validation, the Khronos layer and synchronization
//! validation report into a log the viewer counts.

use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;
use relume_renderer::vk::Context;
use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::Window;

/// Warnings and errors the validation layer reported.
pub type Messages = Arc<Mutex<Vec<String>>>;

/// The instance and the window's surface (and the validation messenger), destroyed on drop
/// after the device.
pub struct Base {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub surface_loader: ash::khr::surface::Instance,
    pub surface: vk::SurfaceKHR,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Kept alive while the messenger may write into it.
    messages: Messages,
}

pub struct Device {
    pub device: ash::Device,
    pub physical: vk::PhysicalDevice,
    pub family: u32,
    pub queue: vk::Queue,
    pub name: String,
    /// Declared last: dropped after the device.
    pub base: Base,
}

impl Device {
    /// Instance, surface for `window`, and a device on `selector` (an index or part of a
    /// name; None: the first device that can present to the surface, a GPU before lavapipe).
    pub fn new(window: &Window, validation: bool, selector: Option<&str>) -> Result<Device> {
        let base = Base::new(window, validation)?;
        let (physical, family, name) = base.pick(selector)?;
        let priorities = [1.0];
        let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
        let extensions = [ash::khr::swapchain::NAME.as_ptr()];
        // What relume documents it needs (Context::from_existing checks the device offers it).
        let features = vk::PhysicalDeviceFeatures::default().shader_storage_image_extended_formats(true);
        let mut v13 = vk::PhysicalDeviceVulkan13Features::default().dynamic_rendering(true).synchronization2(true);
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&extensions)
            .enabled_features(&features)
            .push_next(&mut v13);
        // SAFETY: the create info refers to locals alive for the call.
        let device = unsafe { base.instance.create_device(physical, &info, None) }.with_context(|| format!("Vulkan device on {name}"))?;
        // SAFETY: the family and index were requested above.
        let queue = unsafe { device.get_device_queue(family, 0) };
        Ok(Device { device, physical, family, queue, name, base })
    }

    /// relume's context on this device: the library inside the viewer.
    pub fn relume_context(&self) -> Result<Arc<Context>> {
        let base = &self.base;
        let ctx =
            Context::from_existing(base.entry.clone(), base.instance.clone(), self.physical, self.device.clone(), self.family, self.queue)?;
        Ok(ctx)
    }

    /// The validation log; it outlives the device, so teardown messages can be read after.
    pub fn message_log(&self) -> Messages {
        Arc::clone(&self.base.messages)
    }

    /// Waits for the queue to finish: at teardown and on a swapchain rebuild only.
    pub fn wait_queue_idle(&self) -> Result<()> {
        // SAFETY: the viewer is the queue's only user on this thread.
        unsafe { self.device.queue_wait_idle(self.queue) }?;
        Ok(())
    }
}

impl Drop for Device {
    /// After everything made on the device (relume's context included) is gone.
    fn drop(&mut self) {
        // SAFETY: nothing made on the device is alive.
        unsafe { self.device.destroy_device(None) };
    }
}

impl Base {
    fn new(window: &Window, validation: bool) -> Result<Base> {
        // SAFETY: loading the system Vulkan loader.
        let entry = unsafe { ash::Entry::load() }.context("Vulkan loader (libvulkan.so.1); install libvulkan1")?;
        let display = window.display_handle().map_err(|e| anyhow!("window display handle: {e}"))?.as_raw();
        let mut extensions = ash_window::enumerate_required_extensions(display)?.to_vec();
        if validation {
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
        let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
        let app = vk::ApplicationInfo::default().application_name(c"relume view").api_version(vk::API_VERSION_1_3);
        let mut info = vk::InstanceCreateInfo::default().application_info(&app).enabled_extension_names(&extensions);
        if validation {
            info = info.enabled_layer_names(&layers).push_next(&mut features);
        }
        // SAFETY: every pointer in `info` refers to locals alive for the call.
        let instance =
            unsafe { entry.create_instance(&info, None) }.context("Vulkan instance (with validation: install vulkan-validationlayers)")?;
        let surface_loader = ash::khr::surface::Instance::new(&entry, &instance);
        let messages: Messages = Arc::new(Mutex::new(Vec::new()));
        let mut base = Base { entry, instance, surface_loader, surface: vk::SurfaceKHR::null(), debug: None, messages };
        if validation {
            base.debug = Some(messenger(&base.entry, &base.instance, &base.messages)?);
        }
        let handle = window.window_handle().map_err(|e| anyhow!("window handle: {e}"))?.as_raw();
        // SAFETY: the window outlives the surface (the viewer drops the device first).
        base.surface = unsafe { ash_window::create_surface(&base.entry, &base.instance, display, handle, None) }?;
        Ok(base)
    }

    /// The device to use and its presenting queue family: the first that `selector` (an index
    /// or part of a name) names and that can present here, a GPU before lavapipe.
    fn pick(&self, selector: Option<&str>) -> Result<(vk::PhysicalDevice, u32, String)> {
        // SAFETY: plain queries of a live instance.
        let physicals = unsafe { self.instance.enumerate_physical_devices() }?;
        let mut candidates = Vec::new();
        for (index, &pd) in physicals.iter().enumerate() {
            // SAFETY: as above.
            let props = unsafe { self.instance.get_physical_device_properties(pd) };
            let name = props.device_name_as_c_str().map(|c| c.to_string_lossy().into_owned()).unwrap_or_default();
            let wanted = selector.is_none_or(|s| s.parse::<usize>().ok() == Some(index) || name.to_lowercase().contains(&s.to_lowercase()));
            if let (true, Some(family)) = (wanted, self.presenting_family(pd)) {
                let rank = (props.device_type == vk::PhysicalDeviceType::CPU) as u32;
                candidates.push((rank, pd, family, name));
            }
        }
        candidates.sort_by_key(|c| c.0);
        match candidates.into_iter().next() {
            Some((_, pd, family, name)) => Ok((pd, family, name)),
            None => {
                bail!("no Vulkan device {}can present to this window", selector.map_or(String::new(), |s| format!("matching \"{s}\" ")))
            }
        }
    }

    /// A queue family with graphics, compute and presentation to the surface.
    fn presenting_family(&self, pd: vk::PhysicalDevice) -> Option<u32> {
        // SAFETY: plain queries.
        let families = unsafe { self.instance.get_physical_device_queue_family_properties(pd) };
        families.iter().enumerate().find_map(|(i, f)| {
            let i = i as u32;
            // SAFETY: a plain query of a live surface.
            let presents = unsafe { self.surface_loader.get_physical_device_surface_support(pd, i, self.surface) }.unwrap_or(false);
            (f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE) && presents).then_some(i)
        })
    }
}

impl Drop for Base {
    fn drop(&mut self) {
        // SAFETY: reverse order of creation; the device is gone.
        unsafe {
            if self.surface != vk::SurfaceKHR::null() {
                self.surface_loader.destroy_surface(self.surface, None);
            }
            if let Some((loader, messenger)) = &self.debug {
                loader.destroy_debug_utils_messenger(*messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

fn messenger(
    entry: &ash::Entry,
    instance: &ash::Instance,
    messages: &Messages,
) -> Result<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)> {
    use vk::DebugUtilsMessageSeverityFlagsEXT as Severity;
    use vk::DebugUtilsMessageTypeFlagsEXT as Kind;
    let loader = ash::ext::debug_utils::Instance::new(entry, instance);
    let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(Severity::WARNING | Severity::ERROR)
        .message_type(Kind::GENERAL | Kind::VALIDATION | Kind::PERFORMANCE)
        .pfn_user_callback(Some(log_message))
        .user_data(Arc::as_ptr(messages) as *mut c_void);
    // SAFETY: the user data points into `messages`, which the Device keeps until after the
    // messenger is destroyed.
    let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }?;
    Ok((loader, messenger))
}

unsafe extern "system" fn log_message(
    _severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes valid callback data; user_data is the log set above.
    let (text, log) = unsafe {
        let text: Option<&CStr> = (*data).message_as_c_str();
        (text.map(|t| t.to_string_lossy().into_owned()).unwrap_or_default(), &*(user_data as *const Mutex<Vec<String>>))
    };
    if let Ok(mut log) = log.lock() {
        log.push(text);
    }
    vk::FALSE
}
