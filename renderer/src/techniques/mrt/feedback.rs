//! The solved feedback (compute), §7.3: b = (I - K)^-1 b0 per colour channel, every bounce
//! at once; b = b0 with feedback off: shaders/mrt/feedback.comp.
//!
//! Reads: `feedback`, `b0`. Writes: `b`. Cost: one invocation per (block, mode), 3 D
//! multiply-adds (D = blocks x k_max): 3 D^2 in all, 0.37 M on an 11-block level at k 32.

use super::{Buffers, Dispatch};
use crate::passes::compute::Slot;
use crate::shaders;
use crate::technique::Shared;
use crate::vk::{Access, VkResult};

pub(super) fn new(shared: &Shared, buffers: &Buffers, invocations: u32) -> VkResult<Dispatch> {
    let slots = [
        Slot::Buffer(&buffers.feedback, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.b0, Access::ComputeStorageRead),
        Slot::Buffer(&buffers.b, Access::ComputeStorageWrite),
    ];
    Dispatch::new(shared, "mrt.feedback", shaders::MRT_FEEDBACK_COMP, invocations, &slots)
}
