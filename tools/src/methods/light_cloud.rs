//! Local radiance transfer with light clouds (Kristensen, Akenine-Möller, Jensen,
//! "Precomputed Local Radiance Transfer for Real-Time Lighting Design", 004): a cloud of unit
//! point lights over the scene's grid (and of unit directional lights over the sphere when the
//! scene has a directional light), each vertex's indirect irradiance from each of them by
//! a gather whose noise every light shares; at run time each user point light stands on its m
//! nearest visible cloud lights (§6.1) and one pass sums their transfer per vertex.

use super::params::{Default, Param, Values};
use super::{Loaded, Method, Models};
use anyhow::Result;
use glam::Vec3;
use relume_bake::artifact::Artifact;
use relume_bake::bvh::SceneBvh;
use relume_bake::contract::Baker;
use relume_bake::light_cloud::{self as lc, LightCloud, LightCloudBaker, LightCloudSceneSettings};
use relume_bake::scene::Scene;
use relume_bake::tessellation;
use relume_renderer::techniques::light_cloud::{LightCloudData, Visibility};
use relume_renderer::MakeTechnique;
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
    lc::MAX_DIRECTIONS as u64,
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
const VECTORS: Param =
    Param::count("vectors", "basis vectors per cluster, D (004 §5, Fig. 8)", 0, lc::MAX_VECTORS as u64, Default::Value("8"));
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
    Default::From("8, or one per 16,384 vertices where that is more (004 §4.2: the bake holds a zone's gather at a time)"),
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
const LINKAGE: Param = Param::choice(
    "linkage",
    "when light clustering merges two groups (004 §4.1): complete (every pair across them is close: the paper's rule), single (some pair is: the paper's name for it; nearer Table 1's count on the Cornell box, worse at the same count)",
    &["complete", "single"],
    Default::Value("complete"),
);
const EXPLAINED_VARIANCE: Param = Param::flag(
    "explained-variance",
    "record each principal component's share of the clusters' variance, indirect (stored) and direct (not), in stats.json (004 Fig. 5)",
);
const NO_LIGHT_CLUSTERING: Param = Param::flag("no-light-clustering", "keep every cloud light in every zone (004 §4.1 off)");

const PARAMS: [&Param; 17] = [
    &SAMPLES,
    &EMISSION_BANDS,
    &DIRECTIONS,
    &MAX_EDGE,
    &ZONES,
    &W1,
    &W2,
    &LINKAGE,
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

/// Light clustering's weights as the flags ask; None: no light clustering.
fn weights(values: &Values) -> Result<Option<(f32, f32)>> {
    let clustering = !values.given(&NO_LIGHT_CLUSTERING);
    if !clustering && [&W1, &W2, &LINKAGE].iter().any(|p| values.given(p)) {
        anyhow::bail!("--w1, --w2 and --linkage set light clustering: give them without --no-light-clustering");
    }
    Ok(clustering.then(|| (values.number(&W1) as f32, values.number(&W2) as f32)))
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

    /// Lights it takes, and a grid declared or derivable: no light inside closed geometry, and
    /// a cloud light left outside it (a headlight outside a closed box derives a region whose
    /// every grid point lies inside the box: the bake refused it after `run` had baked others).
    fn suits(&self, scene: &Scene) -> bool {
        let derivable = || {
            let bvh = SceneBvh::new(scene);
            lc::region::reachable(scene, &bvh).is_ok_and(|r| !lc::cloud_points(&bvh, &r.grid).is_empty())
        };
        checked(scene).is_ok_and(|s| s.declared || !has_local_lights(scene) || derivable())
    }

    /// It models all indirect light: an ambient term would count it twice.
    fn ambient(&self, _: &Scene) -> Option<(Vec3, f32)> {
        None
    }

    fn baker(&self, _: &Scene, values: &Values) -> Result<Box<dyn Baker>> {
        Ok(Box::new(LightCloudBaker {
            samples: values.count(&SAMPLES) as u32,
            emission_bands: values.given_count(&EMISSION_BANDS).map(|b| b as usize),
            directions: values.given_count(&DIRECTIONS).map(|d| d as usize),
            max_edge: values.given_number(&MAX_EDGE).map(|e| e as f32),
            compression: compression(values)?,
            zones: values.given_count(&ZONES).map(|z| z as usize),
            weights: weights(values)?,
            linkage: lc::Linkage::parse(values.choice(&LINKAGE)).unwrap_or_default(),
            explained_variance: values.given(&EXPLAINED_VARIANCE),
        }))
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

#[cfg(test)]
mod tests {
    use super::*;
    use relume_bake::contract::Stages;
    use relume_bake::testing::{closed_box, look_at, material, point_light, scene, Facing};
    use relume_bake::work::WorkOptions;

    /// A light just outside a closed box derives a region whose every grid point lies inside
    /// the box, which the bake refuses: the method does not suit the scene, so `run` skips it
    /// (it baked the others first, then failed). A light farther out suits.
    #[test]
    fn a_scene_whose_derived_cloud_lies_inside_closed_geometry_is_not_suited() {
        let lit_from = |z: f32| {
            let camera = look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 0.8);
            let cube = closed_box(Vec3::splat(-1.0), Vec3::ONE, 2, Facing::Outward, 0);
            let grey = material("grey", Vec3::splat(0.5), Vec3::ZERO);
            scene("cube", vec![cube], vec![grey], vec![point_light(Vec3::new(0.0, 0.0, z), Vec3::ONE)], camera)
        };
        let hidden = lit_from(1.05);
        assert!(!LightCloudMethod.suits(&hidden));
        let values = Values::parse("light-cloud", &LightCloudMethod.params(), &[("samples".into(), "1".into())]).unwrap();
        let baker = LightCloudMethod.baker(&hidden, &values).unwrap();
        let error = baker.bake(&hidden, &WorkOptions::default(), &mut Stages::default()).err().expect("the bake refuses it");
        assert!(error.contains("lies inside closed geometry"), "{error}");
        assert!(LightCloudMethod.suits(&lit_from(1.01)));
    }
}
