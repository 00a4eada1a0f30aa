//! The lighting pass (graphics): direct light of every punctual light with visibility from the
//! variance shadow maps (000 §3.4), emission, the ambient light of 001 eq. (5)-(7), and the
//! terms the frame's techniques hand over, for Lambertian surfaces (shaders/lighting_fragment.glsl
//! states the formula). It knows terms by kind, never by technique: at most one occlusion
//! term (an atlas image scaling the ambient light) and one indirect term: irradiance, read
//! through uv1 (texel), per vertex (vertex), through uv1 but per vertex where the vertex says
//! so (texel or vertex), or per pixel (pixel), or exitant radiance in
//! spherical harmonics per vertex. Which terms are there picks the shader's variant
//! (specialization constants; the radiance term its own shaders, lighting_sh.vert and .frag,
//! whose vertex outputs differ); what may change per frame (ambient, beta,
//! the irradiance term's flags, camera, shadow settings) is in the frame's uniform buffer.
//! Absent terms are bound to stand-ins the variant never reads.
//!
//! Reads: the scene's vertex, index, light, shadow-layer, material and frame buffers, the
//! moments, the base-colour texture array and the terms' images or buffer. Writes: `radiance`
//! (linear radiance, RGBA32F, alpha 1) and `depth`, both cleared first. Cost: one draw per
//! mesh; per fragment one shadow-map fetch per light facing it, 4 texel fetches for a texel
//! term (8 when an irradiance term is scaled by the occlusion term: both are read).

use crate::gpu_scene::{vertex_attributes, GpuScene, VERTEX_STRIDE};
use crate::shaders;
use crate::technique::Terms;
use crate::vk::{vk, Access, Binding, Buffer, CommandRecorder, Context, DescriptorSet, GraphicsPipelineDesc, Image, ImageDesc, Pipeline};
use crate::vk::{Sampler, Tracker, Use, VkResult};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub const RADIANCE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

pub struct LightingPass {
    pipeline: Pipeline,
    descriptors: DescriptorSet,
    /// What the pass reads every frame (the terms' stand-ins where absent).
    reads: Vec<Use>,
    // Held so the samplers and stand-ins live as long as the descriptor set that names them.
    _shadow_sampler: Sampler,
    _texture_sampler: Sampler,
    _stand_in_image: Image,
    _stand_in_buffer: Buffer,
}

impl LightingPass {
    pub fn new(ctx: &Arc<Context>, scene: &GpuScene, moments: &Image, terms: &Terms) -> VkResult<LightingPass> {
        let shadow_sampler = Sampler::new(ctx, ctx.info.linear_moments, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;
        // Textures and atlas images are filtered by hand in the shader (texelFetch, with
        // their own wrap modes); the sampler only binds them.
        let texture_sampler = Sampler::new(ctx, false, vk::SamplerAddressMode::REPEAT)?;
        let stand_in_image = Image::new(
            ctx,
            "lighting stand-in",
            ImageDesc {
                width: 1,
                height: 1,
                layers: 1,
                format: vk::Format::R32G32B32A32_SFLOAT,
                usage: vk::ImageUsageFlags::SAMPLED,
                view_type: vk::ImageViewType::TYPE_2D_ARRAY,
            },
        )?;
        let stand_in_buffer = Buffer::new(ctx, "lighting stand-in", 16, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryLocation::GpuOnly)?;
        let sampled = |image: &Image| Binding::SampledImage { view: image.view, sampler: texture_sampler.raw };
        let term_image = |image: Option<&Image>| sampled(image.unwrap_or(&stand_in_image));
        let (texels, pixels) = (terms.texels(), terms.pixels());
        let vertices = terms.vertex_values().unwrap_or(&stand_in_buffer);
        let (vertex, fragment) = match terms.radiance {
            Some(_) => (shaders::LIGHTING_SH_VERT, shaders::LIGHTING_SH_FRAG),
            None => (shaders::LIGHTING_VERT, shaders::LIGHTING_FRAG),
        };
        let descriptors = DescriptorSet::new(
            ctx,
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            &[
                Binding::StorageBuffer(scene.lights.raw),
                Binding::StorageBuffer(scene.layers.raw),
                Binding::SampledImage { view: moments.view, sampler: shadow_sampler.raw },
                Binding::StorageBuffer(scene.materials.raw),
                sampled(&scene.textures),
                term_image(terms.occlusion),
                term_image(texels),
                term_image(pixels),
                Binding::StorageBuffer(vertices.raw),
                Binding::UniformBuffer(scene.frame.raw),
            ],
        )?;
        let sampled = |image: &Image| Use::Image(image.into(), Access::FragmentSampled);
        let mut reads = vec![sampled(moments), sampled(&scene.textures)];
        reads.extend([terms.occlusion, texels, pixels].into_iter().map(|image| sampled(image.unwrap_or(&stand_in_image))));
        reads.push(Use::Buffer(vertices.into(), Access::GraphicsStorageRead));
        let pipeline = Pipeline::graphics(
            ctx,
            &GraphicsPipelineDesc {
                vertex,
                fragment,
                specialization: &[terms.occlusion.is_some() as u32, terms.irradiance_kind()],
                vertex_stride: VERTEX_STRIDE,
                attributes: &vertex_attributes(),
                color_formats: &[RADIANCE_FORMAT],
                depth_format: DEPTH_FORMAT,
                // Surfaces are two-sided, as in the reference path tracer.
                cull_mode: vk::CullModeFlags::NONE,
                set_layout: descriptors.layout,
                push_bytes: 4,
            },
        )?;
        Ok(LightingPass {
            pipeline,
            descriptors,
            reads,
            _shadow_sampler: shadow_sampler,
            _texture_sampler: texture_sampler,
            _stand_in_image: stand_in_image,
            _stand_in_buffer: stand_in_buffer,
        })
    }

    /// Writes `radiance` and `depth`. One draw per mesh, so the material (and its texture) is
    /// uniform across each draw; its index is the push block.
    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, scene: &GpuScene, radiance: &Image, depth: &Image) {
        tracker.declare(rec, &self.reads);
        tracker.use_image(rec, radiance, Access::ColorAttachmentWrite);
        tracker.use_image(rec, depth, Access::DepthAttachmentWrite);
        rec.bind_graphics(self.pipeline.raw, self.pipeline.layout, self.descriptors.set);
        rec.begin_rendering(radiance.desc.extent(), [radiance.view], [0.0; 4], depth.view);
        rec.bind_geometry(scene.vertices.raw, scene.indices.raw);
        for draw in &scene.draws {
            rec.push_constants(self.pipeline.layout, &draw.material);
            rec.draw_indexed(draw.first_index, draw.index_count);
        }
        rec.end_rendering();
    }
}
