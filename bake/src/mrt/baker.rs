//! A level's bake (§6.2-6.3): the scene mapped onto its block proxy (the light map with its
//! padded atlas) and T_b->r by traversal, from a dictionary made (or read) before.

use super::dictionary::{self, Dictionary};
use super::evaluate::LevelTransfer;
use super::level_data::LevelData;
use super::map::{map, Mapped};
use super::proxy::Proxy;
use crate::scene::Scene;

/// The scene on its blocks and the level's tables, made with `dictionary` to `d_max` crossings.
pub fn bake_level(scene: &Scene, dictionary: &Dictionary, d_max: usize) -> Result<(Mapped, LevelData), String> {
    let proxy = Proxy::of(scene)?;
    let level = proxy.level();
    let mapped = map(scene, &proxy, &level, dictionary.settings.samples_per_face)?;
    let (operators, interfaces) = dictionary.operators();
    let transfer = LevelTransfer::new(&level, &operators, &interfaces, d_max)?;
    let data = transfer.level_data(dictionary::checksum(dictionary), &mapped);
    Ok((mapped, data))
}
