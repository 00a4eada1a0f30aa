//! The light-cloud baker: the cloud (a grid's cell centres outside closed geometry) and, per
//! vertex, the indirect irradiance each cloud light gives it (004 eq. 6-7 with n_b = 1).
//!
//! The paper traces a photon map per light, whose noise differs from light to light and
//! inflates both the clustering metric and the PCA rank. relume gathers instead (spec
//! light-clouds.md B11): from each vertex, paths of the reference path tracer's kind (its
//! BSDF, its Russian roulette); every path vertex past the first connects to every cloud light
//! by a shadow ray. The random numbers are the vertex's, shared by all lights, so the noise is
//! shared too. Only light that bounced at least once before reaching the vertex is gathered:
//! the reference's `indirect` layer once the vertex reflects it.

use super::{vertex_count, CloudGrid, LightCloud};
use crate::bsdf::Bsdf;
use crate::bvh::SceneBvh;
use crate::reference::punctual_irradiance;
use crate::sampling::{cosine_hemisphere, orthonormal_basis, PathSampler};
use crate::scene::{Light, LightKind, Scene};
use crate::work::{progress_bar, WorkOptions};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::f32::consts::PI;

/// What a light-cloud bake takes besides the scene.
#[derive(Clone, Debug)]
pub struct LightCloudBakeSettings {
    pub grid: CloudGrid,
    /// Gather paths per vertex.
    pub samples: u32,
    pub work: WorkOptions,
}

/// The first path vertex (0 = the vertex being baked) whose continuation Russian roulette
/// may cut: the reference's rule, counted from the camera's first hit.
const ROULETTE_FROM_VERTEX: u32 = 3;
/// The most scattering events a gather path may have (the reference's default).
const MAX_BOUNCES: u32 = 64;
/// First sampler dimension of the glossy lobe's choice (one per bounce).
const LOBE_DIMENSIONS: u32 = 1 << 29;
/// Gather paths per vertex in one pass: the time limit is checked between passes.
const SAMPLES_PER_PASS: u32 = 8;

/// Grid points inside closed geometry: at least 4 of the 6 axis rays from them first meet a
/// surface from behind (spec light-clouds.md C).
fn inside(bvh: &SceneBvh, point: Vec3) -> bool {
    let axes = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
    let behind =
        axes.iter().filter(|&&dir| bvh.closest_hit(point, dir, f32::INFINITY).is_some_and(|h| h.geometric_normal.dot(dir) > 0.0)).count();
    behind >= 4
}

/// The cloud's lights: the grid's cell centres not inside closed geometry.
pub fn cloud_points(bvh: &SceneBvh, grid: &CloudGrid) -> Vec<Vec3> {
    grid.points().into_iter().filter(|&p| !inside(bvh, p)).collect()
}

/// A cloud light: isotropic, 1 cd white.
fn unit_light(position: Vec3) -> Light {
    Light { name: String::new(), kind: LightKind::Point, intensity: Vec3::ONE, range: None, position, direction: Vec3::NEG_Z }
}

/// Bakes the cloud's transfer; refused when no cloud light is left outside closed geometry.
pub fn bake(scene: &Scene, bvh: &SceneBvh, settings: &LightCloudBakeSettings) -> Result<LightCloud, String> {
    settings.grid.validate()?;
    settings.work.validate()?;
    if settings.samples == 0 {
        return Err("the gather needs at least one path per vertex".into());
    }
    let points = cloud_points(bvh, &settings.grid);
    if points.is_empty() {
        return Err(format!(
            "every one of the {} cloud lights of light_cloud.grid {} .. {} lies inside closed geometry; put the grid's box where lights may move",
            settings.grid.points().len(),
            settings.grid.min,
            settings.grid.max
        ));
    }
    let lights: Vec<Light> = points.iter().map(|&p| unit_light(p)).collect();
    let vertices: Vec<(Vec3, Vec3)> =
        scene.meshes.iter().flat_map(|m| m.positions.iter().copied().zip(m.normals.iter().copied())).collect();
    let row = lights.len() * 3;
    let mut sums = vec![0f64; vertex_count(scene) * row];
    let progress = progress_bar(vertices.len() as u64 * settings.samples as u64, "light cloud", settings.work.progress);
    let gather = Gather { scene, bvh, lights: &lights, seed: settings.work.seed };
    let taken = settings.work.in_passes(settings.samples, SAMPLES_PER_PASS, |samples| {
        sums.par_chunks_mut(row).zip(vertices.par_iter()).enumerate().for_each(|(v, (sums, &(p, n)))| {
            for s in samples.clone() {
                gather.path(v as u32, s, p, n, sums);
            }
            progress.inc(samples.len() as u64);
        });
    });
    progress.finish_and_clear();
    let transfer = sums.iter().map(|s| (s / taken as f64) as f32).collect();
    Ok(LightCloud { lights: points, vertex_count: vertices.len(), transfer, samples: taken })
}

struct Gather<'a> {
    scene: &'a Scene,
    bvh: &'a SceneBvh,
    lights: &'a [Light],
    seed: u64,
}

impl Gather<'_> {
    /// Adds path `s` of vertex `v` (at `p`, normal `n`) to its row of sums, light by light.
    fn path(&self, v: u32, s: u32, p: Vec3, n: Vec3, sums: &mut [f64]) {
        let sampler = PathSampler::new(self.seed, v, s);
        let u = sampler.sobol4(0);
        let (t, b) = orthonormal_basis(n);
        let local = cosine_hemisphere(Vec2::new(u[0], u[1]));
        let mut dir = t * local.x + b * local.y + n * local.z;
        let mut origin = self.bvh.offset_origin(p, n, dir);
        let mut throughput = Vec3::ONE;
        for bounce in 1..=MAX_BOUNCES {
            let Some(hit) = self.bvh.closest_hit(origin, dir, f32::INFINITY) else { return };
            let material = &self.scene.materials[hit.material as usize];
            let wo = -dir;
            let albedo = material.albedo(&self.scene.textures, hit.uv0);
            let ng = if hit.geometric_normal.dot(wo) >= 0.0 { hit.geometric_normal } else { -hit.geometric_normal };
            let ns = if hit.shading_normal.dot(wo) >= 0.0 { hit.shading_normal } else { -hit.shading_normal };
            let bsdf = Bsdf::new(albedo, material.phong.as_ref(), ns, wo);
            for (j, light) in self.lights.iter().enumerate() {
                if let Some((e, wi)) = punctual_irradiance(self.bvh, light, hit.position, ns, ng, true) {
                    // Irradiance at the vertex by cosine sampling: L cos / pdf = pi L.
                    let c = PI * throughput * bsdf.eval(wi) * e;
                    for (sum, c) in sums[j * 3..j * 3 + 3].iter_mut().zip(c.to_array()) {
                        *sum += c as f64;
                    }
                }
            }
            let u = sampler.sobol4(bounce);
            let Some((wi, weight, _)) = bsdf.sample(Vec2::new(u[0], u[1]), || sampler.uniform(LOBE_DIMENSIONS + bounce), ng) else {
                return;
            };
            throughput *= weight;
            if bounce >= ROULETTE_FROM_VERTEX {
                let survive = throughput.max_element().min(0.95);
                if sampler.uniform(2 * bounce + 1) >= survive {
                    return;
                }
                throughput /= survive;
            }
            origin = self.bvh.offset_origin(hit.position, ng, wi);
            dir = wi;
        }
    }
}
