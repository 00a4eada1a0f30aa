//! Texel data laid out as the lightmap atlas (relume_bake::atlas), on the GPU: an RGBA32F
//! 2D-array image, one layer per atlas page, rgb the value and alpha the coverage (> 0
//! covered by geometry, 0 empty), padded once at upload (passes/padding.rs: empty texels then
//! hold their nearest covered texel's rgb and alpha = -distance in texels). Lighting reads
//! only rgb, through each vertex's uv1 (page = floor(u), the page's u = fract(u), v with row
//! 0 at the top). Techniques with a texel term (the obscurance, the light path maps' coverage)
//! are built on it.

use crate::passes::padding::{PaddingPass, ATLAS_FORMAT};
use crate::upload::{submit_blocking, upload_array_layers_blocking};
use crate::vk::{vk, Access, Context, Image, ImageDesc, Readback, TimestampQueries, Tracker, Use, VkError, VkResult};
use glam::Vec4;
use relume_bake::artifact::PageLayout;
use relume_bake::scene::Scene;
use std::sync::Arc;

/// The longest side an atlas image may have: the padding shader's squared distances fit an i32.
pub const MAX_SIDE: u32 = 16384;

/// Texel data on the atlas as the renderer takes it: `pages` layers of `width` x `height`
/// texels, page after page, each row by row from the top (the order of relume_bake's atlas);
/// rgb the value, alpha the coverage (> 0 covered, 0 empty: padded at upload). The scene
/// given to the renderer must carry the atlas's uv1 (`apply_to` of the artifact's atlas).
#[derive(Clone, Copy, Debug)]
pub struct AtlasImage<'d> {
    pub width: u32,
    pub height: u32,
    pub pages: u32,
    pub texels: &'d [Vec4],
}

impl<'d> AtlasImage<'d> {
    pub fn new(layout: PageLayout, texels: &'d [Vec4]) -> Self {
        AtlasImage { width: layout.width, height: layout.height, pages: layout.pages, texels }
    }
}

/// Refuses a scene an atlas of `pages` pages cannot be read through: every mesh needs a finite
/// uv1 for every vertex, on a page the atlas has. The error names the mesh.
pub fn check_uv1(scene: &Scene, pages: u32) -> VkResult<()> {
    let with_uv1 = scene.meshes.iter().filter(|m| m.uv1.is_some()).count();
    for (index, mesh) in scene.meshes.iter().enumerate() {
        let name = format!("{}: mesh {index} \"{}\"", scene.source.display(), mesh.name);
        let Some(uv1) = &mesh.uv1 else {
            return Err(VkError::Invalid(format!(
                "{name} has no uv1 ({with_uv1} of {} meshes have one); a texel term needs every mesh's uv1: apply the bake artifact's atlas to the scene before giving both to the renderer",
                scene.meshes.len()
            )));
        };
        if uv1.len() != mesh.positions.len() {
            return Err(VkError::Invalid(format!("{name} has {} uv1 values for {} vertices", uv1.len(), mesh.positions.len())));
        }
        let off_atlas = uv1.iter().position(|uv| !(uv.is_finite() && uv.x >= 0.0 && uv.x.floor() < pages as f32));
        if let Some(v) = off_atlas {
            return Err(VkError::Invalid(format!(
                "{name}: vertex {v} has uv1 {}, not on one of the atlas's {pages} pages (u in [0, {pages})); was it baked for this scene?",
                uv1[v]
            )));
        }
    }
    Ok(())
}

/// An atlas image uploaded and padded.
pub struct GpuAtlasImage {
    ctx: Arc<Context>,
    pub image: Image,
    padding_ms: Option<f64>,
}

impl GpuAtlasImage {
    /// Uploads `data` and pads every layer, in one submission that is waited for; the image
    /// is then ready for FragmentSampled reads (see [`GpuAtlasImage::register_state`]).
    pub fn upload_blocking(ctx: &Arc<Context>, name: &str, data: &AtlasImage) -> VkResult<Self> {
        check_size(data)?;
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::TRANSFER_DST
            | vk::ImageUsageFlags::TRANSFER_SRC;
        let desc = ImageDesc {
            width: data.width,
            height: data.height,
            layers: data.pages,
            format: ATLAS_FORMAT,
            usage,
            view_type: vk::ImageViewType::TYPE_2D_ARRAY,
        };
        let image = Image::new(ctx, name, desc)?;
        let padding = PaddingPass::new(ctx, &image)?;
        let queries = TimestampQueries::new(ctx)?;
        let extent = image.desc.extent();
        let layers: Vec<_> = data.texels.chunks_exact(data.width as usize * data.height as usize).map(|page| (page, extent)).collect();
        upload_array_layers_blocking(ctx, &image, &layers, |rec, tracker| {
            if let Some(q) = &queries {
                q.reset(rec);
                q.write(rec, 0);
            }
            padding.record(rec, tracker);
            if let Some(q) = &queries {
                q.write(rec, 1);
            }
        })?;
        let padding_ms = match &queries {
            Some(q) => {
                let mut stamps = [0.0; 2];
                q.read_ms(&mut stamps)?;
                Some(stamps[1] - stamps[0])
            }
            None => None,
        };
        Ok(GpuAtlasImage { ctx: Arc::clone(ctx), image, padding_ms })
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

    /// Every texel, in the order `upload_blocking` takes them, through a one-time submission
    /// that is waited for (for tests and tools: no pending work may use the image). The image
    /// is left ready for FragmentSampled reads, as it was.
    pub fn read_back_blocking(&self) -> VkResult<Vec<Vec4>> {
        let readback = Readback::for_image(&self.ctx, "atlas image readback", &self.image)?;
        submit_blocking(&self.ctx, |rec, tracker| {
            self.register_state(tracker);
            readback.record_image(rec, tracker, &self.image);
            tracker.pass(rec, [Use::image(&self.image, Access::FragmentSampled)], |_| {});
        })?;
        Ok(readback.floats()?.chunks_exact(4).map(Vec4::from_slice).collect())
    }
}

fn check_size(data: &AtlasImage) -> VkResult<()> {
    let (width, height, layers) = (data.width, data.height, data.pages);
    if width == 0 || height == 0 || layers == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(VkError::Invalid(format!(
            "an atlas image of {width}x{height} texels and {layers} layers is impossible: sides must be 1..={MAX_SIDE}, layers at least 1"
        )));
    }
    let expected = width as u64 * height as u64 * layers as u64;
    if data.texels.len() as u64 != expected {
        return Err(VkError::Invalid(format!(
            "an atlas image of {width}x{height} texels and {layers} layers needs {expected} texels; {} were given",
            data.texels.len()
        )));
    }
    Ok(())
}
