//! Transfer between blocks (compute), §7.3 step 4, §6.3: r = sum over sources of T_b->r b per
//! receiver: shaders/mrt/transfer.comp.
//!
//! Reads: `shapes`, `blocks`, `receivers`, `sources`, `matrices`, `b`. Writes: `r`. Cost: one
//! invocation per (receiver, response mode), k multiply-adds per source block it hears.

use super::{Buffers, Dispatch};
use crate::passes::compute::Slot;
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{Access, VkResult};

pub(super) fn new(shared: &Shared, buffers: &Buffers, invocations: u32) -> VkResult<Dispatch> {
    let slots = [
        Slot::Buffer(&buffers.shapes, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.blocks, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.receivers, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.sources, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.matrices, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.b, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.r, Access::ComputeStorageWrite),
    ];
    Dispatch::new(shared, "mrt.transfer", shaders::MRT_TRANSFER_COMP, invocations, &slots)
}
