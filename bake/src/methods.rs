//! The bake crate's registry of methods: the block each method reads from a scene's
//! `extras.relume` (its key, and the reader that checks it when the scene loads). One line
//! per method that has scene settings.

use crate::settings::SceneBlock;

pub const SCENE_BLOCKS: [SceneBlock; 5] = [
    crate::obscurance::SCENE_BLOCK,
    crate::light_path_maps::SCENE_BLOCK,
    crate::fiv::SCENE_BLOCK,
    crate::light_cloud::SCENE_BLOCK,
    crate::mrt::SCENE_BLOCK,
];
