//! The light path maps' whole bake behind the bake contract: the obscurance method's bake with
//! the spectral variant (the small scale, 000 §3.3), then entry points from the scene's light
//! region (§3.2.1), their transfers by virtual lights (§3.2.2) and the transfers' clustered PCA
//! (§3.2.3).

use super::{
    bake_transfers, compress, entry_points, fitted, sizes, test_points, Compressed, Compression, EntryPoints, LightPathMapSettings,
    LightPathMapsSceneSettings, LightRegion, Transfers, BUDGET_TEXTURES_MAX,
};
use crate::atlas::stage::short;
use crate::contract::{Baked, Baker, Estimate, Stages};
use crate::obscurance::ObscuranceBaker;
use crate::scene::{LightKind, Scene};
use crate::work::WorkOptions;
use serde_json::json;

pub struct LightPathMapsBaker {
    /// The small scale: its variant is the spectral obscurance unless given otherwise.
    pub obscurance: ObscuranceBaker,
    /// Its `work` is replaced by the bake's.
    pub settings: LightPathMapSettings,
    /// The region's box re-sampled at this many test points.
    pub test_points: Option<u32>,
    pub compression: Compression,
}

/// Bytes a covered texel takes per entry point at the bake's peak (measured: docs/BENCHMARKS.md,
/// "Peak memory"): its transfer (three f32), which clustered PCA reads in place; uncompressed,
/// also every transfer spread over the whole atlas and its EXR's copy.
pub fn bytes_per_transfer(compression: Compression) -> u64 {
    match compression {
        Compression::None => 36,
        _ => 12,
    }
}

/// Bytes an atlas texel takes per stored texture (a cluster's mean or eigen-texture, three f32)
/// while the clusters are made: the clusters' vectors and the textures spread over the atlas.
pub const BYTES_PER_TEXTURE_TEXEL: u64 = 24;

/// The bytes of stored textures (three f32 a texel) that every Vulkan device reads as one
/// storage buffer (maxStorageBufferRange is at least 2^27): the error budget's search keeps
/// within them, so that the size it chooses renders anywhere (a 2 m cube's 137,408 texels took
/// 96 textures, 151 MiB, which lavapipe refused after `run` had baked it).
const GPU_TEXTURE_BYTES: u64 = 1 << 27;

/// Test points a directional light's derived region has (the scenes' declared boxes: 64).
const SUN_TEST_POINTS: u32 = 64;

/// The region the transfers are made for, and whether the scene declares it.
struct Region {
    region: Option<LightRegion>,
    derived: bool,
    light_area: f32,
}

impl LightPathMapsBaker {
    fn region(&self, scene: &Scene) -> Result<Region, String> {
        let block = LightPathMapsSceneSettings::of(scene)?;
        let derived = block.region.is_none();
        let region = match (block.region.or_else(|| derived_region(scene)), self.test_points) {
            (Some(LightRegion::Box { min, max, .. }), Some(m)) => Some(LightRegion::Box { min, max, test_points: m }),
            (_, Some(_)) => return Err(
                "--test-points needs a region that is a box (declared in extras.relume.light_path_maps.region, or a directional light's)"
                    .into(),
            ),
            (region, None) => region,
        };
        Ok(Region { region, derived, light_area: block.light_area })
    }

    /// The transfers' peak: every covered texel's transfer per entry point; fixed beside them,
    /// the search's Gram matrices and the `textures` (C (1 + D)) the compression stores over
    /// the atlas's `texels`.
    pub fn estimate(&self, fixed: &Estimate, texels: usize, covered: usize, entries: usize, textures: usize) -> Estimate {
        let stored = (textures * texels) as u64 * BYTES_PER_TEXTURE_TEXEL;
        Estimate {
            fixed: fixed.bytes() + stored,
            count: covered as u64 * entries as u64,
            bytes_per_unit: bytes_per_transfer(self.compression),
            unit: "covered texels x entry points".into(),
            lever: "--entry-points",
            value: entries as u64,
            power: 1.0,
            // The transfers' Gram matrix, two f64 per pair of entry points.
            squared: 2 * 8,
        }
    }
}

/// The region of a scene that declares none and has a directional light: its bounds, whose
/// every surface the sun may reach. Else None: the point and spot lights where they stand.
fn derived_region(scene: &Scene) -> Option<LightRegion> {
    let (min, max) = scene.settings.bounds;
    scene.lights.iter().any(|l| l.kind == LightKind::Directional).then_some(LightRegion::Box { min, max, test_points: SUN_TEST_POINTS })
}

impl Baker for LightPathMapsBaker {
    fn bake(&self, scene: &Scene, work: &WorkOptions, stages: &mut Stages) -> Result<Baked, String> {
        let settings = LightPathMapSettings { work: *work, ..self.settings.clone() };
        settings.validate().map_err(|e| format!("{e} (--entry-points, --walks, --threshold, --threads)"))?;
        let region = self.region(scene)?;
        let (mut baked, atlas, bvh) = self.obscurance.bake_on_atlas(scene, work, stages, true)?;
        let entries = stages.timed("entry_points", || {
            let tests = test_points(scene, region.region.as_ref(), work.seed)?;
            entry_points(scene, &bvh, tests, settings.entry_points, work.seed)
        })?;
        // Admitted twice: before the walks with the textures known (the sizes given, or none
        // yet), and once the search has chosen them, before the clusters are made.
        let fixed = self.obscurance.estimate(scene, &atlas);
        let (texels, covered, count) = (atlas.texels.len(), atlas.covered_texels(), entries.entries.len());
        let given = match self.compression {
            Compression::Fixed { clusters, basis } => clusters.min(count) * (1 + basis),
            _ => 0,
        };
        work.admit("light path maps", &self.estimate(&fixed, texels, covered, count, given))?;
        let transfers = stages.timed("transfer", || bake_transfers(scene, &bvh, &atlas, &entries.entries, &settings))?;
        // The stored textures the memory limit leaves room for beside the transfers, and one
        // storage buffer of any GPU holds.
        let in_memory = work.memory_limit.map(|limit| {
            let room = limit.saturating_sub(self.estimate(&fixed, texels, covered, count, 0).bytes());
            (room / (texels as u64 * BYTES_PER_TEXTURE_TEXEL).max(1)) as usize
        });
        let on_gpu = (GPU_TEXTURE_BYTES / (texels as u64 * 12).max(1)) as usize;
        let most_textures = Some(in_memory.map_or(on_gpu, |m| m.min(on_gpu)));
        let compressed = stages.timed("cpca", || match sizes(&transfers, &entries.entries, self.compression, most_textures)? {
            None => compress(&transfers, &entries.entries, texels, region.light_area, self.compression),
            Some((clusters, basis)) => {
                let chosen = self.estimate(&fixed, texels, covered, count, clusters.min(count) * (1 + basis));
                work.admit("light path maps' clusters", &chosen).map_err(|e| format!("{e} (or fewer --clusters and --basis)"))?;
                fitted(&transfers, &entries.entries, texels, region.light_area, clusters, basis)
            }
        })?;
        let transfer = &compressed.transfer;
        let facts =
            json!({ "entry_points": transfer.entry_points.len(), "clusters": transfer.cluster_count(), "basis": transfer.basis_count });
        baked.sections.push(super::section(transfer, atlas.layout(), facts)?);
        baked.parameters["light_path_maps"] = json!({
            "entry_points": settings.entry_points,
            "test_points": entries.test_points.len(),
            "walks": settings.walks,
            "threshold": short(settings.threshold),
            "compression": format!("{:?}", self.compression),
            "seed": work.seed,
        });
        baked.stats["light_path_maps"] = stats(&entries, &transfers, &compressed, work.role.is_some());
        baked.summary += &summary(&entries, &transfers, &compressed, work.role.is_some());
        if let Compression::BestWithin(budget) = self.compression {
            if compressed.relative_error > budget {
                let room = match most_textures {
                    Some(m) if m < BUDGET_TEXTURES_MAX => {
                        format!(" that fits --memory-limit and one GPU storage buffer (at most {m} atlas-sized textures, C (1 + D))")
                    }
                    _ => String::new(),
                };
                baked.summary += &format!(
                    "warning: light path maps: no clustering{room} reconstructs the transfers within the default error budget {budget}: the most accurate searched (C = {}, D = {}) reaches {:.4}; more --entry-points or --walks lower the noise PCA cannot compress, --error-budget refuses instead, --clusters with --basis fix the sizes\n",
                    compressed.clusters, compressed.basis, compressed.relative_error
                );
            }
        }
        derived(&mut baked, scene, &region);
        Ok(baked)
    }
}

/// `merged`: the transfers were read from a sharded bake's parts, so this process counted no
/// virtual light or connection (null in stats.json).
fn stats(entries: &EntryPoints, transfers: &Transfers, compressed: &Compressed, merged: bool) -> serde_json::Value {
    let counted = |count: u64| (!merged).then_some(count);
    json!({
        "entry_points": entries.entries.len(),
        "rays_per_test_point": entries.rays_per_test_point,
        "covered_texels": transfers.texels.len(),
        "walks": transfers.walks,
        "virtual_lights": counted(transfers.virtual_lights),
        "connections": counted(transfers.connections),
        "clusters": compressed.clusters,
        "basis": compressed.basis,
        "relative_error": compressed.relative_error,
        "uncompressed_bytes": transfers.values.len() * 12,
        "compressed_bytes": compressed.transfer.size_bytes(),
    })
}

fn summary(entries: &EntryPoints, transfers: &Transfers, compressed: &Compressed, merged: bool) -> String {
    let mib = |bytes: usize| bytes as f64 / (1 << 20) as f64;
    let work = match merged {
        true => "virtual lights and connections made by the shards".to_string(),
        false => format!("{} virtual lights, {} connections", transfers.virtual_lights, transfers.connections),
    };
    format!(
        "light path maps: {} entry points from {} test points, {} texels, {work}; C = {}, D = {}, relative error {:.4}, {:.1} MiB -> {:.1} MiB\n",
        entries.entries.len(),
        entries.test_points.len(),
        transfers.texels.len(),
        compressed.clusters,
        compressed.basis,
        compressed.relative_error,
        mib(transfers.values.len() * 12),
        mib(compressed.transfer.size_bytes()),
    )
}

/// Records the region the bake derived, when the scene declares none.
fn derived(baked: &mut Baked, scene: &Scene, region: &Region) {
    match &region.region {
        _ if !region.derived => {}
        Some(LightRegion::Box { min, max, test_points }) => {
            let how = format!("the scene's bounds {min} .. {max}, {test_points} test points (a directional light may reach every surface)");
            let value = json!({ "box": [min.to_array(), max.to_array()], "test_points": test_points });
            baked.derived("region", value, &how, "extras.relume.light_path_maps.region");
        }
        _ => {
            let points: Vec<[f32; 3]> = scene.local_lights().map(|l| l.position.to_array()).collect();
            let how = format!("the {} light(s) where they stand, as test points (relit well near there only)", points.len());
            baked.derived("region", json!({ "points": points }), &how, "extras.relume.light_path_maps.region");
        }
    }
}
