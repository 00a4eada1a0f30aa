//! Forward lighting pass: the obscurance illumination model of 001 eq. (5)-(7) for Lambertian
//! surfaces (shaders/forward.frag states it in radiometric terms): emission, plus direct light
//! from every punctual light with glTF falloff and visibility from the variance shadow maps
//! (Chebyshev bound, 000 §3.4), plus the ambient term (I_A + beta * every light's unshadowed,
//! cosine-free irradiance) times the obscurance W, filtered by hand from the lightmap through
//! uv1. With I_A = beta = 0 the ambient term is skipped and the lightmap is not read. With
//! light path maps, their indirect irradiance I (read through uv1 like W) is added as
//! `lpm_mode` says (frame.rs's `Composition`; 0 adds nothing and reads nothing).
//!
//! Reads: the scene's vertex, index, light, shadow-layer and material buffers, `moments`, the
//! base-colour texture array, the lightmap and the indirect image (sampled in the fragment
//! shader). Writes: `radiance` (linear radiance, RGBA32F, alpha 1) and `depth`, both cleared
//! first. Cost: one draw per mesh; per fragment one shadow-map fetch per light facing it, and
//! 4 texel fetches for W and 4 for I where they are read.

use crate::gpu_scene::{vertex_attributes, GpuScene, VERTEX_STRIDE};
use crate::shaders;
use crate::vk::{
    vk, Access, Binding, CommandRecorder, Context, DescriptorSet, GraphicsPipelineDesc, Image, Pipeline, Sampler, Tracker, VkResult,
};
use glam::{Mat4, Vec4};

pub const RADIANCE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// Per-frame inputs of the forward pass (push constants; layout of forward_push.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ForwardParams {
    pub clip_from_world: Mat4,
    pub camera_position: Vec4,
    pub light_count: u32,
    pub shadows: u32,
    pub min_variance: f32,
    pub bleeding_reduction: f32,
    /// The material of the current draw (set per draw by the pass).
    pub material: u32,
    /// How the light path maps' indirect irradiance is added (forward.frag's LPM_*): 0 none
    /// (the renderer has none), else `Composition::shader_mode`.
    pub lpm_mode: u32,
    pub _pad: [u32; 2],
    /// rgb: I_A, the ambient irradiance (lux); w: beta (001 eq. (5), (7)).
    pub ambient_beta: Vec4,
}

// 128 bytes: the push-constant size every Vulkan device guarantees (maxPushConstantsSize).
const _: () = assert!(std::mem::size_of::<ForwardParams>() == 128);

pub struct ForwardPass<'a> {
    pipeline: Pipeline<'a>,
    descriptors: DescriptorSet<'a>,
    // Held so the samplers live as long as the descriptor set that names them.
    _shadow_sampler: Sampler<'a>,
    _texture_sampler: Sampler<'a>,
}

impl<'a> ForwardPass<'a> {
    /// `lightmap`: the RGBA32F 2D-array image of a [`crate::lightmap::GpuLightmap`];
    /// `indirect`: the light path maps' indirect image, or a stand-in of that format.
    pub(crate) fn new(
        ctx: &'a Context,
        scene: &GpuScene,
        moments: &Image,
        lightmap: &Image,
        indirect: &Image,
    ) -> VkResult<ForwardPass<'a>> {
        let shadow_sampler = Sampler::new(ctx, ctx.info.linear_moments, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;
        // Textures and the lightmap are filtered by hand in the shader (texelFetch, with their
        // own wrap modes); the sampler only binds them.
        let texture_sampler = Sampler::new(ctx, false, vk::SamplerAddressMode::REPEAT)?;
        let descriptors = DescriptorSet::new(
            ctx,
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            &[
                Binding::StorageBuffer(scene.lights.raw),
                Binding::StorageBuffer(scene.layers.raw),
                Binding::SampledImage { view: moments.view, sampler: shadow_sampler.raw },
                Binding::StorageBuffer(scene.materials.raw),
                Binding::SampledImage { view: scene.textures.view, sampler: texture_sampler.raw },
                Binding::SampledImage { view: lightmap.view, sampler: texture_sampler.raw },
                Binding::SampledImage { view: indirect.view, sampler: texture_sampler.raw },
            ],
        )?;
        let pipeline = Pipeline::graphics(
            ctx,
            &GraphicsPipelineDesc {
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
            },
        )?;
        Ok(ForwardPass { pipeline, descriptors, _shadow_sampler: shadow_sampler, _texture_sampler: texture_sampler })
    }

    /// Reads: `sampled` = (`moments`, `lightmap`, `indirect`: the images given to `new`) and the textures
    /// (sampled), scene buffers. Writes: `targets` = (`radiance`, `depth`). One draw per mesh,
    /// so the material (and its texture) is uniform across each draw.
    pub(crate) fn record(
        &self,
        rec: &CommandRecorder,
        tracker: &mut Tracker,
        scene: &GpuScene,
        sampled: (&Image, &Image, &Image),
        targets: (&Image, &Image),
        params: &ForwardParams,
    ) {
        let (moments, lightmap, indirect) = sampled;
        let (radiance, depth) = targets;
        tracker.use_image(rec, moments, Access::FragmentSampled);
        tracker.use_image(rec, lightmap, Access::FragmentSampled);
        tracker.use_image(rec, indirect, Access::FragmentSampled);
        tracker.use_image(rec, radiance, Access::ColorAttachmentWrite);
        tracker.use_image(rec, depth, Access::DepthAttachmentWrite);
        rec.bind_graphics(self.pipeline.raw, self.pipeline.layout, self.descriptors.set);
        rec.begin_rendering(radiance.desc.extent(), radiance.view, [0.0; 4], depth.view);
        rec.bind_geometry(scene.vertices.raw, scene.indices.raw);
        for draw in &scene.draws {
            rec.push_constants(self.pipeline.layout, &ForwardParams { material: draw.material, ..*params });
            rec.draw_indexed(draw.first_index, draw.index_count);
        }
        rec.end_rendering();
    }
}
