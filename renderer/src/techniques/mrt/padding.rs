//! The MRT light-map padding (compute), the padded atlas of §6-7: each copy record writes a
//! tile's border texel from the sample texel beyond it (across a seam, or its own edge at a
//! crease): shaders/mrt/padding.comp.
//!
//! Reads: `copies`; reads and writes the light map (sources are sample texels, which no record
//! writes). Cost: one invocation per record, 4 (grid + 1) per block face.

use super::{Buffers, Dispatch};
use crate::passes::compute::Slot;
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{Access, Image, VkResult};

pub(super) fn new(shared: &Shared, buffers: &Buffers, light_map: &Image, copies: u32) -> VkResult<Dispatch> {
    let slots = [Slot::Buffer(&buffers.copies, Access::ComputeStorageRead), Slot::StorageImage(light_map, Access::ComputeStorageReadWrite)];
    Dispatch::new(shared, "mrt.padding", shaders::MRT_PADDING_COMP, copies, &slots)
}
