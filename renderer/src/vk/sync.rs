//! Objects a submission needs: a primary command buffer with a pool of its own, a fence and a
//! sampler, each released on drop.

use super::{Context, VkResult};
use ash::vk;
use std::sync::Arc;

/// One primary command buffer from a pool it owns, so that recording into it never needs a
/// lock shared with another thread's command buffers.
pub struct CommandBuffer {
    ctx: Arc<Context>,
    pool: vk::CommandPool,
    pub raw: vk::CommandBuffer,
}

impl CommandBuffer {
    pub fn new(ctx: &Arc<Context>) -> VkResult<Self> {
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: the device is live and the family exists.
        let pool = unsafe { ctx.device.create_command_pool(&pool_info, None) }?;
        let mut buffer = CommandBuffer { ctx: Arc::clone(ctx), pool, raw: vk::CommandBuffer::null() };
        let info =
            vk::CommandBufferAllocateInfo::default().command_pool(pool).level(vk::CommandBufferLevel::PRIMARY).command_buffer_count(1);
        // SAFETY: the pool is live; drop destroys it (and the buffer) if allocation fails.
        buffer.raw = unsafe { ctx.device.allocate_command_buffers(&info) }?[0];
        Ok(buffer)
    }
}

impl Drop for CommandBuffer {
    fn drop(&mut self) {
        // SAFETY: the buffer is not pending (every submission waits for its fence); destroying
        // the pool frees it.
        unsafe { self.ctx.device.destroy_command_pool(self.pool, None) };
    }
}

pub struct Fence {
    ctx: Arc<Context>,
    pub raw: vk::Fence,
}

impl Fence {
    pub fn new(ctx: &Arc<Context>) -> VkResult<Self> {
        // SAFETY: a valid create info on a live device.
        let raw = unsafe { ctx.device.create_fence(&vk::FenceCreateInfo::default(), None) }?;
        Ok(Fence { ctx: Arc::clone(ctx), raw })
    }
}

impl Drop for Fence {
    fn drop(&mut self) {
        // SAFETY: the fence is not pending (every submission waits for it).
        unsafe { self.ctx.device.destroy_fence(self.raw, None) };
    }
}

pub struct Sampler {
    ctx: Arc<Context>,
    pub raw: vk::Sampler,
}

impl Sampler {
    /// A sampler without mipmaps: clamp-to-edge for shadow maps, repeat for material textures.
    pub fn new(ctx: &Arc<Context>, linear: bool, address: vk::SamplerAddressMode) -> VkResult<Self> {
        let filter = if linear { vk::Filter::LINEAR } else { vk::Filter::NEAREST };
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter)
            .min_filter(filter)
            .address_mode_u(address)
            .address_mode_v(address)
            .address_mode_w(address)
            .max_lod(0.0);
        // SAFETY: a valid create info on a live device.
        let raw = unsafe { ctx.device.create_sampler(&info, None) }?;
        Ok(Sampler { ctx: Arc::clone(ctx), raw })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // SAFETY: no pending GPU work uses the sampler.
        unsafe { self.ctx.device.destroy_sampler(self.raw, None) };
    }
}
