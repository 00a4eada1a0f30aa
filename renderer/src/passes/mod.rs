//! The passes of a frame, one file each. A pass is created once (pipelines, descriptor sets)
//! and records into a command buffer it is given; it declares the images and buffers it reads
//! and writes to the tracker, which records the barriers.

pub mod cluster_sums;
pub mod entry_irradiance;
pub mod forward;
pub mod lpm_reconstruct;
pub mod padding;
pub mod tonemap;
pub mod vsm;
pub mod vsm_blur;
