//! The dynamic meshes' light (compute), §7.3 step 9: each vertex of a mesh the scene declares
//! dynamic finds its block, reads the light volume there and writes its irradiance, alpha 1
//! (the lighting pass reads it in place of the light map): shaders/mrt/dynamic.comp.
//!
//! Reads: the scene's vertex buffer (host-written, as the meshes move), `dynamic_vertices`,
//! `volume_blocks`, `volume`. Writes: `vertex_light` (its dynamic vertices only). Cost: one
//! invocation per dynamic vertex, a bounds test per block and Newton's method in the blocks
//! whose bounds hold it.

use super::{Buffers, Dispatch};
use crate::passes::compute::Slot;
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{Access, VkResult};

pub(super) fn new(shared: &Shared, buffers: &Buffers, vertices: u32) -> VkResult<Dispatch> {
    let slots = [
        Slot::Updated(&shared.gpu_scene.vertices),
        Slot::Buffer(&buffers.dynamic_vertices, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.volume_blocks, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.volume, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.vertex_light, Access::ComputeStorageWrite),
    ];
    Dispatch::new(shared, "mrt.dynamic", shaders::MRT_DYNAMIC_COMP, vertices, &slots)
}
