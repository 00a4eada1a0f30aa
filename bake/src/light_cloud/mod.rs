//! Local radiance transfer with light clouds (Kristensen, Akenine-Möller, Jensen,
//! "Precomputed Local Radiance Transfer for Real-Time Lighting Design", 004): the scene's
//! settings of the cloud (`extras.relume.light_cloud`), the transfer it bakes and its artifact
//! section `light-cloud` (this file), the weights that stand a user's light in for cloud
//! lights (`weights.rs`, §6.1) and, behind the `baking` feature, the baker (`baker.rs`: the
//! cloud, the per-vertex gather with random numbers shared by every cloud light).
//!
//! Every surface here is diffuse, so a vertex's transfer is one coefficient per cloud light
//! (004 eq. 7 with n_b = 1). relume stores it as the indirect irradiance (lux per candela)
//! rather than the exitant radiance: the lighting pass multiplies by albedo / pi per pixel,
//! so a textured albedo stays sharp between vertices.

#[cfg(feature = "baking")]
mod baker;
mod weights;
#[cfg(feature = "baking")]
pub use baker::*;
pub use weights::*;

use crate::artifact::{fail, Artifact, ArtifactError, Key, Section, REBAKE};
use crate::binary::{Reader, Writer};
use crate::scene::Scene;
use crate::settings::SceneBlock;
use crate::settings::{as_object, known_keys, vec3};
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
/// scene's bounds.
#[derive(Clone, Debug, PartialEq)]
pub struct LightCloudSceneSettings {
    pub grid: CloudGrid,
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
    Ok(LightCloudSceneSettings { grid })
}

/// The baked transfer: the cloud's lights and, per vertex of the scene (meshes in order, each
/// mesh's vertices in order: the renderer's vertex buffer) and per cloud light, the indirect
/// irradiance a 1 cd isotropic light there gives the vertex (lux), rgb.
#[derive(Clone, Debug, PartialEq)]
pub struct LightCloud {
    pub lights: Vec<Vec3>,
    pub vertex_count: usize,
    /// `[vertex][light][rgb]`: row v holds 3 x lights values (004 eq. 10's rows).
    pub transfer: Vec<f32>,
    /// Gather paths per vertex.
    pub samples: u32,
}

impl LightCloud {
    /// The transfer from cloud light `light` to vertex `vertex`.
    pub fn column(&self, vertex: usize, light: usize) -> Vec3 {
        let i = (vertex * self.lights.len() + light) * 3;
        Vec3::from_slice(&self.transfer[i..i + 3])
    }

    /// The shapes agree and every value is finite and not negative.
    pub fn validate(&self) -> Result<(), String> {
        if self.lights.is_empty() || self.lights.len() > MAX_CLOUD_LIGHTS as usize || self.lights.iter().any(|p| !p.is_finite()) {
            return Err(format!("{} cloud lights: must be 1..={MAX_CLOUD_LIGHTS} finite points", self.lights.len()));
        }
        if self.transfer.len() != self.vertex_count * self.lights.len() * 3 {
            return Err(format!(
                "{} transfer values for {} vertices and {} lights",
                self.transfer.len(),
                self.vertex_count,
                self.lights.len()
            ));
        }
        if let Some(i) = self.transfer.iter().position(|t| !(t.is_finite() && *t >= 0.0)) {
            let (vertex, light) = (i / 3 / self.lights.len(), i / 3 % self.lights.len());
            return Err(format!(
                "the transfer from cloud light {light} to vertex {vertex} is {} (must be finite and >= 0)",
                self.transfer[i]
            ));
        }
        Ok(())
    }

    /// Indirect irradiance per vertex for cloud-light weights (per channel, candela), summed
    /// over `weights` in their order: the CPU oracle of the renderer's reconstruction.
    pub fn irradiance(&self, weights: &[CloudWeight]) -> Vec<Vec3> {
        (0..self.vertex_count)
            .map(|v| weights.iter().fold(Vec3::ZERO, |sum, w| sum + self.column(v, w.light as usize) * w.weight))
            .collect()
    }
}

/// The scene's vertex count in the renderer's order.
pub fn vertex_count(scene: &Scene) -> usize {
    scene.meshes.iter().map(|m| m.positions.len()).sum()
}

pub const SECTION: &str = "light-cloud";
pub const SECTION_VERSION: u32 = 1;
const BIN: &str = "light-cloud.bin";
const MAGIC: &[u8; 8] = b"RLCLOUD\0";

/// The section: `light-cloud.bin` (counts, the lights, the transfer).
pub fn section(cloud: &LightCloud, summary: Value) -> Section {
    let mut w = Writer::new(MAGIC);
    w.u32s(&[cloud.lights.len() as u32, cloud.vertex_count as u32, cloud.samples]);
    w.f32s(&cloud.lights.iter().flat_map(|p| p.to_array()).collect::<Vec<_>>());
    w.f32s(&cloud.transfer);
    Section { name: SECTION.into(), version: SECTION_VERSION, key: Key::Scene, summary, files: vec![(BIN.into(), w.bytes)] }
}

/// The cloud of `artifact`, read for `scene`; refused when it does not hang together.
pub fn read(artifact: &Artifact, scene: &Scene) -> Result<LightCloud, ArtifactError> {
    let data = artifact.section(SECTION, SECTION_VERSION, Some(scene))?;
    let (bin, path) = data.file(BIN)?;
    let mut r = Reader::new(&bin, &path, MAGIC, "light cloud")?;
    let [lights, vertices, samples] = [r.u32("the light count")?, r.u32("the vertex count")?, r.u32("the sample count")?];
    if vertices as usize != vertex_count(scene) || lights == 0 || lights > MAX_CLOUD_LIGHTS {
        let problem = format!("{lights} cloud lights and {vertices} vertices do not fit the scene's {} vertices", vertex_count(scene));
        return Err(fail(&path, problem, REBAKE));
    }
    let positions = r.f32s(lights as usize * 3, "the lights")?;
    let transfer = r.f32s(vertices as usize * lights as usize * 3, "the transfer")?;
    r.finish("the transfer")?;
    let cloud = LightCloud {
        lights: positions.chunks_exact(3).map(Vec3::from_slice).collect(),
        vertex_count: vertices as usize,
        transfer,
        samples,
    };
    cloud.validate().map_err(|e| fail(&path, e, REBAKE))?;
    Ok(cloud)
}
