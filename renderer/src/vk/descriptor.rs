//! Descriptor sets written once at creation: each pass owns its layout, pool and set, so no
//! descriptor is allocated or updated per frame.

use super::{Context, VkResult};
use ash::vk;
use std::sync::Arc;

/// One binding and the resource it points at.
pub enum Binding {
    StorageBuffer(vk::Buffer),
    UniformBuffer(vk::Buffer),
    SampledImage { view: vk::ImageView, sampler: vk::Sampler },
    StorageImage(vk::ImageView),
}

impl Binding {
    fn kind(&self) -> vk::DescriptorType {
        match self {
            Binding::StorageBuffer(_) => vk::DescriptorType::STORAGE_BUFFER,
            Binding::UniformBuffer(_) => vk::DescriptorType::UNIFORM_BUFFER,
            Binding::SampledImage { .. } => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            Binding::StorageImage(_) => vk::DescriptorType::STORAGE_IMAGE,
        }
    }

    fn image_info(&self) -> [vk::DescriptorImageInfo; 1] {
        let info = vk::DescriptorImageInfo::default();
        [match self {
            Binding::SampledImage { view, sampler } => {
                info.image_view(*view).sampler(*sampler).image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
            }
            Binding::StorageImage(view) => info.image_view(*view).image_layout(vk::ImageLayout::GENERAL),
            Binding::StorageBuffer(_) | Binding::UniformBuffer(_) => info,
        }]
    }
}

pub struct DescriptorSet {
    ctx: Arc<Context>,
    /// Binding i's kind: what a pipeline's shaders are checked against.
    pub kinds: Vec<vk::DescriptorType>,
    pub layout: vk::DescriptorSetLayout,
    pub set: vk::DescriptorSet,
    pool: vk::DescriptorPool,
}

impl DescriptorSet {
    /// Creates a set whose binding i is `bindings[i]`, visible to `stages`.
    pub fn new(ctx: &Arc<Context>, stages: vk::ShaderStageFlags, bindings: &[Binding]) -> VkResult<DescriptorSet> {
        let layout_bindings: Vec<_> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(b.kind())
                    .descriptor_count(1)
                    .stage_flags(stages)
            })
            .collect();
        let pool_sizes: Vec<_> = bindings.iter().map(|b| vk::DescriptorPoolSize { ty: b.kind(), descriptor_count: 1 }).collect();
        let device = &ctx.device;
        let mut descriptors = DescriptorSet {
            ctx: Arc::clone(ctx),
            kinds: bindings.iter().map(Binding::kind).collect(),
            layout: vk::DescriptorSetLayout::null(),
            set: vk::DescriptorSet::null(),
            pool: vk::DescriptorPool::null(),
        };
        // SAFETY: create infos refer to locals alive for each call; whatever was made before
        // a failure is destroyed by drop.
        unsafe {
            descriptors.layout =
                device.create_descriptor_set_layout(&vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings), None)?;
            descriptors.pool =
                device.create_descriptor_pool(&vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&pool_sizes), None)?;
            let layouts = [descriptors.layout];
            descriptors.set = device.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default().descriptor_pool(descriptors.pool).set_layouts(&layouts),
            )?[0];
        }
        descriptors.write(bindings);
        Ok(descriptors)
    }

    fn write(&self, bindings: &[Binding]) {
        let buffer_infos: Vec<_> = bindings
            .iter()
            .map(|b| match b {
                Binding::StorageBuffer(buffer) | Binding::UniformBuffer(buffer) => {
                    [vk::DescriptorBufferInfo::default().buffer(*buffer).range(vk::WHOLE_SIZE)]
                }
                _ => [vk::DescriptorBufferInfo::default()],
            })
            .collect();
        let image_infos: Vec<_> = bindings.iter().map(Binding::image_info).collect();
        let writes: Vec<_> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let write = vk::WriteDescriptorSet::default().dst_set(self.set).dst_binding(i as u32).descriptor_type(b.kind());
                match b {
                    Binding::StorageBuffer(_) | Binding::UniformBuffer(_) => write.buffer_info(&buffer_infos[i]),
                    _ => write.image_info(&image_infos[i]),
                }
            })
            .collect();
        // SAFETY: the set is not in use by the GPU yet; every info outlives the call.
        unsafe { self.ctx.device.update_descriptor_sets(&writes, &[]) };
    }
}

impl Drop for DescriptorSet {
    fn drop(&mut self) {
        // SAFETY: no pending GPU work uses the set; null handles are no-ops.
        unsafe {
            self.ctx.device.destroy_descriptor_pool(self.pool, None);
            self.ctx.device.destroy_descriptor_set_layout(self.layout, None);
        }
    }
}
