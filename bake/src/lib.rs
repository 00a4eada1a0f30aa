//! relume's CPU side: the scene, images and error metrics, the bake artifact and every
//! method's scene settings and sections (plain data the renderer reads too) and, behind the
//! `baking` feature, the BVH, the reference path tracer and the bakers.
//!
//! Each method is one folder (its settings, its section, its baker); the shared parts (scene,
//! atlas, clustered PCA, sampling, path tracer) never know the methods.

pub mod artifact;
pub mod atlas;
pub mod binary;
pub mod environment;
pub mod gltf_load;
pub mod image;
pub mod inputs;
pub mod lights_file;
pub mod methods;
pub mod metrics;
pub mod outputs;
pub mod scene;
pub mod settings;
pub mod sh;
pub mod tessellation;
pub mod testing;

pub mod fiv;
pub mod light_cloud;
pub mod light_path_maps;
pub mod mrt;
pub mod obscurance;

#[cfg(feature = "baking")]
mod bsdf;
#[cfg(feature = "baking")]
pub mod bvh;
#[cfg(feature = "baking")]
pub mod contract;
#[cfg(feature = "baking")]
pub mod cpca;
#[cfg(feature = "embree")]
pub mod embree;
#[cfg(feature = "baking")]
mod light_grid;
#[cfg(feature = "baking")]
pub mod ray_bench;
#[cfg(feature = "baking")]
pub mod reference;
#[cfg(feature = "baking")]
pub mod sampling;
#[cfg(feature = "baking")]
pub mod shards;
#[cfg(feature = "baking")]
pub mod work;
