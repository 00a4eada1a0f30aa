//! The rays `relume rays` times: one fixed set per scene, traced the same way by every ray
//! caster, so relume's BVH and another library's can be compared on the same meshes and the
//! same rays in one run.
//!
//! The set is a path tracer's: a camera ray per pixel, then at each hit a shadow ray towards
//! each punctual light that lights it and a cosine-distributed bounce, for a few bounces. Primary rays are
//! coherent, bounces and shadow rays are not, as in every bake and the reference.

use crate::bvh::SceneBvh;
use crate::sampling::{cosine_hemisphere, orthonormal_basis, PathSampler};
use crate::scene::Scene;
use crate::work::with_threads;
use glam::Vec3;
use rayon::prelude::*;
use std::time::Instant;

/// A ray `origin + t dir`, 0 < t < `t_max`, `dir` unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TracedRay {
    pub origin: Vec3,
    pub dir: Vec3,
    pub t_max: f32,
}

/// The rays of one scene: those that want the closest hit and the shadow rays.
#[derive(Clone, Debug, Default)]
pub struct RaySet {
    pub closest: Vec<TracedRay>,
    pub shadow: Vec<TracedRay>,
}

/// What a ray caster answers: the closest hit's distance, and whether anything blocks.
pub trait RayCaster: Sync {
    fn closest_t(&self, ray: &TracedRay) -> Option<f32>;
    fn occluded(&self, ray: &TracedRay) -> bool;
}

impl RayCaster for SceneBvh {
    fn closest_t(&self, ray: &TracedRay) -> Option<f32> {
        self.closest_distance(ray.origin, ray.dir, ray.t_max)
    }

    fn occluded(&self, ray: &TracedRay) -> bool {
        SceneBvh::occluded(self, ray.origin, ray.dir, ray.t_max)
    }
}

/// The paths of `width` x `height` pixels, `bounces` diffuse bounces each, traced with
/// `bvh` (seeded per pixel: the same set at any thread count).
pub fn ray_set(scene: &Scene, bvh: &SceneBvh, width: u32, height: u32, bounces: u32, seed: u64) -> RaySet {
    let per_pixel: Vec<RaySet> =
        (0..width * height).into_par_iter().map(|pixel| path_rays(scene, bvh, pixel, width, height, bounces, seed)).collect();
    let mut set = RaySet::default();
    for p in per_pixel {
        set.closest.extend(p.closest);
        set.shadow.extend(p.shadow);
    }
    set
}

fn path_rays(scene: &Scene, bvh: &SceneBvh, pixel: u32, width: u32, height: u32, bounces: u32, seed: u64) -> RaySet {
    let sampler = PathSampler::new(seed, pixel, 0);
    let (x, y) = (pixel % width, pixel / width);
    let jitter = sampler.sobol4(0);
    let mut ray = TracedRay {
        origin: scene.camera.position(),
        dir: scene.camera.ray_direction(x as f32 + jitter[0], y as f32 + jitter[1], width, height),
        t_max: f32::INFINITY,
    };
    let mut set = RaySet::default();
    for bounce in 0..=bounces {
        set.closest.push(ray);
        let Some(hit) = bvh.closest_hit(ray.origin, ray.dir, ray.t_max) else {
            break;
        };
        let n = if hit.geometric_normal.dot(ray.dir) < 0.0 { hit.geometric_normal } else { -hit.geometric_normal };
        // As the path tracer casts them: none to a light behind the surface, outside its cone
        // or range, and each stopping short of the light by the offset.
        for light in scene.local_lights() {
            let incident = light.incident(hit.position);
            if incident.irradiance.max_element() > 0.0 && n.dot(incident.to_light) > 0.0 {
                let origin = bvh.offset_origin(hit.position, hit.geometric_normal, incident.to_light);
                set.shadow.push(TracedRay { origin, dir: incident.to_light, t_max: (incident.distance - bvh.epsilon()).max(0.0) });
            }
        }
        let u = sampler.sobol4(1 + bounce);
        let (t, b) = orthonormal_basis(n);
        let local = cosine_hemisphere(glam::Vec2::new(u[0], u[1]));
        let dir = (t * local.x + b * local.y + n * local.z).normalize();
        ray = TracedRay { origin: bvh.offset_origin(hit.position, hit.geometric_normal, dir), dir, t_max: f32::INFINITY };
    }
    set
}

/// Rays traced, of them those that hit (or were blocked), and the seconds they took.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayRate {
    pub rays: usize,
    pub hits: usize,
    pub seconds: f64,
}

impl RayRate {
    pub fn rays_per_second(&self) -> f64 {
        if self.seconds > 0.0 {
            self.rays as f64 / self.seconds
        } else {
            0.0
        }
    }
}

/// Times `caster` on the closest-hit rays, then on the shadow rays, on `threads` workers
/// (None: all cores), each `repeats` times over the set.
pub fn time_rays(caster: &impl RayCaster, set: &RaySet, threads: Option<usize>, repeats: u32) -> (RayRate, RayRate) {
    with_threads(threads, || {
        let closest = timed(&set.closest, repeats, |r| caster.closest_t(r).is_some());
        let shadow = timed(&set.shadow, repeats, |r| caster.occluded(r));
        (closest, shadow)
    })
}

fn timed(rays: &[TracedRay], repeats: u32, cast: impl Fn(&TracedRay) -> bool + Sync) -> RayRate {
    let start = Instant::now();
    let mut hits = 0;
    for _ in 0..repeats.max(1) {
        hits = rays.par_chunks(256).map(|chunk| chunk.iter().filter(|r| cast(r)).count()).sum();
    }
    RayRate { rays: rays.len() * repeats.max(1) as usize, hits, seconds: start.elapsed().as_secs_f64() }
}

/// How many rays two casters answer alike: the same hit or miss, and where both hit, distances
/// within `tolerance` relative; the second number counts the shadow rays that agree.
pub fn agreement(a: &impl RayCaster, b: &impl RayCaster, set: &RaySet, tolerance: f32) -> (usize, usize) {
    let same_t = |r: &TracedRay| match (a.closest_t(r), b.closest_t(r)) {
        (None, None) => true,
        (Some(x), Some(y)) => (x - y).abs() <= tolerance * x.max(y).max(1.0),
        _ => false,
    };
    let closest = set.closest.par_iter().filter(|r| same_t(r)).count();
    let shadow = set.shadow.par_iter().filter(|r| a.occluded(r) == b.occluded(r)).count();
    (closest, shadow)
}
