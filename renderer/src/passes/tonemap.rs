//! Tonemap pass (compute): linear radiance to display sRGB in an RGBA8 image, with the same
//! transform as relume_bake::image::tonemap_to_srgb8.

use super::compute::{per_texel, ComputePass, Slot};
use crate::shaders;
use crate::vk::{vk, Access, CommandRecorder, Context, Image, Tracker, VkResult};
use std::sync::Arc;

pub const DISPLAY_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

pub struct TonemapPass {
    pass: ComputePass<f32>,
    groups: [u32; 3],
}

impl TonemapPass {
    /// Reads `radiance` (storage), writes `display` (storage).
    pub fn new(ctx: &Arc<Context>, radiance: &Image, display: &Image) -> VkResult<TonemapPass> {
        let slots = [Slot::StorageImage(radiance, Access::ComputeStorageRead), Slot::StorageImage(display, Access::ComputeStorageWrite)];
        Ok(TonemapPass { pass: ComputePass::new(ctx, "tonemap", shaders::TONEMAP_COMP, &slots)?, groups: per_texel(display) })
    }

    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, exposure: f32) {
        self.pass.dispatch(rec, tracker, 0, &exposure, self.groups);
    }
}
