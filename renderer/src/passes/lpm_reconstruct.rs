//! Light-path-map reconstruction (compute), step 4 of 000 §3.4: per atlas texel, the indirect
//! irradiance I[u, v] = sum_c s_c M^c[u, v] + sum_{c,d} t_cd B^c_d[u, v]
//! (relume_bake::clustered_transfer::ClusteredTransfer::reconstruct on the CPU), into the
//! indirect image with alpha = coverage; empty texels get 0, which the padding pass that
//! follows (GpuLightPathMaps::record_padding) replaces by their nearest covered neighbour.
//!
//! Reads: the cluster-sums buffer, the textures and the coverage. Writes: the indirect image
//! (storage), every texel. Cost: one dispatch over every texel of every page (8 x 8
//! workgroups); a covered texel reads C * (1 + D) sums and rgb texture values, an empty one
//! only its coverage: 12 C (1 + D) bytes of textures per covered texel, the pass's bulk.

use crate::light_path_maps::GpuLightPathMaps;
use crate::shaders;
use crate::vk::{vk, Access, Binding, CommandRecorder, Context, DescriptorSet, Pipeline, Tracker, VkResult};

pub struct LpmReconstructPass<'a> {
    pipeline: Pipeline<'a>,
    descriptors: DescriptorSet<'a>,
}

impl<'a> LpmReconstructPass<'a> {
    pub fn new(ctx: &'a Context, maps: &GpuLightPathMaps) -> VkResult<LpmReconstructPass<'a>> {
        let descriptors = DescriptorSet::new(
            ctx,
            vk::ShaderStageFlags::COMPUTE,
            &[
                Binding::StorageBuffer(maps.cluster_sums.raw),
                Binding::StorageBuffer(maps.textures.raw),
                Binding::StorageBuffer(maps.coverage.raw),
                Binding::StorageImage(maps.indirect.view),
            ],
        )?;
        let pipeline = Pipeline::compute(ctx, shaders::LPM_RECONSTRUCT_COMP, descriptors.layout, 4)?;
        Ok(LpmReconstructPass { pipeline, descriptors })
    }

    /// Reads `maps.cluster_sums` (written by the cluster-sums pass), writes `maps.indirect`;
    /// `maps` is the one given to `new`. Allocates nothing.
    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, maps: &GpuLightPathMaps) {
        let d = maps.indirect.desc;
        tracker.use_buffer(rec, &maps.cluster_sums, Access::ComputeStorageRead);
        tracker.use_image(rec, &maps.indirect, Access::ComputeStorageWrite);
        rec.bind_compute(self.pipeline.raw, self.pipeline.layout, self.descriptors.set);
        rec.push_constants(self.pipeline.layout, &maps.term_count());
        rec.dispatch(d.width.div_ceil(8), d.height.div_ceil(8), d.layers);
    }
}
