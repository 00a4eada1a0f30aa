//! The window's swapchain, as an engine owns it: images in a B8G8R8A8 or R8G8B8A8 UNORM
//! format (lavapipe offers only BGRA; relume's display bytes are already sRGB-encoded, so an
//! UNORM image presents them as they are), one view per image for the overlay's rendering, one
//! acquire semaphore (one frame is in flight at a time) and one render-finished semaphore per
//! image (presentation may hold an image's semaphore past the next frame's fence).

use crate::device::Device;
use anyhow::{bail, Result};
use ash::vk;

pub struct Swapchain {
    loader: ash::khr::swapchain::Device,
    device: ash::Device,
    pub raw: vk::SwapchainKHR,
    pub images: Vec<vk::Image>,
    pub views: Vec<vk::ImageView>,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub acquired: vk::Semaphore,
    pub finished: Vec<vk::Semaphore>,
}

/// What acquiring or presenting found: go on, or rebuild the swapchain first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fit {
    Fits,
    OutOfDate,
}

impl Swapchain {
    /// A swapchain of the window's current size (`wanted` where the surface leaves it to us).
    pub fn new(device: &Device, wanted: vk::Extent2D, old: Option<&Swapchain>) -> Result<Swapchain> {
        let base = &device.base;
        // SAFETY: plain queries of a live surface.
        let (caps, formats) = unsafe {
            (
                base.surface_loader.get_physical_device_surface_capabilities(device.physical, base.surface)?,
                base.surface_loader.get_physical_device_surface_formats(device.physical, base.surface)?,
            )
        };
        let unorm = [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM];
        let Some(format) = formats.iter().find(|f| unorm.contains(&f.format)) else {
            bail!("the window offers no B8G8R8A8_UNORM or R8G8B8A8_UNORM swapchain format (it offers {formats:?})");
        };
        let usage = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::COLOR_ATTACHMENT;
        if !caps.supported_usage_flags.contains(usage) {
            bail!("the window's swapchain images cannot be blitted to, read back and drawn on ({:?})", caps.supported_usage_flags);
        }
        let extent = match caps.current_extent.width {
            u32::MAX => vk::Extent2D {
                width: wanted.width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: wanted.height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            },
            _ => caps.current_extent,
        };
        let count = match caps.max_image_count {
            0 => caps.min_image_count + 1,
            max => (caps.min_image_count + 1).min(max),
        };
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(base.surface)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(vk::PresentModeKHR::FIFO)
            // Screenshots read every pixel, also where another window covers this one.
            .clipped(false)
            .old_swapchain(old.map_or(vk::SwapchainKHR::null(), |o| o.raw));
        let loader = ash::khr::swapchain::Device::new(&base.instance, &device.device);
        let d = &device.device;
        // SAFETY: valid create infos on a live device; `Drop` destroys what was made.
        unsafe {
            let raw = loader.create_swapchain(&info, None)?;
            let mut made = Swapchain {
                loader,
                device: d.clone(),
                raw,
                images: Vec::new(),
                views: Vec::new(),
                format: format.format,
                extent,
                acquired: vk::Semaphore::null(),
                finished: Vec::new(),
            };
            made.images = made.loader.get_swapchain_images(raw)?;
            made.acquired = d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None)?;
            for &image in &made.images.clone() {
                made.finished.push(d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None)?);
                let range = vk::ImageSubresourceRange::default().aspect_mask(vk::ImageAspectFlags::COLOR).level_count(1).layer_count(1);
                let view = vk::ImageViewCreateInfo::default()
                    .image(image)
                    .view_type(vk::ImageViewType::TYPE_2D)
                    .format(made.format)
                    .subresource_range(range);
                made.views.push(d.create_image_view(&view, None)?);
            }
            Ok(made)
        }
    }

    /// The next image to draw into, signalling `acquired` when it is free.
    pub fn acquire(&self) -> Result<(Fit, u32)> {
        // SAFETY: `acquired` is unsignalled: the last frame that waited on it has completed.
        match unsafe { self.loader.acquire_next_image(self.raw, u64::MAX, self.acquired, vk::Fence::null()) } {
            // Suboptimal still presents; the present's answer asks for the rebuild.
            Ok((index, _)) => Ok((Fit::Fits, index)),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok((Fit::OutOfDate, 0)),
            Err(e) => Err(e.into()),
        }
    }

    /// Presents image `index` once its frame's `finished` semaphore is signalled.
    pub fn present(&self, queue: vk::Queue, index: u32) -> Result<Fit> {
        let waits = [self.finished[index as usize]];
        let swapchains = [self.raw];
        let indices = [index];
        let info = vk::PresentInfoKHR::default().wait_semaphores(&waits).swapchains(&swapchains).image_indices(&indices);
        // SAFETY: the image was acquired and its frame submitted, signalling `waits`.
        match unsafe { self.loader.queue_present(queue, &info) } {
            Ok(false) => Ok(Fit::Fits),
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Fit::OutOfDate),
            Err(e) => Err(e.into()),
        }
    }
}

impl Drop for Swapchain {
    /// The queue is idle (the viewer waits for it before a rebuild and at teardown).
    fn drop(&mut self) {
        // SAFETY: nothing in flight uses these objects any more.
        unsafe {
            for &view in &self.views {
                self.device.destroy_image_view(view, None);
            }
            for &semaphore in self.finished.iter().chain([&self.acquired]) {
                if semaphore != vk::Semaphore::null() {
                    self.device.destroy_semaphore(semaphore, None);
                }
            }
            self.loader.destroy_swapchain(self.raw, None);
        }
    }
}
