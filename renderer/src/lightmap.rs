//! A baked lightmap on the GPU: an RGBA32F 2D-array image, one layer per atlas page, rgb the
//! value and alpha the coverage (> 0 covered by geometry, 0 empty), padded once at upload
//! (passes/padding.rs: empty texels then hold their nearest covered texel's rgb and alpha =
//! -distance in texels). Lighting passes read only rgb, through each vertex's uv1
//! (relume_bake::atlas: page = floor(u), the page's u = fract(u), v with row 0 at the top).

use crate::gpu_scene::{submit_once, upload_array_layers};
use crate::passes::padding::{PaddingPass, LIGHTMAP_FORMAT};
use crate::vk::{vk, Access, Buffer, CommandRecorder, Context, Image, ImageDesc, TimestampQueries, Tracker, VkError, VkResult};
use glam::Vec4;
use gpu_allocator::MemoryLocation;
use relume_bake::artifact::PageLayout;
use relume_bake::scene::Scene;

/// The longest side a lightmap may have: the padding shader's squared distances fit an i32.
pub const MAX_SIDE: u32 = 16384;

/// A lightmap as the renderer takes it: `pages` layers of `width` x `height` texels, page
/// after page, each row by row from the top (the order of relume_bake's atlas); rgb the
/// obscurance W, alpha the coverage (> 0 covered, 0 empty: padded at upload). From a bake
/// artifact: `LightmapData::new(baked.layout, &baked.lightmap_rgba())`, with the scene given
/// to the renderer re-indexed by `baked.apply_to(&mut scene)` first.
#[derive(Clone, Copy, Debug)]
pub struct LightmapData<'d> {
    pub width: u32,
    pub height: u32,
    pub pages: u32,
    pub texels: &'d [Vec4],
}

impl<'d> LightmapData<'d> {
    pub fn new(layout: PageLayout, texels: &'d [Vec4]) -> Self {
        LightmapData { width: layout.width, height: layout.height, pages: layout.pages, texels }
    }
}

/// Refuses a scene a lightmap of `pages` pages cannot light: every mesh needs a finite uv1 for
/// every vertex, on a page the lightmap has. The error names the mesh.
pub fn check_uv1(scene: &Scene, pages: u32) -> VkResult<()> {
    let with_uv1 = scene.meshes.iter().filter(|m| m.uv1.is_some()).count();
    for (index, mesh) in scene.meshes.iter().enumerate() {
        let name = format!("{}: mesh {index} \"{}\"", scene.source.display(), mesh.name);
        let Some(uv1) = &mesh.uv1 else {
            return Err(VkError::Invalid(format!(
                "{name} has no uv1 ({with_uv1} of {} meshes have one); a lightmap needs every mesh's uv1: apply the bake artifact to the scene (Baked::apply_to) before giving both to the renderer",
                scene.meshes.len()
            )));
        };
        if uv1.len() != mesh.positions.len() {
            return Err(VkError::Invalid(format!("{name} has {} uv1 values for {} vertices", uv1.len(), mesh.positions.len())));
        }
        let off_atlas = uv1.iter().position(|uv| !(uv.is_finite() && uv.x >= 0.0 && uv.x.floor() < pages as f32));
        if let Some(v) = off_atlas {
            return Err(VkError::Invalid(format!(
                "{name}: vertex {v} has uv1 {}, not on one of the lightmap's {pages} pages (u in [0, {pages})); was the lightmap baked for this scene?",
                uv1[v]
            )));
        }
    }
    Ok(())
}

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
        let image = Image::new(
            ctx,
            "lightmap",
            ImageDesc { width, height, layers, format: LIGHTMAP_FORMAT, usage, view_type: vk::ImageViewType::TYPE_2D_ARRAY },
        )?;
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
        let buffer =
            Buffer::new(self.ctx, "lightmap readback", count as u64 * 16, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu)?;
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
