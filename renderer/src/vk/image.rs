//! Images (2D or 2D arrays) with one view over all their layers.

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

pub struct Image {
    pub raw: vk::Image,
    pub view: vk::ImageView,
    pub desc: ImageDesc,
    allocation: Option<Allocation>,
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
        vk::ImageSubresourceRange::default()
            .aspect_mask(self.aspect())
            .level_count(1)
            .layer_count(self.layers)
    }
}

impl Image {
    pub fn new(ctx: &Context, name: &str, desc: ImageDesc) -> VkResult<Image> {
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
        let requirements = unsafe { ctx.device.get_image_memory_requirements(raw) };
        let allocation = ctx.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let mut image = Image { raw, view: vk::ImageView::null(), desc, allocation: None };
        match allocation {
            Ok(a) => image.allocation = Some(a),
            Err(e) => {
                // SAFETY: the image is unused and unbound.
                unsafe { ctx.device.destroy_image(raw, None) };
                return Err(e.into());
            }
        }
        // SAFETY: the allocation was just made for this image's requirements and is bound once.
        let bound = image.allocation.as_ref().map(|a| unsafe { (a.memory(), a.offset()) }).unwrap_or_default();
        let result = unsafe { ctx.device.bind_image_memory(raw, bound.0, bound.1) }
            .map_err(Into::into)
            .and_then(|_| image.create_view(ctx));
        if let Err(e) = result {
            image.destroy(ctx);
            return Err(e);
        }
        Ok(image)
    }

    fn create_view(&mut self, ctx: &Context) -> VkResult<()> {
        let info = vk::ImageViewCreateInfo::default()
            .image(self.raw)
            .view_type(self.desc.view_type)
            .format(self.desc.format)
            .subresource_range(self.desc.all_layers());
        // SAFETY: the image is bound to memory and the range lies inside it.
        self.view = unsafe { ctx.device.create_image_view(&info, None) }?;
        Ok(())
    }

    /// A view of one layer, for rendering into it; the caller destroys it with `destroy_view`.
    pub fn layer_view(&self, ctx: &Context, layer: u32) -> VkResult<vk::ImageView> {
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(self.desc.aspect())
            .level_count(1)
            .base_array_layer(layer)
            .layer_count(1);
        let info = vk::ImageViewCreateInfo::default()
            .image(self.raw)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(self.desc.format)
            .subresource_range(range);
        // SAFETY: the layer exists in the bound image.
        Ok(unsafe { ctx.device.create_image_view(&info, None) }?)
    }

    pub fn destroy(&mut self, ctx: &Context) {
        // SAFETY: the caller guarantees the GPU no longer uses the image or its view.
        unsafe {
            if self.view != vk::ImageView::null() {
                ctx.device.destroy_image_view(self.view, None);
            }
        }
        if let Some(allocation) = self.allocation.take() {
            unsafe { ctx.device.destroy_image(self.raw, None) };
            let _ = ctx.allocator().free(allocation);
        }
    }
}

pub fn destroy_view(ctx: &Context, view: vk::ImageView) {
    // SAFETY: the caller guarantees the GPU no longer uses the view.
    unsafe { ctx.device.destroy_image_view(view, None) };
}
