//! Tonemap pass (compute): linear radiance to display sRGB in an RGBA8 image, with the same
//! transform as relume_bake::image::tonemap_to_srgb8.

use crate::shaders;
use crate::vk::{vk, Access, Binding, CommandRecorder, Context, DescriptorSet, Image, Pipeline, Tracker, VkResult};

pub const DISPLAY_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

pub struct TonemapPass<'a> {
    pipeline: Pipeline<'a>,
    descriptors: DescriptorSet<'a>,
}

impl<'a> TonemapPass<'a> {
    pub fn new(ctx: &'a Context, radiance: &Image, display: &Image) -> VkResult<TonemapPass<'a>> {
        let descriptors = DescriptorSet::new(
            ctx,
            vk::ShaderStageFlags::COMPUTE,
            &[Binding::StorageImage(radiance.view), Binding::StorageImage(display.view)],
        )?;
        let pipeline = Pipeline::compute(ctx, shaders::TONEMAP_COMP, descriptors.layout, 4)?;
        Ok(TonemapPass { pipeline, descriptors })
    }

    /// Reads `radiance` (storage); writes `display` (storage).
    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, radiance: &Image, display: &Image, exposure: f32) {
        tracker.use_image(rec, radiance, Access::ComputeStorageRead);
        tracker.use_image(rec, display, Access::ComputeStorageWrite);
        rec.bind_compute(self.pipeline.raw, self.pipeline.layout, self.descriptors.set);
        rec.push_constants(self.pipeline.layout, &exposure);
        rec.dispatch(display.desc.width.div_ceil(8), display.desc.height.div_ceil(8), 1);
    }
}
