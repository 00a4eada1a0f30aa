//! What every method baked on the lightmap atlas shares (a shared part, not a method): the
//! atlas's parameters, its bake stage and summary, and reading it back with the scene
//! re-indexed by it.

use super::params::{Default, Param, Values};
use super::Stages;
use anyhow::{bail, Result};
use relume_bake::artifact::{Artifact, Section};
use relume_bake::atlas::{Atlas, AtlasSection, AtlasSettings};
use relume_bake::scene::Scene;
use serde_json::{json, Value};

pub(crate) const TEXEL_DENSITY: Param = Param::number(
    "texel-density",
    "lightmap texels per metre (001 §3's patch grid)",
    (0.0, 1e6, true),
    Default::From("the scene's texel_density"),
);
pub(crate) const PATCHES: Param = Param::count(
    "patches",
    "aim for about this many covered texels instead of a texel density (bisects the density)",
    1,
    1 << 28,
    Default::From("none: the texel density decides"),
);
pub(crate) const GUTTER: Param = Param::count("gutter", "empty texels between charts", 1, 64, Default::Value("2"));
pub(crate) const ATLAS_MAX: Param = Param::count(
    "atlas-max",
    "largest atlas page side in texels; more pages when the charts do not fit one",
    16,
    16384,
    Default::Value("4096"),
);
pub(crate) const DISCONTINUITY_ANGLE: Param = Param::number(
    "discontinuity-angle",
    "largest angle between faces of one chart, degrees (001 §3)",
    (0.0, 180.0, true),
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

/// The atlas stage of a bake: built for the settings (or bisected to about `--patches`
/// covered texels).
pub(crate) fn build(scene: &Scene, values: &Values, stages: &mut Stages) -> Result<(Atlas, AtlasSettings)> {
    let settings = settings(scene, values)?;
    let atlas = stages.timed("atlas", || match values.given_count(&PATCHES) {
        Some(patches) => Atlas::build_for_patch_count(scene, &settings, patches as u32),
        None => Atlas::build(scene, &settings),
    })?;
    Ok((atlas, settings))
}

/// The atlas's section, with its facts for the manifest.
pub(crate) fn section(atlas: &Atlas, settings: &AtlasSettings) -> Section {
    atlas.section(json!({
        "width": atlas.width,
        "height": atlas.height,
        "pages": atlas.pages,
        "charts": atlas.charts.len(),
        "covered_texels": atlas.covered_texels(),
        "utilization": atlas.utilization(),
        "too_small_triangles": atlas.too_small,
        "texel_density": short(settings.texel_density),
    }))
}

/// The atlas's parameters as used, for the manifest.
pub(crate) fn parameters(settings: &AtlasSettings, values: &Values) -> Value {
    json!({
        "texel_density": short(settings.texel_density),
        "patches": values.given_count(&PATCHES),
        "gutter": settings.gutter,
        "atlas_max": settings.max_size,
        "discontinuity_angle_degrees": short(settings.discontinuity_angle.to_degrees()),
    })
}

/// The atlas in a line (and a warning for triangles too small to cover a texel).
pub(crate) fn summary(atlas: &Atlas) -> String {
    let mut text = format!(
        "atlas: {} charts, {} x {} x {} page(s), {} patches, utilization {:.1}%\n",
        atlas.charts.len(),
        atlas.width,
        atlas.height,
        atlas.pages,
        atlas.covered_texels(),
        100.0 * atlas.utilization()
    );
    if !atlas.too_small.is_empty() {
        text.push_str(&format!(
            "warning: {} triangle(s) too small to cover a texel measurably: {:?}\n",
            atlas.too_small.len(),
            atlas.too_small
        ));
    }
    text
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

/// An f32 as JSON in its shortest round-trip form (0.15, not 0.15000000596046448).
pub(crate) fn short(x: f32) -> Value {
    x.to_string().parse::<f64>().map_or(Value::Null, |v| json!(v))
}
