//! The one place barriers come from. Passes declare how they are about to use each image or
//! buffer (`Access`); the tracker knows how each was last used and records the barrier
//! between the two, or none for a read after a read (in the same layout, for images).

use super::{Buffer, CommandRecorder, Image};
use ash::vk;
use std::collections::HashMap;

/// How a pass uses an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Never used yet (or its contents may be discarded).
    Undefined,
    ColorAttachmentWrite,
    DepthAttachmentWrite,
    FragmentSampled,
    /// Sampled (texture reads) by a compute shader.
    ComputeSampled,
    ComputeStorageRead,
    ComputeStorageWrite,
    /// Read and written by one dispatch (or by a shader that could write it, which is how
    /// synchronization validation counts every dispatch of a module that stores to it).
    ComputeStorageReadWrite,
    TransferSource,
    TransferDestination,
}

impl Access {
    fn stage_access_layout(self) -> (vk::PipelineStageFlags2, vk::AccessFlags2, vk::ImageLayout) {
        use vk::{AccessFlags2 as A, ImageLayout as L, PipelineStageFlags2 as S};
        match self {
            Access::Undefined => (S::NONE, A::NONE, L::UNDEFINED),
            Access::ColorAttachmentWrite => (S::COLOR_ATTACHMENT_OUTPUT, A::COLOR_ATTACHMENT_WRITE, L::COLOR_ATTACHMENT_OPTIMAL),
            Access::DepthAttachmentWrite => (
                S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
                A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE,
                L::DEPTH_ATTACHMENT_OPTIMAL,
            ),
            Access::FragmentSampled => (S::FRAGMENT_SHADER, A::SHADER_SAMPLED_READ, L::SHADER_READ_ONLY_OPTIMAL),
            Access::ComputeSampled => (S::COMPUTE_SHADER, A::SHADER_SAMPLED_READ, L::SHADER_READ_ONLY_OPTIMAL),
            Access::ComputeStorageRead => (S::COMPUTE_SHADER, A::SHADER_STORAGE_READ, L::GENERAL),
            Access::ComputeStorageWrite => (S::COMPUTE_SHADER, A::SHADER_STORAGE_WRITE, L::GENERAL),
            Access::ComputeStorageReadWrite => (S::COMPUTE_SHADER, A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE, L::GENERAL),
            Access::TransferSource => (S::COPY, A::TRANSFER_READ, L::TRANSFER_SRC_OPTIMAL),
            Access::TransferDestination => (S::COPY, A::TRANSFER_WRITE, L::TRANSFER_DST_OPTIMAL),
        }
    }

    fn writes(self) -> bool {
        matches!(
            self,
            Access::ColorAttachmentWrite
                | Access::DepthAttachmentWrite
                | Access::ComputeStorageWrite
                | Access::ComputeStorageReadWrite
                | Access::TransferDestination
        )
    }

    /// Whether a buffer can be used this way (attachments and sampling are for images only).
    fn is_buffer_access(self) -> bool {
        matches!(
            self,
            Access::ComputeStorageRead
                | Access::ComputeStorageWrite
                | Access::ComputeStorageReadWrite
                | Access::TransferSource
                | Access::TransferDestination
        )
    }
}

/// The last known use of every image and buffer a frame touches.
#[derive(Default)]
pub struct Tracker {
    last: HashMap<vk::Image, Access>,
    last_buffers: HashMap<vk::Buffer, Access>,
}

impl Tracker {
    /// How `image` was last used: what the frame leaves it in, for the caller.
    pub fn state(&self, image: &Image) -> Access {
        self.last.get(&image.raw).copied().unwrap_or(Access::Undefined)
    }

    /// Takes `access` as the last use of `image`, made by work outside this tracker that has
    /// completed or comes earlier in submission order (an upload), so that the next use
    /// here keeps its contents instead of transitioning from UNDEFINED.
    pub fn assume(&mut self, image: &Image, access: Access) {
        self.set(image, access);
    }

    /// How `buffer` was last used (Undefined: not yet, as far as this tracker knows).
    pub fn buffer_state(&self, buffer: &Buffer) -> Access {
        self.last_buffers.get(&buffer.raw).copied().unwrap_or(Access::Undefined)
    }

    /// Records the barrier that makes `buffer` ready for `next` (a storage or transfer use):
    /// after a write, and before a write that follows a read (write-after-read, also across
    /// frames recorded with the same tracker); none between two reads of the same kind, nor
    /// for a first use.
    pub fn use_buffer(&mut self, rec: &CommandRecorder, buffer: &Buffer, next: Access) {
        debug_assert!(next.is_buffer_access(), "{next:?} is not a way to use a buffer");
        let previous = match self.last_buffers.get_mut(&buffer.raw) {
            Some(last) => std::mem::replace(last, next),
            None => {
                self.last_buffers.insert(buffer.raw, next);
                Access::Undefined
            }
        };
        if previous == Access::Undefined || (previous == next && !next.writes()) {
            return;
        }
        let (src_stage, src_access, _) = previous.stage_access_layout();
        let (dst_stage, dst_access, _) = next.stage_access_layout();
        let barrier = vk::BufferMemoryBarrier2::default()
            .src_stage_mask(src_stage)
            .src_access_mask(src_access)
            .dst_stage_mask(dst_stage)
            .dst_access_mask(dst_access)
            .buffer(buffer.raw)
            .size(vk::WHOLE_SIZE);
        rec.buffer_barrier(barrier);
    }

    /// Records the barrier that makes `image` ready for `next`.
    pub fn use_image(&mut self, rec: &CommandRecorder, image: &Image, next: Access) {
        let previous = self.state(image);
        self.set(image, next);
        if previous == next && !next.writes() {
            return;
        }
        let (src_stage, src_access, old_layout) = previous.stage_access_layout();
        let (dst_stage, dst_access, new_layout) = next.stage_access_layout();
        let barrier = vk::ImageMemoryBarrier2::default()
            .src_stage_mask(src_stage)
            .src_access_mask(src_access)
            .dst_stage_mask(dst_stage)
            .dst_access_mask(dst_access)
            .old_layout(old_layout)
            .new_layout(new_layout)
            .image(image.raw)
            .subresource_range(image.desc.all_layers());
        rec.image_barrier(barrier);
    }

    /// Updates a known image in place: `HashMap::insert` reserves room for one more entry
    /// before it looks for the key, so on a full table even a replacing insert grows it (an
    /// allocation in a frame loop whose images are all known already).
    fn set(&mut self, image: &Image, access: Access) {
        match self.last.get_mut(&image.raw) {
            Some(last) => *last = access,
            None => {
                self.last.insert(image.raw, access);
            }
        }
    }
}
