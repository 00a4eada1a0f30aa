//! Entry-point irradiance (compute), step 2 of 000 §3.4: the irradiance I_e every light sends
//! to every entry point of the light path maps, with the entry point's visibility from the
//! variance shadow maps (shaders/light_path_maps/entry_irradiance.comp states the formula;
//! without shadows it is relume_bake::light_path_maps::entry_irradiance_unshadowed summed
//! over the lights).
//!
//! Reads: the scene's light and shadow-layer buffers and the frame's uniforms, the shadow
//! moments (sampled in compute, through the same filter as the lighting pass), the entry
//! points. Writes: the entry-irradiance buffer (E x vec4). Cost: one dispatch of E
//! invocations (64 a workgroup), each looping over every light with one shadow-map fetch per
//! light that faces the entry point.

use super::Buffers;
use crate::passes::compute::{ComputePass, Slot};
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{vk, Access, CommandRecorder, Sampler, Tracker, VkResult};

/// The technique's constants (push constants; entry_irradiance.comp's EntryIrradiancePush).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct EntryIrradiancePush {
    entry_count: u32,
    /// Delta-l of §3.4, square metres.
    light_area: f32,
}

pub(super) struct EntryIrradiancePass {
    pass: ComputePass<EntryIrradiancePush>,
    push: EntryIrradiancePush,
    // Held so the sampler lives as long as the descriptor set that names it.
    _shadow_sampler: Sampler,
}

impl EntryIrradiancePass {
    pub fn new(shared: &Shared, buffers: &Buffers, light_area: f32) -> VkResult<EntryIrradiancePass> {
        // The lighting pass's shadow sampler: the same filtering, so the same visibility.
        let shadow_sampler = Sampler::new(shared.ctx, shared.ctx.info.linear_moments, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;
        let scene = shared.gpu_scene;
        let slots = [
            Slot::Updated(&scene.lights),
            Slot::Updated(&scene.layers),
            Slot::Sampled(shared.moments, &shadow_sampler),
            Slot::Buffer(&buffers.entry_points, Access::ComputeStorageRead),
            Slot::Buffer(&buffers.entry_irradiance, Access::ComputeStorageWrite),
            Slot::Uniform(&scene.frame),
        ];
        let push = EntryIrradiancePush { entry_count: buffers.entry_count, light_area };
        let pass =
            ComputePass::new(shared.ctx, "light_path_maps.entry_irradiance", shaders::LIGHT_PATH_MAPS_ENTRY_IRRADIANCE_COMP, &slots)?;
        Ok(EntryIrradiancePass { pass, push, _shadow_sampler: shadow_sampler })
    }

    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker) {
        self.pass.dispatch(rec, tracker, 0, &self.push, [self.push.entry_count, 1, 1]);
    }
}
