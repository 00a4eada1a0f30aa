//! The Vulkan backend: the only place in relume that makes unsafe Vulkan calls or touches the
//! allocator. One file per Vulkan object; everything above it is safe Rust.

mod barrier;
mod buffer;
mod context;
mod descriptor;
mod device;
mod image;
mod instance;
mod pipeline;
mod query;
mod readback;
mod reflect;
mod sync;

pub use ash::vk;
pub use barrier::{barrier_between, transition, Access, BufferRef, ImageRef, ImageState, Tracker, Use};
pub use buffer::Buffer;
pub use context::{CommandRecorder, Context, ContextOptions};
pub use descriptor::{Binding, DescriptorSet};
pub use device::DeviceInfo;
pub use image::{Image, ImageDesc, ImageView};
pub use pipeline::{GraphicsPipelineDesc, Pipeline};
pub use query::TimestampQueries;
pub use readback::Readback;
pub use reflect::workgroup_size;
pub use sync::{CommandBuffer, Fence, Sampler};

/// Everything that can go wrong in the backend, each with what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum VkError {
    #[error("cannot load the Vulkan loader (libvulkan.so.1): {0}; install mesa-vulkan-drivers and libvulkan1")]
    Loader(String),
    #[error("no Vulkan device matches {0}; run `vulkaninfo --summary` to list them")]
    NoDevice(String),
    #[error("device {device} lacks {missing}; relume needs Vulkan 1.3 with dynamic rendering and synchronization2")]
    MissingFeature { device: String, missing: String },
    #[error("Vulkan call failed: {0}")]
    Call(#[from] vk::Result),
    #[error("GPU memory allocation failed: {0}")]
    Allocation(#[from] gpu_allocator::AllocationError),
    #[error("{0}")]
    Invalid(String),
}

pub type VkResult<T> = Result<T, VkError>;
