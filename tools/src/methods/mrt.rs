//! Modular radiance transfer (Loos et al. 2011, 002): indirect light of moving lights in a
//! level of blocks (the scene's `extras.relume.mrt` grid) from a dictionary of six block shapes
//! made for every scene; at run time seven passes (§7.3's steps 1-7) relight a padded light map
//! on the blocks' faces, every bounce fed back, and two more (steps 8-9) light the meshes the
//! scene declares dynamic from the blocks' light volume.

use super::params::{Default, Param, Values};
use super::{Bake, Loaded, Method, Models, Stages};
use anyhow::Result;
use glam::Vec3;
use relume_bake::artifact::{Artifact, BakeOutput};
use relume_bake::atlas::AtlasSection;
use relume_bake::bvh::SceneBvh;
use relume_bake::mrt::baker::bake_on;
use relume_bake::mrt::derive::{self, Derived};
use relume_bake::mrt::dictionary::{self, Dictionary};
use relume_bake::mrt::level_data::{self, LevelData};
use relume_bake::mrt::proxy::{dynamic_meshes, Proxy};
use relume_bake::mrt::{BlockSettings, InterfaceSettings};
use relume_bake::scene::Scene;
use relume_bake::tessellation;
use relume_bake::work::WorkOptions;
use relume_renderer::techniques::mrt::MrtData;
use relume_renderer::MakeTechnique;
use serde_json::json;

const SAMPLES_PER_FACE: Param =
    Param::count("samples-per-face", "samples (light-map texels) a block face side (002: 16)", 2, 64, Default::Value("16"));
const GATHER_RAYS: Param = Param::count(
    "gather-rays",
    "rays per sample gathering a block's one-bounce operator F (002: 16,384)",
    16,
    1 << 20,
    Default::Value("16384"),
);
const MODES: Param = Param::count("modes", "k_self: a block's indirect modes (002 Table 2: 32)", 1, 512, Default::Value("32"));
const PRIOR_MODES: Param = Param::count("prior-modes", "k_d: the light prior's modes (002 §4: 64)", 1, 1024, Default::Value("64"));
const NO_ENRICH: Param = Param::flag("no-enrich", "leave the prior without App. A's enrichment (002 Fig. 13's failure)");
const LIGHTFIELD_MODES: Param =
    Param::count("lightfield-modes", "k_rlf: the interface lightfield's modes (002 §5.1: 128)", 1, 1024, Default::Value("128"));
const RESPONSE_MODES: Param =
    Param::count("response-modes", "k_r: a receiver's response modes (002 §5.1: 32)", 1, 512, Default::Value("32"));
const LIGHTFIELD: Param = Param::count(
    "lightfield",
    "an interface lightfield's position cells a side; direction cells are 1.5 times as many (002: 12, with 24; docs/BENCHMARKS.md: 8 costs 0.01 in error)",
    2,
    32,
    Default::Value("8"),
);
const D_MAX: Param =
    Param::count("d-max", "the most interfaces light crosses between blocks (002 §6.3's traversal depth)", 1, 64, Default::Value("8"));
const DICTIONARY: Param = Param::path(
    "dictionary",
    "an artifact folder whose dictionary to reuse (an earlier mrt bake of any scene, made with the same dictionary parameters: refused otherwise, naming the first that differs)",
    "the one kept for these parameters in --dictionary-cache, else made by the bake",
);
const DICTIONARY_CACHE: Param = Param::path(
    "dictionary-cache",
    "the folder where dictionaries are kept by their parameters: a bake without --dictionary reads the one made with its parameters there, or makes it and keeps it there (one that no longer reads is made again)",
    DICTIONARY_CACHE_DEFAULT,
);
/// Where dictionaries are kept when `--dictionary-cache` is not given (relative to the
/// working folder, as the bake's own default `--out`).
const DICTIONARY_CACHE_DEFAULT: &str = "out/mrt-dictionary";
const FEEDBACK: Param = Param::choice(
    "feedback",
    "every bounce (solved: the fixed point of 002 §7.3's frame-to-frame feedback, at once) or the first only (off)",
    &["solved", "off"],
    Default::Value("solved"),
)
.at_render();

const PARAMS: [&Param; 12] = [
    &SAMPLES_PER_FACE,
    &GATHER_RAYS,
    &MODES,
    &PRIOR_MODES,
    &NO_ENRICH,
    &LIGHTFIELD_MODES,
    &RESPONSE_MODES,
    &LIGHTFIELD,
    &D_MAX,
    &DICTIONARY,
    &DICTIONARY_CACHE,
    &FEEDBACK,
];

/// The dictionary's parameters from `values` (the interface's gather: a quarter of the block's
/// rays, 2^2 supersamples: docs/BENCHMARKS.md, "Between blocks").
/// The scene's block proxy and the meshes its light volume lights: as declared, or derived
/// from the scene (with what was derived).
fn proxy(scene: &Scene) -> Result<(Proxy, Vec<usize>, Option<Derived>), String> {
    if Proxy::declared(scene) {
        return Ok((Proxy::of(scene)?, dynamic_meshes(scene)?, None));
    }
    let derived = derive::derive(scene, &SceneBvh::new(scene))?;
    Ok((derived.proxy.clone(), derived.dynamic.clone(), Some(derived)))
}

fn settings(values: &Values, work: &WorkOptions) -> (BlockSettings, InterfaceSettings) {
    let gather_rays = values.count(&GATHER_RAYS) as u32;
    let block = BlockSettings {
        samples_per_face: values.count(&SAMPLES_PER_FACE) as usize,
        gather_rays,
        prior_modes: values.count(&PRIOR_MODES) as usize,
        modes: values.count(&MODES) as usize,
        enrich: !values.given(&NO_ENRICH),
        seed: work.seed,
        threads: work.threads,
        ..BlockSettings::default()
    };
    let positions = values.count(&LIGHTFIELD) as usize;
    let interface = InterfaceSettings {
        positions,
        directions: positions * 3 / 2,
        supersamples: 2,
        lightfield_modes: values.count(&LIGHTFIELD_MODES) as usize,
        response_modes: values.count(&RESPONSE_MODES) as usize,
        gather_rays: (gather_rays / 4).max(16),
        seed: work.seed,
    };
    (block, interface)
}

/// The dictionary of `--dictionary`, checked against the parameters asked for; else the one
/// the cache keeps for these parameters; else one made now (printing its stages) and kept.
fn dictionary(values: &Values, block: &BlockSettings, interface: &InterfaceSettings) -> Result<Dictionary> {
    if let Some(dir) = values.given_path(&DICTIONARY) {
        let artifact = Artifact::read(&dir)?;
        return Ok(dictionary::read(&artifact, Some((block, interface)))?.0);
    }
    let cache = values.given_path(&DICTIONARY_CACHE).unwrap_or_else(|| DICTIONARY_CACHE_DEFAULT.into());
    let dir = cache.join(dictionary::key(block, interface));
    if dir.exists() {
        let kept = Artifact::read(&dir).and_then(|artifact| dictionary::read(&artifact, Some((block, interface))));
        match kept {
            Ok((kept, _)) => {
                eprintln!("mrt: the dictionary made with these parameters, from {}", dir.display());
                return Ok(kept);
            }
            Err(e) => eprintln!("warning: mrt: the kept dictionary does not read, so it is made again: {e}"),
        }
    }
    eprintln!("mrt: the dictionary (six block shapes, then their interfaces) ...");
    let made = Dictionary::build(block, interface, |stage| eprintln!("mrt:   {stage}"));
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

pub(crate) struct MrtMethod;

/// A bake read for a scene.
struct Baked {
    scene: Scene,
    dictionary: Dictionary,
    level: LevelData,
    feedback: bool,
}

impl Loaded for Baked {
    fn scene(&self) -> &Scene {
        &self.scene
    }

    fn techniques(&self) -> Vec<Box<dyn MakeTechnique + '_>> {
        vec![Box::new(MrtData { dictionary: &self.dictionary, level: &self.level, feedback: self.feedback })]
    }
}

impl Method for MrtMethod {
    fn name(&self) -> &'static str {
        "mrt"
    }

    fn description(&self) -> &'static str {
        "indirect light of moving lights in a level of blocks from a dictionary of block shapes (Loos et al. 2011)"
    }

    fn params(&self) -> Vec<&'static Param> {
        PARAMS.to_vec()
    }

    fn bakes(&self) -> bool {
        true
    }

    fn models(&self) -> Models {
        Models::LocalLights
    }

    /// A scene that declares its blocks, or whose blocks can be derived.
    fn suits(&self, scene: &Scene) -> bool {
        proxy(scene).is_ok()
    }

    /// It models all indirect light: an ambient term would count it twice.
    fn ambient(&self, _: &Scene) -> Option<(Vec3, f32)> {
        None
    }

    /// 4,096 gather rays: the dictionary in a quarter of the time, the same error
    /// (docs/BENCHMARKS.md: 0.073 and 0.053 on the mazes either way).
    fn main_job_values(&self, _rays: u32) -> Vec<(String, String)> {
        vec![(GATHER_RAYS.name.into(), "4096".into())]
    }

    fn bake(&self, scene: &Scene, values: &Values, work: WorkOptions, stages: &mut Stages) -> Result<Bake> {
        let at = |e: String| anyhow::anyhow!("{}: {e}", scene.source.display());
        let (proxy, dynamic, derived) = stages.timed("proxy", || proxy(scene)).map_err(at)?;
        let split = derived.as_ref().and_then(|d| d.split.as_ref());
        let fine = split.map(|s| s.apply(scene));
        let source = scene;
        let scene = fine.as_ref().unwrap_or(source);
        let (block, interface) = settings(values, &work);
        if work.time_limit.is_some() {
            eprintln!("mrt: --time-limit does not cut the bake short (a dictionary not yet kept takes 5-11 s on 2 cores, its level a few seconds); fewer --gather-rays shorten the dictionary, --dictionary DIR skips it");
        }
        let dictionary = stages.timed("dictionary", || dictionary(values, &block, &interface))?;
        let d_max = values.count(&D_MAX) as usize;
        let threads = work.threads;
        let (mapped, level_data) = stages
            .timed("level", || relume_bake::work::with_threads(threads, || bake_on(scene, &proxy, &dynamic, &dictionary, d_max)))
            .map_err(at)?;
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
        let mut bake = Bake {
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
                "d_max": d_max,
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
                    relume_bake::light_cloud::vertex_count(source)
                )),
                if names.is_empty() { String::new() } else { format!("; on no block face, lit by the light volume: {}", names.join(", ")) }
            );
            bake.derived("proxy", derived.declared.clone(), &how, "extras.relume.mrt");
        }
        Ok(bake)
    }

    fn load(&self, artifact: Option<&Artifact>, scene: &Scene, values: &Values) -> Result<Box<dyn Loaded>> {
        let artifact = artifact.ok_or_else(|| anyhow::anyhow!("mrt renders from a bake: give --bake"))?;
        let (dictionary, checksum) = dictionary::read(artifact, None)?;
        let fine = tessellation::read(artifact, scene)?.map(|t| t.apply(scene));
        let (_, applied) = super::atlas::read_for(artifact, scene, fine.as_ref().unwrap_or(scene))?;
        let level = level_data::read(artifact, scene, &dictionary, &checksum)?;
        Ok(Box::new(Baked { scene: applied, dictionary, level, feedback: values.choice(&FEEDBACK) == "solved" }))
    }
}
