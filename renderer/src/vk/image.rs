//! Images (2D or 2D arrays) with their memory and one view over all their layers, freed on
//! drop; and views of single layers.

use super::{Context, VkResult};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

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

    pub fn all_layers(&self) -> vk::ImageSubresourceRange {
        self.layers(0, self.layers)
    }

    fn layers(&self, first: u32, count: u32) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange::default().aspect_mask(self.aspect()).level_count(1).base_array_layer(first).layer_count(count)
    }
}

pub struct Image<'a> {
    ctx: &'a Context,
    pub raw: vk::Image,
    pub view: vk::ImageView,
    pub desc: ImageDesc,
    allocation: Option<Allocation>,
}

impl<'a> Image<'a> {
    pub fn new(ctx: &'a Context, name: &str, desc: ImageDesc) -> VkResult<Image<'a>> {
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
        let mut image = Image { ctx, raw, view: vk::ImageView::null(), desc, allocation: None };
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

    /// A 2D view of one layer, for rendering into it.
    pub fn layer_view(&self, layer: u32) -> VkResult<ImageView<'a>> {
        let range = self.desc.layers(layer, 1);
        let raw = create_view(self.ctx, self.raw, &self.desc, vk::ImageViewType::TYPE_2D, range)?;
        Ok(ImageView { ctx: self.ctx, raw })
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

impl Drop for Image<'_> {
    fn drop(&mut self) {
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
pub struct ImageView<'a> {
    ctx: &'a Context,
    pub raw: vk::ImageView,
}

impl Drop for ImageView<'_> {
    fn drop(&mut self) {
        // SAFETY: no pending GPU work uses the view.
        unsafe { self.ctx.device.destroy_image_view(self.raw, None) };
    }
}
