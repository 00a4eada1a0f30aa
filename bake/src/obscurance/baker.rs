//! Obscurance baking (Iones et al., "Fast realistic lighting for video games", §4) into the
//! atlas's texels, with two relatives: ambient occlusion and the spectral obscurance of
//! Umenhoffer et al., "Partial, Multi-scale Precomputed Radiance Transfer", §3.3.
//!
//! Each texel's value is the average over its patch (001 §4.2: "the obscurance of a patch is
//! defined as the average obscurance value over all its points"): every ray starts at its own
//! point, drawn uniformly by area over the face pieces of the patch, and leaves in a
//! cosine-distributed direction about the face's front (counter-clockwise) normal, so a
//! ray's estimate is rho(L) itself (the 1/pi and the cosine cancel the density).
//! The obscurance holds the front side: a two-sided surface shows the same value on its back.

use crate::atlas::Atlas;
use crate::bvh::SceneBvh;
use crate::sampling::{cosine_hemisphere, orthonormal_basis, uniform_triangle, PathSampler};
use crate::scene::Scene;
use crate::settings::{first_failed_check, ValueRange};
use crate::shards::Items;
use crate::work::{Progress, WorkOptions};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::ops::Range;
use std::time::Instant;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// 001 eq. (3) with rho(L) = 1 - exp(-L / tau) below L_max, 1 beyond (eq. 2, 8).
    Obscurance,
    /// rho a step: 0 below L_max, 1 beyond (000 eq. 3).
    AmbientOcclusion,
    /// 000 §3.3: open directions count 1; closed ones the albedo of the point hit over the
    /// scene's average albedo, times rho, per RGB channel.
    Spectral,
}

impl Variant {
    pub fn name(self) -> &'static str {
        match self {
            Variant::Obscurance => "obscurance",
            Variant::AmbientOcclusion => "ao",
            Variant::Spectral => "spectral",
        }
    }

    pub fn parse(name: &str) -> Option<Variant> {
        [Variant::Obscurance, Variant::AmbientOcclusion, Variant::Spectral].into_iter().find(|v| v.name() == name)
    }
}

#[derive(Clone, Debug)]
pub struct ObscuranceSettings {
    pub variant: Variant,
    /// Metres (001 eq. 2).
    pub tau: f32,
    /// Metres (001 §4.4).
    pub l_max: f32,
    pub rays_per_texel: u32,
    /// Seed, threads, progress, and the time limit: stop at a whole pass (see the baker).
    pub work: WorkOptions,
}

impl ObscuranceSettings {
    /// Metres, as tau and L_max.
    pub const DISTANCE: ValueRange = ValueRange::number(0.0, 1e6, true);
    pub const RAYS_PER_TEXEL: ValueRange = ValueRange::count(1, 1 << 20);

    pub fn validate(&self) -> Result<(), String> {
        let checks = [
            (Self::DISTANCE.admits(self.tau.into()), "tau must be in >0..=1e6 metres"),
            (Self::DISTANCE.admits(self.l_max.into()), "l_max must be in >0..=1e6 metres"),
            (Self::RAYS_PER_TEXEL.admits_count(self.rays_per_texel.into()), "rays per texel must be 1..=1048576"),
        ];
        first_failed_check(&checks)?;
        self.work.validate()
    }

    /// 001 eq. (2) cut at L_max (eq. 8), or the step of ambient occlusion.
    pub fn rho(&self, distance: f32) -> f32 {
        match (self.variant, distance >= self.l_max) {
            (_, true) => 1.0,
            (Variant::AmbientOcclusion, false) => 0.0,
            (_, false) => 1.0 - (-distance / self.tau).exp(),
        }
    }
}

/// Per-texel values (zero for empty texels) and what it took to make them.
#[derive(Clone, Debug)]
pub struct ObscuranceMap {
    /// One RGB value per atlas texel; the scalar variants repeat W in all three channels.
    pub values: Vec<Vec3>,
    /// Rays every covered texel received (fewer than asked when the time limit cut in).
    pub rays_per_texel: u32,
    pub rays_traced: u64,
    pub seconds: f64,
}

/// What one ray estimates: the scene, its BVH, the settings and the average albedo.
struct Estimator<'a> {
    scene: &'a Scene,
    bvh: &'a SceneBvh,
    settings: &'a ObscuranceSettings,
    /// 000 §3.3's a-tilde; its zero channels make albedo / a-tilde a 0/0 taken as 0.
    average_albedo: Vec3,
}

impl Estimator<'_> {
    /// One cosine-distributed ray from `point` about the front normal `normal`: rho(L), or
    /// for the spectral variant the colour-bleeding ratio times rho in closed directions.
    fn ray(&self, point: Vec3, normal: Vec3, u: Vec2) -> Vec3 {
        let (t, b) = orthonormal_basis(normal);
        let local = cosine_hemisphere(u);
        let dir = (t * local.x + b * local.y + normal * local.z).normalize();
        let origin = self.bvh.offset_origin(point, normal, dir);
        let Some(hit) = self.bvh.closest_hit(origin, dir, self.settings.l_max) else {
            return Vec3::ONE;
        };
        let rho = self.settings.rho(hit.t);
        if self.settings.variant != Variant::Spectral {
            return Vec3::splat(rho);
        }
        let material = &self.scene.materials[hit.material as usize];
        let albedo = material.albedo(&self.scene.textures, hit.uv0);
        let ratio = Vec3::select(self.average_albedo.cmpgt(Vec3::ZERO), albedo / self.average_albedo, Vec3::ZERO);
        ratio * rho
    }
}

/// The scene's area-weighted average albedo (textures at their mean texel).
pub fn average_albedo(scene: &Scene) -> Vec3 {
    let mut sum = Vec3::ZERO;
    let mut area = 0.0;
    for mesh in &scene.meshes {
        let material = &scene.materials[mesh.material];
        let texture_mean = material.base_color_texture.map_or(Vec3::ONE, |t| {
            let texels = &scene.textures[t].texels;
            texels.iter().map(|c| c.truncate()).sum::<Vec3>() / texels.len().max(1) as f32
        });
        let albedo = material.base_color.truncate() * texture_mean;
        for tri in mesh.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
            let triangle_area = 0.5 * (b - a).cross(c - a).length();
            sum += albedo * triangle_area;
            area += triangle_area;
        }
    }
    if area > 0.0 {
        sum / area
    } else {
        Vec3::ZERO
    }
}

/// Obscurance of a single point with normal `normal`, from `rays` rays (for analytic checks
/// and for probing a scene); the same estimator the texel bake uses.
pub fn point_obscurance(scene: &Scene, bvh: &SceneBvh, settings: &ObscuranceSettings, point: Vec3, normal: Vec3, rays: u32) -> Vec3 {
    let estimator = Estimator { scene, bvh, settings, average_albedo: average_albedo(scene) };
    let sum: Vec3 = (0..rays)
        .map(|i| {
            let s = PathSampler::new(settings.work.seed, 0, i).sobol4(0);
            estimator.ray(point, normal, Vec2::new(s[0], s[1]))
        })
        .sum();
    sum / rays.max(1) as f32
}

/// Rays per pass over all texels: small enough that a time limit stops soon after it is
/// reached, large enough that a pass amortises the scheduling.
const RAYS_PER_PASS: u32 = 32;

/// Bakes every covered texel of `atlas` (built from `scene`, whose BVH is `bvh`).
/// The same inputs and seed give the same values whatever the thread count.
pub fn bake_obscurance(scene: &Scene, bvh: &SceneBvh, atlas: &Atlas, settings: &ObscuranceSettings) -> Result<ObscuranceMap, String> {
    gather_obscurance(scene, bvh, atlas, settings, false)
}

/// As [`bake_obscurance`], its texels one gather of the bake (`followed` by another in a bake
/// that gathers again: `shards::Items`).
pub(crate) fn gather_obscurance(
    scene: &Scene,
    bvh: &SceneBvh,
    atlas: &Atlas,
    settings: &ObscuranceSettings,
    followed: bool,
) -> Result<ObscuranceMap, String> {
    settings.validate()?;
    let estimator = Estimator { scene, bvh, settings, average_albedo: average_albedo(scene) };
    let covered: Vec<u32> = (0..atlas.texels.len() as u32).filter(|&t| atlas.texels[t as usize].coverage > 0.0).collect();
    let mut progress = Progress::new(covered.len() as u64 * settings.rays_per_texel as u64, "obscurance", settings.work.progress);
    let start = Instant::now();
    let mut taken = settings.rays_per_texel;
    let mut values = vec![Vec3::ZERO; atlas.texels.len()];
    let make = |_, range: Range<u64>| {
        let texels = &covered[range.start as usize..range.end as usize];
        let mut sums = vec![Vec3::ZERO; texels.len()];
        taken = settings.work.in_passes(settings.rays_per_texel, RAYS_PER_PASS, |rays| {
            sums.par_chunks_mut(256).zip(texels.par_chunks(256)).for_each(|(sums, texels)| {
                for (sum, &texel) in sums.iter_mut().zip(texels) {
                    *sum += texel_rays(&estimator, atlas, texel, rays.clone());
                }
                progress.inc(texels.len() as u64 * rays.len() as u64);
            });
        });
        Ok(sums.iter().flat_map(|sum| (*sum / taken as f32).to_array()).collect())
    };
    let take = |rows: Vec<f32>| {
        for (&texel, value) in covered.iter().zip(rows.chunks_exact(3)) {
            values[texel as usize] = Vec3::from_slice(value);
        }
        Ok(())
    };
    settings.work.gather(&Items::whole::<f32>(covered.len() as u64, 3).followed(followed), make, take)?;
    progress.finish();
    Ok(ObscuranceMap {
        values,
        rays_per_texel: taken,
        rays_traced: taken as u64 * covered.len() as u64,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The summed estimates of rays `rays` of one texel, each from its own point on the patch.
fn texel_rays(estimator: &Estimator, atlas: &Atlas, texel: u32, rays: std::ops::Range<u32>) -> Vec3 {
    let pieces = atlas.pieces_of(texel as usize);
    let total_area: f32 = pieces.iter().map(|p| p.area).sum();
    let mut sum = Vec3::ZERO;
    for i in rays {
        let sampler = PathSampler::new(estimator.settings.work.seed, texel, i);
        let s = sampler.sobol4(0);
        let mut pick = sampler.uniform(4) * total_area;
        let piece = pieces.iter().find(|p| {
            pick -= p.area;
            pick < 0.0
        });
        let piece = piece.unwrap_or(&pieces[pieces.len() - 1]);
        let w = uniform_triangle(Vec2::new(s[0], s[1]));
        let bary = piece.corners[0] * w.x + piece.corners[1] * w.y + piece.corners[2] * w.z;
        let [p0, p1, p2] = estimator.bvh.primitive_positions(piece.triangle);
        let point = p0 + (p1 - p0) * bary.x + (p2 - p0) * bary.y;
        let point = inset([p0, p1, p2], point, 2.0 * estimator.bvh.epsilon());
        let normal = (p1 - p0).cross(p2 - p0).normalize();
        sum += estimator.ray(point, normal, Vec2::new(s[2], s[3]));
    }
    sum
}

/// `point` moved towards the triangle's incentre so that it lies at least `margin` inside
/// every edge (the whole triangle shrunk about its incentre). A ray starting nearer an edge
/// than the BVH's minimum hit distance would pass through the neighbouring face of a
/// corner unseen and count as open.
fn inset(corners: [Vec3; 3], point: Vec3, margin: f32) -> Vec3 {
    let [a, b, c] = corners;
    let side = [(b - c).length(), (c - a).length(), (a - b).length()];
    let perimeter = side[0] + side[1] + side[2];
    let incentre = (a * side[0] + b * side[1] + c * side[2]) / perimeter;
    let inradius = (b - a).cross(c - a).length() / perimeter;
    let keep = (1.0 - margin / inradius).max(0.0);
    incentre + (point - incentre) * keep
}
