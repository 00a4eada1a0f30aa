//! The shared passes of a frame, one file each: variance shadow maps (moments, blur), the
//! lighting pass, the tonemap, and the atlas padding techniques run on their images; and the
//! one shape every compute pass takes (`compute`) and every graphics pass (`graphics`). A pass
//! is created once (pipelines, descriptor sets, checked against its shaders' SPIR-V) and
//! records into a command buffer it is given; it declares the images and buffers it reads and
//! writes to the tracker, which records the barriers.

pub mod compute;
pub mod graphics;
pub mod lighting;
pub mod padding;
pub mod tonemap;
pub mod vsm;
pub mod vsm_blur;
