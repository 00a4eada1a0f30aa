//! Multi-scale precomputed radiance transfer with light path maps (Umenhoffer et al.,
//! "Partial, Multi-scale Precomputed Radiance Transfer", 000): the atlas and the spectral
//! obscurance (the small scale, §3.3), entry points from the scene's light region (§3.2.1),
//! their transfers by virtual lights with short connections dropped (§3.2.2) and the transfers'
//! clustered PCA (§3.2.3); at run time the obscurance technique and the light path maps'
//! four passes, composed as `--composition` says (§3.4).

use super::obscurance::{self, OnAtlas};
use super::params::{Default, Param, Values};
use super::{atlas, Loaded, Method, Models};
use anyhow::{bail, Result};
use relume_bake::artifact::Artifact;
use relume_bake::contract::Baker;
use relume_bake::light_path_maps::{self, ClusteredTransfer, Compression, LightPathMapSettings, LightPathMapsBaker};
use relume_bake::obscurance::Variant;
use relume_bake::scene::Scene;
use relume_bake::work::WorkOptions;
use relume_renderer::techniques::light_path_maps::{Composition, LightPathMapsData};
use relume_renderer::techniques::obscurance::ObscuranceData;
use relume_renderer::MakeTechnique;

const ENTRY_POINTS: Param = Param::within(
    "entry-points",
    "entry points wanted, E (000 §3.2.1: whole rounds of one ray per test point until E hit)",
    LightPathMapSettings::ENTRY_POINTS,
    Default::Value("4096"),
);
const TEST_POINTS: Param =
    Param::count("test-points", "test points re-sampling the scene's light region box, M", 1, 65536, Default::From("the scene's region"));
const WALKS: Param = Param::within(
    "walks",
    "random walks per entry point (more entry points beat more walks)",
    LightPathMapSettings::WALKS,
    Default::Value("1"),
);
const THRESHOLD: Param = Param::within(
    "threshold",
    "connections shorter than this are dropped, metres (000 §3.2.2 cuts at the small scale's L_max, 0.15 on cornell, for a small-scale term to stand in; 0 keeps every one, which halves cornell's indirect error: docs/BENCHMARKS.md \"The papers' claims\")",
    LightPathMapSettings::THRESHOLD,
    Default::Value("0"),
);
const CLUSTERS: Param =
    Param::count("clusters", "clusters C of the transfers' PCA (with --basis)", 1, 1 << 20, Default::From("chosen by --error-budget"));
const BASIS: Param =
    Param::count("basis", "eigen-textures per cluster D (with --clusters)", 0, 1024, Default::From("chosen by --error-budget"));
const ERROR_BUDGET: Param = Param::number(
    "error-budget",
    "the smallest C in 1, 2, 4 .. 128 and D in 0..8 storing the fewest values within this relative error of the transfers; given, none within it is refused; by default (0.1) the most accurate is taken then, with a warning",
    (0.0, 1e6, false),
    Default::Value("0.1"),
);
const UNCOMPRESSED: Param = Param::flag("uncompressed", "keep every transfer (one cluster per entry point, no PCA)");
const COMPOSITION: Param = Param::choice("composition", "how the indirect irradiance I is added (000 §3.4): plain (albedo/pi I), times-obscurance (albedo/pi W I), times-obscurance-with-direct (albedo/pi W (I + E_direct))", &["plain", "times-obscurance", "times-obscurance-with-direct"], Default::Value("plain")).at_render();

const PARAMS: [&Param; 9] =
    [&ENTRY_POINTS, &TEST_POINTS, &WALKS, &THRESHOLD, &CLUSTERS, &BASIS, &ERROR_BUDGET, &UNCOMPRESSED, &COMPOSITION];

pub(crate) struct LightPathMaps;

/// The compression the flags ask for.
fn compression(values: &Values) -> Result<Compression> {
    let given = |p: &Param| values.given(p);
    if given(&CLUSTERS) != given(&BASIS) {
        bail!("--clusters and --basis: give both, or neither (then --error-budget chooses them)");
    }
    if given(&UNCOMPRESSED) && (given(&CLUSTERS) || given(&ERROR_BUDGET)) {
        bail!("--uncompressed keeps every transfer: give it without --clusters, --basis or --error-budget");
    }
    if given(&CLUSTERS) && given(&ERROR_BUDGET) {
        bail!("--clusters with --basis fix the compression: give them without --error-budget");
    }
    Ok(match (given(&UNCOMPRESSED), values.given_count(&CLUSTERS), values.given_count(&BASIS)) {
        (true, _, _) => Compression::None,
        (false, Some(clusters), Some(basis)) => Compression::Fixed { clusters: clusters as usize, basis: basis as usize },
        _ => match values.given_number(&ERROR_BUDGET) {
            Some(budget) => Compression::Budget(budget),
            None => Compression::BestWithin(values.number(&ERROR_BUDGET)),
        },
    })
}

/// The light path maps' bake from the flags: the spectral obscurance's on the atlas, then the
/// transfers'.
fn baker(scene: &Scene, values: &Values) -> Result<LightPathMapsBaker> {
    let obscurance = obscurance::baker(scene, values, Variant::Spectral)?;
    let settings = LightPathMapSettings {
        entry_points: values.count(&ENTRY_POINTS) as u32,
        walks: values.count(&WALKS) as u32,
        threshold: values.number(&THRESHOLD) as f32,
        max_depth: 64,
        work: WorkOptions::default(),
    };
    settings.validate().map_err(|e| anyhow::anyhow!("{e} (--entry-points, --walks, --threshold)"))?;
    Ok(LightPathMapsBaker {
        obscurance,
        settings,
        test_points: values.given_count(&TEST_POINTS).map(|m| m as u32),
        compression: compression(values)?,
    })
}

/// The spectral obscurance on its atlas and the transfer, as the renderer takes them.
struct Maps {
    on_atlas: OnAtlas,
    transfer: ClusteredTransfer,
    composition: Composition,
}

impl Loaded for Maps {
    fn scene(&self) -> &relume_bake::scene::Scene {
        &self.on_atlas.scene
    }

    fn techniques(&self) -> Vec<Box<dyn MakeTechnique + '_>> {
        let atlas = self.on_atlas.image();
        vec![
            Box::new(ObscuranceData { obscurance: atlas }),
            Box::new(LightPathMapsData { transfer: &self.transfer, atlas, composition: self.composition }),
        ]
    }
}

impl Method for LightPathMaps {
    fn name(&self) -> &'static str {
        "light-path-maps"
    }

    fn description(&self) -> &'static str {
        "direct light plus light path maps' indirect light composed with the spectral obscurance (Umenhoffer et al. 2008)"
    }

    fn params(&self) -> Vec<&'static Param> {
        [&atlas::PARAMS[..], &obscurance::PARAMS[..], &PARAMS[..]].concat()
    }

    fn bakes(&self) -> bool {
        true
    }

    fn models(&self) -> Models {
        Models::LocalLights
    }

    /// 000 §3.2.3's sizes: C = 32 clusters, D = 2 eigen-textures.
    fn main_job_values(&self, rays: u32) -> Vec<(String, String)> {
        [(obscurance::RAYS.name, rays.to_string()), (CLUSTERS.name, "32".into()), (BASIS.name, "2".into())]
            .map(|(k, v)| (k.to_string(), v))
            .to_vec()
    }

    fn baker(&self, scene: &Scene, values: &Values) -> Result<Box<dyn Baker>> {
        Ok(Box::new(baker(scene, values)?))
    }

    fn load(&self, artifact: Option<&Artifact>, scene: &Scene, values: &Values) -> Result<Box<dyn Loaded>> {
        let artifact = artifact.ok_or_else(|| anyhow::anyhow!("light-path-maps renders from a bake: give --bake"))?;
        let on_atlas = OnAtlas::read(artifact, scene)?;
        let transfer = light_path_maps::read(artifact, scene, on_atlas.layout)?;
        let composition = Composition::parse(values.choice(&COMPOSITION)).unwrap_or_default();
        Ok(Box::new(Maps { on_atlas, transfer, composition }))
    }
}
