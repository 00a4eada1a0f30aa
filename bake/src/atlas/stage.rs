//! The atlas stage every texel method's bake begins with: the atlas built for its settings
//! (or bisected to about a patch count), its section, and its facts for the manifest.

use super::{Atlas, AtlasSettings};
use crate::artifact::Section;
use crate::contract::Stages;
use crate::scene::Scene;
use serde_json::{json, Value};

#[derive(Clone, Debug, PartialEq)]
pub struct AtlasStage {
    pub settings: AtlasSettings,
    /// Aim for about this many covered texels instead of the texel density.
    pub patches: Option<u32>,
}

impl AtlasStage {
    pub fn build(&self, scene: &Scene, stages: &mut Stages) -> Result<Atlas, String> {
        let built = stages.timed("atlas", || match self.patches {
            Some(patches) => Atlas::build_for_patch_count(scene, &self.settings, patches),
            None => Atlas::build(scene, &self.settings),
        });
        built.map_err(|e| e.to_string())
    }

    /// The atlas's parameters as used, for the manifest.
    pub fn parameters(&self) -> Value {
        let s = &self.settings;
        json!({
            "texel_density": short(s.texel_density),
            "patches": self.patches,
            "gutter": s.gutter,
            "atlas_max": s.max_size,
            "discontinuity_angle_degrees": short(s.discontinuity_angle.to_degrees()),
        })
    }

    /// The atlas's section, with its facts for the manifest.
    pub fn section(&self, atlas: &Atlas) -> Section {
        atlas.section(json!({
            "width": atlas.width,
            "height": atlas.height,
            "pages": atlas.pages,
            "charts": atlas.charts.len(),
            "covered_texels": atlas.covered_texels(),
            "utilization": atlas.utilization(),
            "too_small_triangles": atlas.too_small,
            "texel_density": short(self.settings.texel_density),
        }))
    }
}

/// The atlas in a line (and a warning for triangles too small to cover a texel).
pub fn summary(atlas: &Atlas) -> String {
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

/// An f32 as JSON in its shortest round-trip form (0.15, not 0.15000000596046448).
pub fn short(x: f32) -> Value {
    x.to_string().parse::<f64>().map_or(Value::Null, |v| json!(v))
}
