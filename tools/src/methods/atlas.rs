//! What every method baked on the lightmap atlas shares (a shared part, not a method): the
//! atlas's parameters, its bake stage and summary, and reading it back with the scene
//! re-indexed by it.

use super::params::{Default, Param, Values};
use anyhow::{bail, Result};
use relume_bake::artifact::Artifact;
use relume_bake::atlas::stage::AtlasStage;
use relume_bake::atlas::{AtlasSection, AtlasSettings};
use relume_bake::scene::Scene;

pub(crate) const TEXEL_DENSITY: Param = Param::within(
    "texel-density",
    "lightmap texels per metre (001 §3's patch grid)",
    AtlasSettings::TEXEL_DENSITY,
    Default::From("the scene's texel_density"),
);
pub(crate) const PATCHES: Param = Param::count(
    "patches",
    "aim for about this many covered texels instead of a texel density (bisects the density)",
    1,
    1 << 28,
    Default::From("none: the texel density decides"),
);
pub(crate) const GUTTER: Param = Param::within("gutter", "empty texels between charts", AtlasSettings::GUTTER, Default::Value("2"));
pub(crate) const ATLAS_MAX: Param = Param::within(
    "atlas-max",
    "largest atlas page side in texels; more pages when the charts do not fit one",
    AtlasSettings::MAX_SIZE,
    Default::Value("4096"),
);
pub(crate) const DISCONTINUITY_ANGLE: Param = Param::within(
    "discontinuity-angle",
    "largest angle between faces of one chart, degrees (001 §3)",
    AtlasSettings::DISCONTINUITY_DEGREES,
    Default::Value("60"),
);

pub(crate) const PARAMS: [&Param; 5] = [&TEXEL_DENSITY, &PATCHES, &GUTTER, &ATLAS_MAX, &DISCONTINUITY_ANGLE];

/// The atlas's settings from `values` over the scene's.
pub(crate) fn settings(scene: &Scene, values: &Values) -> Result<AtlasSettings> {
    if values.given(&TEXEL_DENSITY) && values.given(&PATCHES) {
        bail!("--texel-density and --patches: give one of them");
    }
    let settings = AtlasSettings {
        texel_density: values.given_number(&TEXEL_DENSITY).map_or(scene.settings.texel_density, |d| d as f32),
        gutter: values.count(&GUTTER) as u32,
        max_size: values.count(&ATLAS_MAX) as u32,
        discontinuity_angle: (values.number(&DISCONTINUITY_ANGLE) as f32).to_radians(),
    };
    settings.validate().map_err(|e| anyhow::anyhow!("{e} (--texel-density, --gutter, --atlas-max, --discontinuity-angle)"))?;
    Ok(settings)
}

/// The atlas stage of a bake: built for the settings, or bisected to about `--patches`
/// covered texels.
pub(crate) fn stage(scene: &Scene, values: &Values) -> Result<AtlasStage> {
    Ok(AtlasStage { settings: settings(scene, values)?, patches: values.given_count(&PATCHES).map(|p| p as u32) })
}

/// The artifact's atlas and `scene` re-indexed by it.
pub(crate) fn read(artifact: &Artifact, scene: &Scene) -> Result<(AtlasSection, Scene)> {
    read_for(artifact, scene, scene)
}

/// As `read`, for an atlas made on `scene`'s tessellation `fine` (keyed to `scene`).
pub(crate) fn read_for(artifact: &Artifact, scene: &Scene, fine: &Scene) -> Result<(AtlasSection, Scene)> {
    let atlas = AtlasSection::read_for(artifact, scene, fine)?;
    let mut applied = fine.clone();
    atlas.apply_to(&mut applied);
    Ok((atlas, applied))
}
