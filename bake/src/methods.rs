//! The bake crate's registry of methods: the block each method reads from a scene's
//! `extras.relume` (its key, and the reader that checks it when the scene loads). One line
//! per method that has scene settings.

use glam::Vec3;
use serde_json::Value;

/// A method's block of scene settings.
#[derive(Clone, Copy)]
pub struct SceneBlock {
    /// The key under `extras.relume`.
    pub key: &'static str,
    /// Checks the block of a scene with the given bounds, naming what is wrong.
    pub check: fn(&Value, (Vec3, Vec3)) -> Result<(), String>,
}

pub const SCENE_BLOCKS: [SceneBlock; 2] = [crate::obscurance::SCENE_BLOCK, crate::light_path_maps::SCENE_BLOCK];
