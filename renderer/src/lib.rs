//! relume's Vulkan renderer. A library first: [`Renderer::record`] writes a whole frame into a
//! command buffer the caller owns, on a device the caller may provide
//! ([`vk::Context::from_existing`]), optionally into the caller's own image
//! ([`Renderer::record_to`]); [`Headless`] is the driver relume's own tools use.
//!
//! Layers (docs/ARCHITECTURE.md): `vk` owns every unsafe Vulkan call; `passes` are the shared
//! passes, safe code, one file each; `techniques` holds each method's run-time part, one
//! folder each, behind the [`technique::Technique`] trait; `effect` runs techniques without
//! relume's frame (for an engine's own), and `frame` is relume's frame around an effect.

pub mod atlas_image;
pub mod effect;
pub mod frame;
pub mod gpu_scene;
pub mod headless;
pub mod passes;
pub mod technique;
pub mod techniques;
pub mod upload;
pub mod vk;

pub use atlas_image::AtlasImage;
pub use effect::{Effect, EffectOutput, EngineInputs, TermReads};
pub use frame::{CallerImage, FrameTimings, RenderSettings, Renderer};
pub use gpu_scene::{LightDepth, ShadowMapView};
pub use headless::Headless;
pub use technique::{MakeTechnique, Technique};

/// SPIR-V of every shader in `shaders/`, compiled by build.rs.
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}
