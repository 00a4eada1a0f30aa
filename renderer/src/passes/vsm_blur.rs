//! Separable Gaussian blur of the shadow moments (compute): horizontal into a scratch image,
//! vertical back, all layers in one dispatch each. Filtering moments is what lets variance
//! shadow maps soften edges without aliasing (000 §3.4).

use super::compute::{per_texel, ComputePass, Slot};
use crate::shaders;
use crate::vk::{vk, Access, CommandRecorder, Context, Image, ImageDesc, Tracker, VkResult};
use std::sync::Arc;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BlurPush {
    step: [i32; 2],
    radius: i32,
}

pub struct VsmBlurPass {
    /// Set 0 blurs `moments` horizontally into the scratch image, set 1 vertically back.
    pass: ComputePass<BlurPush>,
    _scratch: Image,
    radius: u32,
    groups: [u32; 3],
}

impl VsmBlurPass {
    /// `radius` in texels (the frame records no blur for 0). Reads and writes `moments`
    /// (storage image), through a scratch image of its size.
    pub fn new(ctx: &Arc<Context>, moments: &Image, radius: u32) -> VkResult<VsmBlurPass> {
        let scratch = Image::new(ctx, "vsm blur scratch", ImageDesc { usage: vk::ImageUsageFlags::STORAGE, ..moments.desc })?;
        let (read, write) = (Access::ComputeStorageRead, Access::ComputeStorageWrite);
        let horizontal = [Slot::StorageImage(moments, read), Slot::StorageImage(&scratch, write)];
        let vertical = [Slot::StorageImage(&scratch, read), Slot::StorageImage(moments, write)];
        let pass = ComputePass::with_sets(ctx, "vsm_blur", shaders::VSM_BLUR_COMP, &[&horizontal, &vertical])?;
        Ok(VsmBlurPass { pass, groups: per_texel(moments), _scratch: scratch, radius })
    }

    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker) {
        for (set, step) in [[1, 0], [0, 1]].into_iter().enumerate() {
            self.pass.dispatch(rec, tracker, set, &BlurPush { step, radius: self.radius as i32 }, self.groups);
        }
    }
}
