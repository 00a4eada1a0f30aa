//! Forward lighting pass: Lambertian direct light from every punctual light with glTF
//! falloff, visibility from the variance shadow maps (Chebyshev bound, 000 §3.4), emission.

use crate::gpu_scene::{vertex_attributes, GpuScene, VERTEX_STRIDE};
use crate::shaders;
use crate::vk::{vk, Access, Binding, CommandRecorder, Context, DescriptorSet, GraphicsPipeline, GraphicsPipelineDesc, Image, Tracker, VkResult};
use glam::{Mat4, Vec4};

pub const RADIANCE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// Per-frame inputs of the forward pass (push constants; layout of forward_push.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ForwardParams {
    pub clip_from_world: Mat4,
    pub camera_position: Vec4,
    pub light_count: u32,
    pub shadows: u32,
    pub min_variance: f32,
    pub bleeding_reduction: f32,
    /// The material of the current draw (set per draw by the pass).
    pub material: u32,
    pub _pad: [u32; 3],
}

pub struct ForwardPass {
    pipeline: GraphicsPipeline,
    descriptors: DescriptorSet,
    texture_sampler: vk::Sampler,
}

impl ForwardPass {
    pub(crate) fn new(ctx: &Context, scene: &GpuScene, moments: &Image, shadow_sampler: vk::Sampler) -> VkResult<ForwardPass> {
        // Textures are filtered by hand in the shader (texelFetch); the sampler only binds them.
        let texture_sampler = ctx.create_sampler(false, vk::SamplerAddressMode::REPEAT)?;
        let descriptors = DescriptorSet::new(
            ctx,
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            &[
                Binding::StorageBuffer(scene.lights.raw),
                Binding::StorageBuffer(scene.layers.raw),
                Binding::SampledImages { views: vec![moments.view], sampler: shadow_sampler },
                Binding::StorageBuffer(scene.materials.raw),
                Binding::SampledImages { views: scene.textures.iter().map(|t| t.view).collect(), sampler: texture_sampler },
            ],
        )?;
        let pipeline = GraphicsPipeline::new(ctx, &GraphicsPipelineDesc {
            vertex: shaders::FORWARD_VERT,
            fragment: shaders::FORWARD_FRAG,
            vertex_stride: VERTEX_STRIDE,
            attributes: &vertex_attributes(),
            color_formats: &[RADIANCE_FORMAT],
            depth_format: DEPTH_FORMAT,
            // Surfaces are two-sided, as in the reference path tracer.
            cull_mode: vk::CullModeFlags::NONE,
            set_layout: descriptors.layout,
            push_bytes: std::mem::size_of::<ForwardParams>() as u32,
            fragment_constants: &[scene.textures.len() as u32],
        })?;
        Ok(ForwardPass { pipeline, descriptors, texture_sampler })
    }

    /// Reads: `moments` and the textures (sampled), scene buffers. Writes: `radiance`, `depth`.
    /// One draw per mesh, so the material (and its texture) is uniform across each draw.
    pub(crate) fn record(
        &self,
        rec: &CommandRecorder,
        tracker: &mut Tracker,
        scene: &GpuScene,
        moments: &Image,
        targets: (&Image, &Image),
        params: &ForwardParams,
    ) {
        let (radiance, depth) = targets;
        tracker.use_image(rec, moments, Access::FragmentSampled);
        tracker.use_image(rec, radiance, Access::ColorAttachmentWrite);
        tracker.use_image(rec, depth, Access::DepthAttachmentWrite);
        rec.bind_graphics(self.pipeline.raw, self.pipeline.layout, self.descriptors.set);
        rec.begin_rendering(radiance.desc.extent(), radiance.view, depth.view);
        rec.bind_geometry(scene.vertices.raw, scene.indices.raw);
        for draw in &scene.draws {
            rec.push_constants(self.pipeline.layout, &ForwardParams { material: draw.material, ..*params });
            rec.draw_indexed(draw.first_index, draw.index_count);
        }
        rec.end_rendering();
    }

    pub fn destroy(&mut self, ctx: &Context) {
        self.pipeline.destroy(ctx);
        self.descriptors.destroy(ctx);
        ctx.destroy_sampler(self.texture_sampler);
    }
}
