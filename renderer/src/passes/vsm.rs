//! Variance shadow maps, moments pass (000 §3.4): every shadow layer of every light renders
//! the scene's depth from the light and stores its first two moments in a layer of one
//! RG32F array image.

use crate::gpu_scene::{vertex_attributes, GpuScene, VERTEX_STRIDE};
use crate::shaders;
use crate::vk::{
    vk, Access, Binding, CommandRecorder, Context, DescriptorSet, GraphicsPipelineDesc, Image, ImageDesc, ImageView, Pipeline, Tracker,
    VkResult,
};
use std::sync::Arc;

pub const MOMENTS_FORMAT: vk::Format = vk::Format::R32G32_SFLOAT;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct VsmPush {
    light: u32,
    layer: u32,
}

pub struct VsmPass {
    pipeline: Pipeline,
    descriptors: DescriptorSet,
    layer_views: Vec<ImageView>,
    /// The moments of every layer; the blur pass, the lighting pass and techniques' passes (light path maps' entry irradiance) read it.
    pub moments: Image,
    depth: Image,
}

impl VsmPass {
    pub(crate) fn new(ctx: &Arc<Context>, scene: &GpuScene, size: u32) -> VkResult<VsmPass> {
        let layers = scene.shadow_views.len().max(1) as u32;
        let moments = Image::new(
            ctx,
            "vsm moments",
            ImageDesc {
                width: size,
                height: size,
                layers,
                format: MOMENTS_FORMAT,
                usage: vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED,
                view_type: vk::ImageViewType::TYPE_2D_ARRAY,
            },
        )?;
        let depth = Image::new(
            ctx,
            "vsm depth",
            ImageDesc {
                width: size,
                height: size,
                layers: 1,
                format: vk::Format::D32_SFLOAT,
                usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
                view_type: vk::ImageViewType::TYPE_2D,
            },
        )?;
        let layer_views = (0..layers).map(|l| moments.layer_view(l)).collect::<VkResult<Vec<_>>>()?;
        let descriptors = DescriptorSet::new(
            ctx,
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            &[Binding::StorageBuffer(scene.lights.raw), Binding::StorageBuffer(scene.layers.raw)],
        )?;
        let pipeline = Pipeline::graphics(
            ctx,
            &GraphicsPipelineDesc {
                vertex: shaders::VSM_MOMENTS_VERT,
                fragment: shaders::VSM_MOMENTS_FRAG,
                specialization: &[],
                vertex_stride: VERTEX_STRIDE,
                attributes: &vertex_attributes()[..1],
                color_formats: &[MOMENTS_FORMAT],
                depth_format: vk::Format::D32_SFLOAT,
                // Both faces: an occluder's back faces are what a closed mesh shows the light.
                cull_mode: vk::CullModeFlags::NONE,
                set_layout: descriptors.layout,
                push_bytes: std::mem::size_of::<VsmPush>() as u32,
            },
        )?;
        Ok(VsmPass { pipeline, descriptors, moments, depth, layer_views })
    }

    /// Writes: `moments` (colour attachment), its depth buffer. Reads: scene buffers.
    /// Texels no geometry covers keep the layer's far depth: nothing occludes there.
    pub(crate) fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, scene: &GpuScene) {
        rec.bind_graphics(self.pipeline.raw, self.pipeline.layout, self.descriptors.set);
        for view in &scene.shadow_views {
            tracker.use_image(rec, &self.moments, Access::ColorAttachmentWrite);
            tracker.use_image(rec, &self.depth, Access::DepthAttachmentWrite);
            rec.push_constants(self.pipeline.layout, &VsmPush { light: view.light, layer: view.layer });
            let clear = [view.far, view.far * view.far, 0.0, 0.0];
            rec.begin_rendering(self.moments.desc.extent(), [self.layer_views[view.layer as usize].raw], clear, self.depth.view);
            rec.bind_geometry(scene.vertices.raw, scene.indices.raw);
            rec.draw_indexed(0, scene.index_count);
            rec.end_rendering();
        }
    }
}
