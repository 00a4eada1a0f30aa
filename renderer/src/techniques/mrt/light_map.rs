//! The light map (compute), §7.3 step 6: every texel, a sample's its indirect irradiance and
//! the rest 0: shaders/mrt/light_map.comp.
//!
//! Reads: `texel_samples`, `indirect`. Writes: the light map (storage), every texel. Cost: one
//! invocation per texel.

use super::{Buffers, Dispatch};
use crate::passes::compute::Slot;
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{Access, Image, VkResult};

pub(super) fn new(shared: &Shared, buffers: &Buffers, light_map: &Image, texels: u32) -> VkResult<Dispatch> {
    let slots = [
        Slot::Buffer(&buffers.texel_samples, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.indirect, Access::ComputeStorageRead),
        Slot::StorageImage(light_map, Access::ComputeStorageWrite),
    ];
    Dispatch::new(shared, "mrt.light_map", shaders::MRT_LIGHT_MAP_COMP, texels, &slots)
}
