//! CPCA vertex reconstruction (compute), 004 eq. (12)-(13): each vertex's indirect irradiance,
//! or its exitant radiance's n_b spherical-harmonic coefficients, as its cluster's x^m plus its
//! coordinates times the cluster's b_d (relume_bake::light_cloud::LightCloud::reconstruct on the
//! CPU). The paper evaluates this in the vertex program; here it runs as a pass of its own so
//! that the lighting pass, shared by every method, only reads a vertex term.
//!
//! Reads: the cluster sums, the vertices' clusters and coordinate starts, the coordinates,
//! the cluster table. Writes: the per-vertex values, every vertex. Cost: one invocation per
//! vertex (workgroups of 64), (1 + D_c) n_b reads of 16 bytes.

use super::Buffers;
use crate::passes::compute::{ComputePass, Slot};
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{Access, CommandRecorder, Tracker, VkResult};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ReconstructPush {
    vertex_count: u32,
    basis: u32,
    coefficients: u32,
}

pub(super) struct ReconstructPass {
    pass: ComputePass<ReconstructPush>,
    push: ReconstructPush,
}

impl ReconstructPass {
    pub fn new(shared: &Shared, buffers: &Buffers, vertex_count: u32, (basis, coefficients): (u32, u32)) -> VkResult<ReconstructPass> {
        let slots = [
            Slot::Buffer(&buffers.cluster_sums, Access::ComputeStorageRead),
            Slot::Buffer(&buffers.vertices, Access::ComputeStorageRead),
            Slot::Buffer(&buffers.coords, Access::ComputeStorageRead),
            Slot::Buffer(&buffers.vertex_values, Access::ComputeStorageWrite),
            Slot::Buffer(&buffers.clusters, Access::ComputeStorageRead),
        ];
        let pass = ComputePass::new(shared.ctx, "light_cloud.reconstruct", shaders::LIGHT_CLOUD_RECONSTRUCT_COMP, &slots)?;
        Ok(ReconstructPass { pass, push: ReconstructPush { vertex_count, basis, coefficients } })
    }

    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker) {
        self.pass.dispatch(rec, tracker, 0, &self.push, [self.push.vertex_count, 1, 1]);
    }
}
