//! A cloud baked zone by zone (004 §4.2: "only one zone at a time needs to reside in memory";
//! spec light-clouds.md 3): each zone's vertices are gathered in turn, then each zone's lights
//! are clustered and its transfer compressed in turn. Light clustering weighs responses by the
//! largest transfer value of the whole cloud, so every zone's gathered rows wait until the last
//! zone is gathered: in memory where they fit `--memory-limit`, else in a scratch file (under
//! the system's temporary folder, `TMPDIR`, unlinked at once). The bytes are the same either
//! way, and the same as a bake of the whole cloud at once (`bake`, `reduce` and `compress`).

use super::reduce::{Clustering, Reduction};
use super::variance::{ExplainedVariance, VarianceSums};
use super::{compress_zone, error_sums, ratio, vertex_normals, vertex_positions, zone_share, Gatherer, LightCloud, Vectors};
use crate::bvh::SceneBvh;
use crate::scene::Scene;
use crate::shards::Items;
use crate::work::{Progress, WorkOptions};
use glam::Vec3;
use std::fs::File;
use std::ops::Range;
use std::os::unix::fs::FileExt;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

/// A cloud put together zone after zone.
pub struct ZonesBuilder {
    cloud: LightCloud,
    coords: Vec<Vec<f32>>,
}

impl ZonesBuilder {
    /// An empty cloud of `vertices` with the shape (coefficients, emission, directions,
    /// samples) of `like`.
    pub fn new(like: &LightCloud, vertices: usize) -> ZonesBuilder {
        let cloud = LightCloud {
            lights: Vec::new(),
            coefficients: like.coefficients,
            emission: like.emission,
            directions: like.directions,
            samples: like.samples,
            zone_lights: vec![0],
            zone_clusters: vec![0],
            vectors: Vec::new(),
            assignment: vec![0; vertices],
            terms: Vec::new(),
            coords: Vec::new(),
        };
        ZonesBuilder { cloud, coords: vec![Vec::new(); vertices] }
    }

    /// Appends `cloud`, one zone whose vertices are `members` of this one, in their order.
    pub fn push(&mut self, members: &[u32], cloud: LightCloud) {
        debug_assert_eq!(members.len(), cloud.vertex_count(), "a zone's cloud has a row per member");
        let c = &mut self.cloud;
        let first = c.cluster_count() as u32;
        let starts = cloud.coord_starts();
        for (k, &v) in members.iter().enumerate() {
            c.assignment[v as usize] = first + cloud.assignment[k];
            self.coords[v as usize] = cloud.coords[starts[k]..starts[k + 1]].to_vec();
        }
        c.zone_clusters.push(first + cloud.cluster_count() as u32);
        c.vectors.extend(cloud.vectors);
        c.terms.extend(cloud.terms);
        c.lights.extend(cloud.lights);
        c.zone_lights.push(c.lights.len() as u32);
    }

    /// The cloud, checked.
    pub fn finish(mut self) -> Result<LightCloud, String> {
        self.cloud.coords = self.coords.concat();
        self.cloud.validate()?;
        Ok(self.cloud)
    }
}

/// Every zone's gathered rows until the last zone is gathered.
pub enum ZoneRows {
    Memory(Vec<Vec<f32>>),
    /// A scratch file, unlinked as soon as it is made (nothing is left behind however the
    /// process ends; its space returns when the file closes), and each zone's first value in it.
    File {
        file: File,
        starts: Vec<u64>,
    },
}

/// Scratch files this process has made (their names stay unique when bakes run side by side).
static SCRATCH_FILES: AtomicU32 = AtomicU32::new(0);

impl ZoneRows {
    /// Rows kept in memory, or (`spill`) in a new scratch file under the temporary folder.
    pub fn new(spill: bool) -> Result<ZoneRows, String> {
        if !spill {
            return Ok(ZoneRows::Memory(Vec::new()));
        }
        let name = format!("relume-light-cloud-{}-{}.rows", std::process::id(), SCRATCH_FILES.fetch_add(1, Ordering::Relaxed));
        let path = std::env::temp_dir().join(name);
        let file = File::options().read(true).write(true).create_new(true).open(&path).map_err(|e| scratch_error(&path, e))?;
        std::fs::remove_file(&path).map_err(|e| scratch_error(&path, e))?;
        Ok(ZoneRows::File { file, starts: vec![0] })
    }

    pub fn push(&mut self, rows: Vec<f32>) -> Result<(), String> {
        match self {
            ZoneRows::Memory(zones) => zones.push(rows),
            ZoneRows::File { file, starts } => {
                let at = *starts.last().unwrap();
                file.write_all_at(bytemuck::cast_slice(&rows), at * 4).map_err(|e| scratch_error(&std::env::temp_dir(), e))?;
                starts.push(at + rows.len() as u64);
            }
        }
        Ok(())
    }

    /// Zone `z`'s rows, in zone order (each zone read once, after every push).
    pub fn take(&mut self, z: usize) -> Result<Vec<f32>, String> {
        match self {
            ZoneRows::Memory(zones) => Ok(std::mem::take(&mut zones[z])),
            ZoneRows::File { file, starts } => {
                let mut rows = vec![0f32; (starts[z + 1] - starts[z]) as usize];
                file.read_exact_at(bytemuck::cast_slice_mut(&mut rows), starts[z] * 4)
                    .map_err(|e| scratch_error(&std::env::temp_dir(), e))?;
                Ok(rows)
            }
        }
    }
}

fn scratch_error(path: &std::path::Path, e: std::io::Error) -> String {
    format!("{}: the light cloud's scratch file: {e} (set TMPDIR to a folder on a disk with room: the rows of every zone)", path.display())
}

/// How the gathered zones are reduced and kept.
pub struct ZoneSettings {
    pub reduction: Reduction,
    /// Clusters and vectors; None: uncompressed.
    pub compression: Option<(usize, Vectors)>,
    /// Record 004 Fig. 5's shares of this many components.
    pub variance_components: Option<usize>,
}

/// A cloud baked zone by zone, with what its reduction cost.
pub struct Zoned {
    pub cloud: LightCloud,
    /// Cloud lights (points and directions) before light clustering.
    pub cloud_lights: usize,
    /// Light clustering's relative error (`Reduced::relative_error`).
    pub clustering_error: f64,
    /// The clustered PCA's relative error against the reduced cloud (0 uncompressed).
    pub error: f64,
    pub variance: Option<ExplainedVariance>,
    /// Values gathered, over every zone.
    pub raw_values: usize,
    /// Seconds of light clustering and of the clustered PCA, over every zone.
    pub seconds: (f64, f64),
}

/// Gathers each of `zones` in turn into `store`: the paths a vertex took and the largest value
/// gathered. Under a time limit the first zone takes the passes its share of the vertices
/// has time for, and every other zone as many, so every vertex takes the same paths.
pub fn gather_zones(gatherer: &Gatherer, zones: &[Vec<u32>], samples: u32, store: &mut ZoneRows) -> Result<(u32, f32), String> {
    let mut progress = gatherer.progress(gatherer.vertices());
    let work = gatherer.work();
    let left = work.time_limit.map(|limit| limit.saturating_sub(work.started.map_or(Duration::ZERO, |s| s.elapsed())));
    let share = |zone: &[u32]| zone.len() as f64 / gatherer.vertices().max(1) as f64;
    let (mut taken, mut scale) = (samples, 0f32);
    let members = zones.concat();
    let items = Items::sized::<f32>(gatherer.row_values(), zones.iter().map(|zone| zone.len() as u64));
    let make = |z: usize, range: Range<u64>| {
        let limit = left.filter(|_| z == 0).map(|left| left.mul_f64(share(&zones[z])));
        let zone_work = WorkOptions { time_limit: limit, started: None, ..*work };
        let (rows, zone_taken) = gatherer.rows(&members[range.start as usize..range.end as usize], taken, &zone_work, &progress);
        taken = zone_taken;
        Ok(rows)
    };
    let take = |rows: Vec<f32>| {
        scale = rows.iter().fold(scale, |m, &x| m.max(x));
        store.push(rows)
    };
    work.gather(&items, make, take)?;
    progress.finish();
    Ok((taken, scale))
}

/// Each zone's lights clustered and its transfer compressed, one zone at a time, from the
/// gathered rows in `store`; `gathered`: the gathered cloud's shape (its lights, no rows).
pub fn reduce_zones(
    scene: &Scene,
    bvh: &SceneBvh,
    gathered: &LightCloud,
    (zones, mut store, scale): (&[Vec<u32>], ZoneRows, f32),
    settings: &ZoneSettings,
    progress: bool,
) -> Result<Zoned, String> {
    let clustering = Clustering::new(scene, bvh, gathered, settings.reduction, scale)?;
    let vertices = zones.iter().map(Vec::len).sum();
    let (positions, normals) = (vertex_positions(scene), vertex_normals(scene));
    let mut variance = settings.variance_components.map(VarianceSums::new);
    let mut out = ZonesBuilder::new(gathered, vertices);
    let (mut merged, mut compressed, mut seconds) = ((0f64, 0f64), (0f64, 0f64), (0f64, 0f64));
    let mut done = Progress::new(vertices as u64, "light cloud's zones (light clustering, clustered PCA)", progress);
    for (z, members) in zones.iter().enumerate() {
        let start = Instant::now();
        let reduced = clustering.reduce_zone(bvh, &gathered.lights, &store.take(z)?);
        merged = (merged.0 + reduced.error, merged.1 + reduced.total);
        let reduced = reduced.cloud(gathered);
        seconds.0 += start.elapsed().as_secs_f64();
        let start = Instant::now();
        let kept = match settings.compression {
            None => reduced,
            Some((clusters, vectors)) => {
                let cloud = compress_zone(&reduced, zone_share(clusters, members.len(), vertices), vectors)?;
                let (error, total) = error_sums(&reduced, &cloud);
                compressed = (compressed.0 + error, compressed.1 + total);
                if let Some(sums) = variance.as_mut() {
                    let at = |all: &[Vec3]| members.iter().map(|&v| all[v as usize]).collect::<Vec<_>>();
                    sums.add(bvh, (&at(&positions), &at(&normals)), &reduced, &cloud);
                }
                cloud
            }
        };
        seconds.1 += start.elapsed().as_secs_f64();
        out.push(members, kept);
        done.inc(members.len() as u64);
    }
    done.finish();
    Ok(Zoned {
        cloud: out.finish()?,
        cloud_lights: gathered.lights.len(),
        clustering_error: ratio(merged.0, merged.1),
        error: ratio(compressed.0, compressed.1),
        variance: variance.map(VarianceSums::finish),
        raw_values: vertices * gathered.per_light() * gathered.lights.len(),
        seconds,
    })
}
