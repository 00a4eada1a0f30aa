//! Local radiance transfer with light clouds (Kristensen, Akenine-Möller, Jensen,
//! "Precomputed Local Radiance Transfer for Real-Time Lighting Design", 004): a cloud of unit
//! point lights over the scene's grid (and of unit directional lights over the sphere when the
//! scene has a directional light), each vertex's indirect irradiance from each of them by
//! a gather whose noise every light shares; at run time each user point light stands on its m
//! nearest visible cloud lights (§6.1) and one pass sums their transfer per vertex.

use super::params::{Default, Param, Values};
use super::{Bake, Loaded, Method, Models, Stages};
use anyhow::Result;
use glam::Vec3;
use relume_bake::artifact::Artifact;
use relume_bake::bvh::SceneBvh;
use relume_bake::light_cloud::{self as lc, LightCloud, LightCloudBakeSettings, LightCloudSceneSettings};
use relume_bake::scene::{LightKind, Scene};
use relume_bake::tessellation::{self, Tessellation};
use relume_bake::work::WorkOptions;
use relume_renderer::techniques::light_cloud::{LightCloudData, Visibility};
use relume_renderer::MakeTechnique;
use serde_json::json;
use std::sync::Arc;

const SAMPLES: Param = Param::count(
    "samples",
    "gather paths per vertex, each connected to every cloud light at every bounce (noise shared by all lights)",
    1,
    1 << 16,
    Default::Value("64"),
);
const EMISSION_BANDS: Param = Param::count(
    "emission-bands",
    "B: each cloud light holds its transfer for the emission functions of spherical-harmonic bands 0..=B ((B + 1)^2 columns), on which a spot light stands with its cone's coefficients (004 §8); 0: isotropic lights, a spot as its cone's share of one",
    0,
    3,
    Default::From("0; 2 when the scene has a spot light"),
);
const DIRECTIONS: Param = Param::count(
    "directions",
    "directions of a cloud of unit directional lights over the sphere, on which a directional light (the sun) stands by angle; 0: none",
    0,
    1024,
    Default::From("0; 128 when the scene has a directional light"),
);
const MAX_EDGE: Param = Param::number(
    "max-edge",
    "metres: the scene's meshes welded and split until no edge is longer (per-vertex light needs vertices across surfaces); 0: the meshes as they are",
    (0.0, 1e6, false),
    Default::From("the scene's diagonal / 20 when its meshes are flat-shaded (most vertices on one triangle); 0 otherwise"),
);
const NEAREST: Param = Param::count(
    "nearest",
    "m: the nearest visible cloud lights each light stands on (004 §6.1; 1 is nearest-neighbour)",
    1,
    16,
    Default::Value("8"),
)
.at_render();

const NEAREST_DIRECTIONS: Param = Param::count(
    "nearest-directions",
    "the cloud's directions nearest by angle each directional light stands on (the kernel of --nearest, over angles)",
    1,
    16,
    Default::Value("3"),
)
.at_render();

const FADE: Param = Param::number(
    "fade",
    "seconds a cloud light takes to fade in or out as it comes into or leaves a moving light's sight (spec B5's 0.25 measured no better: docs/BENCHMARKS.md)",
    (0.0, 60.0, false),
    Default::Value("0"),
)
.at_render();

const CLUSTERS: Param =
    Param::count("clusters", "clusters of vertices of the transfer's clustered PCA (004 §5)", 1, 1 << 20, Default::Value("32"));
const VECTORS: Param = Param::count("vectors", "basis vectors per cluster, D (004 §5, Fig. 8)", 0, 1024, Default::Value("8"));
const VARIABLE_VECTORS: Param = Param::flag(
    "variable-vectors",
    "share each zone's C x D basis vectors out among its clusters by eigenvalue (Sloan et al. 2003's variable allocation): D becomes the mean",
);
const UNCOMPRESSED: Param = Param::flag("uncompressed", "keep every vertex's transfer (one cluster per vertex, no basis)");

const ZONES: Param = Param::count(
    "zones",
    "zones of vertices, each with its own reduced cloud and clusters (004 §4.2: split at the median of the longest axis)",
    1,
    256,
    Default::Value("8"),
);
const W1: Param = Param::number(
    "w1",
    "light clustering's distance weight, per scene diagonal (004 eq. 9; Table 1's Cornell box: 0.5)",
    (0.0, 1e6, false),
    Default::Value("0.5"),
);
const W2: Param = Param::number(
    "w2",
    "light clustering's response weight, per largest transfer value (004 eq. 9; Table 1's Cornell box: 20)",
    (0.0, 1e6, false),
    Default::Value("20"),
);
const EXPLAINED_VARIANCE: Param = Param::flag(
    "explained-variance",
    "record each principal component's share of the clusters' variance, indirect (stored) and direct (not), in stats.json (004 Fig. 5)",
);
const NO_LIGHT_CLUSTERING: Param = Param::flag("no-light-clustering", "keep every cloud light in every zone (004 §4.1 off)");

const PARAMS: [&Param; 16] = [
    &SAMPLES,
    &EMISSION_BANDS,
    &DIRECTIONS,
    &MAX_EDGE,
    &ZONES,
    &W1,
    &W2,
    &NO_LIGHT_CLUSTERING,
    &CLUSTERS,
    &VECTORS,
    &VARIABLE_VECTORS,
    &UNCOMPRESSED,
    &EXPLAINED_VARIANCE,
    &NEAREST,
    &NEAREST_DIRECTIONS,
    &FADE,
];

/// Components of 004 Fig. 5 recorded.
const VARIANCE_COMPONENTS: usize = 16;

/// The zones and light clustering the flags ask for.
fn reduction(values: &Values) -> Result<lc::Reduction> {
    let clustering = !values.given(&NO_LIGHT_CLUSTERING);
    if !clustering && (values.given(&W1) || values.given(&W2)) {
        anyhow::bail!("--w1 and --w2 weigh light clustering: give them without --no-light-clustering");
    }
    let weights = clustering.then(|| (values.number(&W1) as f32, values.number(&W2) as f32));
    Ok(lc::Reduction { zones: values.count(&ZONES) as usize, weights })
}

/// The clusters and vectors the flags ask for; None: uncompressed.
fn compression(values: &Values) -> Result<Option<(usize, lc::Vectors)>> {
    if values.given(&UNCOMPRESSED) {
        if [&CLUSTERS, &VECTORS, &VARIABLE_VECTORS, &EXPLAINED_VARIANCE].iter().any(|p| values.given(p)) {
            anyhow::bail!(
                "--uncompressed keeps every vertex's transfer: give it without --clusters, --vectors, --variable-vectors or --explained-variance (of the clusters' PCA)"
            );
        }
        return Ok(None);
    }
    let d = values.count(&VECTORS) as usize;
    let vectors = if values.given(&VARIABLE_VECTORS) { lc::Vectors::Shared(d) } else { lc::Vectors::Each(d) };
    Ok(Some((values.count(&CLUSTERS) as usize, vectors)))
}

pub(crate) struct LightCloudMethod;

/// Edges per scene diagonal of the tessellation a flat-shaded scene gets (cornell-cloud's
/// welded grids: 20).
const EDGES_PER_DIAGONAL: f32 = 20.0;

/// The largest edge given, or the one the scene needs: its diagonal / 20 when it is
/// flat-shaded, else none (0).
fn max_edge(scene: &Scene, values: &Values) -> f32 {
    let diagonal = relume_bake::settings::diagonal(scene.settings.bounds);
    let derived = if tessellation::flat_shaded(scene) { diagonal / EDGES_PER_DIAGONAL } else { 0.0 };
    values.given_number(&MAX_EDGE).map_or(derived, |e| e as f32)
}

/// The emission bands given, or those the scene's lights need: 0 (isotropic cloud lights) for
/// point lights, `SPOT_BANDS` when any is a spot.
fn emission_bands(scene: &Scene, values: &Values) -> usize {
    let spots = scene.lights.iter().any(|l| matches!(l.kind, LightKind::Spot { .. }));
    values.given_count(&EMISSION_BANDS).map_or(if spots { SPOT_BANDS } else { 0 }, |b| b as usize)
}

/// The emission bands a scene with spot lights gets when none are given (docs/BENCHMARKS.md
/// measures 0 to 3 against the path tracer).
const SPOT_BANDS: usize = 2;

/// The directions given, or those the scene's lights need: `SUN_DIRECTIONS` when any is
/// directional, else none.
fn directions(scene: &Scene, values: &Values) -> usize {
    let sun = scene.lights.iter().any(|l| l.kind == LightKind::Directional);
    values.given_count(&DIRECTIONS).map_or(if sun { SUN_DIRECTIONS } else { 0 }, |d| d as usize)
}

/// The directions a scene with a directional light gets when none are given (about 18
/// degrees apart; docs/BENCHMARKS.md measures 16 to 256 against the path tracer).
const SUN_DIRECTIONS: usize = 128;

/// The scene's settings, naming the scene.
fn checked(scene: &Scene) -> Result<LightCloudSceneSettings> {
    LightCloudSceneSettings::of(scene).map_err(|e| anyhow::anyhow!("{}: {e}", scene.source.display()))
}

/// Whether the scene has a light that stands somewhere (else the cloud needs no points unless
/// the scene declares a grid).
fn has_local_lights(scene: &Scene) -> bool {
    scene.local_lights().next().is_some()
}

/// A bake read for a scene, with the run-time m and fade and the scene's visibility.
struct Baked {
    scene: Scene,
    cloud: LightCloud,
    nearest: usize,
    nearest_directions: usize,
    fade_seconds: f32,
    visibility: Visibility,
}

impl Loaded for Baked {
    fn scene(&self) -> &Scene {
        &self.scene
    }

    fn techniques(&self) -> Vec<Box<dyn MakeTechnique + '_>> {
        vec![Box::new(LightCloudData {
            cloud: &self.cloud,
            nearest: self.nearest,
            nearest_directions: self.nearest_directions,
            fade_seconds: self.fade_seconds,
            visibility: Arc::clone(&self.visibility),
        })]
    }
}

/// Segments between a light and the cloud, traced in the scene's BVH.
fn visibility(scene: &Scene) -> Visibility {
    let bvh = SceneBvh::new(scene);
    Arc::new(move |a: Vec3, b: Vec3| bvh.visible(a, b))
}

impl Method for LightCloudMethod {
    fn name(&self) -> &'static str {
        "light-cloud"
    }

    fn description(&self) -> &'static str {
        "indirect light of moving point, spot and directional lights from a cloud of baked unit lights and directions, per vertex (Kristensen et al. 2005)"
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

    /// Lights it takes, and a grid declared or derivable (no light inside closed geometry).
    fn suits(&self, scene: &Scene) -> bool {
        checked(scene).is_ok_and(|s| s.declared || !has_local_lights(scene) || lc::region::reachable(scene, &SceneBvh::new(scene)).is_ok())
    }

    /// It models all indirect light: an ambient term would count it twice.
    fn ambient(&self, _: &Scene) -> Option<(Vec3, f32)> {
        None
    }

    fn bake(&self, source: &Scene, values: &Values, work: WorkOptions, stages: &mut Stages) -> Result<Bake> {
        let declared = checked(source)?;
        let compression = compression(values)?;
        let reduction = reduction(values)?;
        let bands = emission_bands(source, values);
        let at = |e: String| anyhow::anyhow!("{}: {e}", source.source.display());
        let edge = max_edge(source, values);
        let tessellation =
            (edge > 0.0).then(|| stages.timed("tessellation", || Tessellation::new(source, edge))).transpose().map_err(at)?;
        let fine = tessellation.as_ref().map(|t| t.apply(source));
        let scene = fine.as_ref().unwrap_or(source);
        let bvh = stages.timed("bvh", || SceneBvh::new(scene));
        let derive = !declared.declared && has_local_lights(scene);
        let reachable = derive.then(|| stages.timed("region", || lc::region::reachable(scene, &bvh))).transpose().map_err(at)?;
        // Points where the scene declares a grid or has a light that stands somewhere.
        let grid = match &reachable {
            Some(r) => Some(r.grid.clone()),
            None => declared.declared.then_some(declared.grid),
        };
        let directions = directions(source, values);
        let settings =
            LightCloudBakeSettings { grid, directions, samples: values.count(&SAMPLES) as u32, emission: (bands + 1) * (bands + 1), work };
        let gathered = stages.timed("gather", || lc::bake(scene, &bvh, &settings)).map_err(at)?;
        let raw_bytes = gathered.terms.len() * 4;
        let reduced = stages.timed("light clustering", || lc::reduce(scene, &bvh, &gathered, reduction)).map_err(at)?;
        let (cloud, error, variance) = match compression {
            None => (reduced.cloud, 0.0, None),
            Some((clusters, vectors)) => {
                let cloud = stages.timed("cpca", || lc::compress(&reduced.cloud, clusters, vectors)).map_err(at)?;
                let error = lc::relative_error(&reduced.cloud, &cloud);
                let variance = values.given(&EXPLAINED_VARIANCE).then(|| {
                    stages.timed("explained variance", || lc::explained_variance(scene, &bvh, &reduced.cloud, &cloud, VARIANCE_COMPONENTS))
                });
                (cloud, error, variance)
            }
        };
        let per_zone: Vec<usize> = (0..cloud.zone_count()).map(|z| cloud.zone_light_range(z).len()).collect();
        let bytes = (cloud.terms.len() + cloud.coords.len() + cloud.assignment.len() + cloud.vectors.len()) * 4;
        let (fewest_vectors, vectors_mean) = (
            cloud.vectors.iter().min().copied().unwrap_or(0),
            cloud.vectors.iter().sum::<u32>() as f64 / cloud.cluster_count().max(1) as f64,
        );
        let cloud_lights = gathered.lights.len() - directions;
        let grid_points = settings.grid.as_ref().map_or(0, |g| g.points().len());
        let mean_per_zone = per_zone.iter().sum::<usize>() as f64 / per_zone.len() as f64;
        let (fewest, most) = (per_zone.iter().min().copied().unwrap_or(0), per_zone.iter().max().copied().unwrap_or(0));
        let facts = json!({
            "cloud_lights": cloud_lights,
            "grid_points": grid_points,
            "directions": directions,
            "vertices": cloud.vertex_count(),
            "zones": cloud.zone_count(),
            "lights_per_zone": per_zone,
            "clusters": cloud.cluster_count(),
            "vectors": { "min": fewest_vectors, "max": cloud.basis(), "mean": vectors_mean },
            "light_clustering_error": reduced.relative_error,
            "relative_error": error,
        });
        let mut summary = format!(
            "{cloud_lights} cloud lights ({grid_points} grid points less those inside closed geometry) and {directions} directions, {} vertices, {} paths a vertex\n\
             {} zones of {fewest}..{most} lights (mean {mean_per_zone:.1}) after light clustering, relative error {:.4}\n\
             {} clusters of D = {fewest_vectors}..{} (mean {vectors_mean:.1}), relative error {error:.4}; {:.2} MiB -> {:.2} MiB\n",
            cloud.vertex_count(),
            cloud.samples,
            cloud.zone_count(),
            reduced.relative_error,
            cloud.cluster_count(),
            cloud.basis(),
            raw_bytes as f64 / (1 << 20) as f64,
            bytes as f64 / (1 << 20) as f64
        );
        if let Some(v) = &variance {
            let first = |shares: &[f64]| shares.iter().take(4).map(|s| format!("{s:.3}")).collect::<Vec<_>>().join(" ");
            summary.push_str(&format!(
                "the first components' shares of the variance (004 Fig. 5): indirect {}, direct {}\n",
                first(&v.indirect),
                first(&v.direct)
            ));
        }
        let (lone, vertices) = tessellation::lone_vertices(scene);
        if 2 * lone > vertices {
            summary.push_str(&format!(
                "warning: {lone} of {vertices} vertices belong to one triangle only (flat-shaded meshes): per-vertex transfer has almost nothing to interpolate; weld and tessellate the meshes (--max-edge, or as scenes/cornell-cloud is)\n"
            ));
        }
        let mut sections = vec![lc::section(&cloud, facts)];
        sections.extend(tessellation.as_ref().map(tessellation::section));
        let mut bake = Bake {
            sections,
            parameters: json!({
                "samples": settings.samples,
                "emission_bands": bands,
                "max_edge": edge,
                "zones": reduction.zones,
                "light_clustering": reduction.weights.map(|(w1, w2)| json!({ "w1": w1, "w2": w2 })),
                "clusters": compression.map(|c| c.0),
                "vectors": compression.map(|(_, v)| v.count()),
                "variable_vectors": matches!(compression, Some((_, lc::Vectors::Shared(_)))),
                "directions": directions,
                "grid": settings.grid.as_ref().map(|g| json!({ "box": [g.min.to_array(), g.max.to_array()], "counts": g.counts })),
            }),
            stats: json!({
                "explained_variance": variance.map(|v| json!({ "indirect": v.indirect, "direct": v.direct })),
                "cloud_lights": cloud_lights,
                "directions": directions,
                "zones": cloud.zone_count(),
                "lights_per_zone_mean": mean_per_zone,
                "lights_per_zone_min": fewest,
                "lights_per_zone_max": most,
                "light_clustering_error": reduced.relative_error,
                "vertices": cloud.vertex_count(),
                "samples": cloud.samples,
                "clusters": cloud.cluster_count(),
                "vectors_min": fewest_vectors,
                "vectors_max": cloud.basis(),
                "vectors_mean": vectors_mean,
                "relative_error": error,
                "uncompressed_bytes": raw_bytes,
                "transfer_bytes": bytes,
            }),
            summary,
        };
        if let Some(r) = &reachable {
            let g = &r.grid;
            let how = format!(
                "box {:.3?} .. {:.3?}, {:?} cells (the space the lights reach: {} of {} voxels over the scene's bounds)",
                g.min.to_array(),
                g.max.to_array(),
                g.counts,
                r.reached,
                r.voxels
            );
            let value = json!({ "box": [g.min.to_array(), g.max.to_array()], "counts": g.counts });
            bake.derived("grid", value, &how, "extras.relume.light_cloud.grid");
        }
        if !values.given(&DIRECTIONS) && directions > 0 {
            let how = format!("{directions} (the scene has a directional light: it stands on the nearest of {directions} unit directional lights over the sphere)");
            bake.derived("directions", json!(directions), &how, "--directions");
        }
        if !values.given(&EMISSION_BANDS) && bands > 0 {
            let how = format!("{bands} (the scene has spot lights: each cloud light holds {} emission functions)", settings.emission);
            bake.derived("emission_bands", json!(bands), &how, "--emission-bands");
        }
        if let Some(t) = tessellation.as_ref().filter(|_| !values.given(&MAX_EDGE)) {
            let how = format!(
                "{edge:.4} m (the scene's meshes are flat-shaded: welded and split to {} vertices from {})",
                t.vertex_count(),
                lc::vertex_count(source)
            );
            bake.derived("max_edge", json!(edge), &how, "--max-edge");
        }
        Ok(bake)
    }

    fn load(&self, artifact: Option<&Artifact>, scene: &Scene, values: &Values) -> Result<Box<dyn Loaded>> {
        let artifact = artifact.ok_or_else(|| anyhow::anyhow!("light-cloud renders from a bake: give --bake"))?;
        let fine = tessellation::read(artifact, scene)?.map_or_else(|| scene.clone(), |t| t.apply(scene));
        let cloud = lc::read_for(artifact, scene, lc::vertex_count(&fine))?;
        lc::refuse_lights(&scene.lights, cloud.directions).map_err(|e| anyhow::anyhow!("{}: {e}", scene.source.display()))?;
        Ok(Box::new(Baked {
            visibility: visibility(&fine),
            scene: fine,
            cloud,
            nearest: values.count(&NEAREST) as usize,
            nearest_directions: values.count(&NEAREST_DIRECTIONS) as usize,
            fade_seconds: values.number(&FADE) as f32,
        }))
    }
}
