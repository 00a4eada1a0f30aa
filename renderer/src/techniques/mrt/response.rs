//! The samples' indirect light (compute), §7.3 steps 3 and 5: U_b b of the sample's block
//! plus U_r r of each receiver landing on it: shaders/mrt/response.comp.
//!
//! Reads: `shapes`, `operators`, `blocks`, `sample_rows`, `b`, `r`. Writes: `indirect`. Cost:
//! one invocation per sample, k + (receivers) k_r multiply-adds.

use super::{Buffers, Dispatch};
use crate::passes::compute::Slot;
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{Access, VkResult};

pub(super) fn new(shared: &Shared, buffers: &Buffers, samples: u32) -> VkResult<Dispatch> {
    let slots = [
        Slot::Buffer(&buffers.shapes, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.operators, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.blocks, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.sample_rows, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.b, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.r, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.indirect, Access::ComputeStorageWrite),
    ];
    Dispatch::new(shared, "mrt.response", shaders::MRT_RESPONSE_COMP, samples, &slots)
}
