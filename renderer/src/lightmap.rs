//! A baked lightmap on the GPU: an RGBA32F 2D-array image, one layer per atlas page, rgb the
//! value and alpha the coverage (> 0 covered by geometry, 0 empty), padded once at upload
//! (passes/padding.rs: empty texels then hold their nearest covered texel's rgb and alpha =
//! -distance in texels). Lighting passes read only rgb.

use crate::gpu_scene::{submit_once, upload_array_layers};
use crate::passes::padding::{PaddingPass, LIGHTMAP_FORMAT};
use crate::vk::{vk, Access, Buffer, CommandRecorder, Context, Image, ImageDesc, TimestampQueries, Tracker, VkError, VkResult};
use glam::Vec4;
use gpu_allocator::MemoryLocation;

/// The longest side a lightmap may have: the padding shader's squared distances fit an i32.
pub const MAX_SIDE: u32 = 16384;

pub struct GpuLightmap<'a> {
    ctx: &'a Context,
    padding: PaddingPass<'a>,
    pub image: Image<'a>,
    padding_ms: Option<f64>,
}

impl<'a> GpuLightmap<'a> {
    /// Uploads `texels` (layer after layer, each row by row from the top, left to right) and
    /// pads every layer, in one submission that is waited for; the image is then ready for
    /// FragmentSampled reads (see [`GpuLightmap::register_state`]).
    pub fn upload(ctx: &'a Context, width: u32, height: u32, layers: u32, texels: &[Vec4]) -> VkResult<Self> {
        check_size(width, height, layers, texels.len())?;
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::TRANSFER_DST
            | vk::ImageUsageFlags::TRANSFER_SRC;
        let image = Image::new(ctx, "lightmap", ImageDesc {
            width,
            height,
            layers,
            format: LIGHTMAP_FORMAT,
            usage,
            view_type: vk::ImageViewType::TYPE_2D_ARRAY,
        })?;
        let mut lightmap = GpuLightmap { ctx, padding: PaddingPass::new(ctx, &image)?, image, padding_ms: None };
        let queries = TimestampQueries::new(ctx)?;
        let extents = vec![lightmap.image.desc.extent(); layers as usize];
        upload_array_layers(ctx, &lightmap.image, texels, &extents, |rec, tracker| {
            let timestamp = |i| {
                if let Some(q) = &queries {
                    q.write(rec, i)
                }
            };
            if let Some(q) = &queries {
                q.reset(rec);
            }
            timestamp(0);
            lightmap.record_padding(rec, tracker);
            timestamp(1);
        })?;
        lightmap.padding_ms = queries.map(|q| q.read_ms().map(|[start, end]: [f64; 2]| end - start)).transpose()?;
        Ok(lightmap)
    }

    /// Records the padding pass over the image (see passes/padding.rs for what it reads,
    /// writes and costs): `upload` runs it once; a pass that writes new texels into the
    /// image on the GPU runs it again, with a tracker that knows the image's state.
    pub fn record_padding(&self, rec: &CommandRecorder, tracker: &mut Tracker) {
        self.padding.record(rec, tracker, &self.image);
    }

    /// Tells a frame's tracker that the image is ready for FragmentSampled reads, as the
    /// upload left it; without this the frame's first use would transition it from
    /// UNDEFINED and discard the texels.
    pub fn register_state(&self, tracker: &mut Tracker) {
        tracker.assume(&self.image, Access::FragmentSampled);
    }

    /// GPU time of the padding at upload, in milliseconds (None without timestamps).
    pub fn padding_ms(&self) -> Option<f64> {
        self.padding_ms
    }

    /// Every texel, in the order `upload` takes them, through a one-time submission that is
    /// waited for (for tests and tools: no pending work may use the image). The image is left
    /// ready for FragmentSampled reads, as it was.
    pub fn read_back(&self) -> VkResult<Vec<Vec4>> {
        let d = self.image.desc;
        let count = d.width as usize * d.height as usize * d.layers as usize;
        let buffer = Buffer::new(self.ctx, "lightmap readback", count as u64 * 16, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu)?;
        submit_once(self.ctx, |rec, tracker| {
            self.register_state(tracker);
            tracker.use_image(rec, &self.image, Access::TransferSource);
            rec.copy_image_to_buffer(&self.image, buffer.raw);
            rec.transfer_to_host_barrier();
            tracker.use_image(rec, &self.image, Access::FragmentSampled);
        })?;
        let floats: &[f32] = bytemuck::try_cast_slice(buffer.mapped_bytes(count * 16)?)
            .map_err(|e| VkError::Invalid(format!("lightmap readback is not f32 data: {e}")))?;
        Ok(floats.chunks_exact(4).map(Vec4::from_slice).collect())
    }
}

fn check_size(width: u32, height: u32, layers: u32, texel_count: usize) -> VkResult<()> {
    if width == 0 || height == 0 || layers == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(VkError::Invalid(format!(
            "a lightmap of {width}x{height} texels and {layers} layers is impossible: sides must be 1..={MAX_SIDE}, layers at least 1"
        )));
    }
    let expected = width as u64 * height as u64 * layers as u64;
    if texel_count as u64 != expected {
        return Err(VkError::Invalid(format!(
            "a lightmap of {width}x{height} texels and {layers} layers needs {expected} texels; {texel_count} were given"
        )));
    }
    Ok(())
}
