//! Local radiance transfer with light clouds (Kristensen, Akenine-Möller, Jensen,
//! "Precomputed Local Radiance Transfer for Real-Time Lighting Design", 004): a cloud of unit
//! point lights over the scene's grid, each vertex's indirect irradiance from each of them by
//! a gather whose noise every light shares; at run time each user point light stands on its m
//! nearest visible cloud lights (§6.1) and one pass sums their transfer per vertex.

use super::params::{Default, Param, Values};
use super::{Bake, Loaded, Method, Stages};
use anyhow::Result;
use glam::Vec3;
use relume_bake::artifact::Artifact;
use relume_bake::bvh::SceneBvh;
use relume_bake::light_cloud::{self as lc, LightCloud, LightCloudBakeSettings, LightCloudSceneSettings};
use relume_bake::scene::Scene;
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
const NEAREST: Param = Param::count(
    "nearest",
    "m: the nearest visible cloud lights each light stands on (004 §6.1; 1 is nearest-neighbour)",
    1,
    16,
    Default::Value("8"),
)
.at_render();

const CLUSTERS: Param =
    Param::count("clusters", "clusters of vertices of the transfer's clustered PCA (004 §5)", 1, 1 << 20, Default::Value("32"));
const VECTORS: Param = Param::count("vectors", "basis vectors per cluster, D (004 §5, Fig. 8)", 0, 1024, Default::Value("8"));
const UNCOMPRESSED: Param = Param::flag("uncompressed", "keep every vertex's transfer (one cluster per vertex, no basis)");

const PARAMS: [&Param; 5] = [&SAMPLES, &CLUSTERS, &VECTORS, &UNCOMPRESSED, &NEAREST];

/// The clusters and vectors the flags ask for; None: uncompressed.
fn compression(values: &Values) -> Result<Option<(usize, usize)>> {
    if values.given(&UNCOMPRESSED) {
        if values.given(&CLUSTERS) || values.given(&VECTORS) {
            anyhow::bail!("--uncompressed keeps every vertex's transfer: give it without --clusters or --vectors");
        }
        return Ok(None);
    }
    Ok(Some((values.count(&CLUSTERS) as usize, values.count(&VECTORS) as usize)))
}

pub(crate) struct LightCloudMethod;

/// The scene's settings, or its lights refused, naming the scene.
fn checked(scene: &Scene) -> Result<LightCloudSceneSettings> {
    let at = |e: String| anyhow::anyhow!("{}: {e}", scene.source.display());
    lc::refuse_lights(&scene.lights).map_err(at)?;
    LightCloudSceneSettings::of(scene).map_err(at)
}

/// A bake read for a scene, with the run-time m and the scene's visibility.
struct Baked {
    scene: Scene,
    cloud: LightCloud,
    nearest: usize,
    visibility: Visibility,
}

impl Loaded for Baked {
    fn scene(&self) -> &Scene {
        &self.scene
    }

    fn techniques(&self) -> Vec<Box<dyn MakeTechnique + '_>> {
        vec![Box::new(LightCloudData { cloud: &self.cloud, nearest: self.nearest, visibility: Arc::clone(&self.visibility) })]
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
        "indirect light of moving point lights from a cloud of baked unit lights, per vertex (Kristensen et al. 2005)"
    }

    fn params(&self) -> Vec<&'static Param> {
        PARAMS.to_vec()
    }

    fn bakes(&self) -> bool {
        true
    }

    /// A scene lit by point lights only, without an environment.
    fn suits(&self, scene: &Scene) -> bool {
        scene.environment.is_none() && !scene.lights.is_empty() && checked(scene).is_ok()
    }

    /// It models all indirect light: an ambient term would count it twice.
    fn ambient(&self, _: &Scene) -> Option<(Vec3, f32)> {
        None
    }

    fn bake(&self, scene: &Scene, values: &Values, work: WorkOptions, stages: &mut Stages) -> Result<Bake> {
        let grid = checked(scene)?.grid;
        let compression = compression(values)?;
        let settings = LightCloudBakeSettings { grid, samples: values.count(&SAMPLES) as u32, work };
        let at = |e: String| anyhow::anyhow!("{}: {e}", scene.source.display());
        let bvh = stages.timed("bvh", || SceneBvh::new(scene));
        let gathered = stages.timed("gather", || lc::bake(scene, &bvh, &settings)).map_err(at)?;
        let raw_bytes = gathered.terms.len() * 4;
        let (cloud, error) = match compression {
            None => (gathered, 0.0),
            Some((clusters, vectors)) => {
                let cloud = stages.timed("cpca", || lc::compress(&gathered, clusters, vectors)).map_err(at)?;
                let error = lc::relative_error(&gathered, &cloud);
                (cloud, error)
            }
        };
        let bytes = (cloud.terms.len() + cloud.coords.len() + cloud.assignment.len()) * 4;
        let facts = json!({
            "cloud_lights": cloud.lights.len(),
            "grid_points": settings.grid.points().len(),
            "vertices": cloud.vertex_count(),
            "clusters": cloud.cluster_count(),
            "vectors": cloud.basis,
            "relative_error": error,
        });
        let mut summary = format!(
            "{} cloud lights ({} grid points less those inside closed geometry), {} vertices, {} paths a vertex; {} clusters of D = {}, relative error {error:.4}, {:.2} MiB -> {:.2} MiB\n",
            cloud.lights.len(),
            settings.grid.points().len(),
            cloud.vertex_count(),
            cloud.samples,
            cloud.cluster_count(),
            cloud.basis,
            raw_bytes as f64 / (1 << 20) as f64,
            bytes as f64 / (1 << 20) as f64
        );
        let (lone, vertices) = lc::lone_vertices(scene);
        if 2 * lone > vertices {
            summary.push_str(&format!(
                "warning: {lone} of {vertices} vertices belong to one triangle only (flat-shaded meshes): per-vertex transfer has almost nothing to interpolate; weld and tessellate the meshes (as scenes/cornell-cloud is)\n"
            ));
        }
        Ok(Bake {
            sections: vec![lc::section(&cloud, facts)],
            parameters: json!({
                "samples": settings.samples,
                "clusters": compression.map(|c| c.0),
                "vectors": compression.map(|c| c.1),
                "grid": { "box": [settings.grid.min.to_array(), settings.grid.max.to_array()], "counts": settings.grid.counts },
            }),
            stats: json!({
                "cloud_lights": cloud.lights.len(),
                "vertices": cloud.vertex_count(),
                "samples": cloud.samples,
                "clusters": cloud.cluster_count(),
                "vectors": cloud.basis,
                "relative_error": error,
                "uncompressed_bytes": raw_bytes,
                "transfer_bytes": bytes,
            }),
            summary,
        })
    }

    fn load(&self, artifact: Option<&Artifact>, scene: &Scene, values: &Values) -> Result<Box<dyn Loaded>> {
        let artifact = artifact.ok_or_else(|| anyhow::anyhow!("light-cloud renders from a bake: give --bake"))?;
        checked(scene)?;
        let cloud = lc::read(artifact, scene)?;
        Ok(Box::new(Baked { visibility: visibility(scene), scene: scene.clone(), cloud, nearest: values.count(&NEAREST) as usize }))
    }
}
