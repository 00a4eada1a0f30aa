//! Cluster sums (compute), step 3 of 000 §3.4: per cluster c of entry points, s_c = sum_e I_e
//! and t_cd = sum_e I_e w^e_d (relume_bake::light_path_maps::ClusteredTransfer::cluster_sums
//! on the CPU), which turn the per-texel sum over every entry point into one over the
//! clusters' C * (1 + D) textures.
//!
//! Reads: the entry-irradiance buffer, the weights and the cluster starts. Writes: the
//! cluster-sums buffer (C * (1 + D) x vec4, cluster after cluster, s_c first). Cost: one
//! dispatch of C x (1 + D) workgroups of 64 invocations; workgroup (c, k) reads the cluster's
//! I_e (and weight k) once and reduces them in shared memory in a fixed order, so the sums
//! are the same on every run. E (1 + D) reads in all.

use super::Buffers;
use crate::passes::compute::{ComputePass, Slot};
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{Access, CommandRecorder, Tracker, VkResult};

pub(super) struct ClusterSumsPass {
    pass: ComputePass<u32>,
    clusters: u32,
    basis: u32,
}

impl ClusterSumsPass {
    pub fn new(shared: &Shared, buffers: &Buffers) -> VkResult<ClusterSumsPass> {
        let slots = [
            Slot::Buffer(&buffers.entry_irradiance, Access::ComputeStorageRead),
            Slot::Buffer(&buffers.weights, Access::ComputeStorageRead),
            Slot::Buffer(&buffers.cluster_starts, Access::ComputeStorageRead),
            Slot::Buffer(&buffers.cluster_sums, Access::ComputeStorageWrite),
        ];
        let pass = ComputePass::new(shared.ctx, "light_path_maps.cluster_sums", shaders::LIGHT_PATH_MAPS_CLUSTER_SUMS_COMP, &slots)?;
        Ok(ClusterSumsPass { pass, clusters: buffers.cluster_count, basis: buffers.basis_count })
    }

    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker) {
        self.pass.dispatch_groups(rec, tracker, 0, &self.basis, [self.clusters, 1 + self.basis, 1]);
    }
}
