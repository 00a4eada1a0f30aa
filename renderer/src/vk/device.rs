//! Physical device choice (a real GPU when there is one, else lavapipe; a name or index forces
//! one), logical device creation with the features relume needs, and one queue.

use super::{VkError, VkResult};
use ash::vk;

/// What relume learned about the device it runs on.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub name: String,
    pub driver: String,
    pub device_type: String,
    /// Nanoseconds per timestamp tick; None when the queue cannot write timestamps.
    pub timestamp_period_ns: Option<f64>,
    /// Whether RG32F shadow moments can be filtered bilinearly.
    pub linear_moments: bool,
    /// The most bytes one storage-buffer binding may span (maxStorageBufferRange).
    pub max_storage_buffer_range: u64,
}

pub(super) struct DeviceParts {
    pub physical: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue_family: u32,
    pub queue: vk::Queue,
    pub info: DeviceInfo,
}

/// `selector` is a device index or a case-insensitive part of its name. Without one, the
/// best suitable device: a discrete GPU, then integrated, virtual, CPU (lavapipe).
pub(super) fn create(instance: &ash::Instance, selector: Option<&str>) -> VkResult<DeviceParts> {
    // SAFETY: plain queries of a live instance.
    let physicals = unsafe { instance.enumerate_physical_devices() }?;
    let mut listed = Vec::new();
    let mut suitable = Vec::new();
    for (index, &pd) in physicals.iter().enumerate() {
        // SAFETY: plain query of an enumerated device.
        let props = unsafe { instance.get_physical_device_properties(pd) };
        let name = props.device_name_as_c_str().map(|c| c.to_string_lossy().into_owned()).unwrap_or_default();
        let wanted =
            selector.is_none_or(|sel| sel.parse::<usize>().ok() == Some(index) || name.to_lowercase().contains(&sel.to_lowercase()));
        let verdict = graphics_compute_family(instance, pd)
            .ok_or_else(|| VkError::MissingFeature { device: name.clone(), missing: "a graphics+compute queue".into() })
            .and_then(|family| check_and_describe(instance, pd, family).map(|info| (family, info)));
        match verdict {
            Ok((family, info)) if wanted => suitable.push((type_rank(props.device_type), pd, family, info)),
            Ok(_) => listed.push(format!("{index}: {name}")),
            Err(e) => listed.push(format!("{index}: {name} (unsuitable: {e})")),
        }
    }
    suitable.sort_by_key(|candidate| candidate.0);
    let Some((_, physical, family, info)) = suitable.into_iter().next() else {
        let wanted = selector.map_or("a suitable device".into(), |s| format!("\"{s}\""));
        return Err(VkError::NoDevice(format!("{wanted} (devices: {})", listed.join(", "))));
    };
    let device = create_logical(instance, physical, family)?;
    // SAFETY: the queue family and index were requested at device creation.
    let queue = unsafe { device.get_device_queue(family, 0) };
    Ok(DeviceParts { physical, device, queue_family: family, queue, info })
}

/// Checks that a device has everything relume needs and describes it.
pub(super) fn check_and_describe(instance: &ash::Instance, pd: vk::PhysicalDevice, family: u32) -> VkResult<DeviceInfo> {
    // SAFETY: plain query.
    let props = unsafe { instance.get_physical_device_properties(pd) };
    let name = props.device_name_as_c_str().map(|c| c.to_string_lossy().into_owned()).unwrap_or_default();
    if props.api_version < vk::API_VERSION_1_3 {
        return Err(VkError::MissingFeature { device: name, missing: "Vulkan 1.3".into() });
    }
    check_features(instance, pd, &name)?;
    Ok(describe(instance, pd, &props, &name, family))
}

fn type_rank(kind: vk::PhysicalDeviceType) -> u32 {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

fn graphics_compute_family(instance: &ash::Instance, pd: vk::PhysicalDevice) -> Option<u32> {
    // SAFETY: plain query.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    families.iter().position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE)).map(|i| i as u32)
}

fn check_features(instance: &ash::Instance, pd: vk::PhysicalDevice, name: &str) -> VkResult<()> {
    let mut v13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut v13);
    // SAFETY: plain query into structures that live for the call.
    unsafe { instance.get_physical_device_features2(pd, &mut features) };
    let base = features.features;
    let missing = [
        (v13.dynamic_rendering, "dynamicRendering"),
        (v13.synchronization2, "synchronization2"),
        (base.shader_storage_image_extended_formats, "shaderStorageImageExtendedFormats"),
    ];
    match missing.iter().find(|(have, _)| *have == vk::FALSE) {
        Some((_, feature)) => Err(VkError::MissingFeature { device: name.into(), missing: (*feature).into() }),
        None => Ok(()),
    }
}

fn create_logical(instance: &ash::Instance, pd: vk::PhysicalDevice, family: u32) -> VkResult<ash::Device> {
    let priorities = [1.0];
    let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
    let base = vk::PhysicalDeviceFeatures::default().shader_storage_image_extended_formats(true);
    let mut v13 = vk::PhysicalDeviceVulkan13Features::default().dynamic_rendering(true).synchronization2(true);
    let info = vk::DeviceCreateInfo::default().queue_create_infos(&queues).enabled_features(&base).push_next(&mut v13);
    // SAFETY: the create info refers to locals alive for the call; features were checked.
    Ok(unsafe { instance.create_device(pd, &info, None) }?)
}

fn describe(instance: &ash::Instance, pd: vk::PhysicalDevice, props: &vk::PhysicalDeviceProperties, name: &str, family: u32) -> DeviceInfo {
    let mut driver_props = vk::PhysicalDeviceDriverProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver_props);
    // SAFETY: plain queries of a live physical device into structures alive for the calls.
    let (families, format) = unsafe {
        instance.get_physical_device_properties2(pd, &mut props2);
        (
            instance.get_physical_device_queue_family_properties(pd),
            instance.get_physical_device_format_properties(pd, vk::Format::R32G32_SFLOAT),
        )
    };
    let driver = format!(
        "{} {}",
        driver_props.driver_name_as_c_str().map(|c| c.to_string_lossy().into_owned()).unwrap_or_default(),
        driver_props.driver_info_as_c_str().map(|c| c.to_string_lossy().into_owned()).unwrap_or_default()
    );
    let timestamps = families.get(family as usize).is_some_and(|f| f.timestamp_valid_bits > 0) && props.limits.timestamp_period > 0.0;
    DeviceInfo {
        name: name.to_string(),
        driver: driver.trim().to_string(),
        device_type: format!("{:?}", props.device_type),
        timestamp_period_ns: timestamps.then_some(props.limits.timestamp_period as f64),
        linear_moments: format.optimal_tiling_features.contains(vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR),
        max_storage_buffer_range: props.limits.max_storage_buffer_range as u64,
    }
}
