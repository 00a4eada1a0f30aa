//! Multi-scale precomputed radiance transfer with light path maps (Umenhoffer et al.,
//! "Partial, Multi-scale Precomputed Radiance Transfer", 000): the atlas and the spectral
//! obscurance (the small scale, §3.3), entry points from the scene's light region (§3.2.1),
//! their transfers by virtual lights with short connections dropped (§3.2.2) and the transfers'
//! clustered PCA (§3.2.3); at run time the obscurance technique and the light path maps'
//! four passes, composed as `--composition` says (§3.4).

use super::obscurance::{self, OnAtlas};
use super::params::{Default, Param, Values};
use super::{atlas, Bake, Loaded, Method, Models, Stages};
use anyhow::{bail, Result};
use relume_bake::artifact::Artifact;
use relume_bake::atlas::Atlas;
use relume_bake::bvh::SceneBvh;
use relume_bake::light_path_maps::{self, ClusteredTransfer, Compression, LightPathMapSettings, LightPathMapsSceneSettings, LightRegion};
use relume_bake::obscurance::Variant;
use relume_bake::scene::{LightKind, Scene};
use relume_bake::work::WorkOptions;
use relume_renderer::techniques::light_path_maps::{Composition, LightPathMapsData};
use relume_renderer::techniques::obscurance::ObscuranceData;
use relume_renderer::MakeTechnique;
use serde_json::json;

const ENTRY_POINTS: Param = Param::count(
    "entry-points",
    "entry points wanted, E (000 §3.2.1: whole rounds of one ray per test point until E hit)",
    1,
    1 << 20,
    Default::Value("4096"),
);
const TEST_POINTS: Param =
    Param::count("test-points", "test points re-sampling the scene's light region box, M", 1, 65536, Default::From("the scene's region"));
const WALKS: Param =
    Param::count("walks", "random walks per entry point (more entry points beat more walks)", 1, 65536, Default::Value("1"));
const THRESHOLD: Param = Param::number(
    "threshold",
    "connections shorter than this are dropped, metres (000 §3.2.2; 0 keeps every one)",
    (0.0, 1e6, false),
    Default::From("L_max"),
);
const CLUSTERS: Param =
    Param::count("clusters", "clusters C of the transfers' PCA (with --basis)", 1, 1 << 20, Default::From("chosen by --error-budget"));
const BASIS: Param =
    Param::count("basis", "eigen-textures per cluster D (with --clusters)", 0, 1024, Default::From("chosen by --error-budget"));
const ERROR_BUDGET: Param = Param::number(
    "error-budget",
    "the smallest C in 1, 2, 4 .. 128 and D in 0..8 storing the fewest values within this relative error of the transfers",
    (0.0, 1e6, false),
    Default::Value("0.1"),
);
const UNCOMPRESSED: Param = Param::flag("uncompressed", "keep every transfer (one cluster per entry point, no PCA)");
const COMPOSITION: Param = Param::choice("composition", "how the indirect irradiance I is added (000 §3.4): plain (albedo/pi I), times-obscurance (albedo/pi W I), times-obscurance-with-direct (albedo/pi W (I + E_direct))", &["plain", "times-obscurance", "times-obscurance-with-direct"], Default::Value("times-obscurance")).at_render();

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
        _ => Compression::Budget(values.number(&ERROR_BUDGET)),
    })
}

/// What the transfer stages are made with, from the flags over the scene's block: worked out
/// and checked before any stage runs.
struct Plan {
    settings: LightPathMapSettings,
    region: Option<LightRegion>,
    /// Whether the scene declares no region (the bake then derives one: `derived_region`).
    derived: bool,
    compression: Compression,
    light_area: f32,
}

fn plan(scene: &Scene, values: &Values, l_max: f32, work: WorkOptions) -> Result<Plan> {
    let settings = LightPathMapSettings {
        entry_points: values.count(&ENTRY_POINTS) as u32,
        walks: values.count(&WALKS) as u32,
        threshold: values.given_number(&THRESHOLD).map_or(l_max, |t| t as f32),
        max_depth: 64,
        work,
    };
    settings.validate().map_err(|e| anyhow::anyhow!("{e} (--entry-points, --walks, --threshold, --threads)"))?;
    let block = LightPathMapsSceneSettings::of(scene).map_err(anyhow::Error::msg)?;
    let derived = block.region.is_none();
    // The scene's region, or the one derived, with its box re-sampled at `--test-points` when given.
    let region = match (block.region.or_else(|| derived_region(scene)), values.given_count(&TEST_POINTS)) {
        (Some(LightRegion::Box { min, max, .. }), Some(m)) => Some(LightRegion::Box { min, max, test_points: m as u32 }),
        (_, Some(_)) => {
            bail!("--test-points needs a region that is a box (declared in extras.relume.light_path_maps.region, or a directional light's)")
        }
        (region, None) => region,
    };
    Ok(Plan { settings, region, derived, compression: compression(values)?, light_area: block.light_area })
}

/// Test points a directional light's derived region has (the scenes' declared boxes: 64).
const SUN_TEST_POINTS: u32 = 64;

/// The region of a scene that declares none and has a directional light: its bounds, whose
/// every surface the sun may reach. Else None: the point and spot lights where they stand.
fn derived_region(scene: &Scene) -> Option<LightRegion> {
    let (min, max) = scene.settings.bounds;
    scene.lights.iter().any(|l| l.kind == LightKind::Directional).then_some(LightRegion::Box { min, max, test_points: SUN_TEST_POINTS })
}

/// Entry points, transfers and their compression (000 §3.2), each a timed stage; returns the
/// transfer and the facts for the manifest, stats.json and the summary.
fn bake_transfer(scene: &Scene, bvh: &SceneBvh, atlas: &Atlas, plan: &Plan, stages: &mut Stages) -> Result<(ClusteredTransfer, Bake)> {
    let Plan { settings, region, compression, light_area, .. } = plan;
    let (work, compression, light_area) = (settings.work, *compression, *light_area);
    let entries = stages
        .timed("entry_points", || {
            let tests = light_path_maps::test_points(scene, region.as_ref(), work.seed)?;
            light_path_maps::entry_points(scene, bvh, tests, settings.entry_points, work.seed)
        })
        .map_err(anyhow::Error::msg)?;
    let transfers = stages
        .timed("transfer", || light_path_maps::bake_transfers(scene, bvh, atlas, &entries.entries, settings))
        .map_err(anyhow::Error::msg)?;
    let compressed = stages
        .timed("cpca", || light_path_maps::compress(&transfers, &entries.entries, atlas.texels.len(), light_area, compression))
        .map_err(anyhow::Error::msg)?;
    let uncompressed_bytes = transfers.values.len() * 12;
    let mib = |bytes: usize| bytes as f64 / (1 << 20) as f64;
    let summary = format!(
        "light path maps: {} entry points from {} test points, {} texels, {} virtual lights, {} connections; C = {}, D = {}, relative error {:.4}, {:.1} MiB -> {:.1} MiB\n",
        entries.entries.len(),
        entries.test_points.len(),
        transfers.texels.len(),
        transfers.virtual_lights,
        transfers.connections,
        compressed.clusters,
        compressed.basis,
        compressed.relative_error,
        mib(uncompressed_bytes),
        mib(compressed.transfer.size_bytes()),
    );
    let facts = Bake {
        sections: Vec::new(),
        parameters: json!({
            "entry_points": settings.entry_points,
            "test_points": entries.test_points.len(),
            "walks": settings.walks,
            "threshold": atlas::short(settings.threshold),
            "compression": format!("{compression:?}"),
            "seed": work.seed,
        }),
        stats: json!({
            "entry_points": entries.entries.len(),
            "rays_per_test_point": entries.rays_per_test_point,
            "covered_texels": transfers.texels.len(),
            "walks": transfers.walks,
            "virtual_lights": transfers.virtual_lights,
            "connections": transfers.connections,
            "clusters": compressed.clusters,
            "basis": compressed.basis,
            "relative_error": compressed.relative_error,
            "uncompressed_bytes": uncompressed_bytes,
            "compressed_bytes": compressed.transfer.size_bytes(),
        }),
        summary,
    };
    Ok((compressed.transfer, facts))
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

    fn bake(&self, scene: &Scene, values: &Values, work: WorkOptions, stages: &mut Stages) -> Result<Bake> {
        let spectral = obscurance::settings(scene, values, Variant::Spectral, work)?;
        let plan = plan(scene, values, spectral.l_max, work)?;
        let (mut bake, atlas, bvh) = obscurance::bake_on_atlas(scene, values, &spectral, stages)?;
        let (transfer, facts) = bake_transfer(scene, &bvh, &atlas, &plan, stages)?;
        let summary =
            json!({ "entry_points": transfer.entry_points.len(), "clusters": transfer.cluster_count(), "basis": transfer.basis_count });
        bake.sections.push(light_path_maps::section(&transfer, atlas.layout(), summary).map_err(anyhow::Error::msg)?);
        bake.parameters["light_path_maps"] = facts.parameters;
        bake.stats["light_path_maps"] = facts.stats;
        bake.summary += &facts.summary;
        match &plan.region {
            _ if !plan.derived => {}
            Some(LightRegion::Box { min, max, test_points }) => {
                let how =
                    format!("the scene's bounds {min} .. {max}, {test_points} test points (a directional light may reach every surface)");
                let value = json!({ "box": [min.to_array(), max.to_array()], "test_points": test_points });
                bake.derived("region", value, &how, "extras.relume.light_path_maps.region");
            }
            _ => {
                let points: Vec<[f32; 3]> = scene.local_lights().map(|l| l.position.to_array()).collect();
                let how = format!("the {} light(s) where they stand, as test points (relit well near there only)", points.len());
                bake.derived("region", json!({ "points": points }), &how, "extras.relume.light_path_maps.region");
            }
        }
        Ok(bake)
    }

    fn load(&self, artifact: Option<&Artifact>, scene: &Scene, values: &Values) -> Result<Box<dyn Loaded>> {
        let artifact = artifact.ok_or_else(|| anyhow::anyhow!("light-path-maps renders from a bake: give --bake"))?;
        let on_atlas = OnAtlas::read(artifact, scene)?;
        let transfer = light_path_maps::read(artifact, scene, on_atlas.layout)?;
        let composition = Composition::parse(values.choice(&COMPOSITION)).unwrap_or_default();
        Ok(Box::new(Maps { on_atlas, transfer, composition }))
    }
}
