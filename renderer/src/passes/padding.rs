//! Atlas padding (compute): fills every empty texel of every layer of an atlas image (texel
//! data laid out as the lightmap atlas: the obscurance, the light path maps' indirect light)
//! with the value of its nearest covered texel, so that bilinear filtering and mipmapping near
//! chart edges never blend in gutter texels. Jump flooding (Rong & Tan 2006, "Jump flooding in
//! GPU with applications to Voronoi diagram and distance transform") with the extra k = 1
//! step of JFA+1, which makes it exact or within a texel of the Euclidean nearest.
//!
//! Alpha is coverage: > 0 covered, <= 0 empty. After the pass, covered texels are unchanged,
//! every empty texel holds the rgb of the covered texel it copied and alpha = -d, d >= 1 its
//! distance in texels; alpha stays 0 only in a layer with no covered texel, which is left as
//! it was. Padding a padded image again changes nothing.

use super::compute::{per_texel, ComputePass, Slot};
use crate::shaders;
use crate::vk::{vk, Access, CommandRecorder, Context, Image, ImageDesc, Tracker, VkError, VkResult};
use std::sync::Arc;

/// The format of every atlas image (texel data laid out as the atlas: rgb a value, alpha the
/// coverage) that the padding fills.
pub const ATLAS_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const SEED_FORMAT: vk::Format = vk::Format::R32G32_SINT;

/// The modes of padding.comp.
const SEED: i32 = 0;
const JUMP: i32 = 1;
const RESOLVE: i32 = 2;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PaddingPush {
    mode: i32,
    step: i32,
}

pub struct PaddingPass {
    /// Set i writes `seeds[i]` and reads the other; dispatch t of the pass uses set t % 2.
    pass: ComputePass<PaddingPush>,
    _seeds: [Image; 2],
    groups: [u32; 3],
    size: u32,
}

impl PaddingPass {
    /// For `image`: an RGBA32F 2D-array image with storage usage, read and written through
    /// two seed images (8 bytes a texel each). Nothing is made per recording.
    pub fn new(ctx: &Arc<Context>, image: &Image) -> VkResult<PaddingPass> {
        let d = image.desc;
        if d.format != ATLAS_FORMAT || d.view_type != vk::ImageViewType::TYPE_2D_ARRAY || !d.usage.contains(vk::ImageUsageFlags::STORAGE) {
            return Err(VkError::Invalid(format!(
                "padding needs an RGBA32F 2D-array storage image; the image is {:?} {:?} with usage {:?}",
                d.format, d.view_type, d.usage
            )));
        }
        let seed_desc = ImageDesc { format: SEED_FORMAT, usage: vk::ImageUsageFlags::STORAGE, ..d };
        let seeds = [Image::new(ctx, "padding seeds 0", seed_desc)?, Image::new(ctx, "padding seeds 1", seed_desc)?];
        // The module statically uses all three images in every mode, and validation counts
        // each dispatch as using them all: the image as read and written (resolve stores to
        // it), the seeds as read and written through their bindings.
        let set = |write: usize| {
            [
                Slot::StorageImage(image, Access::ComputeStorageReadWrite),
                Slot::StorageImage(&seeds[1 - write], Access::ComputeStorageRead),
                Slot::StorageImage(&seeds[write], Access::ComputeStorageWrite),
            ]
        };
        let (set0, set1) = (set(0), set(1));
        let pass = ComputePass::with_sets(ctx, "padding", shaders::PADDING_COMP, &[&set0, &set1])?;
        Ok(PaddingPass { pass, groups: per_texel(image), size: d.width.max(d.height), _seeds: seeds })
    }

    /// Pads the image given to `new`. Cost: 3 + ceil(log2(max(width, height))) dispatches
    /// over every texel of every layer (seed, the jump steps, the extra k = 1 step,
    /// resolve), each jump reading 9 seeds a texel, with a barrier between consecutive
    /// dispatches. Allocates nothing.
    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker) {
        let jumps = jump_steps(self.size).map(|step| PaddingPush { mode: JUMP, step });
        let dispatches = std::iter::once(PaddingPush { mode: SEED, step: 0 })
            .chain(jumps)
            .chain(std::iter::once(PaddingPush { mode: RESOLVE, step: 0 }));
        for (t, push) in dispatches.enumerate() {
            self.pass.dispatch(rec, tracker, t % 2, &push, self.groups);
        }
    }
}

/// The jump lengths for an image whose longer side is `size`: the largest power of two below
/// `size`, halving down to 1, then 1 once more (JFA+1).
fn jump_steps(size: u32) -> impl Iterator<Item = i32> {
    let levels = u32::BITS - size.saturating_sub(1).leading_zeros();
    (0..levels).rev().map(|level| 1 << level).chain(std::iter::once(1))
}

#[cfg(test)]
mod tests {
    use super::jump_steps;

    #[test]
    fn jumps_start_below_the_longer_side_and_end_with_two_unit_steps() {
        let steps = |size| jump_steps(size).collect::<Vec<_>>();
        assert_eq!(steps(64), [32, 16, 8, 4, 2, 1, 1]);
        assert_eq!(steps(48), [32, 16, 8, 4, 2, 1, 1]);
        assert_eq!(steps(65), [64, 32, 16, 8, 4, 2, 1, 1]);
        assert_eq!(steps(2), [1, 1]);
        assert_eq!(steps(1), [1]);
    }
}
