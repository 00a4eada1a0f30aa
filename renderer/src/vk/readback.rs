//! The one way relume reads GPU data back: a host-visible buffer sized for an image or a
//! buffer, the copy into it recorded after the data's last use (declared to the tracker), and
//! the bytes once the submission that copied them has completed.

use super::{Access, Buffer, CommandRecorder, Context, Image, Tracker, VkError, VkResult};
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub struct Readback {
    buffer: Buffer,
    len: u64,
}

impl Readback {
    /// Room for every texel of `image` (all layers, tightly packed).
    pub fn for_image(ctx: &Arc<Context>, name: &str, image: &Image) -> VkResult<Readback> {
        Readback::new(ctx, name, image.desc.texel_count() * image.desc.texel_bytes())
    }

    /// Room for the first `len` bytes of a buffer.
    pub fn new(ctx: &Arc<Context>, name: &str, len: u64) -> VkResult<Readback> {
        let buffer = Buffer::new(ctx, name, len, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu)?;
        Ok(Readback { buffer, len })
    }

    /// Records the copy of `image` (the one this readback was sized for) after its last use.
    pub fn record_image(&self, rec: &CommandRecorder, tracker: &mut Tracker, image: &Image) {
        tracker.use_image(rec, image, Access::TransferSource);
        rec.copy_image_to_buffer(image, self.buffer.raw);
        rec.transfer_to_host_barrier();
    }

    /// Records the copy of the first `len` bytes of `buffer` after its last use.
    pub fn record_buffer(&self, rec: &CommandRecorder, tracker: &mut Tracker, buffer: &Buffer) {
        tracker.use_buffer(rec, buffer, Access::TransferSource);
        rec.copy_buffer(buffer.raw, 0, self.buffer.raw, self.len);
        rec.transfer_to_host_barrier();
    }

    /// The bytes, once the submission that recorded the copy has completed.
    pub fn bytes(&self) -> VkResult<&[u8]> {
        self.buffer.mapped_bytes(self.len as usize)
    }

    /// The bytes as f32 values (every format relume reads back as floats is f32).
    pub fn floats(&self) -> VkResult<&[f32]> {
        bytemuck::try_cast_slice(self.bytes()?).map_err(|e| VkError::Invalid(format!("readback is not f32 data: {e}")))
    }
}
