//! Local radiance transfer with light clouds (Kristensen, Akenine-Möller, Jensen,
//! "Precomputed Local Radiance Transfer for Real-Time Lighting Design", 004): the scene's
//! settings of the cloud (`extras.relume.light_cloud`), the transfer it bakes and its artifact
//! section `light-cloud` (this file), the weights that stand a user's light in for cloud
//! lights (`weights.rs`, §6.1) and, behind the `baking` feature, the baker (`baker.rs`: the
//! cloud, the per-vertex gather with random numbers shared by every cloud light).
//!
//! Where every surface is diffuse, a vertex's transfer is one coefficient per cloud light
//! (004 eq. 7 with n_b = 1). relume stores it as the indirect irradiance (lux per candela)
//! rather than the exitant radiance: the lighting pass multiplies by albedo / pi per pixel,
//! so a textured albedo stays sharp between vertices. A scene with a glossy material stores
//! every vertex's exitant radiance as 16 spherical-harmonic coefficients ("third order",
//! n_b = 16, `crate::sh`), fitted over the vertex's hemisphere (spec light-clouds.md B10).

#[cfg(feature = "baking")]
mod baker;
#[cfg(feature = "baking")]
mod reduce;
#[cfg(feature = "baking")]
pub mod region;
#[cfg(feature = "baking")]
mod variance;
mod weights;
#[cfg(feature = "baking")]
mod zones;
#[cfg(feature = "baking")]
pub use baker::*;
#[cfg(feature = "baking")]
mod bake;
#[cfg(feature = "baking")]
pub use bake::*;
#[cfg(feature = "baking")]
pub use reduce::*;
#[cfg(feature = "baking")]
pub use variance::*;
pub use weights::*;
#[cfg(feature = "baking")]
pub use zones::*;

use crate::artifact::{fail, Artifact, ArtifactError, Key, Section, REBAKE};
use crate::binary::{Reader, Writer};
use crate::scene::Scene;
use crate::settings::SceneBlock;
use crate::settings::{as_object, known_keys, vec3};
use crate::sh;
use glam::Vec3;
use serde_json::Value;

/// The cloud's lights: the centres of a grid's cells over a box (004 §3: "a uniform sampling
/// of the region of interest"), less those inside closed geometry.
#[derive(Clone, Debug, PartialEq)]
pub struct CloudGrid {
    pub min: Vec3,
    pub max: Vec3,
    pub counts: [u32; 3],
}

/// The most cloud lights a grid may hold (the paper's largest cloud has 1,024).
pub const MAX_CLOUD_LIGHTS: u32 = 4096;

impl CloudGrid {
    /// The grid over the scene's bounds, 6 x 6 x 6 (the paper's Cornell cloud), for a scene
    /// without a block.
    pub fn over(bounds: (Vec3, Vec3)) -> CloudGrid {
        CloudGrid { min: bounds.0, max: bounds.1, counts: [6; 3] }
    }

    pub fn validate(&self) -> Result<(), String> {
        let count: u64 = self.counts.iter().map(|&c| c as u64).product();
        crate::settings::first_failed_check(&[
            (
                self.min.is_finite() && self.max.is_finite() && self.min.cmple(self.max).all(),
                "light_cloud.grid.box must be finite with min <= max on every axis",
            ),
            (self.counts.iter().all(|&c| c >= 1), "light_cloud.grid.counts must be at least 1 on every axis"),
            (count <= MAX_CLOUD_LIGHTS as u64, "light_cloud.grid.counts may make at most 4096 lights"),
        ])
    }

    /// The cell centres, x fastest, then y, then z.
    pub fn points(&self) -> Vec<Vec3> {
        let [nx, ny, nz] = self.counts;
        let cell = (self.max - self.min) / Vec3::new(nx as f32, ny as f32, nz as f32);
        let mut points = Vec::with_capacity((nx * ny * nz) as usize);
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    points.push(self.min + cell * (Vec3::new(x as f32, y as f32, z as f32) + 0.5));
                }
            }
        }
        points
    }
}

/// The scene's cloud, from `extras.relume.light_cloud`; without a block, 6 x 6 x 6 over the
/// scene's bounds (a bake derives a better one: `region::reachable`).
#[derive(Clone, Debug, PartialEq)]
pub struct LightCloudSceneSettings {
    pub grid: CloudGrid,
    /// Whether the scene declares its grid (else the bake derives one).
    pub declared: bool,
}

impl LightCloudSceneSettings {
    /// The scene's settings (checked when it loaded).
    pub fn of(scene: &Scene) -> Result<Self, String> {
        from_block(scene.settings.block(KEY), scene.settings.bounds)
    }
}

const KEY: &str = "light_cloud";

pub const SCENE_BLOCK: SceneBlock = SceneBlock { key: KEY, check: |block, bounds| from_block(Some(block), bounds).map(|_| ()) };

fn from_block(block: Option<&Value>, bounds: (Vec3, Vec3)) -> Result<LightCloudSceneSettings, String> {
    let mut grid = CloudGrid::over(bounds);
    let declared = block.is_some_and(|b| b.get("grid").is_some());
    if let Some(block) = block {
        let key = "extras.relume.light_cloud";
        let block = as_object(block, key)?;
        known_keys(block, key, &["grid"])?;
        if let Some(g) = block.get("grid") {
            let g = as_object(g, &format!("{key}.grid"))?;
            known_keys(g, &format!("{key}.grid"), &["box", "counts"])?;
            if let Some(b) = g.get("box") {
                let corners = b
                    .as_array()
                    .filter(|a| a.len() == 2)
                    .ok_or_else(|| format!("{key}.grid.box must be [[min x, y, z], [max x, y, z]]"))?;
                grid.min = vec3(&corners[0], &format!("{key}.grid.box[0]"))?;
                grid.max = vec3(&corners[1], &format!("{key}.grid.box[1]"))?;
            }
            if let Some(c) = g.get("counts") {
                let counts: Vec<Option<u32>> =
                    c.as_array().map(|a| a.iter().map(|v| v.as_u64().and_then(|n| u32::try_from(n).ok())).collect()).unwrap_or_default();
                let [Some(x), Some(y), Some(z)] = counts[..] else {
                    return Err(format!("{key}.grid.counts must be three whole numbers [x, y, z]"));
                };
                grid.counts = [x, y, z];
            }
        }
    }
    grid.validate().map_err(|e| format!("extras.relume.{e}"))?;
    Ok(LightCloudSceneSettings { grid, declared })
}

/// The baked transfer, by zone (004 §4.2): each zone has its own cloud lights (the cloud's,
/// or fewer after light clustering, §4.1) and its own clusters of vertices. Per vertex of the
/// scene (meshes in order, each mesh's vertices in order: the renderer's vertex buffer) and
/// per light of its zone, the indirect irradiance a 1 cd isotropic light there gives the
/// vertex (lux, rgb), as a clustered PCA (004 §5, eq. 11): vertex v of cluster c stores
/// X_v ~ X^c + sum_{d <= D_c} z_vd B^c_d, each term a row of 3 x (the zone's lights) values
/// (rgb per light, spec light-clouds.md B8). Uncompressed, every vertex is its own cluster and
/// D_c = 0: the terms are the rows as gathered.
///
/// With emission bands (`emission` > 1), each cloud light holds one transfer per function of
/// its emission, e_k(w) = y_k(w) / y_0 of the direction w light leaves it by (bands l <= B of
/// `crate::sh`, e_0 = 1: the isotropic light): a spot light stands on the cloud lights with
/// its cone's coefficients in those functions (004 §8's "spotlights with emission described
/// by spherical harmonics"; `emission`). A cloud light's transfers are its `emission`
/// columns, light after light; everything that weighs, sums or reconstructs works on columns.
///
/// A scene with a directional light (the sun through a window) has a cloud of directions too
/// (004 §4.1 leaves it open: "a cloud of directions"): the last `directions` lights of every
/// zone are unit directional lights of 1 lux from a set of directions over the sphere
/// (`directions`), on which a user's directional light stands by angle (`Weigher`). Their
/// light has no emission pattern: a direction's first column holds its transfer, the others
/// are zero.
#[derive(Clone, Debug, PartialEq)]
pub struct LightCloud {
    /// Every zone's lights, zone after zone: a point light's position, a directional light's
    /// unit direction (the way its light travels, as `Light::direction`).
    pub lights: Vec<Vec3>,
    /// How many of each zone's lights, its last, are directional (the same in every zone).
    pub directions: usize,
    /// n_b: 1 (indirect irradiance, lux) or `sh::COEFFICIENTS` (exitant radiance in spherical
    /// harmonics).
    pub coefficients: usize,
    /// Columns a cloud light has: its emission functions, (B + 1)^2 for bands l <= B (1: an
    /// isotropic light alone).
    pub emission: usize,
    /// Zone z's lights are `lights[zone_lights[z]..zone_lights[z + 1]]` (zones + 1 entries).
    pub zone_lights: Vec<u32>,
    /// Zone z's clusters are `zone_clusters[z]..zone_clusters[z + 1]` (zones + 1 entries).
    pub zone_clusters: Vec<u32>,
    /// Gather paths per vertex.
    pub samples: u32,
    /// Per vertex, its cluster.
    pub assignment: Vec<u32>,
    /// D_c, each cluster's basis vectors: the same for every cluster, or shared out by
    /// eigenvalue (Sloan et al. 2003's variable allocation).
    pub vectors: Vec<u32>,
    /// Cluster after cluster, `[term][zone light][emission function][coefficient][rgb]`: term 0
    /// the cluster's mean X^c, term d its B^c_d.
    pub terms: Vec<f32>,
    /// Vertex after vertex, its cluster's D_c coordinates z_vd, d from 1.
    pub coords: Vec<f32>,
}

/// Where one cluster's terms lie and which columns (cloud light x emission function) they
/// weigh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClusterLayout {
    /// The first value of its terms in `LightCloud::terms`.
    pub offset: usize,
    /// D_c: its terms are its mean and D_c basis vectors.
    pub vectors: u32,
    /// Its zone's first column and column count.
    pub first_column: u32,
    pub columns: u32,
}

impl LightCloud {
    /// Rows as gathered, `[vertex][light][coefficient][rgb]`: one zone, one cluster per vertex,
    /// no basis.
    pub fn uncompressed(lights: Vec<Vec3>, (coefficients, emission): (usize, usize), samples: u32, rows: Vec<f32>) -> LightCloud {
        let vertices = rows.len() / (3 * coefficients * emission * lights.len()).max(1);
        LightCloud {
            coefficients,
            emission,
            directions: 0,
            zone_lights: vec![0, lights.len() as u32],
            zone_clusters: vec![0, vertices as u32],
            lights,
            samples,
            assignment: (0..vertices as u32).collect(),
            vectors: vec![0; vertices],
            terms: rows,
            coords: Vec::new(),
        }
    }

    pub fn vertex_count(&self) -> usize {
        self.assignment.len()
    }

    /// Zone `z` of an uncompressed cloud as a cloud of its own: its lights, and the rows of
    /// `members` (its vertices), in their order (`compress` of a whole cloud, zone by zone).
    pub fn zone(&self, z: usize, members: &[u32]) -> LightCloud {
        let layout = self.layout();
        let cols = self.per_light() * self.zone_light_range(z).len();
        let rows =
            members.iter().flat_map(|&v| &self.terms[layout[self.assignment[v as usize] as usize].offset..][..cols]).copied().collect();
        let lights = self.lights[self.zone_light_range(z)].to_vec();
        LightCloud {
            directions: self.directions,
            ..LightCloud::uncompressed(lights, (self.coefficients, self.emission), self.samples, rows)
        }
    }

    pub fn zone_count(&self) -> usize {
        self.zone_lights.len().saturating_sub(1)
    }

    /// Values a light has in one term: rgb per coefficient per emission function.
    pub fn per_light(&self) -> usize {
        3 * self.coefficients * self.emission
    }

    /// Values a column (one emission function of one light) has in one term: rgb per
    /// coefficient.
    pub fn per_column(&self) -> usize {
        3 * self.coefficients
    }

    pub fn cluster_count(&self) -> usize {
        self.zone_clusters.last().map_or(0, |&c| c as usize)
    }

    /// D: the most basis vectors a cluster has (the stride of `cluster_sums`).
    pub fn basis(&self) -> usize {
        self.vectors.iter().max().map_or(0, |&d| d as usize)
    }

    /// Where each vertex's coordinates start in `coords`, and their end (vertices + 1 entries).
    pub fn coord_starts(&self) -> Vec<usize> {
        let d = |&c: &u32| self.vectors.get(c as usize).map_or(0, |&d| d as usize);
        std::iter::once(0).chain(self.assignment.iter().scan(0, |at, c| Some(*at + d(c)).inspect(|&end| *at = end))).collect()
    }

    /// Zone z's lights, as indices into `lights`.
    pub fn zone_light_range(&self, zone: usize) -> std::ops::Range<usize> {
        self.zone_lights[zone] as usize..self.zone_lights[zone + 1] as usize
    }

    /// How many values the clusters' terms hold, by the layout.
    pub fn term_values(&self) -> usize {
        self.layout().last().map_or(0, |l| l.offset + (1 + l.vectors as usize) * self.per_column() * l.columns as usize)
    }

    /// Every cluster's layout, in cluster order (clusters lie zone after zone).
    pub fn layout(&self) -> Vec<ClusterLayout> {
        let mut offset = 0;
        let mut layout = Vec::with_capacity(self.cluster_count());
        for zone in 0..self.zone_count() {
            let lights = self.zone_light_range(zone);
            let (first_column, columns) = ((lights.start * self.emission) as u32, (lights.len() * self.emission) as u32);
            for c in self.zone_clusters[zone]..self.zone_clusters[zone + 1] {
                let vectors = self.vectors[c as usize];
                layout.push(ClusterLayout { offset, vectors, first_column, columns });
                offset += (1 + vectors as usize) * self.per_column() * columns as usize;
            }
        }
        layout
    }

    /// The shapes agree, every value is finite, every zone has lights and clusters, every
    /// vertex's cluster exists, and an uncompressed transfer is not negative.
    pub fn validate(&self) -> Result<(), String> {
        if self.coefficients != 1 && self.coefficients != sh::COEFFICIENTS {
            return Err(format!(
                "{} coefficients a light: 1 (irradiance) or {} (spherical harmonics)",
                self.coefficients,
                sh::COEFFICIENTS
            ));
        }
        if !EMISSION_COUNTS.contains(&self.emission) {
            return Err(format!("{} emission functions a light: one of {EMISSION_COUNTS:?} (bands 0 to 3)", self.emission));
        }
        if self.lights.is_empty() || self.lights.iter().any(|p| !p.is_finite()) {
            return Err(format!("{} cloud lights: must be at least one, each a finite point", self.lights.len()));
        }
        check_zones(&self.zone_lights, &self.zone_clusters, self.lights.len(), self.cluster_count())?;
        if let Some(z) = (0..self.zone_count()).find(|&z| self.zone_light_range(z).len() > MAX_CLOUD_LIGHTS as usize) {
            return Err(format!("zone {z} has {} lights: at most {MAX_CLOUD_LIGHTS}", self.zone_light_range(z).len()));
        }
        self.check_directions()?;
        let clusters = self.cluster_count();
        if self.vectors.len() != clusters || self.basis() > MAX_VECTORS {
            return Err(format!("{} vector counts for {clusters} clusters, each at most {MAX_VECTORS}", self.vectors.len()));
        }
        let expected = self.term_values();
        if self.terms.len() != expected {
            return Err(format!("{} term values for clusters that hold {expected}", self.terms.len()));
        }
        if let Some(v) = self.assignment.iter().position(|&c| c as usize >= clusters) {
            return Err(format!("vertex {v} is in cluster {}, of {clusters}", self.assignment[v]));
        }
        let coords = self.coord_starts().last().copied().unwrap_or(0);
        if self.coords.len() != coords {
            return Err(format!("{} coordinates for vertices whose clusters' vectors hold {coords}", self.coords.len()));
        }
        // Basis vectors and spherical harmonics (of exitance or emission) take both signs;
        // irradiance does not.
        let negative_allowed = self.basis() > 0 || self.coefficients > 1 || self.emission > 1;
        if let Some(i) =
            self.terms.iter().chain(&self.coords).position(|t| !(crate::artifact::stored(*t) && (negative_allowed || *t >= 0.0)))
        {
            return Err(format!(
                "transfer value {i} is {} (must be finite, within 1e9, and >= 0 uncompressed)",
                self.terms.iter().chain(&self.coords).nth(i).unwrap()
            ));
        }
        Ok(())
    }

    /// Whether light `j` (an index into `lights`) is one of its zone's directions.
    pub fn is_direction(&self, j: usize) -> bool {
        let zone = self.zone_lights.partition_point(|&start| start as usize <= j) - 1;
        j >= self.zone_lights[zone + 1] as usize - self.directions
    }

    /// Every zone ends with the same `directions` unit vectors.
    fn check_directions(&self) -> Result<(), String> {
        let tail = |z: usize| {
            let lights = self.zone_light_range(z);
            &self.lights[lights.end - self.directions.min(lights.len())..lights.end]
        };
        let fits = (0..self.zone_count()).all(|z| tail(z).len() == self.directions && tail(z) == tail(0));
        let unit = tail(0).iter().all(|d| (d.length() - 1.0).abs() < 1e-4);
        if !(fits && unit && self.directions <= MAX_DIRECTIONS) {
            return Err(format!(
                "{} directions: every zone must end with the same unit vectors, at most {MAX_DIRECTIONS}",
                self.directions
            ));
        }
        Ok(())
    }

    /// Each cluster's terms weighed by column weights (per channel, candela), summed over the
    /// weights of its zone's columns in their order: x^m and b_d of 004 eq. (12), cluster after
    /// cluster, 1 + D terms each (zero past the cluster's D_c), coefficient after coefficient.
    pub fn cluster_sums(&self, weights: &[CloudWeight]) -> Vec<Vec3> {
        let (n, basis) = (self.per_column(), self.basis());
        let mut sums = Vec::with_capacity(self.cluster_count() * (1 + basis) * self.coefficients);
        for at in self.layout() {
            let row = n * at.columns as usize;
            for term in self.terms[at.offset..][..(1 + at.vectors as usize) * row].chunks_exact(row) {
                for k in 0..self.coefficients {
                    let zone = weights.iter().filter(|w| (at.first_column..at.first_column + at.columns).contains(&w.column));
                    sums.push(zone.fold(Vec3::ZERO, |sum, w| {
                        sum + Vec3::from_slice(&term[n * (w.column - at.first_column) as usize + 3 * k..][..3]) * w.weight
                    }));
                }
            }
            sums.resize(sums.len() + (basis - at.vectors as usize) * self.coefficients, Vec3::ZERO);
        }
        sums
    }

    /// Per vertex and coefficient, the transfer for cloud-light weights: x^m + sum_d z_d b_d
    /// (004 eq. 12-13), irradiance clamped at zero (spherical harmonics are clamped where they
    /// are evaluated): the CPU oracle of the renderer's two passes.
    pub fn reconstruct(&self, weights: &[CloudWeight]) -> Vec<Vec3> {
        let sums = self.cluster_sums(weights);
        let (terms, n, starts) = (1 + self.basis(), self.coefficients, self.coord_starts());
        let mut out = Vec::with_capacity(self.vertex_count() * n);
        for v in 0..self.vertex_count() {
            let first = self.assignment[v] as usize * terms * n;
            let z = &self.coords[starts[v]..starts[v + 1]];
            for k in 0..n {
                let a = z.iter().enumerate().fold(sums[first + k], |a, (d, z)| a + sums[first + (d + 1) * n + k] * *z);
                out.push(if n == 1 { a.max(Vec3::ZERO) } else { a });
            }
        }
        out
    }
}

/// A cloud's single values reconstructed, its layout computed once.
pub struct Columns<'c> {
    cloud: &'c LightCloud,
    layout: Vec<ClusterLayout>,
    starts: Vec<usize>,
}

impl<'c> Columns<'c> {
    pub fn new(cloud: &'c LightCloud) -> Columns<'c> {
        Columns { cloud, layout: cloud.layout(), starts: cloud.coord_starts() }
    }

    /// The transfer from column `column` (cloud light `column / emission`, emission function
    /// `column % emission`) to vertex `vertex`, reconstructed: the irradiance, or the
    /// radiance's first coefficient; zero for a column of another zone.
    pub fn column(&self, vertex: usize, column: usize) -> Vec3 {
        self.coefficient(vertex, column, 0)
    }

    /// Coefficient `k` of the transfer from column `column` to vertex `vertex`, reconstructed;
    /// zero for a column of another zone.
    pub fn coefficient(&self, vertex: usize, column: usize, k: usize) -> Vec3 {
        let cloud = self.cloud;
        let at = self.layout[cloud.assignment[vertex] as usize];
        let Some(j) = column.checked_sub(at.first_column as usize).filter(|&j| j < at.columns as usize) else { return Vec3::ZERO };
        let row = cloud.per_column() * at.columns as usize;
        let value = |t: usize| Vec3::from_slice(&cloud.terms[at.offset + t * row + cloud.per_column() * j + 3 * k..][..3]);
        let z = &cloud.coords[self.starts[vertex]..self.starts[vertex + 1]];
        z.iter().enumerate().fold(value(0), |sum, (d, z)| sum + value(d + 1) * *z)
    }
}

/// Zone starts: as many of lights as of clusters, each from 0, increasing (every zone has
/// lights and clusters), to `lights` and `clusters`.
fn check_zones(zone_lights: &[u32], zone_clusters: &[u32], lights: usize, clusters: usize) -> Result<(), String> {
    let starts =
        |s: &[u32], end: usize| s.len() >= 2 && s[0] == 0 && s.windows(2).all(|w| w[0] < w[1]) && *s.last().unwrap() as usize == end;
    if zone_clusters.len() != zone_lights.len() || !starts(zone_lights, lights) || !starts(zone_clusters, clusters) {
        return Err(format!(
            "zones {zone_lights:?} of lights and {zone_clusters:?} of clusters: each zone needs lights and clusters, in order"
        ));
    }
    Ok(())
}

/// The scene's vertex count in the renderer's order.
pub fn vertex_count(scene: &Scene) -> usize {
    scene.meshes.iter().map(|m| m.positions.len()).sum()
}

/// Every vertex's position, meshes in order (the renderer's vertex order).
pub fn vertex_positions(scene: &Scene) -> Vec<Vec3> {
    scene.meshes.iter().flat_map(|m| m.positions.iter().copied()).collect()
}

/// Every vertex's normal, meshes in order.
pub fn vertex_normals(scene: &Scene) -> Vec<Vec3> {
    scene.meshes.iter().flat_map(|m| m.normals.iter().copied()).collect()
}

/// sqrt(error / total), 0 where there is nothing: a relative error from its squared sums.
pub fn ratio(error: f64, total: f64) -> f64 {
    if total > 0.0 {
        (error / total).sqrt()
    } else {
        0.0
    }
}

pub const SECTION: &str = "light-cloud";
/// Version 7: a cloud of directions beside the points (version 6 had points only, version 5 had isotropic lights only,
/// version 4 one D for all, version 3 irradiance only, version 2 one zone, version 1 rows
/// only).
pub const SECTION_VERSION: u32 = 7;
/// Emission functions a cloud light may have: bands 0 to 3 of spherical harmonics.
pub const EMISSION_COUNTS: [usize; 4] = [1, 4, 9, 16];
/// The most directions a cloud may have.
pub const MAX_DIRECTIONS: usize = 1024;

/// `count` directions spread evenly over the sphere (a Fibonacci lattice: equal areas, no
/// pole crowding), the first pointing most nearly down (+y up), each the way a directional
/// light's light would travel.
pub fn directions(count: usize) -> Vec<Vec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..count)
        .map(|i| {
            let y = 1.0 - (2.0 * i as f64 + 1.0) / count as f64;
            let (radius, phi) = ((1.0 - y * y).sqrt(), golden * i as f64);
            -glam::DVec3::new(radius * phi.cos(), y, radius * phi.sin()).as_vec3()
        })
        .collect()
}

/// The most basis vectors a cluster may have.
pub const MAX_VECTORS: usize = 1024;
const BIN: &str = "light-cloud.bin";
const MAGIC: &[u8; 8] = b"RLCLOUD\0";

/// The section: `light-cloud.bin` (counts, the lights, the zones, each cluster's D_c, the
/// clustered transfer).
pub fn section(cloud: &LightCloud, summary: Value) -> Section {
    let mut w = Writer::new(MAGIC);
    w.u32s(&[
        cloud.lights.len() as u32,
        cloud.vertex_count() as u32,
        cloud.samples,
        cloud.cluster_count() as u32,
        cloud.basis() as u32,
        cloud.zone_count() as u32,
        cloud.coefficients as u32,
        cloud.emission as u32,
        cloud.directions as u32,
    ]);
    w.f32s(&cloud.lights.iter().flat_map(|p| p.to_array()).collect::<Vec<_>>());
    w.u32s(&cloud.zone_lights);
    w.u32s(&cloud.zone_clusters);
    w.u32s(&cloud.vectors);
    w.u32s(&cloud.assignment);
    w.f32s(&cloud.terms);
    w.f32s(&cloud.coords);
    Section { name: SECTION.into(), version: SECTION_VERSION, key: Key::Scene, summary, files: vec![(BIN.into(), w.bytes)] }
}

/// The cloud of `artifact`, read for `scene`; refused when it does not hang together.
pub fn read(artifact: &Artifact, scene: &Scene) -> Result<LightCloud, ArtifactError> {
    read_for(artifact, scene, vertex_count(scene))
}

/// The cloud of `artifact`, keyed to `scene` and made for `vertices` vertices (the scene's
/// tessellation's, when the bake tessellated it).
pub fn read_for(artifact: &Artifact, scene: &Scene, vertices_expected: usize) -> Result<LightCloud, ArtifactError> {
    let data = artifact.section(SECTION, SECTION_VERSION, Some(scene))?;
    let (bin, path) = data.file(BIN)?;
    let mut r = Reader::new(&bin, &path, MAGIC, "light cloud")?;
    let [lights, vertices, samples, clusters, basis, zones, coefficients, emission, directions] = [
        r.u32("the light count")?,
        r.u32("the vertex count")?,
        r.u32("the sample count")?,
        r.u32("the cluster count")?,
        r.u32("D")?,
        r.u32("the zone count")?,
        r.u32("the coefficient count")?,
        r.u32("the emission function count")?,
        r.u32("the direction count")?,
    ];
    if vertices as usize != vertices_expected
        || lights == 0
        || lights as u64 > MAX_CLOUD_LIGHTS as u64 * zones as u64
        || clusters == 0
        || clusters > vertices
        || basis as usize > MAX_VECTORS
        || zones == 0
        || zones > clusters.min(lights)
        || (coefficients != 1 && coefficients as usize != sh::COEFFICIENTS)
        || !EMISSION_COUNTS.contains(&(emission as usize))
        || directions as usize > MAX_DIRECTIONS
    {
        let problem = format!(
            "{lights} cloud lights ({directions} directions a zone) of {emission} emission functions and {coefficients} coefficients, {vertices} vertices, {clusters} clusters of D = {basis} in {zones} zones do not fit the scene's {vertices_expected} vertices"
        );
        return Err(fail(&path, problem, REBAKE));
    }
    let positions = r.f32s(lights as usize * 3, "the lights")?;
    let zone_lights = r.u32s(zones as usize + 1, "the zones' lights")?;
    let zone_clusters = r.u32s(zones as usize + 1, "the zones' clusters")?;
    check_zones(&zone_lights, &zone_clusters, lights as usize, clusters as usize).map_err(|e| fail(&path, e, REBAKE))?;
    let vectors = r.u32s(clusters as usize, "the clusters' vector counts")?;
    if vectors.iter().max() != Some(&basis) {
        return Err(fail(&path, format!("the clusters' vector counts do not reach D = {basis}"), REBAKE));
    }
    let assignment = r.u32s(vertices as usize, "the clusters")?;
    if let Some(v) = assignment.iter().position(|&c| c >= clusters) {
        return Err(fail(&path, format!("vertex {v} is in cluster {}, of {clusters}", assignment[v]), REBAKE));
    }
    let mut cloud = LightCloud {
        lights: positions.chunks_exact(3).map(Vec3::from_slice).collect(),
        coefficients: coefficients as usize,
        emission: emission as usize,
        directions: directions as usize,
        zone_lights,
        zone_clusters,
        samples,
        assignment,
        vectors,
        terms: Vec::new(),
        coords: Vec::new(),
    };
    cloud.terms = r.f32s(cloud.term_values(), "the terms")?;
    cloud.coords = r.f32s(*cloud.coord_starts().last().unwrap_or(&0), "the coordinates")?;
    r.finish("the coordinates")?;
    cloud.validate().map_err(|e| fail(&path, e, REBAKE))?;
    Ok(cloud)
}
