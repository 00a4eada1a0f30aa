//! One-time submissions: what creation uploads, and read-backs outside the frame. Each
//! records into a command buffer of its own, submits it on the context's queue and waits for
//! its own fence (never the device); every function here says so in its name (`_blocking`),
//! and none runs in a frame.

use crate::vk::{vk, Access, Buffer, CommandBuffer, CommandRecorder, Context, Fence, Image, Tracker, Use, VkError, VkResult};
use glam::Vec4;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// Records `work` with a fresh tracker, submits it and waits for its fence.
pub fn submit_blocking(ctx: &Arc<Context>, work: impl FnOnce(&CommandRecorder, &mut Tracker)) -> VkResult<()> {
    let cmd = CommandBuffer::new(ctx)?;
    let fence = Fence::new(ctx)?;
    let rec = ctx.begin(cmd.raw)?;
    work(&rec, &mut Tracker::default());
    ctx.submit_and_wait(rec, &fence)
}

/// Fills the top-left extent of layer i of an RGBA32F array image from `layers[i]` (its
/// texels, tightly packed, and its extent) through one staging buffer, records `then` (with
/// the image in TransferDestination), and leaves the image ready for FragmentSampled reads;
/// one submission, waited for.
pub fn upload_array_layers_blocking(
    ctx: &Arc<Context>,
    image: &Image,
    layers: &[(&[Vec4], vk::Extent2D)],
    then: impl FnOnce(&CommandRecorder, &mut Tracker),
) -> VkResult<()> {
    let area = |e: &vk::Extent2D| e.width as u64 * e.height as u64;
    if let Some((layer, (texels, extent))) = layers.iter().enumerate().find(|(_, (t, e))| t.len() as u64 != area(e)) {
        return Err(VkError::Invalid(format!("{} texels given for layer {layer} of {}x{}", texels.len(), extent.width, extent.height)));
    }
    let total: usize = layers.iter().map(|(texels, _)| std::mem::size_of_val(*texels)).sum();
    let staging = Buffer::new(ctx, "upload staging", total as u64, vk::BufferUsageFlags::TRANSFER_SRC, MemoryLocation::CpuToGpu)?;
    let mut offset = 0;
    for (texels, _) in layers {
        staging.write_at(offset, texels)?;
        offset += std::mem::size_of_val(*texels);
    }
    submit_blocking(ctx, |rec, tracker| {
        tracker.pass(rec, [Use::image(image, Access::TransferDestination)], |rec| {
            let mut offset = 0;
            for (layer, (_, extent)) in layers.iter().enumerate() {
                rec.copy_buffer_to_image_layer(staging.raw, offset, image, layer as u32, *extent);
                offset += area(extent) * 16;
            }
        });
        then(rec, tracker);
        tracker.pass(rec, [Use::image(image, Access::FragmentSampled)], |_| {});
    })
}

/// Device-local storage buffers holding `sources` (name, bytes), filled through one staging
/// buffer and one submission, waited for; they are then ready for compute-shader reads (and
/// may be read back: a technique's passes may write one it uploaded with its first contents).
pub fn upload_buffers_blocking<const N: usize>(ctx: &Arc<Context>, sources: [(&str, &[u8]); N]) -> VkResult<[Buffer; N]> {
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC;
    let made = sources
        .iter()
        .map(|(name, bytes)| Buffer::new(ctx, name, bytes.len() as u64, usage, MemoryLocation::GpuOnly))
        .collect::<VkResult<Vec<_>>>()?;
    let Ok(buffers) = <[Buffer; N]>::try_from(made) else { unreachable!("one buffer per source") };
    let total: usize = sources.iter().map(|(_, bytes)| bytes.len()).sum();
    let staging = Buffer::new(ctx, "upload staging", total as u64, vk::BufferUsageFlags::TRANSFER_SRC, MemoryLocation::CpuToGpu)?;
    let mut offset = 0;
    for (_, bytes) in sources {
        staging.write_at(offset, bytes)?;
        offset += bytes.len();
    }
    submit_blocking(ctx, |rec, tracker| {
        let mut offset = 0u64;
        for (buffer, (_, bytes)) in buffers.iter().zip(sources) {
            if !bytes.is_empty() {
                tracker.pass(rec, [Use::buffer(buffer, Access::TransferDestination)], |rec| {
                    rec.copy_buffer(staging.raw, offset, buffer.raw, bytes.len() as u64)
                });
                tracker.pass(rec, [Use::buffer(buffer, Access::ComputeStorageRead)], |_| {});
            }
            offset += bytes.len() as u64;
        }
    })?;
    Ok(buffers)
}
