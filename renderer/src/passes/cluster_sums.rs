//! Cluster sums (compute), step 3 of 000 §3.4: per cluster c of entry points, s_c = sum_e I_e
//! and t_cd = sum_e I_e w^e_d (relume_bake::clustered_transfer::ClusteredTransfer::cluster_sums
//! on the CPU), which turn the per-texel sum over every entry point into one over the
//! clusters' C * (1 + D) textures.
//!
//! Reads: the entry-irradiance buffer, the weights and the cluster starts. Writes: the
//! cluster-sums buffer (C * (1 + D) x vec4, cluster after cluster, s_c first). Cost: one
//! dispatch of C x (1 + D) workgroups of 64 invocations; workgroup (c, k) reads the cluster's
//! I_e (and weight k) once and reduces them in shared memory in a fixed order, so the sums
//! are the same on every run. E (1 + D) reads in all.

use crate::light_path_maps::GpuLightPathMaps;
use crate::shaders;
use crate::vk::{vk, Access, Binding, CommandRecorder, Context, DescriptorSet, Pipeline, Tracker, VkResult};

pub struct ClusterSumsPass<'a> {
    pipeline: Pipeline<'a>,
    descriptors: DescriptorSet<'a>,
}

impl<'a> ClusterSumsPass<'a> {
    pub fn new(ctx: &'a Context, maps: &GpuLightPathMaps) -> VkResult<ClusterSumsPass<'a>> {
        let descriptors = DescriptorSet::new(
            ctx,
            vk::ShaderStageFlags::COMPUTE,
            &[
                Binding::StorageBuffer(maps.entry_irradiance.raw),
                Binding::StorageBuffer(maps.weights.raw),
                Binding::StorageBuffer(maps.cluster_starts.raw),
                Binding::StorageBuffer(maps.cluster_sums.raw),
            ],
        )?;
        let pipeline = Pipeline::compute(ctx, shaders::CLUSTER_SUMS_COMP, descriptors.layout, 4)?;
        Ok(ClusterSumsPass { pipeline, descriptors })
    }

    /// Reads `maps.entry_irradiance` (written by the entry-irradiance pass), writes
    /// `maps.cluster_sums`; `maps` is the one given to `new`. Allocates nothing.
    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, maps: &GpuLightPathMaps) {
        tracker.use_buffer(rec, &maps.entry_irradiance, Access::ComputeStorageRead);
        tracker.use_buffer(rec, &maps.cluster_sums, Access::ComputeStorageWrite);
        rec.bind_compute(self.pipeline.raw, self.pipeline.layout, self.descriptors.set);
        rec.push_constants(self.pipeline.layout, &maps.basis_count);
        rec.dispatch(maps.cluster_count, 1 + maps.basis_count, 1);
    }
}
