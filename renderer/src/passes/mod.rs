//! The passes of a frame, one file each. A pass is created once (pipelines, descriptor sets)
//! and records into a command buffer it is given; it declares the images it reads and writes
//! to the tracker, which records the barriers.

pub mod forward;
pub mod padding;
pub mod tonemap;
pub mod vsm;
pub mod vsm_blur;
