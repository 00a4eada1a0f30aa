//! Modular radiance transfer (Loos et al. 2011, 002): indirect light of moving lights in a
//! level of blocks (the scene's `extras.relume.mrt` grid) from a dictionary of six block shapes
//! made for every scene; at run time seven passes (§7.3's steps 1-7) relight a padded light map
//! on the blocks' faces, every bounce fed back, and two more (steps 8-9) light the meshes the
//! scene declares dynamic from the blocks' light volume.

use super::params::{Default, Param, Values};
use super::{Loaded, Method, Models};
use anyhow::Result;
use glam::Vec3;
use relume_bake::artifact::Artifact;
use relume_bake::contract::Baker;
use relume_bake::mrt::dictionary::{self, Dictionary};
use relume_bake::mrt::level_data::{self, LevelData};
use relume_bake::mrt::{self, BlockSettings, DictionarySource, InterfaceSettings, MrtBaker, PriorLattice};
use relume_bake::scene::Scene;
use relume_bake::tessellation;
use relume_renderer::techniques::mrt::MrtData;
use relume_renderer::MakeTechnique;

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
const PRIOR_LATTICE: Param = Param::choice(
    "prior-lattice",
    "where the light prior's 6^3 sphere lights stand (002 §4.1: \"uniformly in the volume\"): centres (of the cells, most a twelfth of a side from a wall) or inset (1/7 apart and from the walls: Table 2's modes)",
    &["centres", "inset"],
    Default::Value("centres"),
);
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

const PARAMS: [&Param; 13] = [
    &SAMPLES_PER_FACE,
    &GATHER_RAYS,
    &MODES,
    &PRIOR_MODES,
    &PRIOR_LATTICE,
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
/// rays, 2^2 supersamples: docs/BENCHMARKS.md, "Between blocks"), and where it comes from.
fn baker(values: &Values) -> MrtBaker {
    let gather_rays = values.count(&GATHER_RAYS) as u32;
    let block = BlockSettings {
        samples_per_face: values.count(&SAMPLES_PER_FACE) as usize,
        gather_rays,
        prior_modes: values.count(&PRIOR_MODES) as usize,
        modes: values.count(&MODES) as usize,
        enrich: !values.given(&NO_ENRICH),
        prior_lattice: PriorLattice::parse(values.choice(&PRIOR_LATTICE)).unwrap_or(PriorLattice::Centres),
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
        seed: 0,
    };
    let dictionary = match values.given_path(&DICTIONARY) {
        Some(dir) => DictionarySource::Given(dir),
        None => DictionarySource::Cache(values.given_path(&DICTIONARY_CACHE).unwrap_or_else(|| DICTIONARY_CACHE_DEFAULT.into())),
    };
    MrtBaker { block, interface, d_max: values.count(&D_MAX) as usize, dictionary }
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
        mrt::proxy(scene, relume_bake::bvh::RayBackend::Obvhs).is_ok()
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

    fn baker(&self, _: &Scene, values: &Values) -> Result<Box<dyn Baker>> {
        Ok(Box::new(baker(values)))
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
