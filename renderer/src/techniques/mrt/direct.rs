//! Direct light at the level's samples (compute), §7.3 step 1: shaders/mrt/direct.comp.
//!
//! Reads: the scene's light and shadow-layer buffers and the frame's uniforms, the shadow
//! moments (through the lighting pass's filter), the samples. Writes: `light` (rho E_d) and
//! `direct` (E_d). Cost: one invocation per sample, a shadow-map fetch per light facing it.

use super::{Buffers, Dispatch};
use crate::passes::compute::Slot;
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{Access, Sampler, VkResult};

pub(super) fn new(shared: &Shared, buffers: &Buffers, shadow_sampler: &Sampler, samples: u32) -> VkResult<Dispatch> {
    let scene = shared.gpu_scene;
    let slots = [
        Slot::Updated(&scene.lights),
        Slot::Updated(&scene.layers),
        Slot::Sampled(shared.moments, shadow_sampler),
        Slot::Buffer(&buffers.samples, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.light, Access::ComputeStorageWrite),
        Slot::Buffer(&buffers.direct, Access::ComputeStorageWrite),
        Slot::Uniform(&scene.frame),
    ];
    Dispatch::new(shared, "mrt.direct", shaders::MRT_DIRECT_COMP, samples, &slots)
}
