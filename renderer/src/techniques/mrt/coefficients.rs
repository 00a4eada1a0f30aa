//! Block coefficients (compute), §7.3 step 2, eq. 3: b0 = T_d->b l_d per block, on its
//! dictionary shape's rows: shaders/mrt/coefficients.comp.
//!
//! Reads: `shapes`, `operators`, `blocks`, `rows`, `light`. Writes: `b0`. Cost: one invocation
//! per (block, mode), each n multiply-adds (n = the shape's samples, up to 1536).

use super::{Buffers, Dispatch};
use crate::passes::compute::Slot;
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{Access, VkResult};

pub(super) fn new(shared: &Shared, buffers: &Buffers, invocations: u32) -> VkResult<Dispatch> {
    let slots = [
        Slot::Buffer(&buffers.shapes, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.operators, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.blocks, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.rows, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.light, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.b0, Access::ComputeStorageWrite),
    ];
    Dispatch::new(shared, "mrt.coefficients", shaders::MRT_COEFFICIENTS_COMP, invocations, &slots)
}
