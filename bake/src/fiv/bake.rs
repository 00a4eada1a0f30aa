//! FIV's whole bake behind the bake contract: the environment's terms and a table per occluder
//! type (003 §4), with the facts the manifest and stats.json keep.

use super::{bake_types, first_names, occluders, sections, FivBakeSettings, FivSceneSettings};
use crate::contract::{scene_bytes, Baked, Baker, Estimate, Stages};
use crate::scene::Scene;
use crate::work::WorkOptions;
use serde_json::json;

pub struct FivBaker {
    pub settings: FivBakeSettings,
}

/// Bytes a table sample holds while it bakes and is stored: three rgb f32 (36 bytes, 003
/// Table 1) for the free table and for the surface table, their flags, and the section's copy.
pub const BYTES_PER_SAMPLE: u64 = 160;

impl FivBaker {
    /// The tables' peak: every sample of every occluder type's tables.
    pub fn estimate(&self, scene: &Scene, types: usize) -> Estimate {
        let samples = self.settings.grid.samples() as u64;
        Estimate {
            fixed: scene_bytes(scene),
            count: types as u64 * samples,
            bytes_per_unit: BYTES_PER_SAMPLE,
            unit: "occluder types x table samples".into(),
            lever: "table samples per occluder type (--grid)",
            value: samples,
            power: 1.0,
            squared: 0,
        }
    }
}

impl Baker for FivBaker {
    fn bake(&self, scene: &Scene, work: &WorkOptions, stages: &mut Stages) -> Result<Baked, String> {
        let settings = &self.settings;
        settings.validate().map_err(|e| format!("{e} (--distance-min, --distance-max, --mask-supersample, --difmap-width)"))?;
        let declared = FivSceneSettings::of(scene)?;
        let types = super::occluder_types(scene, &declared)?;
        work.admit("fiv", &self.estimate(scene, types.len()))?;
        let fiv = stages.timed("fiv", || bake_types(scene, &types, settings, work))?;
        let representatives: Vec<&str> = types.iter().map(|t| scene.meshes[t.meshes[0]].name.as_str()).collect();
        let samples = settings.grid.samples();
        let occluder_count = occluders(scene, &types).len();
        // 36 bytes a sample as 003 Table 1, and the surface points' masks of self-shadowing.
        let table_bytes: usize = fiv.tables.iter().map(|t| (t.fiv.len() + t.surface.len()) * 36).sum();
        let facts = json!({ "grid": settings.grid.name(), "types": types.len(), "occluders": occluder_count });
        let mut baked = Baked {
            sections: sections(&fiv, &representatives, facts),
            parameters: json!({
                "grid": settings.grid.name(),
                "distance_min": settings.distance_min,
                "distance_max": settings.distance_max,
                "mask_supersample": settings.mask_supersample,
                "difmap_width": settings.difmap_width,
            }),
            stats: json!({ "table_bytes": table_bytes, "samples_per_type": samples, "types": types.len() }),
            summary: format!(
                "{} occluder types ({occluder_count} occluders), grid {} ({samples} samples per type), tables {:.2} MiB\n",
                types.len(),
                settings.grid.name(),
                table_bytes as f64 / (1 << 20) as f64
            ),
        };
        if declared.derived {
            let how = format!("{} (the closed meshes under 80 % of the scene's footprint)", first_names(&declared.occluders));
            baked.derived("occluders", json!(declared.occluders), &how, "extras.relume.fiv.occluders");
        }
        Ok(baked)
    }
}
