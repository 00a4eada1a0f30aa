//! Objects a submission needs: a primary command buffer from the context's pool, a fence and a
//! sampler, each released on drop.

use super::{Context, VkResult};
use ash::vk;

pub struct CommandBuffer<'a> {
    ctx: &'a Context,
    pub raw: vk::CommandBuffer,
}

impl<'a> CommandBuffer<'a> {
    pub fn new(ctx: &'a Context) -> VkResult<Self> {
        let raw = ctx.allocate_command_buffer()?;
        Ok(CommandBuffer { ctx, raw })
    }
}

impl Drop for CommandBuffer<'_> {
    fn drop(&mut self) {
        self.ctx.free_command_buffer(self.raw);
    }
}

pub struct Fence<'a> {
    ctx: &'a Context,
    pub raw: vk::Fence,
}

impl<'a> Fence<'a> {
    pub fn new(ctx: &'a Context) -> VkResult<Self> {
        // SAFETY: a valid create info on a live device.
        let raw = unsafe { ctx.device.create_fence(&vk::FenceCreateInfo::default(), None) }?;
        Ok(Fence { ctx, raw })
    }
}

impl Drop for Fence<'_> {
    fn drop(&mut self) {
        // SAFETY: the fence is not pending (every submission waits for it).
        unsafe { self.ctx.device.destroy_fence(self.raw, None) };
    }
}

pub struct Sampler<'a> {
    ctx: &'a Context,
    pub raw: vk::Sampler,
}

impl<'a> Sampler<'a> {
    /// A sampler without mipmaps: clamp-to-edge for shadow maps, repeat for material textures.
    pub fn new(ctx: &'a Context, linear: bool, address: vk::SamplerAddressMode) -> VkResult<Self> {
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
        Ok(Sampler { ctx, raw })
    }
}

impl Drop for Sampler<'_> {
    fn drop(&mut self) {
        // SAFETY: no pending GPU work uses the sampler.
        unsafe { self.ctx.device.destroy_sampler(self.raw, None) };
    }
}
