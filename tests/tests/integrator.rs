//! An engine that already has a Vulkan device hands it to relume (`Context::from_existing`):
//! the frame renders the same pixels as on relume's own device, and relume never destroys
//! the engine's device or instance (the engine does, after relume is gone).

use ash::vk;
use relume_renderer::vk::{Context, ContextOptions};
use relume_renderer::{RenderSettings, Renderer};
use relume_tests::*;

/// The engine's own device: Vulkan 1.3 with the features relume documents.
struct EngineDevice {
    entry: ash::Entry,
    instance: ash::Instance,
    physical: vk::PhysicalDevice,
    device: ash::Device,
    family: u32,
}

fn engine_device() -> EngineDevice {
    // SAFETY: the test plays an engine: it loads Vulkan, creates an instance and a device
    // with valid create infos, and destroys them itself at the end of the test.
    unsafe {
        let entry = ash::Entry::load().expect("Vulkan loader");
        let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
        let instance = entry.create_instance(&vk::InstanceCreateInfo::default().application_info(&app), None).expect("instance");
        let physical = instance.enumerate_physical_devices().expect("devices")[0];
        let family = instance
            .get_physical_device_queue_family_properties(physical)
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
            .expect("a graphics+compute queue") as u32;
        let priorities = [1.0];
        let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
        let features = vk::PhysicalDeviceFeatures::default().shader_storage_image_extended_formats(true);
        let mut v13 = vk::PhysicalDeviceVulkan13Features::default().dynamic_rendering(true).synchronization2(true);
        let info = vk::DeviceCreateInfo::default().queue_create_infos(&queues).enabled_features(&features).push_next(&mut v13);
        let device = instance.create_device(physical, &info, None).expect("device");
        EngineDevice { entry, instance, physical, device, family }
    }
}

#[test]
fn a_frame_on_the_engines_device_matches_one_on_relumes_own() {
    let scene = load_scene("occluder-plane");
    let settings = RenderSettings { width: 128, height: 128, ..RenderSettings::default() };
    let engine = engine_device();
    // relume's own context on the same physical device, so the pixels can be compared.
    // SAFETY: a plain query of the engine's live physical device.
    let props = unsafe { engine.instance.get_physical_device_properties(engine.physical) };
    let name = props.device_name_as_c_str().expect("device name").to_string_lossy().into_owned();
    let ctx = Context::headless(&ContextOptions { validation: true, device: Some(name) }).expect("context");
    let log = ctx.message_log();
    let mut renderer = Renderer::new(&ctx, &scene, &settings).expect("renderer");
    let (own, _) = renderer.render_and_read().expect("frame");
    drop(renderer);
    drop(ctx);
    assert_no_validation_messages(&log.lock().unwrap());

    // SAFETY: the queue family and index were requested at device creation.
    let queue = unsafe { engine.device.get_device_queue(engine.family, 0) };
    let ctx =
        Context::from_existing(engine.entry.clone(), engine.instance.clone(), engine.physical, engine.device.clone(), engine.family, queue)
            .expect("relume accepts the engine's device");
    let mut renderer = Renderer::new(&ctx, &scene, &settings).expect("renderer");
    let (on_engine_device, _) = renderer.render_and_read().expect("frame");
    drop(renderer);
    drop(ctx);
    assert_eq!(own, on_engine_device);

    // SAFETY: relume is gone and left the device and instance alive: the engine still
    // owns them, waits for its queue and destroys them (a double destroy would crash here).
    unsafe {
        engine.device.device_wait_idle().expect("the engine's device is still alive");
        engine.device.destroy_device(None);
        engine.instance.destroy_instance(None);
    }
}
