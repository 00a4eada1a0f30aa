//! The obscurance method's whole bake behind the bake contract: the atlas, the BVH and the
//! obscurance on the atlas (001 §4). The light path maps' bake begins with it too (their small
//! scale is the spectral obscurance, 000 §3.3).

use super::baker::gather_obscurance;
use super::{section, ObscuranceMap, ObscuranceSettings};
use crate::atlas::stage::{self, short, AtlasStage};
use crate::atlas::Atlas;
use crate::bvh::SceneBvh;
use crate::contract::{scene_bytes, Baked, Baker, Estimate, Stages};
use crate::scene::Scene;
use crate::work::WorkOptions;
use serde_json::{json, Value};

pub struct ObscuranceBaker {
    pub atlas: AtlasStage,
    /// Its `work` is replaced by the bake's.
    pub obscurance: ObscuranceSettings,
}

/// Bytes a texel of the atlas holds while the obscurance bakes: its texel and piece records,
/// its value and its running sum (measured: docs/BENCHMARKS.md, "Peak memory").
pub const BYTES_PER_TEXEL: u64 = 180;

impl ObscuranceBaker {
    /// The atlas, the BVH and the obscurance on the atlas, each a timed stage; returns the
    /// bake with the atlas and BVH for the stages that follow (`followed`: they gather again,
    /// and read nothing of the obscurance before).
    pub fn bake_on_atlas(
        &self,
        scene: &Scene,
        work: &WorkOptions,
        stages: &mut Stages,
        followed: bool,
    ) -> Result<(Baked, Atlas, SceneBvh), String> {
        let settings = ObscuranceSettings { work: *work, ..self.obscurance.clone() };
        settings.validate()?;
        let atlas = self.atlas.build(scene, stages)?;
        work.admit("obscurance", &self.estimate(scene, &atlas))?;
        let bvh = stages.timed("bvh", || SceneBvh::build(scene, work.ray_backend))?;
        let map = stages.timed("obscurance", || gather_obscurance(scene, &bvh, &atlas, &settings, followed))?;
        let facts = json!({ "variant": settings.variant.name(), "rays_per_texel": map.rays_per_texel });
        let obscurance = section(&map.values, atlas.layout(), facts)?;
        let mut parameters = parameters(&settings);
        parameters["atlas"] = self.atlas.parameters();
        let baked = Baked {
            sections: vec![self.atlas.section(&atlas), obscurance],
            parameters,
            stats: stats(&map, &settings),
            summary: stage::summary(&atlas) + &summary(&map),
        };
        Ok((baked, atlas, bvh))
    }

    /// The obscurance's peak: the scene and its BVH, and every texel of the atlas; the lever
    /// is the covered texels (`--patches`).
    pub fn estimate(&self, scene: &Scene, atlas: &Atlas) -> Estimate {
        Estimate {
            fixed: scene_bytes(scene),
            count: atlas.texels.len() as u64,
            bytes_per_unit: BYTES_PER_TEXEL,
            unit: "texels".into(),
            lever: "--patches",
            value: atlas.covered_texels() as u64,
            power: 1.0,
            squared: 0,
        }
    }
}

impl Baker for ObscuranceBaker {
    fn bake(&self, scene: &Scene, work: &WorkOptions, stages: &mut Stages) -> Result<Baked, String> {
        Ok(self.bake_on_atlas(scene, work, stages, false)?.0)
    }
}

fn parameters(settings: &ObscuranceSettings) -> Value {
    json!({
        "variant": settings.variant.name(),
        "tau": short(settings.tau),
        "l_max": short(settings.l_max),
        "rays_per_texel": settings.rays_per_texel,
        "seed": settings.work.seed,
    })
}

fn stats(map: &ObscuranceMap, settings: &ObscuranceSettings) -> Value {
    json!({
        "rays_per_texel": map.rays_per_texel,
        "rays_per_texel_asked": settings.rays_per_texel,
        "rays_traced": map.rays_traced,
        "rays_per_second": map.rays_traced as f64 / map.seconds.max(1e-9),
    })
}

fn summary(map: &ObscuranceMap) -> String {
    let rate = map.rays_traced as f64 / map.seconds.max(1e-9) / 1e6;
    format!("{} rays per texel, {} rays in {:.3} s ({rate:.2} M rays/s)\n", map.rays_per_texel, map.rays_traced, map.seconds)
}
