//! Light-path-map reconstruction (compute), step 4 of 000 §3.4: per atlas texel, the indirect
//! irradiance I[u, v] = sum_c s_c M^c[u, v] + sum_{c,d} t_cd B^c_d[u, v]
//! (relume_bake::light_path_maps::ClusteredTransfer::reconstruct on the CPU), into the
//! indirect image with alpha = coverage; empty texels get 0, which the padding pass that
//! follows replaces by their nearest covered neighbour.
//!
//! Reads: the cluster-sums buffer, the textures and the coverage. Writes: the indirect image
//! (storage), every texel. Cost: one dispatch over every texel of every page (8 x 8
//! workgroups); a covered texel reads C * (1 + D) sums and rgb texture values, an empty one
//! only its coverage: 12 C (1 + D) bytes of textures per covered texel, the pass's bulk.

use super::Buffers;
use crate::passes::compute::{per_texel, ComputePass, Slot};
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{Access, CommandRecorder, Image, Tracker, VkResult};

pub(super) struct ReconstructPass {
    pass: ComputePass<u32>,
    terms: u32,
    groups: [u32; 3],
}

impl ReconstructPass {
    pub fn new(shared: &Shared, buffers: &Buffers, indirect: &Image) -> VkResult<ReconstructPass> {
        let slots = [
            Slot::Buffer(&buffers.cluster_sums, Access::ComputeStorageRead),
            Slot::Buffer(&buffers.textures, Access::ComputeStorageRead),
            Slot::Buffer(&buffers.coverage, Access::ComputeStorageRead),
            Slot::StorageImage(indirect, Access::ComputeStorageWrite),
        ];
        let pass = ComputePass::new(shared.ctx, "light_path_maps.reconstruct", shaders::LIGHT_PATH_MAPS_RECONSTRUCT_COMP, &slots)?;
        Ok(ReconstructPass { pass, terms: buffers.term_count(), groups: per_texel(indirect) })
    }

    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker) {
        self.pass.dispatch(rec, tracker, 0, &self.terms, self.groups);
    }
}
