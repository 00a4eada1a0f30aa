//! Baking light path maps (Umenhoffer et al., "Partial, Multi-scale Precomputed Radiance Transfer",
//! §3.2.1-3.2.2): entry points shot from the test points of the region lights may move in,
//! and for each entry point e the transfer T_e to every atlas texel, by random walks whose
//! vertices act as virtual lights. Connections shorter than the small-scale threshold are
//! dropped: the spectral obscurance carries that part (§3.3), so no path counts twice.
//!
//! Units: T_e[t] is the irradiance at texel t (lux, rgb) from paths that start with unit
//! irradiance at e and bounce at least once (at e itself), divided by the entry-point
//! density d(e), so that sum_e I_e T_e[t] estimates the indirect irradiance at t
//! (`transfer.rs` holds the formula the renderer evaluates).

use super::{entry_irradiance_unshadowed, ClusteredTransfer, EntryPoint, LightRegion};
use crate::atlas::Atlas;
use crate::atlas::Texel;
use crate::bvh::SceneBvh;
use crate::cpca;
use crate::sampling::{cosine_hemisphere, orthonormal_basis, PathSampler};
use crate::scene::{Light, Scene};
use crate::settings::{first_failed_check, ValueRange};
use crate::shards::Items;
use crate::work::{Progress, WorkOptions};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::f32::consts::PI;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Sobol groups of the test points and entry directions, apart from the walks' (0, 1, ...).
const TEST_POINT_GROUP: u32 = u32::MAX;
const ENTRY_DIRECTION_GROUP: u32 = u32::MAX - 1;
const OPENNESS_GROUP: u32 = u32::MAX - 2;
const EXIT_GROUP: u32 = u32::MAX - 3;

#[derive(Clone, Debug)]
pub struct LightPathMapSettings {
    /// E: entry points wanted (whole rounds of one ray per test point are shot until there
    /// are this many hits; an open scene may end with fewer).
    pub entry_points: u32,
    /// Random walks per entry point; their virtual lights' contributions are averaged.
    pub walks: u32,
    /// Connections shorter than this (metres) are dropped: the obscurance's L_max.
    pub threshold: f32,
    /// Virtual lights per walk at most (Russian roulette usually ends a walk sooner).
    pub max_depth: u32,
    /// Seed, threads, progress, and the time limit: stop at a whole pass (see the baker).
    pub work: WorkOptions,
}

impl LightPathMapSettings {
    /// E entry points and a short-connection threshold, the rest at the command line's
    /// defaults: one walk, 64 virtual lights at most, seed 0, every core, no time limit, quiet.
    pub fn new(entry_points: u32, threshold: f32) -> Self {
        LightPathMapSettings { entry_points, walks: 1, threshold, max_depth: 64, work: WorkOptions::default() }
    }

    pub const ENTRY_POINTS: ValueRange = ValueRange::count(1, 1 << 20);
    pub const WALKS: ValueRange = ValueRange::count(1, 1 << 16);
    /// Metres; 0 keeps every connection.
    pub const THRESHOLD: ValueRange = ValueRange::number(0.0, 1e6, false);

    pub fn validate(&self) -> Result<(), String> {
        let checks = [
            (Self::ENTRY_POINTS.admits_count(self.entry_points.into()), "entry points must be 1..=1048576"),
            (Self::WALKS.admits_count(self.walks.into()), "walks per entry point must be 1..=65536"),
            (Self::THRESHOLD.admits(self.threshold.into()), "the short-connection threshold must be in 0..=1e6 metres"),
            ((1..=1024).contains(&self.max_depth), "the walk depth must be 1..=1024"),
        ];
        first_failed_check(&checks)?;
        self.work.validate()
    }
}

/// An entry point with what only the bake needs: its density and albedo.
#[derive(Clone, Copy, Debug)]
pub struct BakedEntry {
    pub point: EntryPoint,
    /// d(e) of §3.2.1: expected entry points per square metre at e.
    pub density: f32,
    pub albedo: Vec3,
}

/// Entry points and how they were made.
#[derive(Clone, Debug)]
pub struct EntryPoints {
    pub entries: Vec<BakedEntry>,
    pub test_points: Vec<Vec3>,
    /// N_t: directions shot from every test point.
    pub rays_per_test_point: u32,
}

/// The test points Y_1..Y_M (§3.2.1): the region's own points, or its box sampled by a
/// scrambled Sobol sequence; without a region, the scene's point and spot lights.
pub fn test_points(scene: &Scene, region: Option<&LightRegion>, seed: u64) -> Result<Vec<Vec3>, String> {
    match region {
        Some(LightRegion::Points(points)) => Ok(points.clone()),
        Some(LightRegion::Box { min, max, test_points }) => Ok((0..*test_points)
            .map(|i| {
                let s = PathSampler::new(seed, 0, i).sobol4(TEST_POINT_GROUP);
                *min + (*max - *min) * Vec3::new(s[0], s[1], s[2])
            })
            .collect()),
        None => {
            let lights: Vec<Vec3> = scene.local_lights().map(|l| l.position).collect();
            if lights.is_empty() {
                return Err(format!(
                    "{}: no light region and no point or spot light to place entry points from; declare extras.relume.light_path_maps.region",
                    scene.source.display()
                ));
            }
            Ok(lights)
        }
    }
}

/// A uniform direction on the sphere: p_m(omega) = 1 / (4 pi), mimicking an isotropic light.
fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Shoots rounds of one direction per test point until `target` rays have hit the scene
/// (or 64 times the rounds that would need in a closed scene), then weighs every hit by the
/// density of §3.2.1: d(e) = N_t sum_m p_m cos(theta_e) / |Y_m - e|^2 v(Y_m, e).
pub fn entry_points(scene: &Scene, bvh: &SceneBvh, test_points: Vec<Vec3>, target: u32, seed: u64) -> Result<EntryPoints, String> {
    let m = test_points.len() as u32;
    let max_rounds = target.div_ceil(m.max(1)).saturating_mul(64);
    let mut hits = Vec::new();
    let mut rounds = 0;
    while (hits.len() as u32) < target && rounds < max_rounds {
        for (i, &y) in test_points.iter().enumerate() {
            let s = PathSampler::new(seed, i as u32, rounds).sobol4(ENTRY_DIRECTION_GROUP);
            let dir = uniform_sphere(Vec2::new(s[0], s[1]));
            if let Some(hit) = bvh.closest_hit(y, dir, f32::INFINITY) {
                let normal = if hit.geometric_normal.dot(dir) < 0.0 { hit.geometric_normal } else { -hit.geometric_normal };
                let albedo = scene.materials[hit.material as usize].albedo(&scene.textures, hit.uv0);
                hits.push(BakedEntry { point: EntryPoint { position: hit.position, normal }, density: 0.0, albedo });
            }
        }
        rounds += 1;
    }
    if hits.is_empty() {
        return Err(format!("{}: no ray from the {m} test points hits the scene; move the light region inside it", scene.source.display()));
    }
    hits.par_iter_mut().for_each(|e| e.density = density(bvh, &test_points, rounds, &e.point));
    Ok(EntryPoints { entries: hits, test_points, rays_per_test_point: rounds })
}

fn density(bvh: &SceneBvh, test_points: &[Vec3], rays_per_test_point: u32, e: &EntryPoint) -> f32 {
    let sum: f32 = test_points
        .iter()
        .map(|&y| {
            let offset = y - e.position;
            let d2 = offset.length_squared();
            let to_y = offset / d2.sqrt();
            let cos = e.normal.dot(to_y);
            if cos <= 0.0 || bvh.occluded(bvh.offset_origin(e.position, e.normal, to_y), to_y, d2.sqrt() - bvh.epsilon()) {
                return 0.0;
            }
            cos / (4.0 * PI * d2)
        })
        .sum();
    // The test point that shot e always sees it; a sum of 0 means e sits within epsilon of an
    // occluder, and the floor keeps its weight finite.
    rays_per_test_point as f32 * sum.max(f32::MIN_POSITIVE)
}

/// Irradiance at an entry point from `light` with ray-traced visibility: the "true" I_e the
/// transfer is checked with (the renderer takes visibility from the variance shadow map).
pub fn entry_irradiance(bvh: &SceneBvh, light: &Light, entry: &EntryPoint, light_area: f32) -> Vec3 {
    let unshadowed = entry_irradiance_unshadowed(light, entry, light_area);
    if unshadowed == Vec3::ZERO {
        return unshadowed;
    }
    let incident = light.incident(entry.position);
    let origin = bvh.offset_origin(entry.position, entry.normal, incident.to_light);
    if bvh.occluded(origin, incident.to_light, incident.distance - bvh.epsilon()) {
        return Vec3::ZERO;
    }
    unshadowed
}

/// The transfer of every entry point to every covered texel.
#[derive(Clone, Debug)]
pub struct Transfers {
    /// The covered texels (atlas indices), the columns of `values`.
    pub texels: Vec<u32>,
    /// T_e, one row of `texels.len()` rgb values per entry point.
    pub values: Vec<Vec3>,
    /// Walks every entry point received (fewer than asked when the time limit cut in).
    pub walks: u32,
    pub virtual_lights: u64,
    /// Shadow rays traced to connect virtual lights to texels.
    pub connections: u64,
    pub seconds: f64,
}

impl Transfers {
    pub fn row(&self, entry: usize) -> &[Vec3] {
        let n = self.texels.len();
        &self.values[entry * n..(entry + 1) * n]
    }

    /// sum_e I_e T_e over every atlas texel (0 for empty ones): the indirect irradiance.
    pub fn irradiance(&self, entry_irradiance: &[Vec3], texel_count: usize) -> Vec<Vec3> {
        let mut out = vec![Vec3::ZERO; texel_count];
        for (e, i) in entry_irradiance.iter().enumerate() {
            for (&t, v) in self.texels.iter().zip(self.row(e)) {
                out[t as usize] += *i * *v;
            }
        }
        out
    }
}

/// A vertex of a walk: it reflects `power` (irradiance times albedo / pi, over d(e)) from
/// the side `normal` faces.
struct VirtualLight {
    position: Vec3,
    normal: Vec3,
    power: Vec3,
    /// The surface area the light stands for, over pi (square metres): see `connect`.
    area_over_pi: f32,
}

/// What every walk and connection needs.
struct Walker<'a> {
    scene: &'a Scene,
    bvh: &'a SceneBvh,
    settings: &'a LightPathMapSettings,
    texels: Vec<Texel>,
    /// Each texel's patch area over pi (square metres): see `connect`.
    patch_area_over_pi: Vec<f32>,
    /// The area a bounce's virtual light stands for: the scene's over the walks of a pass.
    bounce_area: f32,
}

impl Walker<'_> {
    /// Walk `walk` of entry `index`: cosine sampling (the Lambertian BRDF), Russian roulette
    /// on the albedo; each vertex a virtual light (Keller 1997, as §3.2.2 uses it).
    fn walk(&self, index: u32, entry: &BakedEntry, walk: u32, lights: &mut Vec<VirtualLight>) {
        lights.clear();
        let sampler = PathSampler::new(self.settings.work.seed, index, walk);
        let (mut position, mut normal, mut albedo) = (entry.point.position, entry.point.normal, entry.albedo);
        let mut throughput = Vec3::splat(1.0 / entry.density);
        for depth in 0..self.settings.max_depth {
            let area = if depth == 0 { 1.0 / entry.density } else { self.bounce_area };
            lights.push(VirtualLight { position, normal, power: throughput * albedo / PI, area_over_pi: area / PI });
            let survive = albedo.max_element().min(0.95);
            let s = sampler.sobol4(depth);
            if s[2] >= survive {
                return;
            }
            throughput *= albedo / survive;
            let (t, b) = orthonormal_basis(normal);
            let local = cosine_hemisphere(Vec2::new(s[0], s[1]));
            let dir = (t * local.x + b * local.y + normal * local.z).normalize();
            let Some(hit) = self.bvh.closest_hit(self.bvh.offset_origin(position, normal, dir), dir, f32::INFINITY) else { return };
            position = hit.position;
            normal = if hit.geometric_normal.dot(dir) < 0.0 { hit.geometric_normal } else { -hit.geometric_normal };
            albedo = self.scene.materials[hit.material as usize].albedo(&self.scene.textures, hit.uv0);
        }
    }

    /// Adds every virtual light's irradiance at every texel it sees, over a connection at
    /// least the threshold long, to `row`; returns the shadow rays traced. A texel stands
    /// for its patch: the squared distance is widened by the patch area over pi, 000 §3.4's
    /// approximation of a light of area delta-l used the other way round, so a virtual light
    /// a texel away gives the patch's bounded average rather than a point's spike.
    fn connect(&self, lights: &[VirtualLight], row: &mut [Vec3]) -> u64 {
        let eps = self.bvh.epsilon();
        let min_d2 = (self.settings.threshold * self.settings.threshold).max(1e-12);
        let mut rays = 0;
        for light in lights {
            for ((value, texel), widen) in row.iter_mut().zip(&self.texels).zip(&self.patch_area_over_pi) {
                let offset = texel.centre - light.position;
                let d2 = offset.length_squared();
                if d2 < min_d2 {
                    continue;
                }
                let w = offset / d2.sqrt();
                let (cos_light, cos_texel) = (light.normal.dot(w), -texel.normal.dot(w));
                if cos_light <= 0.0 || cos_texel <= 0.0 {
                    continue;
                }
                let from = light.position + light.normal * eps;
                let to = texel.centre + texel.normal * eps;
                let span = to - from;
                let length = span.length();
                rays += 1;
                if self.bvh.occluded(from, span / length, length - eps) {
                    continue;
                }
                *value += light.power * (cos_light * cos_texel / (d2 + widen + light.area_over_pi));
            }
        }
        rays
    }
}

/// Rays that decide whether a point is inside closed geometry, and candidate points per texel.
const OPENNESS_RAYS: u32 = 16;
const EXIT_CANDIDATES: u32 = 16;

/// Whether most cosine-distributed rays from `point` about `normal` meet the back of a face:
/// then the point lies inside closed geometry (the floor under a box), where no light comes.
fn enclosed(bvh: &SceneBvh, point: Vec3, normal: Vec3, seed: u64, key: u32) -> bool {
    let (t, b) = orthonormal_basis(normal);
    let back_hits = (0..OPENNESS_RAYS)
        .filter(|&i| {
            let s = PathSampler::new(seed, key, i).sobol4(OPENNESS_GROUP);
            let local = cosine_hemisphere(Vec2::new(s[0], s[1]));
            let dir = (t * local.x + b * local.y + normal * local.z).normalize();
            bvh.closest_hit(bvh.offset_origin(point, normal, dir), dir, f32::INFINITY).is_some_and(|h| h.geometric_normal.dot(dir) > 0.0)
        })
        .count() as u32;
    2 * back_hits > OPENNESS_RAYS
}

/// The exit point of texel `t` (§3.2.2's texel centre): the patch centre, or where that lies
/// inside closed geometry (a texel straddling the foot of a box), the nearest of a few
/// points drawn over the patch that does not; a patch wholly inside keeps its centre and
/// receives nothing. Without this the covered-but-hidden half of such a texel would darken
/// its whole texel, and bilinear filtering would spread the dark a texel into the open.
fn exit_point(atlas: &Atlas, bvh: &SceneBvh, t: u32, seed: u64) -> Texel {
    let texel = atlas.texels[t as usize];
    if !enclosed(bvh, texel.centre, texel.normal, seed, t) {
        return texel;
    }
    let pieces = atlas.pieces_of(t as usize);
    let total: f32 = pieces.iter().map(|p| p.area).sum();
    let open = (0..EXIT_CANDIDATES).filter_map(|i| {
        let s = PathSampler::new(seed, t, i).sobol4(EXIT_GROUP);
        let mut pick = s[2] * total;
        let piece = pieces.iter().find(|p| {
            pick -= p.area;
            pick < 0.0
        })?;
        let w = crate::sampling::uniform_triangle(Vec2::new(s[0], s[1]));
        let bary = piece.corners[0] * w.x + piece.corners[1] * w.y + piece.corners[2] * w.z;
        let [p0, p1, p2] = bvh.primitive_positions(piece.triangle);
        let point = p0 + (p1 - p0) * bary.x + (p2 - p0) * bary.y;
        (!enclosed(bvh, point, texel.normal, seed, t ^ (i + 1) << 24)).then_some(point)
    });
    match open.min_by(|a, b| a.distance_squared(texel.centre).total_cmp(&b.distance_squared(texel.centre))) {
        Some(centre) => Texel { centre, ..texel },
        None => texel,
    }
}

/// T_e for every entry point and covered texel of `texels` (the atlas's). Passes of one
/// walk per entry point until `walks` are done or the time limit is reached; the result is
/// the same whatever the thread count.
pub fn bake_transfers(
    scene: &Scene,
    bvh: &SceneBvh,
    atlas: &Atlas,
    entries: &[BakedEntry],
    settings: &LightPathMapSettings,
) -> Result<Transfers, String> {
    settings.validate()?;
    let covered: Vec<u32> = (0..atlas.texels.len() as u32).filter(|&t| atlas.texels[t as usize].coverage > 0.0).collect();
    if covered.is_empty() {
        return Err("the atlas has no covered texel to transfer light to".into());
    }
    let walker = Walker {
        scene,
        bvh,
        settings,
        texels: covered.par_iter().map(|&t| exit_point(atlas, bvh, t, settings.work.seed)).collect(),
        patch_area_over_pi: covered.iter().map(|&t| atlas.pieces_of(t as usize).iter().map(|p| p.area).sum::<f32>() / PI).collect(),
        bounce_area: scene_area(scene) / entries.len().max(1) as f32,
    };
    let n = covered.len();
    let mut values = Vec::new();
    let (lights_made, rays) = (AtomicU64::new(0), AtomicU64::new(0));
    let mut progress = Progress::new(entries.len() as u64 * settings.walks as u64, "light path maps", settings.work.progress);
    let start = Instant::now();
    let mut walks = settings.walks;
    // An entry point's transfers are its row; its walks are seeded by its index.
    let make = |_, range: Range<u64>| {
        let first = range.start as usize;
        let mut rows = vec![Vec3::ZERO; (range.end - range.start) as usize * n];
        walks = settings.work.in_passes(settings.walks, 1, |walk| {
            let mine = &entries[first..range.end as usize];
            rows.par_chunks_mut(n).zip(mine.par_iter()).enumerate().for_each_init(Vec::new, |lights, (k, (row, entry))| {
                walker.walk((first + k) as u32, entry, walk.start, lights);
                lights_made.fetch_add(lights.len() as u64, Ordering::Relaxed);
                rays.fetch_add(walker.connect(lights, row), Ordering::Relaxed);
                progress.inc(1);
            });
        });
        let scale = 1.0 / walks as f32;
        rows.iter_mut().for_each(|v| *v *= scale);
        Ok(rows)
    };
    let take = |rows: Vec<Vec3>| {
        values = rows;
        Ok(())
    };
    settings.work.gather(&Items::whole::<Vec3>(entries.len() as u64, n), make, take)?;
    progress.finish();
    Ok(Transfers {
        texels: covered,
        values,
        walks,
        virtual_lights: lights_made.into_inner(),
        connections: rays.into_inner(),
        seconds: start.elapsed().as_secs_f64(),
    })
}

fn scene_area(scene: &Scene) -> f32 {
    scene
        .meshes
        .iter()
        .flat_map(|m| m.indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| m.positions[t[k] as usize])))
        .map(|[a, b, c]| 0.5 * (b - a).cross(c - a).length())
        .sum()
}

/// How the transfers are stored (§3.2.3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Compression {
    /// Every T_e kept: one cluster per entry point, its mean T_e itself, no eigen-textures.
    None,
    /// C clusters of D eigen-textures.
    Fixed { clusters: usize, basis: usize },
    /// The smallest (C, D) whose relative reconstruction error of the T_e is within the budget;
    /// refused when none is.
    Budget(f64),
    /// As `Budget`, or the most accurate (C, D) when none is within it (the default budget: a
    /// bake whose noise no clustering compresses that far still ends, and says so).
    BestWithin(f64),
}

/// Cluster counts and eigen-texture counts the error budget chooses among.
const BUDGET_CLUSTERS: [usize; 8] = [1, 2, 4, 8, 16, 32, 64, 128];
const BUDGET_CLUSTERS_MAX: usize = BUDGET_CLUSTERS[7];
const BUDGET_BASIS_MAX: usize = 8;
/// The most stored textures, C (1 + D), of any size the error budget searches.
pub const BUDGET_TEXTURES_MAX: usize = BUDGET_CLUSTERS_MAX * (1 + BUDGET_BASIS_MAX);

/// The stored transfer and what compressing it cost in accuracy.
#[derive(Clone, Debug)]
pub struct Compressed {
    pub transfer: ClusteredTransfer,
    pub clusters: usize,
    pub basis: usize,
    /// sqrt(sum_e |T_e - T~_e|^2 / sum_e |T_e|^2).
    pub relative_error: f64,
}

/// Clusters the entry points by position and normal and compresses their transfers by
/// clustered PCA (`cpca`), into the atlas's texel grid of `texel_count` texels.
pub fn compress(
    transfers: &Transfers,
    entries: &[BakedEntry],
    texel_count: usize,
    light_area: f32,
    compression: Compression,
) -> Result<Compressed, String> {
    match sizes(transfers, entries, compression, None)? {
        None => Ok(uncompressed(transfers, entries, texel_count, light_area)),
        Some((clusters, basis)) => Ok(fitted(transfers, entries, texel_count, light_area, clusters, basis)?),
    }
}

/// The transfers as rows of floats, in place: a copy would double the bake's peak memory.
fn rows(transfers: &Transfers) -> (&[f32], usize) {
    (bytemuck::cast_slice(&transfers.values), 3 * transfers.texels.len())
}

/// The clusters C and eigen-textures D the compression stores: given, or chosen by the error
/// budget's search; None: uncompressed. The default budget (`BestWithin`) searches only the
/// sizes of at most `most_textures` stored textures, C (1 + D), where given: those that fit
/// the memory limit, so that a large scene gets the most accurate clustering it has room for
/// instead of a refusal after its walks.
pub fn sizes(
    transfers: &Transfers,
    entries: &[BakedEntry],
    compression: Compression,
    most_textures: Option<usize>,
) -> Result<Option<(usize, usize)>, String> {
    let (budget, refuse) = match compression {
        Compression::None => return Ok(None),
        Compression::Fixed { clusters, basis } => return Ok(Some((clusters, basis))),
        Compression::Budget(budget) => (budget, true),
        Compression::BestWithin(budget) => (budget, false),
    };
    let (data, cols) = rows(transfers);
    let counts: Vec<usize> = BUDGET_CLUSTERS.into_iter().filter(|&c| c <= entries.len()).collect();
    let mut table = cpca::error_table(data, cols, &entry_features(entries), FEATURE_DIMS, &counts, BUDGET_BASIS_MAX)?;
    if !refuse {
        table.retain(|c| most_textures.is_none_or(|m| c.clusters * (1 + c.basis) <= m));
    }
    let most_accurate =
        table.iter().min_by(|a, b| a.relative_error.total_cmp(&b.relative_error).then(a.stored_values.cmp(&b.stored_values)));
    let best = match (cpca::choose(&table, budget), most_accurate) {
        (Some(best), _) => best,
        (None, Some(most)) if !refuse => *most,
        (None, None) => return Err("not even one cluster's mean texture fits the memory limit beside the transfers; raise --memory-limit or give fewer --entry-points".into()),
        _ => return Err(format!("no clustering of up to {BUDGET_CLUSTERS_MAX} clusters and {BUDGET_BASIS_MAX} eigen-textures reconstructs the transfers within a relative error of {budget}; raise the budget or give clusters and basis")),
    };
    Ok(Some((best.clusters, best.basis)))
}

/// The clustered PCA of the transfers into `clusters` clusters of `basis` eigen-textures.
pub fn fitted(
    transfers: &Transfers,
    entries: &[BakedEntry],
    texel_count: usize,
    light_area: f32,
    clusters: usize,
    basis: usize,
) -> Result<Compressed, String> {
    let (data, cols) = rows(transfers);
    let fit = cpca::fit(data, cols, &entry_features(entries), FEATURE_DIMS, clusters, basis)?;
    let relative_error = fit.relative_error(data);
    let transfer = clustered(&fit, transfers, entries, texel_count, light_area);
    Ok(Compressed { clusters: fit.clusters.len(), basis, relative_error, transfer })
}

/// Position over the scene's extent and normal at half weight: "entry points that are
/// close to each other and are on similarly oriented surface" (§3.2.3).
const FEATURE_DIMS: usize = 6;
const NORMAL_WEIGHT: f32 = 0.5;

fn entry_features(entries: &[BakedEntry]) -> Vec<f32> {
    let (lo, hi) =
        entries.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), e| (lo.min(e.point.position), hi.max(e.point.position)));
    let extent = (hi - lo).length().max(1e-6);
    entries
        .iter()
        .flat_map(|e| (e.point.position / extent).to_array().into_iter().chain((e.point.normal * NORMAL_WEIGHT).to_array()))
        .collect()
}

/// A covered-texel vector (3 floats a texel) spread over the whole texel grid.
fn spread(texels: &[u32], values: impl Iterator<Item = Vec3>, texel_count: usize) -> Vec<Vec3> {
    let mut grid = vec![Vec3::ZERO; texel_count];
    for (&t, v) in texels.iter().zip(values) {
        grid[t as usize] = v;
    }
    grid
}

fn uncompressed(transfers: &Transfers, entries: &[BakedEntry], texel_count: usize, light_area: f32) -> Compressed {
    let textures = (0..entries.len()).flat_map(|e| spread(&transfers.texels, transfers.row(e).iter().copied(), texel_count)).collect();
    let transfer = ClusteredTransfer {
        entry_points: entries.iter().map(|e| e.point).collect(),
        cluster_starts: (0..=entries.len() as u32).collect(),
        basis_count: 0,
        weights: Vec::new(),
        texel_count,
        textures,
        light_area,
    };
    Compressed { transfer, clusters: entries.len(), basis: 0, relative_error: 0.0 }
}

fn clustered(fit: &cpca::Cpca, transfers: &Transfers, entries: &[BakedEntry], texel_count: usize, light_area: f32) -> ClusteredTransfer {
    let as_rgb = |v: &[f32]| v.chunks_exact(3).map(Vec3::from_slice).collect::<Vec<_>>();
    let mut out =
        ClusteredTransfer { basis_count: fit.basis as u32, texel_count, light_area, cluster_starts: vec![0], ..Default::default() };
    for cluster in &fit.clusters {
        out.entry_points.extend(cluster.members.iter().map(|&e| entries[e as usize].point));
        out.cluster_starts.push(out.entry_points.len() as u32);
        out.weights.extend(cluster.weights.iter().flatten());
        for texture in std::iter::once(&cluster.mean).chain(&cluster.basis) {
            out.textures.extend(spread(&transfers.texels, as_rgb(texture).into_iter(), texel_count));
        }
    }
    out
}
