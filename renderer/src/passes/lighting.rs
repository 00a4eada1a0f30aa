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

use super::compute::Slot;
use super::graphics::{GraphicsPass, Shaders, Target};
use crate::gpu_scene::GpuScene;
use crate::shaders;
use crate::technique::Terms;
use crate::vk::{vk, Access, Buffer, CommandRecorder, Context, Image, ImageDesc, Sampler, Tracker, VkResult};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub const RADIANCE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

pub struct LightingPass {
    pass: GraphicsPass<u32, 1>,
    /// Where it draws: `radiance`'s extent and view, `depth`'s view.
    target: (vk::Extent2D, vk::ImageView, vk::ImageView),
    // Held so the samplers and stand-ins live as long as the descriptor set that names them.
    _shadow_sampler: Sampler,
    _texture_sampler: Sampler,
    _stand_in_image: Image,
    _stand_in_buffer: Buffer,
}

impl LightingPass {
    /// Writes `radiance` and `depth`, reading the scene, the moments and the terms.
    pub fn new(
        ctx: &Arc<Context>,
        scene: &GpuScene,
        moments: &Image,
        terms: &Terms,
        (radiance, depth): (&Image, &Image),
    ) -> VkResult<LightingPass> {
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
        let (vertex, fragment) = match terms.radiance {
            Some(_) => (shaders::LIGHTING_SH_VERT, shaders::LIGHTING_SH_FRAG),
            None => (shaders::LIGHTING_VERT, shaders::LIGHTING_FRAG),
        };
        let read = Access::GraphicsStorageRead;
        let slots = [
            Slot::Updated(&scene.lights),
            Slot::Updated(&scene.layers),
            Slot::Sampled(moments, &shadow_sampler),
            Slot::Buffer(&scene.materials, read),
            Slot::Sampled(&scene.textures, &texture_sampler),
            Slot::Sampled(terms.occlusion.unwrap_or(&stand_in_image), &texture_sampler),
            Slot::Sampled(terms.texels().unwrap_or(&stand_in_image), &texture_sampler),
            Slot::Sampled(terms.pixels().unwrap_or(&stand_in_image), &texture_sampler),
            Slot::Buffer(terms.vertex_values().unwrap_or(&stand_in_buffer), read),
            Slot::Uniform(&scene.frame),
        ];
        let specialization = [terms.occlusion.is_some() as u32, terms.irradiance_kind()];
        let shaders = Shaders { vertex, fragment, specialization: &specialization, attributes: 4 };
        let pass = GraphicsPass::new(ctx, "lighting", scene, &shaders, &slots, ([radiance], depth))?;
        Ok(LightingPass {
            pass,
            target: (radiance.desc.extent(), radiance.view, depth.view),
            _shadow_sampler: shadow_sampler,
            _texture_sampler: texture_sampler,
            _stand_in_image: stand_in_image,
            _stand_in_buffer: stand_in_buffer,
        })
    }

    /// Writes `radiance` and `depth`, each cleared first. One draw per mesh, so the material
    /// (and its texture) is uniform across each draw; its index is the push block.
    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, scene: &GpuScene) {
        let (extent, radiance, depth) = self.target;
        let target = Target { extent, colors: [radiance], clear: [0.0; 4], depth };
        self.pass.record(rec, tracker, target, scene.draws.iter().map(|d| (d.material, d.first_index, d.index_count)));
    }
}
