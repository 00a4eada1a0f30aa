//! FIV's surfaces pass (graphics): every pixel's world position (alpha 1 where a surface is)
//! and interpolated normal, rasterised as the lighting pass rasterises (the same position
//! expression from the same buffers), so the occluder sums cover the pixels the lighting
//! pass shades (the GPU test checks the lighting pass's pixels against this pass's).
//!
//! Reads: the scene's vertex and index buffers and the frame's uniforms. Writes: `positions`
//! (xyz, w 1 on a surface) and `normals` (unit, towards the viewer; w the occluder the
//! surface belongs to plus one, 0 for none), colour attachments cleared to 0, and its own
//! depth. Cost: one draw per mesh (the push constant names its occluder).

use crate::gpu_scene::{vertex_attributes, VERTEX_STRIDE};
use crate::passes::lighting::DEPTH_FORMAT;
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{vk, Access, Binding, CommandRecorder, DescriptorSet, GraphicsPipelineDesc, Image, ImageDesc, Pipeline, Tracker, VkResult};

pub(super) const SURFACE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

pub(super) struct SurfacesPass {
    pipeline: Pipeline,
    descriptors: DescriptorSet,
    pub positions: Image,
    pub normals: Image,
    depth: Image,
    /// The scene's geometry (its buffers live as long as the renderer; moved meshes are
    /// rewritten in place) and per mesh its indices and its occluder index + 1 (0: none).
    vertices: vk::Buffer,
    indices: vk::Buffer,
    draws: Vec<(u32, u32, u32)>,
}

impl SurfacesPass {
    /// `occluder_of_mesh[m]`: the occluder index + 1 of the scene's mesh m, 0 for none.
    pub fn new(shared: &Shared, occluder_of_mesh: &[u32]) -> VkResult<SurfacesPass> {
        let (ctx, settings) = (shared.ctx, shared.settings);
        let target = |name, format, usage| {
            let desc = ImageDesc {
                width: settings.width,
                height: settings.height,
                layers: 1,
                format,
                usage,
                view_type: vk::ImageViewType::TYPE_2D,
            };
            Image::new(ctx, name, desc)
        };
        use vk::ImageUsageFlags as U;
        let surface_usage = U::COLOR_ATTACHMENT | U::STORAGE | U::TRANSFER_SRC;
        let positions = target("fiv positions", SURFACE_FORMAT, surface_usage)?;
        let normals = target("fiv normals", SURFACE_FORMAT, surface_usage)?;
        let depth = target("fiv depth", DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT)?;
        let descriptors = DescriptorSet::new(
            ctx,
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            &[Binding::UniformBuffer(shared.gpu_scene.frame.raw)],
        )?;
        let pipeline = Pipeline::graphics(
            ctx,
            &GraphicsPipelineDesc {
                vertex: shaders::FIV_SURFACES_VERT,
                fragment: shaders::FIV_SURFACES_FRAG,
                specialization: &[],
                vertex_stride: VERTEX_STRIDE,
                attributes: &vertex_attributes()[..2],
                color_formats: &[SURFACE_FORMAT, SURFACE_FORMAT],
                depth_format: DEPTH_FORMAT,
                // Two-sided, as the lighting pass draws.
                cull_mode: vk::CullModeFlags::NONE,
                set_layout: descriptors.layout,
                push_bytes: 4,
            },
        )?;
        let scene = shared.gpu_scene;
        Ok(SurfacesPass {
            pipeline,
            descriptors,
            positions,
            normals,
            depth,
            vertices: scene.vertices.raw,
            indices: scene.indices.raw,
            draws: scene.draws.iter().zip(occluder_of_mesh).map(|(d, id)| (d.first_index, d.index_count, *id)).collect(),
        })
    }

    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker) {
        tracker.use_image(rec, &self.positions, Access::ColorAttachmentWrite);
        tracker.use_image(rec, &self.normals, Access::ColorAttachmentWrite);
        tracker.use_image(rec, &self.depth, Access::DepthAttachmentWrite);
        rec.bind_graphics(self.pipeline.raw, self.pipeline.layout, self.descriptors.set);
        rec.begin_rendering(self.positions.desc.extent(), [self.positions.view, self.normals.view], [0.0; 4], self.depth.view);
        rec.bind_geometry(self.vertices, self.indices);
        for (first_index, index_count, occluder) in &self.draws {
            rec.push_constants(self.pipeline.layout, occluder);
            rec.draw_indexed(*first_index, *index_count);
        }
        rec.end_rendering();
    }
}
