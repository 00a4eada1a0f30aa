//! Descriptor sets written once at creation: each pass owns its layout, pool and set, so no
//! descriptor is allocated or updated per frame.

use super::{Context, VkResult};
use ash::vk;

/// One binding and the resource it points at.
pub enum Binding {
    StorageBuffer(vk::Buffer),
    /// An array of sampled images, all read through one sampler (one view: a single image).
    SampledImages { views: Vec<vk::ImageView>, sampler: vk::Sampler },
    StorageImage(vk::ImageView),
}

impl Binding {
    fn kind(&self) -> vk::DescriptorType {
        match self {
            Binding::StorageBuffer(_) => vk::DescriptorType::STORAGE_BUFFER,
            Binding::SampledImages { .. } => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            Binding::StorageImage(_) => vk::DescriptorType::STORAGE_IMAGE,
        }
    }

    fn count(&self) -> u32 {
        match self {
            Binding::SampledImages { views, .. } => views.len() as u32,
            _ => 1,
        }
    }

    fn image_infos(&self) -> Vec<vk::DescriptorImageInfo> {
        match self {
            Binding::SampledImages { views, sampler } => views
                .iter()
                .map(|view| {
                    vk::DescriptorImageInfo::default()
                        .image_view(*view)
                        .sampler(*sampler)
                        .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
                })
                .collect(),
            Binding::StorageImage(view) => {
                vec![vk::DescriptorImageInfo::default().image_view(*view).image_layout(vk::ImageLayout::GENERAL)]
            }
            Binding::StorageBuffer(_) => Vec::new(),
        }
    }
}

pub struct DescriptorSet {
    pub layout: vk::DescriptorSetLayout,
    pub set: vk::DescriptorSet,
    pool: vk::DescriptorPool,
}

impl DescriptorSet {
    /// Creates a set whose binding i is `bindings[i]`, visible to `stages`.
    pub fn new(ctx: &Context, stages: vk::ShaderStageFlags, bindings: &[Binding]) -> VkResult<DescriptorSet> {
        let layout_bindings: Vec<_> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(b.kind())
                    .descriptor_count(b.count())
                    .stage_flags(stages)
            })
            .collect();
        let pool_sizes: Vec<_> = bindings
            .iter()
            .map(|b| vk::DescriptorPoolSize { ty: b.kind(), descriptor_count: b.count() })
            .collect();
        let device = &ctx.device;
        // SAFETY: create infos refer to locals alive for each call; objects are destroyed in
        // `destroy` in reverse order.
        unsafe {
            let layout = device.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings),
                None,
            )?;
            let pool = device.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&pool_sizes),
                None,
            )?;
            let layouts = [layout];
            let set = device.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&layouts),
            )?[0];
            let descriptors = DescriptorSet { layout, set, pool };
            descriptors.write(ctx, bindings);
            Ok(descriptors)
        }
    }

    fn write(&self, ctx: &Context, bindings: &[Binding]) {
        let buffer_infos: Vec<_> = bindings
            .iter()
            .map(|b| match b {
                Binding::StorageBuffer(buffer) => [vk::DescriptorBufferInfo::default().buffer(*buffer).range(vk::WHOLE_SIZE)],
                _ => [vk::DescriptorBufferInfo::default()],
            })
            .collect();
        let image_infos: Vec<_> = bindings.iter().map(Binding::image_infos).collect();
        let writes: Vec<_> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let write = vk::WriteDescriptorSet::default()
                    .dst_set(self.set)
                    .dst_binding(i as u32)
                    .descriptor_type(b.kind());
                match b {
                    Binding::StorageBuffer(_) => write.buffer_info(&buffer_infos[i]),
                    _ => write.image_info(&image_infos[i]),
                }
            })
            .collect();
        // SAFETY: the set is not in use by the GPU yet; every info outlives the call.
        unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };
    }

    pub fn destroy(&mut self, ctx: &Context) {
        // SAFETY: the caller guarantees the GPU no longer uses the set.
        unsafe {
            ctx.device.destroy_descriptor_pool(self.pool, None);
            ctx.device.destroy_descriptor_set_layout(self.layout, None);
        }
    }
}
