//! relume's CPU side: the scene, images and error metrics (plain data the renderer reads too)
//! and, behind the `baking` feature, the BVH and the reference path tracer.

pub mod artifact;
pub mod clustered_transfer;
pub mod gltf_load;
pub mod image;
pub mod metrics;
pub mod scene;
pub mod settings;
pub mod testing;

#[cfg(feature = "baking")]
pub mod atlas;
#[cfg(feature = "baking")]
pub mod bvh;
#[cfg(feature = "baking")]
pub mod cpca;
#[cfg(feature = "baking")]
pub mod light_path_maps;
#[cfg(feature = "baking")]
pub mod obscurance;
#[cfg(feature = "baking")]
pub mod reference;
#[cfg(feature = "baking")]
pub mod sampling;
#[cfg(feature = "baking")]
pub mod work;
