//! The obscurances of Iones et al., "Fast realistic lighting for video games" (001): the
//! scene's settings of them (`extras.relume.obscurance`: tau and L_max), their artifact
//! section `obscurance` (W per atlas texel), and, behind the `baking` feature, the baker
//! (`baker.rs`: obscurance, ambient occlusion, and the spectral obscurance of 000 §3.3).

#[cfg(feature = "baking")]
mod baker;
#[cfg(feature = "baking")]
pub use baker::*;
#[cfg(feature = "baking")]
mod bake;
#[cfg(feature = "baking")]
pub use bake::*;

use crate::artifact::{fail, Artifact, ArtifactError, Key, PageLayout, Section, REBAKE};
use crate::image::encode_exr_layer;
use crate::scene::Scene;
use crate::settings::{as_object, diagonal, first_failed_check, known_keys, number, SceneBlock};
use glam::Vec3;
use serde_json::Value;

/// tau and L_max of 001 eq. (2) and §4.4, from the scene's `extras.relume.obscurance`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObscuranceSceneSettings {
    /// tau of eq. (2), metres: rho(L) = 1 - exp(-L / tau).
    pub tau: f32,
    /// L_max of §4.4, metres: rho is 1 from this distance on. Also the small-scale threshold
    /// of the light path maps (000 §3.2.2), so no path is counted twice.
    pub l_max: f32,
}

impl ObscuranceSceneSettings {
    /// For a scene that states none: L_max a tenth of the bounding-box diagonal, tau a third
    /// of L_max (so rho(L_max) = 0.95 and the cut at L_max is small).
    pub fn defaults_for(bounds: (Vec3, Vec3)) -> Self {
        let l_max = 0.1 * diagonal(bounds);
        ObscuranceSceneSettings { tau: l_max / 3.0, l_max }
    }

    /// The scene's settings (checked when it loaded), over the defaults for its bounds.
    pub fn of(scene: &Scene) -> Result<Self, String> {
        from_block(scene.settings.block(KEY), scene.settings.bounds)
    }
}

const KEY: &str = "obscurance";

pub const SCENE_BLOCK: SceneBlock = SceneBlock { key: KEY, check: |block, bounds| from_block(Some(block), bounds).map(|_| ()) };

fn from_block(block: Option<&Value>, bounds: (Vec3, Vec3)) -> Result<ObscuranceSceneSettings, String> {
    let mut s = ObscuranceSceneSettings::defaults_for(bounds);
    let Some(block) = block else { return Ok(s) };
    let o = as_object(block, "extras.relume.obscurance")?;
    known_keys(o, "extras.relume.obscurance", &["tau", "l_max"])?;
    if let Some(v) = o.get("tau") {
        s.tau = number(v, "extras.relume.obscurance.tau")?;
    }
    if let Some(v) = o.get("l_max") {
        s.l_max = number(v, "extras.relume.obscurance.l_max")?;
    }
    let checks = [
        (s.tau.is_finite() && s.tau > 0.0, "extras.relume.obscurance.tau must be finite and > 0 (metres)"),
        (s.l_max.is_finite() && s.l_max > 0.0, "extras.relume.obscurance.l_max must be finite and > 0 (metres)"),
    ];
    first_failed_check(&checks)?;
    Ok(s)
}

pub const SECTION: &str = "obscurance";
pub const SECTION_VERSION: u32 = 1;
const FILE: &str = "obscurance.exr";
const LAYER: &str = "W";

/// The section: W (rgb) per atlas texel, page after page, each row by row from the top.
pub fn section(values: &[Vec3], layout: PageLayout, summary: Value) -> Result<Section, String> {
    if values.len() != layout.texel_count() {
        return Err(format!("{} values for an atlas of {} texels", values.len(), layout.texel_count()));
    }
    let bytes = encode_exr_layer(LAYER, layout.width, values)?;
    Ok(Section { name: SECTION.into(), version: SECTION_VERSION, key: Key::Scene, summary, files: vec![(FILE.into(), bytes)] })
}

/// W of `artifact`, read for `scene`, on the atlas of `layout`; refused when its size is not
/// the atlas's or a value is not in 0..=1e9.
pub fn read(artifact: &Artifact, scene: &Scene, layout: PageLayout) -> Result<Vec<Vec3>, ArtifactError> {
    let data = artifact.section(SECTION, SECTION_VERSION, Some(scene))?;
    let (image, path) = data.exr_layer(FILE, LAYER, (layout.width, layout.height * layout.pages))?;
    let admitted = |w: &Vec3| w.is_finite() && w.min_element() >= 0.0 && w.max_element() <= crate::scene::MAX_LIGHT;
    if let Some(t) = image.pixels.iter().position(|w| !admitted(w)) {
        return Err(fail(&path, format!("texel {t} holds {}, not a value in 0..=1e9", image.pixels[t]), REBAKE));
    }
    Ok(image.pixels)
}
