//! The light clouds' whole bake behind the bake contract: the meshes tessellated where they
//! are flat-shaded, the cloud's grid (declared, or the space the lights reach), the gather
//! (004 eq. 6-7), light clustering by zone (§4) and the clustered PCA (§5), a zone at a time
//! (zones.rs), with the facts the manifest and stats.json keep.

use super::zones::{gather_zones, reduce_zones, ZoneRows, ZoneSettings, Zoned};
use super::{
    region, section, split_zones, vertex_count, vertex_positions, Gatherer, LightCloud, LightCloudBakeSettings, LightCloudSceneSettings,
    Linkage, Reduction, Vectors,
};
use crate::bvh::SceneBvh;
use crate::contract::{scene_bytes, Baked, Baker, Estimate, Stages};
use crate::scene::{LightKind, Scene};
use crate::settings::diagonal;
use crate::tessellation::{self, Tessellation};
use crate::work::WorkOptions;
use serde_json::{json, Value};

pub struct LightCloudBaker {
    /// Gather paths per vertex.
    pub samples: u32,
    /// B: emission functions of bands 0..=B; None: 0, or `SPOT_BANDS` when the scene has a spot.
    pub emission_bands: Option<usize>,
    /// None: `SUN_DIRECTIONS` when the scene has a directional light, else 0.
    pub directions: Option<usize>,
    /// None: the scene's diagonal / `EDGES_PER_DIAGONAL` when it is flat-shaded, else 0.
    pub max_edge: Option<f32>,
    /// Zones; None: `ZONES`, or one per `VERTICES_PER_ZONE` vertices where that is more.
    pub zones: Option<usize>,
    /// Light clustering's weights (004 eq. 9); None: every zone keeps every cloud light.
    pub weights: Option<(f32, f32)>,
    pub linkage: Linkage,
    /// Clusters and vectors; None: uncompressed.
    pub compression: Option<(usize, Vectors)>,
    /// Record 004 Fig. 5's shares of the first `VARIANCE_COMPONENTS` components.
    pub explained_variance: bool,
}

/// Edges per scene diagonal of the tessellation a flat-shaded scene gets (cornell-cloud's
/// welded grids: 20).
pub const EDGES_PER_DIAGONAL: f32 = 20.0;
/// The emission bands a scene with spot lights gets when none are given (docs/BENCHMARKS.md
/// measures 0 to 3 against the path tracer).
pub const SPOT_BANDS: usize = 2;
/// The directions a scene with a directional light gets when none are given (about 18
/// degrees apart; docs/BENCHMARKS.md measures 16 to 256 against the path tracer).
pub const SUN_DIRECTIONS: usize = 128;
/// The zones a scene gets when none are given (004 Table 1's Cornell box) ...
pub const ZONES: usize = 8;
/// ... or one per this many vertices where that is more: a zone then holds about this many
/// vertices, at most twice as many (zones split the largest in halves; 004 §4.2 holds one zone
/// in memory at a time; Table 1's Sponza has 247 zones for 114k triangles).
pub const VERTICES_PER_ZONE: usize = 16_384;
/// Components of 004 Fig. 5 recorded.
const VARIANCE_COMPONENTS: usize = 16;
/// Bytes a transfer value (a vertex's, per cloud light, emission function, SH coefficient and
/// colour) of the zone being gathered holds: its f64 sum and its f32 row (reduced, a zone holds
/// less: its row read back and its reduced row) (docs/BENCHMARKS.md, "Peak memory").
pub const ZONE_BYTES_PER_VALUE: u64 = 12;
/// Bytes every zone's gathered value holds until the last zone is gathered, when kept in memory
/// (and, uncompressed, in the cloud the bake returns).
pub const KEPT_BYTES_PER_VALUE: u64 = 4;
/// Copies of a cluster's PCA matrix (f64, as wide as the smaller of its members and the values
/// a vertex has of its zone's lights) alive at once: the matrix, the eigensolver's copy and its
/// eigenvectors (a matrix over 2,048 wide, solved for its leading pairs, holds fewer).
const COVARIANCE_COPIES: u64 = 3;

/// What the bake chose where nothing was given.
struct Chosen {
    edge: f32,
    bands: usize,
    directions: usize,
}

impl LightCloudBaker {
    fn chosen(&self, scene: &Scene) -> Chosen {
        let flat = tessellation::flat_shaded(scene);
        let spots = scene.lights.iter().any(|l| matches!(l.kind, LightKind::Spot { .. }));
        let sun = scene.lights.iter().any(|l| l.kind == LightKind::Directional);
        Chosen {
            edge: self.max_edge.unwrap_or(if flat { diagonal(scene.settings.bounds) / EDGES_PER_DIAGONAL } else { 0.0 }),
            bands: self.emission_bands.unwrap_or(if spots { SPOT_BANDS } else { 0 }),
            directions: self.directions.unwrap_or(if sun { SUN_DIRECTIONS } else { 0 }),
        }
    }

    /// The bake's peak: the largest zone's transfer values from every cloud light and direction,
    /// every zone's gathered values when they are kept in memory (`spill`: in a scratch file),
    /// and, compressed, the matrix of a cluster's PCA as large as a zone that keeps every cloud
    /// light allows.
    pub fn estimate(
        &self,
        scene: &Scene,
        (lights, largest_zone, spill): (usize, usize, bool),
        settings: &LightCloudBakeSettings,
    ) -> Estimate {
        let coefficients = if scene.materials.iter().any(|m| m.phong.is_some()) { crate::sh::COEFFICIENTS } else { 1 };
        let per_vertex = (lights * 3 * coefficients * settings.emission) as u64;
        let kept = if spill { 0 } else { vertex_count(scene) as u64 * per_vertex * KEPT_BYTES_PER_VALUE };
        // A cluster's PCA solves the smaller of its covariance and its Gram matrix.
        let side = per_vertex.min(largest_zone as u64);
        let covariance = if self.compression.is_some() { COVARIANCE_COPIES * 8 * side * side } else { 0 };
        Estimate {
            fixed: scene_bytes(scene) + covariance,
            count: (largest_zone as u64 * per_vertex * ZONE_BYTES_PER_VALUE + kept) / KEPT_BYTES_PER_VALUE,
            bytes_per_unit: KEPT_BYTES_PER_VALUE,
            unit: "4-byte transfer values (vertices x cloud lights x colours, emission functions, SH coefficients: the largest zone's x 3, every zone's when kept in memory)".into(),
            lever: "cloud lights (the grid's counts, extras.relume.light_cloud.grid, and --directions), or more --zones",
            value: lights as u64,
            power: 1.0,
            squared: 0,
        }
    }

    /// The zones: as given, or `ZONES`, or one per `VERTICES_PER_ZONE` where that is more.
    fn zone_count(&self, scene: &Scene) -> usize {
        self.zones.unwrap_or_else(|| ZONES.max(vertex_count(scene).div_ceil(VERTICES_PER_ZONE)))
    }

    /// Whether the zones' gathered rows wait in a scratch file: when they would not fit the
    /// memory limit beside the zone baked, and the cloud is compressed (uncompressed, they are
    /// the cloud the bake returns).
    fn spills(&self, scene: &Scene, shape: (usize, usize), settings: &LightCloudBakeSettings) -> bool {
        let kept = self.estimate(scene, (shape.0, shape.1, false), settings);
        self.compression.is_some() && settings.work.memory_limit.is_some_and(|limit| kept.bytes() > limit)
    }
}

impl Baker for LightCloudBaker {
    fn bake(&self, source: &Scene, work: &WorkOptions, stages: &mut Stages) -> Result<Baked, String> {
        let declared = LightCloudSceneSettings::of(source)?;
        let chosen = self.chosen(source);
        let tessellation =
            (chosen.edge > 0.0).then(|| stages.timed("tessellation", || Tessellation::new(source, chosen.edge))).transpose()?;
        let fine = tessellation.as_ref().map(|t| t.apply(source));
        let scene = fine.as_ref().unwrap_or(source);
        let bvh = stages.timed("bvh", || SceneBvh::build(scene, work.ray_backend))?;
        let derive = !declared.declared && scene.local_lights().next().is_some();
        let reachable = derive.then(|| stages.timed("region", || region::reachable(scene, &bvh))).transpose()?;
        // Points where the scene declares a grid or has a light that stands somewhere.
        let grid = match &reachable {
            Some(r) => Some(r.grid.clone()),
            None => declared.declared.then_some(declared.grid),
        };
        let emission = (chosen.bands + 1) * (chosen.bands + 1);
        let settings = LightCloudBakeSettings { grid, directions: chosen.directions, samples: self.samples, emission, work: *work };
        let gatherer = Gatherer::new(scene, &bvh, &settings)?;
        let reduction = Reduction { zones: self.zone_count(scene), weights: self.weights, linkage: self.linkage };
        reduction.validate()?;
        let zones = split_zones(&vertex_positions(scene), reduction.zones);
        let shape = (gatherer.lights(), zones.iter().map(Vec::len).max().unwrap_or(0));
        let spill = self.spills(scene, shape, &settings);
        work.admit("light cloud", &self.estimate(scene, (shape.0, shape.1, spill), &settings))?;
        let mut store = ZoneRows::new(spill)?;
        let (taken, scale) = stages.timed("gather", || gather_zones(&gatherer, &zones, settings.samples, &mut store))?;
        let gathered = gatherer.shape(taken, Vec::new());
        let zone_settings = ZoneSettings {
            reduction,
            compression: self.compression,
            variance_components: self.explained_variance.then_some(VARIANCE_COMPONENTS),
        };
        let zoned =
            stages.timed("zones", || reduce_zones(scene, &bvh, &gathered, (&zones, store, scale), &zone_settings, work.progress))?;
        let Zoned { cloud, clustering_error, error, variance, raw_values, seconds, cloud_lights } = zoned;
        let raw_bytes = raw_values * 4;
        let variance = variance.map(|v| (v.indirect, v.direct));
        let facts = Facts::of(&cloud, clustering_error, &settings, cloud_lights - chosen.directions, error);
        let mut sections = vec![section(&cloud, facts.manifest(&cloud))];
        sections.extend(tessellation.as_ref().map(tessellation::section));
        let mut summary = facts.summary(&cloud, raw_bytes);
        if let Some((indirect, direct)) = &variance {
            let first = |shares: &[f64]| shares.iter().take(4).map(|s| format!("{s:.3}")).collect::<Vec<_>>().join(" ");
            summary.push_str(&format!(
                "the first components' shares of the variance (004 Fig. 5): indirect {}, direct {}\n",
                first(indirect),
                first(direct)
            ));
        }
        let (lone, vertices) = tessellation::lone_vertices(scene);
        if 2 * lone > vertices {
            summary.push_str(&format!(
                "warning: {lone} of {vertices} vertices belong to one triangle only (flat-shaded meshes): per-vertex transfer has almost nothing to interpolate; weld and tessellate the meshes (--max-edge, or as scenes/cornell-cloud is)\n"
            ));
        }
        let mut stats = facts.stats(&cloud, raw_bytes);
        stats["explained_variance"] = json!(variance.map(|(indirect, direct)| json!({ "indirect": indirect, "direct": direct })));
        stats["zones_seconds"] = json!({ "light_clustering": seconds.0, "cpca": seconds.1 });
        stats["scratch_file"] = json!(spill);
        let mut baked = Baked { sections, parameters: self.parameters(&chosen, &settings, reduction.zones), stats, summary };
        self.record_derived(&mut baked, source, &chosen, tessellation.as_ref(), reachable.as_ref());
        if self.zones.is_none() && reduction.zones > ZONES {
            let how = format!("{} (one per {VERTICES_PER_ZONE} of the scene's {} vertices)", reduction.zones, vertex_count(scene));
            baked.derived("zones", json!(reduction.zones), &how, "--zones");
        }
        Ok(baked)
    }
}

impl LightCloudBaker {
    fn parameters(&self, chosen: &Chosen, settings: &LightCloudBakeSettings, zones: usize) -> Value {
        let compression = self.compression;
        json!({
            "samples": settings.samples,
            "emission_bands": chosen.bands,
            "max_edge": chosen.edge,
            "zones": zones,
            "light_clustering": self.weights.map(|(w1, w2)| json!({ "w1": w1, "w2": w2, "linkage": self.linkage.name() })),
            "clusters": compression.map(|c| c.0),
            "vectors": compression.map(|(_, v)| v.count()),
            "variable_vectors": matches!(compression, Some((_, Vectors::Shared(_)))),
            "directions": chosen.directions,
            "grid": settings.grid.as_ref().map(|g| json!({ "box": [g.min.to_array(), g.max.to_array()], "counts": g.counts })),
        })
    }

    /// Records each setting the bake chose for the scene because none was given.
    fn record_derived(
        &self,
        baked: &mut Baked,
        source: &Scene,
        chosen: &Chosen,
        tessellation: Option<&Tessellation>,
        reachable: Option<&region::Reachable>,
    ) {
        if let Some(r) = reachable {
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
            baked.derived("grid", value, &how, "extras.relume.light_cloud.grid");
        }
        let directions = chosen.directions;
        if self.directions.is_none() && directions > 0 {
            let how = format!("{directions} (the scene has a directional light: it stands on the nearest of {directions} unit directional lights over the sphere)");
            baked.derived("directions", json!(directions), &how, "--directions");
        }
        if self.emission_bands.is_none() && chosen.bands > 0 {
            let emission = (chosen.bands + 1) * (chosen.bands + 1);
            let how = format!("{} (the scene has spot lights: each cloud light holds {emission} emission functions)", chosen.bands);
            baked.derived("emission_bands", json!(chosen.bands), &how, "--emission-bands");
        }
        if let Some(t) = tessellation.filter(|_| self.max_edge.is_none()) {
            let how = format!(
                "{:.4} m (the scene's meshes are flat-shaded: welded and split to {} vertices from {})",
                chosen.edge,
                t.vertex_count(),
                vertex_count(source)
            );
            baked.derived("max_edge", json!(chosen.edge), &how, "--max-edge");
        }
    }
}

/// The cloud's facts after reduction and compression.
struct Facts {
    cloud_lights: usize,
    grid_points: usize,
    directions: usize,
    per_zone: Vec<usize>,
    light_clustering_error: f64,
    relative_error: f64,
    fewest_vectors: u32,
    vectors_mean: f64,
    bytes: usize,
}

impl Facts {
    fn of(cloud: &LightCloud, clustering_error: f64, settings: &LightCloudBakeSettings, cloud_lights: usize, error: f64) -> Facts {
        Facts {
            cloud_lights,
            grid_points: settings.grid.as_ref().map_or(0, |g| g.points().len()),
            directions: settings.directions,
            per_zone: (0..cloud.zone_count()).map(|z| cloud.zone_light_range(z).len()).collect(),
            light_clustering_error: clustering_error,
            relative_error: error,
            fewest_vectors: cloud.vectors.iter().min().copied().unwrap_or(0),
            vectors_mean: cloud.vectors.iter().sum::<u32>() as f64 / cloud.cluster_count().max(1) as f64,
            bytes: (cloud.terms.len() + cloud.coords.len() + cloud.assignment.len() + cloud.vectors.len()) * 4,
        }
    }

    fn zone_range(&self) -> (usize, usize, f64) {
        let mean = self.per_zone.iter().sum::<usize>() as f64 / self.per_zone.len() as f64;
        (self.per_zone.iter().min().copied().unwrap_or(0), self.per_zone.iter().max().copied().unwrap_or(0), mean)
    }

    fn manifest(&self, cloud: &LightCloud) -> Value {
        json!({
            "cloud_lights": self.cloud_lights,
            "grid_points": self.grid_points,
            "directions": self.directions,
            "vertices": cloud.vertex_count(),
            "zones": cloud.zone_count(),
            "lights_per_zone": self.per_zone,
            "clusters": cloud.cluster_count(),
            "vectors": { "min": self.fewest_vectors, "max": cloud.basis(), "mean": self.vectors_mean },
            "light_clustering_error": self.light_clustering_error,
            "relative_error": self.relative_error,
        })
    }

    fn stats(&self, cloud: &LightCloud, raw_bytes: usize) -> Value {
        let (fewest, most, mean) = self.zone_range();
        json!({
            "cloud_lights": self.cloud_lights,
            "directions": self.directions,
            "zones": cloud.zone_count(),
            "lights_per_zone_mean": mean,
            "lights_per_zone_min": fewest,
            "lights_per_zone_max": most,
            "light_clustering_error": self.light_clustering_error,
            "vertices": cloud.vertex_count(),
            "samples": cloud.samples,
            "clusters": cloud.cluster_count(),
            "vectors_min": self.fewest_vectors,
            "vectors_max": cloud.basis(),
            "vectors_mean": self.vectors_mean,
            "relative_error": self.relative_error,
            "uncompressed_bytes": raw_bytes,
            "transfer_bytes": self.bytes,
        })
    }

    fn summary(&self, cloud: &LightCloud, raw_bytes: usize) -> String {
        let (fewest, most, mean) = self.zone_range();
        format!(
            "{} cloud lights ({} grid points less those inside closed geometry) and {} directions, {} vertices, {} paths a vertex\n\
             {} zones of {fewest}..{most} lights (mean {mean:.1}) after light clustering, relative error {:.4}\n\
             {} clusters of D = {}..{} (mean {:.1}), relative error {:.4}; {:.2} MiB -> {:.2} MiB\n",
            self.cloud_lights,
            self.grid_points,
            self.directions,
            cloud.vertex_count(),
            cloud.samples,
            cloud.zone_count(),
            self.light_clustering_error,
            cloud.cluster_count(),
            self.fewest_vectors,
            cloud.basis(),
            self.vectors_mean,
            self.relative_error,
            raw_bytes as f64 / (1 << 20) as f64,
            self.bytes as f64 / (1 << 20) as f64
        )
    }
}
