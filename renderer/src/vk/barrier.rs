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
    /// A storage buffer read by the vertex and fragment stages (a lighting pass's vertex term).
    GraphicsStorageRead,
    /// Read and written by one dispatch (or by a shader that could write it, which is how
    /// synchronization validation counts every dispatch of a module that stores to it).
    ComputeStorageReadWrite,
    TransferSource,
    TransferDestination,
}

/// Where an image stands between two uses: the pipeline stages and memory accesses of its last
/// use, and its layout. What a caller hands relume with its own image, and what relume hands
/// back (see `Renderer::record_to`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageState {
    pub stage: vk::PipelineStageFlags2,
    pub access: vk::AccessFlags2,
    pub layout: vk::ImageLayout,
}

impl Access {
    /// The stages, accesses and layout of this use.
    pub fn state(self) -> ImageState {
        let (stage, access, layout) = self.stage_access_layout();
        ImageState { stage, access, layout }
    }

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
            Access::GraphicsStorageRead => (S::VERTEX_SHADER | S::FRAGMENT_SHADER, A::SHADER_STORAGE_READ, L::GENERAL),
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
                | Access::GraphicsStorageRead
                | Access::TransferSource
                | Access::TransferDestination
        )
    }
}

/// An image as barriers name it: its handle and the range they cover (every layer).
#[derive(Clone, Copy, Debug)]
pub struct ImageRef {
    pub raw: vk::Image,
    pub range: vk::ImageSubresourceRange,
}

impl From<&Image> for ImageRef {
    fn from(image: &Image) -> Self {
        ImageRef { raw: image.raw, range: image.desc.all_layers() }
    }
}

/// A buffer as barriers name it (the whole buffer).
#[derive(Clone, Copy, Debug)]
pub struct BufferRef {
    pub raw: vk::Buffer,
}

impl From<&Buffer> for BufferRef {
    fn from(buffer: &Buffer) -> Self {
        BufferRef { raw: buffer.raw }
    }
}

/// A resource a pass reads or writes and how: what the pass declares to the tracker before
/// it runs.
#[derive(Clone, Copy, Debug)]
pub enum Use {
    Buffer(BufferRef, Access),
    Image(ImageRef, Access),
}

impl Use {
    pub fn image(image: impl Into<ImageRef>, access: Access) -> Use {
        Use::Image(image.into(), access)
    }

    pub fn buffer(buffer: impl Into<BufferRef>, access: Access) -> Use {
        Use::Buffer(buffer.into(), access)
    }
}

/// The last known use of every image and buffer a frame touches.
#[derive(Default)]
pub struct Tracker {
    last: HashMap<vk::Image, Access>,
    last_buffers: HashMap<vk::Buffer, Access>,
}

impl Tracker {
    /// How `image` was last used: what the frame leaves it in.
    pub fn state(&self, image: impl Into<ImageRef>) -> Access {
        self.last.get(&image.into().raw).copied().unwrap_or(Access::Undefined)
    }

    /// Takes `access` as the last use of `image`, made by work outside this tracker that has
    /// completed or comes earlier in submission order (an upload), so that the next use
    /// here keeps its contents instead of transitioning from UNDEFINED.
    pub fn assume(&mut self, image: impl Into<ImageRef>, access: Access) {
        self.set(image.into().raw, access);
    }

    /// Records a pass: the barriers that bring every resource of `uses` into its access,
    /// derived from how each was last used, then `commands`. Outside the backend this is the
    /// one way a barrier is recorded: a pass declares its uses and never writes one by hand.
    pub fn pass(&mut self, rec: &CommandRecorder, uses: impl IntoIterator<Item = Use>, commands: impl FnOnce(&CommandRecorder)) {
        self.declare(rec, uses);
        commands(rec);
    }

    /// Brings every resource of `uses` into its access.
    fn declare(&mut self, rec: &CommandRecorder, uses: impl IntoIterator<Item = Use>) {
        for used in uses {
            match used {
                Use::Buffer(buffer, access) => self.use_buffer(rec, buffer, access),
                Use::Image(image, access) => self.use_image(rec, image, access),
            }
        }
    }

    /// Records the barrier that makes `buffer` ready for `next` (a storage or transfer use):
    /// after a write, and before a write that follows a read (write-after-read, also across
    /// frames recorded with the same tracker); none between two reads of the same kind, nor
    /// for a first use.
    pub(super) fn use_buffer(&mut self, rec: &CommandRecorder, buffer: impl Into<BufferRef>, next: Access) {
        debug_assert!(next.is_buffer_access(), "{next:?} is not a way to use a buffer");
        let raw = buffer.into().raw;
        let previous = match self.last_buffers.get_mut(&raw) {
            Some(last) => std::mem::replace(last, next),
            None => {
                self.last_buffers.insert(raw, next);
                Access::Undefined
            }
        };
        if previous == Access::Undefined || (previous == next && !next.writes()) {
            return;
        }
        let (src, dst) = (previous.state(), next.state());
        let barrier = vk::BufferMemoryBarrier2::default()
            .src_stage_mask(src.stage)
            .src_access_mask(src.access)
            .dst_stage_mask(dst.stage)
            .dst_access_mask(dst.access)
            .buffer(raw)
            .size(vk::WHOLE_SIZE);
        rec.buffer_barrier(barrier);
    }

    /// Records the barrier that makes `image` ready for `next`.
    pub(super) fn use_image(&mut self, rec: &CommandRecorder, image: impl Into<ImageRef>, next: Access) {
        let image = image.into();
        let previous = self.state(image);
        self.set(image.raw, next);
        if previous == next && !next.writes() {
            return;
        }
        transition(rec, image, previous.state(), next);
    }

    /// Updates a known image in place: `HashMap::insert` reserves room for one more entry
    /// before it looks for the key, so on a full table even a replacing insert grows it (an
    /// allocation in a frame loop whose images are all known already).
    fn set(&mut self, raw: vk::Image, access: Access) {
        match self.last.get_mut(&raw) {
            Some(last) => *last = access,
            None => {
                self.last.insert(raw, access);
            }
        }
    }
}

/// Records the barrier that takes `image` from `from` (as its owner says it stands) to
/// `next`; returns the state it is left in. For images no tracker knows (a caller's).
pub fn transition(rec: &CommandRecorder, image: ImageRef, from: ImageState, next: Access) -> ImageState {
    let to = next.state();
    barrier_between(rec, image, from, to);
    to
}

/// Records the barrier that takes `image` from one state to another, for uses relume's
/// `Access` does not name (a caller's blit, presentation).
pub fn barrier_between(rec: &CommandRecorder, image: ImageRef, from: ImageState, to: ImageState) {
    let barrier = vk::ImageMemoryBarrier2::default()
        .src_stage_mask(from.stage)
        .src_access_mask(from.access)
        .dst_stage_mask(to.stage)
        .dst_access_mask(to.access)
        .old_layout(from.layout)
        .new_layout(to.layout)
        .image(image.raw)
        .subresource_range(image.range);
    rec.image_barrier(barrier);
}
