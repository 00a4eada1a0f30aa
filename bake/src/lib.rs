//! relume's CPU side: the scene, images and error metrics (plain data the renderer reads too)
//! and, behind the `baking` feature, the BVH and the reference path tracer.

pub mod image;
pub mod scene;
