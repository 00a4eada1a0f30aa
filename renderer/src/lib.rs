//! relume's Vulkan renderer. A library first: [`Renderer::record`] writes a whole frame into a
//! command buffer the caller owns, on a device the caller may provide
//! ([`vk::Context::from_existing`]); [`Renderer::render`] is the headless driver.
//!
//! Layers: `vk` owns every unsafe Vulkan call; `passes` are safe code, one file per pass;
//! `frame` wires them in order; `lightmap` uploads a baked lightmap and pads it once; the
//! forward pass reads it through uv1 (the obscurance model, 001 eq. (5)-(7));
//! `light_path_maps` uploads the clustered transfer of 000, from which four compute passes
//! make each frame's large-scale indirect irradiance (000 §3.4).

pub mod frame;
pub mod gpu_scene;
pub mod light_path_maps;
pub mod lightmap;
pub mod passes;
pub mod vk;

pub use frame::{Composition, FrameTimings, RenderSettings, Renderer, PASS_NAMES};
pub use lightmap::LightmapData;

/// SPIR-V of every shader in `shaders/`, compiled by build.rs.
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}
