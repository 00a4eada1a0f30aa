//! Every technique: a method's run-time part, one folder each (docs/ARCHITECTURE.md).

pub mod fiv;
pub mod light_cloud;
pub mod light_path_maps;
pub mod mrt;
pub mod obscurance;
