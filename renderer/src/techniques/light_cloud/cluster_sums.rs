//! Cluster sums (compute), 004 eq. (12): per cluster its mean and basis vectors weighed by
//! this frame's cloud-light weights, x^m = X^m w and b_d = B_d w, each of n_b coefficients
//! (relume_bake::light_cloud::LightCloud::cluster_sums on the CPU).
//!
//! Reads: the terms, the cluster table, the weights (rewritten in the command stream just
//! before). Writes: the cluster-sums buffer, C (1 + D) n_b vec4. Cost: one invocation per
//! term and coefficient,
//! each reading every non-zero weight (m per user light and zone at most) in a fixed order and
//! 12 bytes of terms for each of its zone's.

use super::Buffers;
use crate::passes::compute::{ComputePass, Slot};
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{Access, CommandRecorder, Tracker, VkResult};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ClusterSumsPush {
    term_count: u32,
    terms: u32,
    weight_count: u32,
    coefficients: u32,
}

pub(super) struct ClusterSumsPass {
    pass: ComputePass<ClusterSumsPush>,
    term_count: u32,
    terms: u32,
    coefficients: u32,
}

impl ClusterSumsPass {
    /// `term_count`: C (1 + D) n_b sums; `terms`: 1 + D, the terms of each cluster;
    /// `coefficients`: n_b.
    pub fn new(shared: &Shared, buffers: &Buffers, (term_count, terms, coefficients): (u32, u32, u32)) -> VkResult<ClusterSumsPass> {
        let slots = [
            Slot::Buffer(&buffers.terms, Access::ComputeStorageRead),
            Slot::Updated(&buffers.weights),
            Slot::Buffer(&buffers.cluster_sums, Access::ComputeStorageWrite),
            Slot::Buffer(&buffers.clusters, Access::ComputeStorageRead),
        ];
        let pass = ComputePass::new(shared.ctx, "light_cloud.cluster_sums", shaders::LIGHT_CLOUD_CLUSTER_SUMS_COMP, &slots)?;
        Ok(ClusterSumsPass { pass, term_count, terms, coefficients })
    }

    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, weight_count: u32) {
        let push = ClusterSumsPush { term_count: self.term_count, terms: self.terms, weight_count, coefficients: self.coefficients };
        self.pass.dispatch(rec, tracker, 0, &push, [self.term_count, 1, 1]);
    }
}
