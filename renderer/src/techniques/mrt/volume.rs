//! The light volume (compute), §7.3 step 8 (§6.5): every block's 4^3 probes of 9 spherical-
//! harmonic coefficients of radiance, U_bvol b plus U_rvol r of each receiver at the block:
//! shaders/mrt/volume.comp.
//!
//! Reads: `operators`, `volume_blocks`, `b`, `r`. Writes: `volume`. Cost: one invocation per
//! block, probe and coefficient (576 a block), k + (receivers) k_r multiply-adds each.

use super::{Buffers, Dispatch};
use crate::passes::compute::Slot;
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{Access, VkResult};

pub(super) fn new(shared: &Shared, buffers: &Buffers, rows: u32) -> VkResult<Dispatch> {
    let slots = [
        Slot::Buffer(&buffers.operators, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.volume_blocks, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.b, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.r, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.volume, Access::ComputeStorageWrite),
    ];
    Dispatch::new(shared, "mrt.volume", shaders::MRT_VOLUME_COMP, rows, &slots)
}
