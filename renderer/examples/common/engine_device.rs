//! The engine's own device, shared by the engine examples (integrator.rs, engine.rs): its
//! instance (validation and synchronization validation on request, with its own message log),
//! a device with what relume documents it needs (`Context::from_existing`), its queue and its
//! submissions. relume borrows the device and never destroys it.

use ash::vk;
use relume_renderer::vk::Context;
use std::error::Error;
use std::ffi::c_void;
use std::sync::{Arc, Mutex};

/// The engine's own Vulkan objects.
pub struct Engine {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    pub messages: Box<Mutex<Vec<String>>>,
    pub physical: vk::PhysicalDevice,
    pub name: String,
    pub device: ash::Device,
    pub family: u32,
    pub queue: vk::Queue,
}

impl Engine {
    /// The engine's instance (with validation and synchronization validation when asked) and a
    /// device with what relume documents it needs.
    pub fn new(validation: bool) -> Result<Engine, Box<dyn Error>> {
        let messages = Box::new(Mutex::new(Vec::new()));
        // SAFETY: the engine loads Vulkan and creates an instance and a device from valid
        // create infos whose pointers outlive each call; `destroy` undoes it in reverse.
        unsafe {
            let entry = ash::Entry::load()?;
            let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
            let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
            let extensions = [ash::ext::debug_utils::NAME.as_ptr()];
            let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
            let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
            let mut info = vk::InstanceCreateInfo::default().application_info(&app);
            if validation {
                info = info.enabled_layer_names(&layers).enabled_extension_names(&extensions).push_next(&mut features);
            }
            let instance = entry.create_instance(&info, None)?;
            let debug = match validation {
                true => {
                    let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
                    let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
                        .message_type(vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL)
                        .pfn_user_callback(Some(collect_message))
                        .user_data(&*messages as *const Mutex<Vec<String>> as *mut c_void);
                    let messenger = loader.create_debug_utils_messenger(&info, None)?;
                    Some((loader, messenger))
                }
                false => None,
            };
            let physical = instance.enumerate_physical_devices()?[0];
            let props = instance.get_physical_device_properties(physical);
            let name = props.device_name_as_c_str()?.to_string_lossy().into_owned();
            let family = instance
                .get_physical_device_queue_family_properties(physical)
                .iter()
                .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
                .ok_or("no graphics and compute queue")? as u32;
            let priorities = [1.0];
            let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
            // What relume documents it needs (Context::from_existing).
            let base = vk::PhysicalDeviceFeatures::default().shader_storage_image_extended_formats(true);
            let mut v13 = vk::PhysicalDeviceVulkan13Features::default().dynamic_rendering(true).synchronization2(true);
            let info = vk::DeviceCreateInfo::default().queue_create_infos(&queues).enabled_features(&base).push_next(&mut v13);
            let device = instance.create_device(physical, &info, None)?;
            let queue = device.get_device_queue(family, 0);
            Ok(Engine { entry, instance, debug, messages, physical, name, device, family, queue })
        }
    }

    /// relume's context on the engine's device: relume borrows it and never destroys it.
    pub fn context(&self) -> Result<Arc<Context>, Box<dyn Error>> {
        Ok(Context::from_existing(self.entry.clone(), self.instance.clone(), self.physical, self.device.clone(), self.family, self.queue)?)
    }

    /// The validation layer's warnings and errors so far (empty without it).
    pub fn validation_messages(&self) -> Vec<String> {
        self.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }

    /// Ends `cmd`, submits it and waits for `fence`: the engine's own submission.
    pub fn end_submit_and_wait(&self, cmd: vk::CommandBuffer, fence: vk::Fence) -> Result<(), Box<dyn Error>> {
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        // SAFETY: `cmd` is recording and `fence` unsignalled; the engine submits from one
        // thread, and relume submits on this queue only at creation, never during a frame.
        unsafe {
            self.device.end_command_buffer(cmd)?;
            self.device.queue_submit2(self.queue, &[vk::SubmitInfo2::default().command_buffer_infos(&cmds)], fence)?;
            self.device.wait_for_fences(&[fence], true, u64::MAX)?;
        }
        Ok(())
    }

    /// The engine's teardown, after relume is gone (relume never destroys what it was lent).
    pub fn destroy(self) {
        // SAFETY: nothing made from the device or instance is alive any more.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_device(None);
            if let Some((loader, messenger)) = &self.debug {
                loader.destroy_debug_utils_messenger(*messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

unsafe extern "system" fn collect_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes valid callback data; user_data is the engine's boxed log,
    // alive until the messenger is destroyed.
    let (message, log) = unsafe {
        let text = (*data).message_as_c_str().map(|m| m.to_string_lossy().into_owned());
        (text.unwrap_or_default(), &*(user_data as *const Mutex<Vec<String>>))
    };
    if let Ok(mut messages) = log.lock() {
        messages.push(format!("[{severity:?}] {message}"));
    }
    vk::FALSE
}
