//! Separable Gaussian blur of the shadow moments (compute): horizontal into a scratch image,
//! vertical back, all layers in one dispatch each. Filtering moments is what lets variance
//! shadow maps soften edges without aliasing (000 §3.4).

use crate::shaders;
use crate::vk::{vk, Access, Binding, CommandRecorder, Context, DescriptorSet, Image, ImageDesc, Pipeline, Tracker, VkResult};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BlurPush {
    step: [i32; 2],
    radius: i32,
}

pub struct VsmBlurPass<'a> {
    pipeline: Pipeline<'a>,
    horizontal: DescriptorSet<'a>,
    vertical: DescriptorSet<'a>,
    scratch: Image<'a>,
    radius: u32,
}

impl<'a> VsmBlurPass<'a> {
    /// `radius` in texels; 0 makes the pass record nothing.
    pub fn new(ctx: &'a Context, moments: &Image, radius: u32) -> VkResult<VsmBlurPass<'a>> {
        let scratch = Image::new(ctx, "vsm blur scratch", ImageDesc { usage: vk::ImageUsageFlags::STORAGE, ..moments.desc })?;
        let stage = vk::ShaderStageFlags::COMPUTE;
        let horizontal = DescriptorSet::new(ctx, stage, &[Binding::StorageImage(moments.view), Binding::StorageImage(scratch.view)])?;
        let vertical = DescriptorSet::new(ctx, stage, &[Binding::StorageImage(scratch.view), Binding::StorageImage(moments.view)])?;
        let pipeline = Pipeline::compute(ctx, shaders::VSM_BLUR_COMP, horizontal.layout, std::mem::size_of::<BlurPush>() as u32)?;
        Ok(VsmBlurPass { pipeline, horizontal, vertical, scratch, radius })
    }

    /// Reads and writes `moments` (storage image), through the scratch image.
    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, moments: &Image) {
        if self.radius == 0 {
            return;
        }
        let d = moments.desc;
        let groups = (d.width.div_ceil(8), d.height.div_ceil(8), d.layers);
        let steps = [([1, 0], &self.horizontal, moments, &self.scratch), ([0, 1], &self.vertical, &self.scratch, moments)];
        for (step, set, source, target) in steps {
            tracker.use_image(rec, source, Access::ComputeStorageRead);
            tracker.use_image(rec, target, Access::ComputeStorageWrite);
            rec.bind_compute(self.pipeline.raw, self.pipeline.layout, set.set);
            rec.push_constants(self.pipeline.layout, &BlurPush { step, radius: self.radius as i32 });
            rec.dispatch(groups.0, groups.1, groups.2);
        }
    }
}
