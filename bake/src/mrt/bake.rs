//! Modular radiance transfer's whole bake behind the bake contract: the scene's block proxy
//! (declared, or derived with the triangles split at the blocks' boundaries), the dictionary
//! (given, kept in a cache by its parameters, or made: 002 §4-5), and the level's tables
//! (§6.2-6.3, the feedback solved, §7.3).

use super::baker::bake_on;
use super::derive::{self, Derived};
use super::dictionary::{self, Dictionary};
use super::level_data;
use super::proxy::{dynamic_meshes, Proxy};
use super::{BlockSettings, InterfaceSettings};
use crate::artifact::{Artifact, BakeOutput};
use crate::atlas::AtlasSection;
use crate::bvh::{RayBackend, SceneBvh};
use crate::contract::{scene_bytes, Baked, Baker, Estimate, Stages};
use crate::scene::Scene;
use crate::tessellation;
use crate::work::{with_threads, WorkOptions};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

pub struct MrtBaker {
    /// Its seed and threads are replaced by the bake's.
    pub block: BlockSettings,
    /// Its seed is replaced by the bake's.
    pub interface: InterfaceSettings,
    pub d_max: usize,
    pub dictionary: DictionarySource,
}

/// Where the dictionary comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum DictionarySource {
    /// An earlier mrt bake's folder, whose dictionary must have been made with the same
    /// parameters.
    Given(PathBuf),
    /// The folder where dictionaries are kept by their parameters: read from there, or made
    /// and kept there.
    Cache(PathBuf),
}

/// What a dictionary's build holds besides the scene (measured: docs/BENCHMARKS.md, "Peak
/// memory"): its own working set, the block shapes' operators (bytes per squared block sample
/// n^2, n = 6 x samples per face side: F as gathered rows and as a matrix, and the rest of the
/// reduction) and, the most at the default sizes, the interfaces' lightfield operators (bytes
/// per lightfield cell and mode: positions^2 x directions^2 cells, k_rlf modes).
pub const DICTIONARY_BYTES: u64 = 24 << 20;
pub const BYTES_PER_SAMPLE_PAIR: u64 = 32;
pub const BYTES_PER_CELL_MODE: u64 = 112;
/// What the level holds per squared feedback coefficient (D = blocks x k_self; measured:
/// docs/BENCHMARKS.md, "Scale sweep"): the solved feedback's 3 f32 (12 bytes) and, per colour
/// channel solved at once, I - K and its inverse in f64 (16 bytes); T_b->r adds at most 16
/// k_r / k_self (a receiver on each side face of a block, from every block).
pub const FEEDBACK_BYTES: u64 = 12;
pub const SOLVE_BYTES: u64 = 16;
pub const TRANSFER_BYTES: u64 = 16;

impl MrtBaker {
    /// The dictionary's peak: one block shape's n x n operators, then the interfaces'
    /// lightfield operators; the lever is the lightfield's position cells a side.
    pub fn estimate(&self, scene: &Scene) -> Estimate {
        let n = (6 * self.block.samples_per_face * self.block.samples_per_face) as u64;
        let (p, d) = (self.interface.positions as u64, self.interface.directions as u64);
        Estimate {
            fixed: scene_bytes(scene) + DICTIONARY_BYTES + n * n * BYTES_PER_SAMPLE_PAIR,
            count: p * p * d * d * self.interface.lightfield_modes as u64,
            bytes_per_unit: BYTES_PER_CELL_MODE,
            unit: "lightfield cells x modes".into(),
            lever: "--lightfield",
            value: p,
            power: 4.0,
            squared: 0,
        }
    }

    /// The level's peak, at its feedback solve, for `blocks` blocks of k_self modes each; the
    /// lever is k_self (the coefficients grow as its square).
    pub fn level_estimate(&self, scene: &Scene, blocks: usize, work: &WorkOptions) -> Estimate {
        let modes = self.block.modes as u64;
        let channels = work.threads.unwrap_or_else(rayon::current_num_threads).clamp(1, 3) as u64;
        let transfers = (TRANSFER_BYTES * self.interface.response_modes as u64).div_ceil(modes);
        Estimate {
            fixed: scene_bytes(scene),
            count: (blocks as u64 * modes).pow(2),
            bytes_per_unit: FEEDBACK_BYTES + SOLVE_BYTES * channels + transfers,
            unit: "squared feedback coefficients".into(),
            lever: "--modes",
            value: modes,
            power: 2.0,
            squared: 0,
        }
    }

    /// The dictionary given, or the one the cache keeps for these parameters, or one made now
    /// (printing its stages, stopped when the time limit runs out) and kept.
    fn dictionary(
        &self,
        scene: &Scene,
        block: &BlockSettings,
        interface: &InterfaceSettings,
        work: &WorkOptions,
    ) -> Result<Dictionary, String> {
        let cache = match &self.dictionary {
            DictionarySource::Given(dir) => {
                let artifact = Artifact::read(dir).map_err(|e| e.to_string())?;
                return Ok(dictionary::read(&artifact, Some((block, interface))).map_err(|e| e.to_string())?.0);
            }
            DictionarySource::Cache(cache) => cache,
        };
        let dir = cache.join(dictionary::key(block, interface));
        // A sharded bake makes its dictionary: its shapes' F are what its shards split.
        if dir.exists() && work.role.is_none() {
            match Artifact::read(&dir).and_then(|artifact| dictionary::read(&artifact, Some((block, interface)))) {
                Ok((kept, _)) => {
                    eprintln!("mrt: the dictionary made with these parameters, from {}", dir.display());
                    return Ok(kept);
                }
                Err(e) => {
                    crate::inputs::release(&dir);
                    eprintln!("warning: mrt: the kept dictionary does not read, so it is made again: {e}")
                }
            }
        }
        work.admit("mrt", &self.estimate(scene))?;
        eprintln!("mrt: the dictionary (six block shapes, then their interfaces) ...");
        let start = Instant::now();
        let made = Dictionary::build_in_role(block, interface, work.role, |stage| {
            if work.out_of_time(start) {
                return Err(format!("--time-limit ran out before the dictionary's {stage}; a dictionary needs all its stages: give fewer --gather-rays, a longer --time-limit, or an earlier bake's dictionary with --dictionary DIR"));
            }
            eprintln!("mrt:   {stage}");
            Ok(())
        })?;
        let kept = BakeOutput {
            method: "mrt",
            scene: None,
            parameters: json!({ "kept": "the dictionary alone, by its parameters" }),
            sections: vec![dictionary::section(&made, json!({ "shapes": made.blocks.len() }))],
            stats: json!({}),
        };
        match kept.write(&dir) {
            Ok(()) => eprintln!("mrt: the dictionary kept in {}", dir.display()),
            Err(e) => eprintln!("warning: mrt: the dictionary is not kept: {e}"),
        }
        Ok(made)
    }
}

/// The scene's block proxy and the meshes its light volume lights: as declared, or derived
/// from the scene with `backend`'s rays (with what was derived).
pub fn proxy(scene: &Scene, backend: RayBackend) -> Result<(Proxy, Vec<usize>, Option<Derived>), String> {
    if Proxy::declared(scene) {
        return Ok((Proxy::of(scene)?, dynamic_meshes(scene)?, None));
    }
    let derived = derive::derive(scene, &SceneBvh::build(scene, backend)?)?;
    Ok((derived.proxy.clone(), derived.dynamic.clone(), Some(derived)))
}

impl Baker for MrtBaker {
    fn bake(&self, source: &Scene, work: &WorkOptions, stages: &mut Stages) -> Result<Baked, String> {
        let (proxy, dynamic, derived) = stages.timed("proxy", || proxy(source, work.ray_backend))?;
        work.admit("mrt level", &self.level_estimate(source, proxy.corners.len(), work))?;
        let split = derived.as_ref().and_then(|d| d.split.as_ref());
        let fine = split.map(|s| s.apply(source));
        let scene = fine.as_ref().unwrap_or(source);
        let block = BlockSettings { seed: work.seed, threads: work.threads, ..self.block.clone() };
        let interface = InterfaceSettings { seed: work.seed, ..self.interface.clone() };
        let dictionary = stages.timed("dictionary", || self.dictionary(scene, &block, &interface, work))?;
        let (mapped, level_data) =
            stages.timed("level", || with_threads(work.threads, || bake_on(scene, &proxy, &dynamic, &dictionary, self.d_max)))?;
        let matrices: usize = level_data.receivers.iter().flat_map(|r| r.sources.iter().map(|s| s.1.len())).sum();
        let facts = json!({
            "blocks": level_data.blocks.len(),
            "receivers": level_data.receivers.len(),
            "samples": level_data.samples.len(),
            "transfer_values": matrices,
        });
        let summary = format!(
            "{} blocks, {} receivers, {} samples on a {} x {} light map; T_b->r {:.2} MiB; dictionary k_self {} k_rlf {} k_r {}\n",
            level_data.blocks.len(),
            level_data.receivers.len(),
            level_data.samples.len(),
            mapped.layout.width,
            mapped.layout.height,
            matrices as f64 * 4.0 / (1 << 20) as f64,
            block.modes,
            dictionary.interfaces.lightfield_modes,
            dictionary.interfaces.response_modes
        );
        let layout = mapped.layout;
        let atlas = AtlasSection { meshes: mapped.meshes, layout, texels: mapped.texels };
        let mut sections = vec![
            atlas.section(json!({ "width": layout.width, "height": layout.height })),
            dictionary::section(&dictionary, json!({ "shapes": dictionary.blocks.len() })),
            level_data::section(&level_data, facts.clone()),
        ];
        sections.extend(split.map(tessellation::section));
        let mut baked = Baked {
            sections,
            parameters: json!({
                "samples_per_face": block.samples_per_face,
                "gather_rays": block.gather_rays,
                "modes": block.modes,
                "prior_modes": block.prior_modes,
                "enrich": block.enrich,
                "lightfield": interface.positions,
                "lightfield_modes": interface.lightfield_modes,
                "response_modes": interface.response_modes,
                "d_max": self.d_max,
                "seed": work.seed,
            }),
            stats: facts,
            summary,
        };
        if let Some(derived) = &derived {
            let names: Vec<&str> = dynamic.iter().map(|&m| scene.meshes[m].name.as_str()).collect();
            let how = format!(
                "{} blocks on {} x {} cells{}{} (the declaration is in manifest.json)",
                proxy.corners.len(),
                derived.cells[0],
                derived.cells[1],
                split.map_or(String::new(), |s| format!(
                    "; triangles split at their boundaries: {} vertices from {}",
                    s.vertex_count(),
                    crate::light_cloud::vertex_count(source)
                )),
                if names.is_empty() { String::new() } else { format!("; on no block face, lit by the light volume: {}", names.join(", ")) }
            );
            baked.derived("proxy", derived.declared.clone(), &how, "extras.relume.mrt");
        }
        Ok(baked)
    }
}
