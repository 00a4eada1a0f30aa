//! Entry-point irradiance (compute), step 2 of 000 §3.4: the irradiance I_e every light sends
//! to every entry point of the light path maps, with the entry point's visibility from the
//! variance shadow maps (shaders/entry_irradiance.comp states the formula; without shadows it
//! is relume_bake::clustered_transfer::entry_irradiance_unshadowed summed over the lights).
//!
//! Reads: the scene's light and shadow-layer buffers, `moments` (sampled in compute, through
//! the same filter as the forward pass), the entry points. Writes: the entry-irradiance
//! buffer (E x vec4). Cost: one dispatch of E invocations (64 a workgroup), each looping over
//! every light with one shadow-map fetch per light that faces the entry point.

use crate::gpu_scene::GpuScene;
use crate::light_path_maps::GpuLightPathMaps;
use crate::shaders;
use crate::vk::{vk, Access, Binding, CommandRecorder, Context, DescriptorSet, Image, Pipeline, Sampler, Tracker, VkResult};

/// Per-frame inputs (push constants; layout of entry_irradiance.comp's EntryIrradiancePush).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct EntryIrradianceParams {
    pub light_count: u32,
    /// 0: every light fully visible.
    pub shadows: u32,
    pub min_variance: f32,
    pub bleeding_reduction: f32,
    pub entry_count: u32,
    /// Delta-l of §3.4, square metres.
    pub light_area: f32,
}

pub struct EntryIrradiancePass<'a> {
    pipeline: Pipeline<'a>,
    descriptors: DescriptorSet<'a>,
    // Held so the sampler lives as long as the descriptor set that names it.
    _shadow_sampler: Sampler<'a>,
}

impl<'a> EntryIrradiancePass<'a> {
    pub(crate) fn new(ctx: &'a Context, scene: &GpuScene, moments: &Image, maps: &GpuLightPathMaps) -> VkResult<EntryIrradiancePass<'a>> {
        // The forward pass's shadow sampler: the same filtering, so the same visibility.
        let shadow_sampler = Sampler::new(ctx, ctx.info.linear_moments, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;
        let descriptors = DescriptorSet::new(
            ctx,
            vk::ShaderStageFlags::COMPUTE,
            &[
                Binding::StorageBuffer(scene.lights.raw),
                Binding::StorageBuffer(scene.layers.raw),
                Binding::SampledImage { view: moments.view, sampler: shadow_sampler.raw },
                Binding::StorageBuffer(maps.entry_points.raw),
                Binding::StorageBuffer(maps.entry_irradiance.raw),
            ],
        )?;
        let push_bytes = std::mem::size_of::<EntryIrradianceParams>() as u32;
        let pipeline = Pipeline::compute(ctx, shaders::ENTRY_IRRADIANCE_COMP, descriptors.layout, push_bytes)?;
        Ok(EntryIrradiancePass { pipeline, descriptors, _shadow_sampler: shadow_sampler })
    }

    /// Reads `moments` (the image given to `new`) and the buffers named above; writes
    /// `maps.entry_irradiance`. Allocates nothing.
    pub(crate) fn record(
        &self,
        rec: &CommandRecorder,
        tracker: &mut Tracker,
        moments: &Image,
        maps: &GpuLightPathMaps,
        params: &EntryIrradianceParams,
    ) {
        tracker.use_image(rec, moments, Access::ComputeSampled);
        tracker.use_buffer(rec, &maps.entry_irradiance, Access::ComputeStorageWrite);
        rec.bind_compute(self.pipeline.raw, self.pipeline.layout, self.descriptors.set);
        rec.push_constants(self.pipeline.layout, params);
        rec.dispatch(params.entry_count.div_ceil(64), 1, 1);
    }
}
