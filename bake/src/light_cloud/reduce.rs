//! Zones and light clustering (004 §4.1-4.2): the scene's vertices split into zones, and in
//! each zone the cloud's lights merged where the zone's vertices cannot tell them apart, so
//! that each zone keeps fewer lights than the cloud.
//!
//! - Zones (spec light-clouds.md B7): the zone with the most vertices is split at the median
//!   of its vertices along the longest axis of their box, until there are as many zones as
//!   asked (or no zone has two vertices).
//! - The metric (004 eq. 9): Delta_jk = w1 |p_j - p_k| / diagonal + w2 max_(v, rgb)
//!   |X_vj - X_vk| / X_max + V_jk, the maximum over the zone's vertices, V_jk = 1 when the two
//!   lights do not see each other. The paper only says w1 scales with 1 / (scene size) and w2
//!   with 1 / (largest intensity): relume divides by the scene's diagonal and by the largest
//!   transfer value of the whole cloud, so Table 1's weights (0.5 / 20 for the Cornell box)
//!   carry over. That value is a maximum: one cloud light a few centimetres from a wall raises
//!   it and makes every other light's responses look alike (tune w2 per scene, as Table 1 does).
//! - The merge (§4.1): the paper names single linkage but states complete linkage's rule
//!   ("only if Delta_jk < 1 for all possible pairs"). relume takes the rule (spec B2,
//!   `Linkage::Complete`): two groups merge only if every pair across them has Delta < 1.
//!   `Linkage::Single` merges them when any pair does: nearer Table 1's count on the Cornell
//!   box, but worse at the same count (docs/BENCHMARKS.md, "The papers' claims"). Either way the closest pair of groups merges
//!   first (ties to the lowest indices), until none is left.
//! - The merged light (spec B3): its members' mean position (the member nearest it when the
//!   mean does not see every member), and per vertex the mean of its members' transfer.

use super::zones::ZonesBuilder;
use super::{ratio, vertex_positions, LightCloud};
use crate::bvh::SceneBvh;
use crate::scene::Scene;
use glam::Vec3;
use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// How a gathered cloud is reduced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reduction {
    pub zones: usize,
    /// Light clustering's weights (004 eq. 9); None: every zone keeps every cloud light.
    pub weights: Option<(f32, f32)>,
    pub linkage: Linkage,
}

/// When two groups of lights may merge (004 §4.1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Linkage {
    /// Every pair across the groups is close (the paper's rule).
    #[default]
    Complete,
    /// Some pair across the groups is close (the paper's name for it).
    Single,
}

impl Linkage {
    pub const ALL: [Linkage; 2] = [Linkage::Complete, Linkage::Single];

    /// The name the command line, sweeps and stats.json give.
    pub fn name(self) -> &'static str {
        match self {
            Linkage::Complete => "complete",
            Linkage::Single => "single",
        }
    }

    pub fn parse(name: &str) -> Option<Linkage> {
        Linkage::ALL.into_iter().find(|l| l.name() == name)
    }

    /// The merged group's distance to a third from the two groups' distances to it.
    fn merged(self, a: f32, b: f32) -> f32 {
        match self {
            Linkage::Complete => a.max(b),
            Linkage::Single => a.min(b),
        }
    }
}

impl Reduction {
    /// Refuses no zones and negative or non-finite weights.
    pub fn validate(&self) -> Result<(), String> {
        if self.zones == 0 {
            return Err("zones must be at least 1".into());
        }
        match self.weights {
            Some((w1, w2)) if !(w1.is_finite() && w2.is_finite() && w1 >= 0.0 && w2 >= 0.0) => {
                Err(format!("light clustering's weights w1 = {w1}, w2 = {w2} must be finite and >= 0"))
            }
            _ => Ok(()),
        }
    }
}

/// A reduced cloud (uncompressed, by zone) and what the reduction cost.
pub struct Reduced {
    pub cloud: LightCloud,
    /// Per zone, the cloud lights each of its lights stands for (ascending, by first member).
    pub groups: Vec<Vec<Vec<u32>>>,
    /// sqrt(sum |X_vj - X'_v(j)|^2 / sum |X_vj|^2) over every vertex and cloud light j, X'_v(j)
    /// the transfer of the merged light that stands for j in v's zone.
    pub relative_error: f64,
}

/// Splits a gathered cloud (one zone, uncompressed) into zones and clusters each zone's
/// lights: the whole cloud at once (a bake reduces a zone at a time, zones.rs; the tests hold
/// one against the other).
pub fn reduce(scene: &Scene, bvh: &SceneBvh, gathered: &LightCloud, reduction: Reduction) -> Result<Reduced, String> {
    if gathered.basis() != 0 || gathered.zone_count() != 1 || gathered.cluster_count() != gathered.vertex_count() {
        return Err("only a gathered cloud (one zone, uncompressed) can be reduced".into());
    }
    let zones = split_zones(&vertex_positions(scene), reduction.zones);
    let scale = gathered.terms.iter().fold(0f32, |m, &x| m.max(x));
    let clustering = Clustering::new(scene, bvh, gathered, reduction, scale)?;
    let row_values = gathered.per_light() * gathered.lights.len();
    let mut out = ZonesBuilder::new(gathered, gathered.vertex_count());
    let (mut groups, mut error, mut total) = (Vec::new(), 0f64, 0f64);
    for zone in &zones {
        let rows: Vec<f32> = zone.iter().flat_map(|&v| &gathered.terms[v as usize * row_values..][..row_values]).copied().collect();
        let mut reduced = clustering.reduce_zone(bvh, &gathered.lights, &rows);
        (error, total) = (error + reduced.error, total + reduced.total);
        groups.push(std::mem::take(&mut reduced.groups));
        out.push(zone, reduced.cloud(gathered));
    }
    Ok(Reduced { cloud: out.finish()?, groups, relative_error: ratio(error, total) })
}

/// What light clustering needs of the whole cloud: eq. (9)'s part every zone shares and the
/// response weight per largest transfer value.
pub struct Clustering {
    /// None: every zone keeps every cloud light.
    base: Option<Vec<f32>>,
    w2: f32,
    linkage: Linkage,
    per_light: usize,
}

impl Clustering {
    /// Refuses negative or non-finite weights and no zones. `scale`: the largest transfer value
    /// of the whole gathered cloud.
    pub fn new(scene: &Scene, bvh: &SceneBvh, gathered: &LightCloud, reduction: Reduction, scale: f32) -> Result<Clustering, String> {
        reduction.validate()?;
        let per_light = gathered.per_light();
        let Some((w1, w2)) = reduction.weights else {
            return Ok(Clustering { base: None, w2: 0.0, linkage: reduction.linkage, per_light });
        };
        let (lo, hi) = scene.settings.bounds;
        let diagonal = (hi - lo).length().max(f32::MIN_POSITIVE);
        let n = gathered.lights.len();
        let base = pair_base(bvh, &gathered.lights[..n - gathered.directions], n, w1 / diagonal);
        Ok(Clustering { base: Some(base), w2: w2 / scale.max(f32::MIN_POSITIVE), linkage: reduction.linkage, per_light })
    }

    /// One zone's lights clustered over its gathered `rows` (vertex after vertex, every cloud
    /// light's values): its merged lights and its rows over them.
    pub fn reduce_zone(&self, bvh: &SceneBvh, lights: &[Vec3], rows: &[f32]) -> ReducedZone {
        let (n, per_light) = (lights.len(), self.per_light);
        let vertices = rows.len() / (n * per_light).max(1);
        let row = |v: u32| &rows[v as usize * per_light * n..][..per_light * n];
        let groups: Vec<Vec<u32>> = match &self.base {
            None => (0..n as u32).map(|j| vec![j]).collect(),
            Some(base) => link(n, &zone_metric(base, rows, (n, per_light), self.w2), self.linkage),
        };
        let mut zone = ReducedZone {
            lights: groups.iter().map(|g| merged_position(bvh, lights, g)).collect(),
            rows: Vec::with_capacity(vertices * groups.len() * per_light),
            groups: Vec::new(),
            error: 0.0,
            total: 0.0,
        };
        for v in 0..vertices as u32 {
            let x = row(v);
            for group in &groups {
                for k in (0..per_light).step_by(3) {
                    let value = |j: u32| Vec3::from_slice(&x[per_light * j as usize + k..][..3]);
                    let mean = group.iter().fold(Vec3::ZERO, |s, &j| s + value(j)) / group.len() as f32;
                    zone.rows.extend(mean.to_array());
                    for &j in group {
                        zone.error += (value(j).as_dvec3() - mean.as_dvec3()).length_squared();
                        zone.total += value(j).as_dvec3().length_squared();
                    }
                }
            }
        }
        zone.groups = groups;
        zone
    }
}

/// One zone's reduced cloud: its lights and, vertex after vertex (the zone's order), its
/// transfer from each of them; with the squared error and squared total of the merge.
pub struct ReducedZone {
    pub lights: Vec<Vec3>,
    pub rows: Vec<f32>,
    /// The cloud lights each of its lights stands for.
    pub groups: Vec<Vec<u32>>,
    pub error: f64,
    pub total: f64,
}

impl ReducedZone {
    /// The zone as a cloud of its own (uncompressed, its vertices in the zone's order), shaped as
    /// `gathered`.
    pub fn cloud(self, gathered: &LightCloud) -> LightCloud {
        LightCloud {
            directions: gathered.directions,
            ..LightCloud::uncompressed(self.lights, (gathered.coefficients, gathered.emission), gathered.samples, self.rows)
        }
    }
}

/// The vertices of each zone (each list ascending): the zone with the most vertices is split
/// at its median along the longest axis of its vertices' box, ties to the lower zone and axis.
pub fn split_zones(positions: &[Vec3], zones: usize) -> Vec<Vec<u32>> {
    let mut out = vec![(0..positions.len() as u32).collect::<Vec<u32>>()];
    while out.len() < zones {
        let (largest, _) = out.iter().enumerate().fold((0, 0), |best, (z, m)| if m.len() > best.1 { (z, m.len()) } else { best });
        if out[largest].len() < 2 {
            break;
        }
        let members = &mut out[largest];
        let (lo, hi) = members
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &v| (lo.min(positions[v as usize]), hi.max(positions[v as usize])));
        let extent = hi - lo;
        let axis = (0..3).fold(0, |a, k| if extent[k] > extent[a] { k } else { a });
        members.sort_by(|&a, &b| positions[a as usize][axis].total_cmp(&positions[b as usize][axis]).then(a.cmp(&b)));
        let mut upper = members.split_off(members.len() / 2);
        members.sort_unstable();
        upper.sort_unstable();
        out.push(upper);
    }
    out
}

/// A symmetric n x n matrix, row-major, from its upper triangle: `pair(j, k)` for j < k.
fn symmetric(n: usize, pair: impl Fn(usize, usize) -> f32 + Sync) -> Vec<f32> {
    let upper: Vec<Vec<f32>> = (0..n).into_par_iter().map(|j| (j + 1..n).map(|k| pair(j, k)).collect()).collect();
    let mut matrix = vec![0f32; n * n];
    for (j, row) in upper.iter().enumerate() {
        for (k, &value) in (j + 1..n).zip(row) {
            matrix[j * n + k] = value;
            matrix[k * n + j] = value;
        }
    }
    matrix
}

/// Per pair of the `n` cloud lights, the part of eq. (9) every zone shares: `w1` times their
/// distance, plus 1 when they do not see each other (V_jk). Lights past the `points` are
/// directions, which never merge: a light from afar stands for no other.
fn pair_base(bvh: &SceneBvh, points: &[Vec3], n: usize, w1: f32) -> Vec<f32> {
    symmetric(n, |j, k| {
        let (Some(a), Some(b)) = (points.get(j), points.get(k)) else { return f32::INFINITY };
        let hidden = !bvh.visible(*a, *b);
        w1 * a.distance(*b) + if hidden { 1.0 } else { 0.0 }
    })
}

/// Eq. (9) for one zone: the shared part plus `w2` times the largest difference of the two
/// lights' transfer over the zone's vertices, coefficients and rgb (spec B1); `n` lights of
/// `per_light` values in each of the zone's `rows` (vertex after vertex).
fn zone_metric(base: &[f32], rows: &[f32], (n, per_light): (usize, usize), w2: f32) -> Vec<f32> {
    let differences = largest_differences(rows, (n, per_light));
    let mut metric = vec![0f32; n * n];
    for j in 0..n {
        for k in j + 1..n {
            let value = base[j * n + k] + w2 * differences[j * n + k];
            metric[j * n + k] = value;
            metric[k * n + j] = value;
        }
    }
    metric
}

/// Per pair of lights j < k (the upper triangle of an n x n matrix), the largest |x_j - x_k|
/// over the rows' values. Vertex by vertex, so a row (every light's values) stays in cache
/// while all its pairs are compared (light by light, each pair streamed both lights' values
/// over the whole zone from memory: minutes a zone of 16k vertices); the maximum is exact in
/// any order, so the bytes do not depend on the threads.
fn largest_differences(rows: &[f32], (n, per_light): (usize, usize)) -> Vec<f32> {
    let row_values = (n * per_light).max(1);
    let pairs = |mut largest: Vec<f32>, row: &[f32]| {
        for j in 0..n {
            let x = &row[j * per_light..][..per_light];
            for k in j + 1..n {
                let y = &row[k * per_light..][..per_light];
                largest[j * n + k] = largest[j * n + k].max(largest_difference(x, y));
            }
        }
        largest
    };
    let zero = || vec![0f32; n * n];
    rows.par_chunks(row_values * VERTICES_A_TASK).fold(zero, |largest, chunk| chunk.chunks_exact(row_values).fold(largest, pairs)).reduce(
        zero,
        |mut a, b| {
            a.iter_mut().zip(&b).for_each(|(x, y)| *x = x.max(*y));
            a
        },
    )
}

/// The largest |x_i - y_i|, in eight lanes: a chain of one scalar maximum after another waited
/// on each (a seventh of a light cloud's zone on the scale scene); the maximum is exact in any
/// order.
fn largest_difference(x: &[f32], y: &[f32]) -> f32 {
    let (xs, ys) = (x.chunks_exact(8), y.chunks_exact(8));
    let tail = xs.remainder().iter().zip(ys.remainder()).fold(0f32, |m, (a, b)| m.max((a - b).abs()));
    let mut lanes = [0f32; 8];
    for (a, b) in xs.zip(ys) {
        for (lane, (a, b)) in lanes.iter_mut().zip(a.iter().zip(b)) {
            let d = (a - b).abs();
            *lane = if d > *lane { d } else { *lane };
        }
    }
    lanes.into_iter().fold(tail, f32::max)
}

/// Vertices one task of `largest_differences` compares.
const VERTICES_A_TASK: usize = 64;

/// A metric value as a heap key: total order, NaN last.
#[derive(Clone, Copy, PartialEq)]
struct Key(f32);

impl Eq for Key {}

impl PartialOrd for Key {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Key {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// Clustering of `n` items by the symmetric row-major `metric`: groups merge, closest first
/// (ties to the lowest indices), while some pair of groups is below 1 by the `linkage` (004
/// §4.1, spec B2). The groups, each ascending, ordered by their first member.
pub fn link(n: usize, metric: &[f32], linkage: Linkage) -> Vec<Vec<u32>> {
    let mut distance = metric.to_vec();
    let mut members: Vec<Vec<u32>> = (0..n as u32).map(|j| vec![j]).collect();
    let mut heap = BinaryHeap::new();
    for j in 0..n {
        for k in j + 1..n {
            if distance[j * n + k] < 1.0 {
                heap.push(Reverse((Key(distance[j * n + k]), j, k)));
            }
        }
    }
    while let Some(Reverse((Key(d), g, h))) = heap.pop() {
        // Skip pairs whose group merged away or whose distance changed since.
        if members[g].is_empty() || members[h].is_empty() || distance[g * n + h] != d {
            continue;
        }
        let moved = std::mem::take(&mut members[h]);
        members[g].extend(moved);
        for k in (0..n).filter(|&k| k != g && !members[k].is_empty()) {
            let merged = linkage.merged(distance[g * n + k], distance[h * n + k]);
            let changed = merged != distance[g * n + k];
            distance[g * n + k] = merged;
            distance[k * n + g] = merged;
            if changed && merged < 1.0 {
                heap.push(Reverse((Key(merged), g.min(k), g.max(k))));
            }
        }
    }
    let mut groups: Vec<Vec<u32>> = members.into_iter().filter(|m| !m.is_empty()).collect();
    groups.iter_mut().for_each(|g| g.sort_unstable());
    groups.sort_unstable_by_key(|g| g[0]);
    groups
}

/// The merged light's position: its members' mean, or the member nearest the mean (ties to the
/// lowest) when the mean does not see every member.
fn merged_position(bvh: &SceneBvh, lights: &[Vec3], group: &[u32]) -> Vec3 {
    // A lone light (a direction always) is its own.
    if let [j] = group {
        return lights[*j as usize];
    }
    let mean = group.iter().fold(Vec3::ZERO, |s, &j| s + lights[j as usize]) / group.len() as f32;
    if group.iter().all(|&j| bvh.visible(mean, lights[j as usize])) {
        return mean;
    }
    let nearest =
        group.iter().fold(
            group[0],
            |best, &j| {
                if lights[j as usize].distance(mean) < lights[best as usize].distance(mean) {
                    j
                } else {
                    best
                }
            },
        );
    lights[nearest as usize]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{hash_u32, u32_to_unit};

    /// Against the plain maximum over every vertex and value, at widths off a multiple of the
    /// eight lanes and vertex counts across a task's edge.
    #[test]
    fn the_largest_differences_are_the_plain_maxima() {
        for (vertices, n, per_light) in [(130usize, 5usize, 27usize), (3, 4, 8), (65, 3, 3), (1, 2, 17)] {
            let rows: Vec<f32> = (0..vertices * n * per_light).map(|i| u32_to_unit(hash_u32(3, i as u32, 0, 0)) * 4.0 - 2.0).collect();
            let largest = largest_differences(&rows, (n, per_light));
            for (j, k) in (0..n).flat_map(|j| (j + 1..n).map(move |k| (j, k))) {
                let value = |v: usize, light: usize, i: usize| rows[(v * n + light) * per_light + i];
                let plain =
                    (0..vertices).flat_map(|v| (0..per_light).map(move |i| (v, i))).map(|(v, i)| (value(v, j, i) - value(v, k, i)).abs());
                assert_eq!(largest[j * n + k], plain.fold(0.0, f32::max), "{vertices} x {n} lights x {per_light}: ({j}, {k})");
            }
        }
    }
}
