//! Images (2D or 2D arrays) with their memory and one view over all their layers, freed on
//! drop; and views of single layers.

use super::{Context, VkResult};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

#[derive(Clone, Copy, Debug)]
pub struct ImageDesc {
    pub width: u32,
    pub height: u32,
    pub layers: u32,
    pub format: vk::Format,
    pub usage: vk::ImageUsageFlags,
    /// TYPE_2D, or TYPE_2D_ARRAY for images shaders read as arrays (even of one layer).
    pub view_type: vk::ImageViewType,
}

impl ImageDesc {
    pub fn aspect(&self) -> vk::ImageAspectFlags {
        match self.format {
            vk::Format::D32_SFLOAT | vk::Format::D16_UNORM => vk::ImageAspectFlags::DEPTH,
            _ => vk::ImageAspectFlags::COLOR,
        }
    }

    pub fn extent(&self) -> vk::Extent2D {
        vk::Extent2D { width: self.width, height: self.height }
    }

    /// Bytes of one texel of the formats relume's images use (0 for any other).
    pub fn texel_bytes(&self) -> u64 {
        match self.format {
            vk::Format::R32G32B32A32_SFLOAT => 16,
            vk::Format::R32G32_SFLOAT | vk::Format::R32G32_SINT => 8,
            vk::Format::R8G8B8A8_UNORM | vk::Format::R8G8B8A8_SRGB | vk::Format::D32_SFLOAT | vk::Format::R32_SFLOAT => 4,
            _ => 0,
        }
    }

    /// Texels in all layers.
    pub fn texel_count(&self) -> u64 {
        self.width as u64 * self.height as u64 * self.layers as u64
    }

    pub fn all_layers(&self) -> vk::ImageSubresourceRange {
        self.layers(0, self.layers)
    }

    fn layers(&self, first: u32, count: u32) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange::default().aspect_mask(self.aspect()).level_count(1).base_array_layer(first).layer_count(count)
    }
}

pub struct Image {
    ctx: Arc<Context>,
    pub raw: vk::Image,
    pub view: vk::ImageView,
    pub desc: ImageDesc,
    allocation: Option<Allocation>,
    /// False for an image the caller lent (`Image::borrowed`): never destroyed here.
    owned: bool,
}

impl Image {
    pub fn new(ctx: &Arc<Context>, name: &str, desc: ImageDesc) -> VkResult<Image> {
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D { width: desc.width, height: desc.height, depth: 1 })
            .mip_levels(1)
            .array_layers(desc.layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: a valid create info on a live device.
        let raw = unsafe { ctx.device.create_image(&info, None) }?;
        let mut image = Image { ctx: Arc::clone(ctx), raw, view: vk::ImageView::null(), desc, allocation: None, owned: true };
        // SAFETY: a plain query of the image just made.
        let requirements = unsafe { ctx.device.get_image_memory_requirements(raw) };
        let allocation = ctx.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        })?;
        // SAFETY: the allocation was made for this image's requirements and is bound once;
        // it is stored first so that drop frees it if binding fails.
        let (memory, offset) = unsafe { (allocation.memory(), allocation.offset()) };
        image.allocation = Some(allocation);
        unsafe { ctx.device.bind_image_memory(raw, memory, offset) }?;
        image.view = create_view(ctx, raw, &desc, desc.view_type, desc.all_layers())?;
        Ok(image)
    }

    /// An image and a view over all its layers that the caller made and owns (an engine's
    /// G-buffer), lent to relume: `desc` must describe them, and the image has one mip level
    /// (relume's barriers cover level 0). relume binds and barriers it like its
    /// own, and never destroys it; the caller keeps both alive as long as relume uses them.
    pub fn borrowed(ctx: &Arc<Context>, raw: vk::Image, view: vk::ImageView, desc: ImageDesc) -> Image {
        Image { ctx: Arc::clone(ctx), raw, view, desc, allocation: None, owned: false }
    }

    /// A 2D view of one layer, for rendering into it.
    pub fn layer_view(&self, layer: u32) -> VkResult<ImageView> {
        let range = self.desc.layers(layer, 1);
        let raw = create_view(&self.ctx, self.raw, &self.desc, vk::ImageViewType::TYPE_2D, range)?;
        Ok(ImageView { ctx: Arc::clone(&self.ctx), raw })
    }
}

fn create_view(
    ctx: &Context,
    image: vk::Image,
    desc: &ImageDesc,
    view_type: vk::ImageViewType,
    range: vk::ImageSubresourceRange,
) -> VkResult<vk::ImageView> {
    let info = vk::ImageViewCreateInfo::default().image(image).view_type(view_type).format(desc.format).subresource_range(range);
    // SAFETY: the image is bound to memory and the range lies inside it.
    Ok(unsafe { ctx.device.create_image_view(&info, None) }?)
}

impl Drop for Image {
    fn drop(&mut self) {
        if !self.owned {
            return;
        }
        // SAFETY: no pending GPU work uses the image; destroying a null view is a no-op.
        unsafe {
            self.ctx.device.destroy_image_view(self.view, None);
            self.ctx.device.destroy_image(self.raw, None);
        }
        if let Some(allocation) = self.allocation.take() {
            let _ = self.ctx.allocator().free(allocation);
        }
    }
}

/// A view owned apart from its image (one layer of an array), destroyed on drop.
pub struct ImageView {
    ctx: Arc<Context>,
    pub raw: vk::ImageView,
}

impl Drop for ImageView {
    fn drop(&mut self) {
        // SAFETY: no pending GPU work uses the view.
        unsafe { self.ctx.device.destroy_image_view(self.raw, None) };
    }
}
