//! Per-vertex reconstruction (compute), 004 eq. (12): each vertex's indirect irradiance as
//! this frame's cloud-light weights times its stored transfer
//! (relume_bake::light_cloud::LightCloud::irradiance on the CPU).
//!
//! Reads: the transfer, the weights (rewritten in the command stream just before). Writes: the
//! irradiance buffer, every vertex. Cost: one invocation per vertex (workgroups of 64), each
//! reading 12 bytes of transfer per non-zero weight (m per user light at most).

use super::Buffers;
use crate::passes::compute::{ComputePass, Slot};
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{Access, CommandRecorder, Tracker, VkResult};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ReconstructPush {
    vertex_count: u32,
    light_count: u32,
    weight_count: u32,
}

pub(super) struct ReconstructPass {
    pass: ComputePass,
    vertex_count: u32,
    light_count: u32,
}

impl ReconstructPass {
    pub fn new(shared: &Shared, buffers: &Buffers, vertex_count: u32, light_count: u32) -> VkResult<ReconstructPass> {
        let slots = [
            Slot::Buffer(&buffers.transfer, Access::ComputeStorageRead),
            Slot::Updated(&buffers.weights),
            Slot::Buffer(&buffers.irradiance, Access::ComputeStorageWrite),
        ];
        let pass = ComputePass::new(shared.ctx, shaders::LIGHT_CLOUD_RECONSTRUCT_COMP, 12, &slots)?;
        Ok(ReconstructPass { pass, vertex_count, light_count })
    }

    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, weight_count: u32) {
        let push = ReconstructPush { vertex_count: self.vertex_count, light_count: self.light_count, weight_count };
        self.pass.dispatch(rec, tracker, 0, &push, [self.vertex_count.div_ceil(64), 1, 1]);
    }
}
