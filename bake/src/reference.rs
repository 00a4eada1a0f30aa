//! The ground-truth path tracer every method in relume is measured against.
//!
//! Light transport, deliberately plain so that it can be trusted:
//! - Surfaces are Lambertian, f = albedo / pi, albedo = [`Material::albedo`] at uv0. They
//!   scatter on both sides: the shading normal is flipped to face the arriving ray. A direction
//!   below the *geometric* surface gets f = 0 (as pbrt does), so interpolated normals never
//!   let light through a surface.
//! - Emissive triangles emit [`Material::emission`] from their front face only (the side of
//!   the counter-clockwise geometric normal, glTF's front face).
//! - Punctual lights are delta lights, reached only by next-event estimation: every vertex
//!   asks every light for [`Light::incident`], times the cosine at the receiver, times a shadow
//!   ray that stops at [`Incident::distance`](crate::scene::Incident::distance).
//! - Emissive triangles are reached by both next-event estimation (a triangle picked in
//!   proportion to its power, a uniform point on it) and BSDF sampling (cosine-weighted), the
//!   two combined by multiple importance sampling with the power heuristic (Veach and Guibas,
//!   1995). Both pdfs are solid-angle densities at the shading point and use the same
//!   triangle-selection probability, so the weights sum to one for every path.
//! - Russian roulette on every continuation from the fourth path vertex on (light with up to
//!   four bounces is never cut), survival probability min(max throughput channel, 0.95),
//!   throughput divided by it: unbiased, which the furnace test checks to 0.5 %.
//! - A distant environment (`Scene::environment`, a working cube of constant-radiance texels)
//!   is reached by next-event estimation (a texel picked in proportion to luminance times
//!   solid angle, a uniform point on its square of the cube face) and by BSDF sampling (a
//!   continuation ray that hits nothing sees the environment), combined by MIS with the power
//!   heuristic like the emissive triangles. A camera ray that hits nothing sees black: the
//!   background is not scored. Without an environment every ray that hits nothing sees black.
//!
//! "Bounces" counts scattering events between the light and the camera: emission seen
//! directly has 0, light reflected once has 1. The `direct` layer holds bounces 0 and 1, the
//! `indirect` layer 2 and more.
//!
//! Determinism: every random number is a function of (seed, pixel, sample, dimension)
//! ([`crate::sampling`]) and each pixel sums its samples in sample order, so the output bytes
//! depend on the settings and the seed only, never on the thread count or on how samples were
//! split into passes.

use crate::bsdf::Bsdf;
use crate::bvh::{Hit, SceneBvh};
use crate::environment::{face_point, face_rectangle_solid_angle, luminance};
use crate::image::Image;
use crate::light_grid::LightGrid;
use crate::sampling::{uniform_triangle, PathSampler};
use crate::scene::{Light, Material, Scene};
use crate::work::{with_threads, Progress, WorkOptions};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::time::Instant;

/// The first path vertex (0 = where the camera ray lands) whose continuation Russian roulette
/// may cut.
const ROULETTE_FROM_VERTEX: u32 = 3;
/// The first random dimension of the environment's light samples (three per path vertex):
/// far above the two per vertex that emitter choice and Russian roulette take, so scenes
/// without an environment draw exactly the numbers they drew before it existed.
const ENVIRONMENT_DIMENSIONS: u32 = 1 << 30;
/// First sampler dimension of the glossy lobe's choice (one per bounce; only a material with a
/// lobe reads it).
pub(crate) const LOBE_DIMENSIONS: u32 = 1 << 29;
/// Scenes with up to this many punctual lights trace a shadow ray to each at every path
/// vertex; with more, `SAMPLED_LIGHTS` of them are drawn at each vertex from the light grid
/// (`light_grid.rs`), so that a path's cost does not grow with the lights (the scale scene has
/// one a bay: docs/BENCHMARKS.md, "Scale sweep").
pub const TRACED_LIGHTS: usize = 8;
const SAMPLED_LIGHTS: u32 = 2;
/// First sampler dimension of the light choices with many lights (`SAMPLED_LIGHTS` per
/// vertex): apart from every other dimension, so scenes of few lights draw what they drew.
const LIGHT_DIMENSIONS: u32 = 1 << 28;
/// The largest number of samples per pixel one pass over the image takes: small enough that
/// a time limit is not overshot by much and the progress bar moves.
const MAX_PASS_SAMPLES: u32 = 16;

#[derive(Clone, Debug)]
pub struct ReferenceSettings {
    pub samples_per_pixel: u32,
    pub width: u32,
    pub height: u32,
    /// The most scattering events a path may have (Russian roulette usually ends it sooner).
    pub max_bounces: u32,
    /// Every sample goes through its pixel's centre instead of a jittered point in the pixel,
    /// so each pixel sees exactly the surface point a rasteriser shades there.
    pub pixel_centres: bool,
    /// When false, punctual lights ignore visibility (a debug mode for comparing unshadowed
    /// shading against the rasteriser). Emissive triangles are always shadowed.
    pub shadows: bool,
    /// Seed, threads, progress, and the time limit: stop after the last whole pass over the
    /// image that fits in it (at least one sample per pixel is always taken).
    pub work: WorkOptions,
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        ReferenceSettings {
            samples_per_pixel: 64,
            width: 256,
            height: 256,
            max_bounces: 64,
            pixel_centres: false,
            shadows: true,
            work: WorkOptions::default(),
        }
    }
}

#[derive(Clone, Debug)]
pub struct ReferenceImages {
    /// Emission seen directly plus light after exactly one bounce.
    pub direct: Image,
    /// Light after two or more bounces.
    pub indirect: Image,
    /// `direct + indirect`, computed per pixel in f32 so the identity holds exactly.
    pub combined: Image,
    /// Samples per pixel actually taken: fewer than asked when the time limit hit.
    pub samples_per_pixel: u32,
    /// Camera paths traced per second of wall time.
    pub paths_per_second: f64,
    /// Samples whose contribution was NaN or infinite, counted as black. Always zero unless
    /// the scene holds degenerate data; reported so that a failure is never silent.
    pub nonfinite_samples: u64,
}

/// Renders the scene's camera view with the reference path tracer.
pub fn render_reference(scene: &Scene, bvh: &SceneBvh, settings: &ReferenceSettings) -> ReferenceImages {
    let integrator = Integrator::new(scene, bvh, settings);
    let (width, height) = (settings.width, settings.height);
    let pixel_count = (width as usize) * (height as usize);
    // Per pixel: direct rgb, indirect rgb, summed in f64 in sample order.
    let mut sums = vec![[0.0f64; 6]; pixel_count];
    let mut nonfinite = vec![0u64; height as usize];

    let mut progress = Progress::new(settings.samples_per_pixel as u64 * height as u64, "reference", settings.work.progress);

    let start = Instant::now();
    let mut taken = 0u32;
    let mut pass = 1u32;
    with_threads(settings.work.threads, || {
        while taken < settings.samples_per_pixel && pixel_count > 0 {
            if let (Some(limit), true) = (settings.work.time_limit, taken > 0) {
                let elapsed = start.elapsed();
                let per_sample = elapsed.as_secs_f64() / taken as f64;
                let fit = (limit.saturating_sub(elapsed).as_secs_f64() / per_sample).floor();
                if fit < 1.0 {
                    break;
                }
                pass = pass.min(fit as u32);
            }
            let samples = taken..taken + pass.min(settings.samples_per_pixel - taken);
            sums.par_chunks_mut(width as usize).zip(nonfinite.par_iter_mut()).enumerate().for_each(|(y, (row, bad))| {
                for (x, sum) in row.iter_mut().enumerate() {
                    *bad += integrator.pixel(x as u32, y as u32, samples.clone(), sum);
                }
                progress.inc(samples.len() as u64);
            });
            taken = samples.end;
            pass = (pass * 2).min(MAX_PASS_SAMPLES);
        }
    });
    let seconds = start.elapsed().as_secs_f64();
    progress.finish();

    let mut direct = Image::new(width, height);
    let mut indirect = Image::new(width, height);
    let mut combined = Image::new(width, height);
    if taken > 0 {
        let scale = 1.0 / taken as f64;
        for (i, s) in sums.iter().enumerate() {
            let d = Vec3::new((s[0] * scale) as f32, (s[1] * scale) as f32, (s[2] * scale) as f32);
            let n = Vec3::new((s[3] * scale) as f32, (s[4] * scale) as f32, (s[5] * scale) as f32);
            direct.pixels[i] = d;
            indirect.pixels[i] = n;
            combined.pixels[i] = d + n;
        }
    }
    let paths = taken as f64 * pixel_count as f64;
    ReferenceImages {
        direct,
        indirect,
        combined,
        samples_per_pixel: taken,
        paths_per_second: if seconds > 0.0 { paths / seconds } else { 0.0 },
        nonfinite_samples: nonfinite.iter().sum(),
    }
}

/// The image mean of the radiance that reaches the camera after exactly k bounces, for
/// k = 0..=`last_bounce` (element k). Traced exactly as [`render_reference`] traces (same
/// paths, same seed); `work.time_limit` and `work.progress` are ignored, every sample is taken. For a
/// closed scene with albedo a and no emitters in view, element k + 1 is about a times
/// element k: what the energy test checks.
pub fn radiance_by_bounce(scene: &Scene, bvh: &SceneBvh, settings: &ReferenceSettings, last_bounce: u32) -> Vec<Vec3> {
    let integrator = Integrator::new(scene, bvh, settings);
    let slots = last_bounce as usize + 1;
    let rows: Vec<Vec<[f64; 3]>> = with_threads(settings.work.threads, || {
        (0..settings.height)
            .into_par_iter()
            .map(|y| {
                let mut row = vec![[0.0f64; 3]; slots];
                for x in 0..settings.width {
                    for s in 0..settings.samples_per_pixel {
                        integrator.trace_sample(x, y, s, &mut |bounce, l| {
                            if let Some(r) = row.get_mut(bounce as usize) {
                                r[0] += l.x as f64;
                                r[1] += l.y as f64;
                                r[2] += l.z as f64;
                            }
                        });
                    }
                }
                row
            })
            .collect()
    });
    // Summed in row order, so the result does not depend on the thread count.
    let mut total = vec![[0.0f64; 3]; slots];
    for row in &rows {
        for (t, r) in total.iter_mut().zip(row) {
            for c in 0..3 {
                t[c] += r[c];
            }
        }
    }
    let n = settings.samples_per_pixel as f64 * settings.width as f64 * settings.height as f64;
    let scale = if n > 0.0 { 1.0 / n } else { 0.0 };
    total.iter().map(|t| Vec3::new((t[0] * scale) as f32, (t[1] * scale) as f32, (t[2] * scale) as f32)).collect()
}

/// Irradiance from the scene's punctual lights at `point` on a surface with unit `normal`,
/// with visibility: the sum over lights of [`Light::incident`] irradiance times the cosine,
/// for lights in front of the surface and not blocked. Shadow rays start
/// [`SceneBvh::epsilon`] off the point along `normal`. Emissive triangles are not included.
pub fn direct_irradiance(scene: &Scene, bvh: &SceneBvh, point: Vec3, normal: Vec3) -> Vec3 {
    scene.lights.iter().filter_map(|light| punctual_irradiance(bvh, light, point, normal, normal, true)).map(|(e, _)| e).sum()
}

/// Irradiance from the scene's environment at `point` on a surface with unit `normal`, with
/// visibility, by deterministic quadrature: each cube texel is split into k x k cells
/// (k = ceil(sqrt(`rays_per_texel`))), one shadow ray through each cell's centre, weighted by
/// the cell's exact solid angle and the cosine. Zero without an environment.
pub fn environment_irradiance(scene: &Scene, bvh: &SceneBvh, point: Vec3, normal: Vec3, rays_per_texel: u32) -> Vec3 {
    let Some(environment) = &scene.environment else { return Vec3::ZERO };
    let (n, k) = (environment.face, (rays_per_texel.max(1) as f64).sqrt().ceil() as u32);
    let cells = n * k;
    let edge = |i: u32| 2.0 * i as f64 / cells as f64 - 1.0;
    let mut sum = [0.0f64; 3];
    for (texel, radiance) in environment.radiance.iter().enumerate() {
        let (face, t, s) = (texel / (n * n) as usize, (texel as u32 / n) % n, texel as u32 % n);
        for j in t * k..(t + 1) * k {
            for i in s * k..(s + 1) * k {
                let centre = |c: u32| ((edge(c) + edge(c + 1)) * 0.5) as f32;
                let wi = face_point(face, centre(i), centre(j)).normalize();
                let cos = normal.dot(wi);
                if cos <= 0.0 || bvh.occluded(bvh.offset_origin(point, normal, wi), wi, f32::INFINITY) {
                    continue;
                }
                let weight = face_rectangle_solid_angle(edge(i), edge(j), edge(i + 1), edge(j + 1)) * cos as f64;
                (0..3).for_each(|c| sum[c] += radiance[c] as f64 * weight);
            }
        }
    }
    Vec3::new(sum[0] as f32, sum[1] as f32, sum[2] as f32)
}

/// Irradiance on the shading normal `ns` from one punctual light and the direction to it, or
/// None when the light is behind the surface (either normal), outside its cone or range, or
/// blocked.
#[inline]
pub(crate) fn punctual_irradiance(bvh: &SceneBvh, light: &Light, point: Vec3, ns: Vec3, ng: Vec3, shadows: bool) -> Option<(Vec3, Vec3)> {
    let incident = light.incident(point);
    if incident.irradiance.max_element() <= 0.0 {
        return None;
    }
    let cos = ns.dot(incident.to_light);
    if cos <= 0.0 || ng.dot(incident.to_light) <= 0.0 {
        return None;
    }
    if shadows {
        let origin = bvh.offset_origin(point, ng, incident.to_light);
        let t_max = (incident.distance - bvh.epsilon()).max(0.0);
        if bvh.occluded(origin, incident.to_light, t_max) {
            return None;
        }
    }
    Some((incident.irradiance * cos, incident.to_light))
}

/// Russian roulette on the continuation from path vertex `vertex`: from the fourth on, the
/// path survives with probability min(max throughput channel, 0.95), its throughput divided
/// by it; `u` draws the uniform number only when the roulette is played.
#[inline]
pub(crate) fn survives_roulette(throughput: &mut Vec3, vertex: u32, u: impl FnOnce() -> f32) -> bool {
    if vertex < ROULETTE_FROM_VERTEX {
        return true;
    }
    let survive = throughput.max_element().min(0.95);
    if u() >= survive {
        return false;
    }
    *throughput /= survive;
    true
}

/// Power heuristic (beta = 2) weight of the strategy with density `a` against one with `b`.
#[inline]
fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

/// Emissive triangles and the distribution next-event estimation picks them from.
struct Emitters {
    /// Flattened primitive index of each emissive triangle.
    primitives: Vec<u32>,
    /// Cumulative selection probability; the last entry is 1. In f64 and picked with 53-bit
    /// numbers, so that even among millions of emitters the odds of each are what `pdf_area`
    /// says.
    cdf: Vec<f64>,
    /// For every flattened primitive: its selection probability divided by its area (the
    /// area density of a light sample on it), 0 for non-emitters. The probability is the
    /// difference of consecutive `cdf` entries, exactly what sampling the cdf yields, so both
    /// MIS strategies see the same number.
    pdf_area: Vec<f32>,
}

impl Emitters {
    fn new(scene: &Scene, bvh: &SceneBvh) -> Self {
        let mut primitives = Vec::new();
        let mut power = Vec::new();
        let mut areas = Vec::new();
        for (m, mesh) in scene.meshes.iter().enumerate() {
            let emission = scene.materials[mesh.material].emission;
            let lum = luminance(emission);
            if lum <= 0.0 {
                continue;
            }
            for t in 0..mesh.indices.len() / 3 {
                let prim = bvh.primitive_index(m, t);
                let [p0, p1, p2] = bvh.primitive_positions(prim);
                let area = 0.5 * (p1 - p0).cross(p2 - p0).length();
                if area > 0.0 && area.is_finite() {
                    primitives.push(prim);
                    power.push(lum as f64 * area as f64);
                    areas.push(area);
                }
            }
        }
        let total: f64 = power.iter().sum();
        let mut cdf = Vec::with_capacity(power.len());
        let mut running = 0.0f64;
        for p in &power {
            running += p;
            cdf.push(running / total);
        }
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        let mut pdf_area = vec![0.0f32; bvh.triangle_count()];
        for (i, &prim) in primitives.iter().enumerate() {
            let previous = if i == 0 { 0.0 } else { cdf[i - 1] };
            pdf_area[prim as usize] = ((cdf[i] - previous) / areas[i] as f64) as f32;
        }
        Emitters { primitives, cdf, pdf_area }
    }

    /// The emitter a uniform number in [0, 1) picks.
    #[inline]
    fn pick(&self, u: f64) -> u32 {
        let i = self.cdf.partition_point(|&c| c <= u).min(self.cdf.len() - 1);
        self.primitives[i]
    }
}

struct Integrator<'a> {
    scene: &'a Scene,
    bvh: &'a SceneBvh,
    emitters: Emitters,
    seed: u64,
    width: u32,
    height: u32,
    max_bounces: u32,
    pixel_centres: bool,
    shadows: bool,
    /// The lights' odds by place, in a scene of more than `TRACED_LIGHTS`.
    light_grid: Option<LightGrid>,
}

impl<'a> Integrator<'a> {
    fn new(scene: &'a Scene, bvh: &'a SceneBvh, settings: &ReferenceSettings) -> Self {
        Integrator {
            scene,
            bvh,
            emitters: Emitters::new(scene, bvh),
            seed: settings.work.seed,
            width: settings.width,
            height: settings.height,
            max_bounces: settings.max_bounces,
            pixel_centres: settings.pixel_centres,
            shadows: settings.shadows,
            light_grid: (scene.lights.len() > TRACED_LIGHTS).then(|| LightGrid::new(scene)),
        }
    }

    /// Adds samples `samples` of pixel (x, y) to `sum` (direct rgb, indirect rgb); returns
    /// how many samples were non-finite (left out of the sum, so counted as black).
    fn pixel(&self, x: u32, y: u32, samples: std::ops::Range<u32>, sum: &mut [f64; 6]) -> u64 {
        let mut bad = 0;
        for s in samples {
            let (mut direct, mut indirect) = (Vec3::ZERO, Vec3::ZERO);
            self.trace_sample(x, y, s, &mut |bounce, l| {
                if bounce <= 1 {
                    direct += l;
                } else {
                    indirect += l;
                }
            });
            if direct.is_finite() && indirect.is_finite() {
                for c in 0..3 {
                    sum[c] += direct[c] as f64;
                    sum[3 + c] += indirect[c] as f64;
                }
            } else {
                bad += 1;
            }
        }
        bad
    }

    /// Traces sample `s` of pixel (x, y), handing each contribution and its bounce count to
    /// `sink`.
    fn trace_sample(&self, x: u32, y: u32, s: u32, sink: &mut impl FnMut(u32, Vec3)) {
        let sampler = PathSampler::new(self.seed, y * self.width + x, s);
        let jitter = if self.pixel_centres {
            Vec2::splat(0.5)
        } else {
            let u = sampler.sobol4(0);
            Vec2::new(u[0], u[1])
        };
        let camera = &self.scene.camera;
        let dir = camera.ray_direction(x as f32 + jitter.x, y as f32 + jitter.y, self.width, self.height);
        self.trace_path(&sampler, camera.position(), dir, sink);
    }

    fn trace_path(&self, sampler: &PathSampler, mut origin: Vec3, mut dir: Vec3, sink: &mut impl FnMut(u32, Vec3)) {
        let scene = self.scene;
        let mut throughput = Vec3::ONE;
        // Solid-angle density with which `dir` was sampled and the point it left from (both
        // unused for the camera ray, which cannot be produced by light sampling).
        let mut bsdf_pdf = 0.0f32;
        let mut previous = origin;
        for bounce in 0.. {
            let Some(hit) = self.bvh.closest_hit(origin, dir, f32::INFINITY) else {
                if let (Some(environment), true) = (&scene.environment, bounce > 0) {
                    let weight = power_heuristic(bsdf_pdf, environment.pdf(dir));
                    sink(bounce, throughput * environment.radiance_towards(dir) * weight);
                }
                break;
            };
            let material: &Material = &scene.materials[hit.material as usize];
            let wo = -dir;

            // Emission reaching the path here: light that has bounced `bounce` times.
            let cos_light = hit.geometric_normal.dot(wo);
            if cos_light > 0.0 && material.emission.max_element() > 0.0 {
                let weight = if bounce == 0 {
                    1.0
                } else {
                    let distance2 = (hit.position - previous).length_squared();
                    let light_pdf = self.emitters.pdf_area[hit.primitive as usize] * distance2 / cos_light;
                    power_heuristic(bsdf_pdf, light_pdf)
                };
                sink(bounce, throughput * material.emission * weight);
            }
            if bounce >= self.max_bounces {
                break;
            }
            let albedo = material.albedo(&scene.textures, hit.uv0);
            let specular = material.phong.map_or(0.0, |p| p.specular.max_element());
            if albedo.max_element() <= 0.0 && specular <= 0.0 {
                break;
            }
            // Two-sided scattering: both normals on the side the ray came from.
            let ng = if hit.geometric_normal.dot(wo) >= 0.0 { hit.geometric_normal } else { -hit.geometric_normal };
            let ns = if hit.shading_normal.dot(wo) >= 0.0 { hit.shading_normal } else { -hit.shading_normal };
            let p = hit.position;
            let bsdf = Bsdf::new(albedo, material.phong.as_ref(), ns, wo);

            self.punctual_lights(sampler, bounce, &bsdf, p, ns, ng, &mut |l| sink(bounce + 1, throughput * l));

            let u = sampler.sobol4(1 + bounce);
            if !self.emitters.primitives.is_empty() {
                let pick = sampler.uniform_f64(2 * bounce);
                if let Some((l, wi)) = self.sample_emitter(&hit, &bsdf, p, ns, ng, pick, Vec2::new(u[2], u[3])) {
                    sink(bounce + 1, throughput * bsdf.eval(wi) * l);
                }
            }

            if let Some((l, wi)) = self.sample_environment(sampler, &bsdf, bounce, p, ns, ng) {
                sink(bounce + 1, throughput * bsdf.eval(wi) * l);
            }

            // Continuation by the BSDF's sampling: f cos / pdf (the albedo for a Lambertian one).
            let Some((wi, weight, pdf)) = bsdf.sample(Vec2::new(u[0], u[1]), || sampler.uniform(LOBE_DIMENSIONS + bounce), ng) else {
                break;
            };
            throughput *= weight;
            if !survives_roulette(&mut throughput, bounce, || sampler.uniform(2 * bounce + 1)) {
                break;
            }
            bsdf_pdf = pdf;
            previous = p;
            origin = self.bvh.offset_origin(p, ng, wi);
            dir = wi;
        }
    }

    /// Next-event estimates from the punctual lights at `p` (f E cos each, still to be
    /// multiplied by the throughput): every light's, in a scene of up to `TRACED_LIGHTS`;
    /// otherwise `SAMPLED_LIGHTS` drawn by the light grid, each divided by its odds and their
    /// count: the same mean.
    #[allow(clippy::too_many_arguments)]
    fn punctual_lights(&self, sampler: &PathSampler, bounce: u32, bsdf: &Bsdf, p: Vec3, ns: Vec3, ng: Vec3, add: &mut impl FnMut(Vec3)) {
        let lights = &self.scene.lights;
        let Some(grid) = &self.light_grid else {
            for light in lights {
                if let Some((e, wi)) = punctual_irradiance(self.bvh, light, p, ns, ng, self.shadows) {
                    add(bsdf.eval(wi) * e);
                }
            }
            return;
        };
        for j in 0..SAMPLED_LIGHTS {
            let (i, odds) = grid.pick(p, sampler.uniform_f64(LIGHT_DIMENSIONS + SAMPLED_LIGHTS * bounce + j));
            if let Some((e, wi)) = punctual_irradiance(self.bvh, &lights[i], p, ns, ng, self.shadows) {
                add(bsdf.eval(wi) * e / (odds * SAMPLED_LIGHTS as f64) as f32);
            }
        }
    }

    /// Next-event estimate from the environment at `p`, MIS-weighted against BSDF sampling:
    /// L cos / pdf times the weight, still to be multiplied by f and the throughput; with its
    /// direction.
    fn sample_environment(&self, sampler: &PathSampler, bsdf: &Bsdf, bounce: u32, p: Vec3, ns: Vec3, ng: Vec3) -> Option<(Vec3, Vec3)> {
        let environment = self.scene.environment.as_ref()?;
        let dims = ENVIRONMENT_DIMENSIONS + 3 * bounce;
        let u = Vec2::new(sampler.uniform(dims + 1), sampler.uniform(dims + 2));
        let (wi, radiance, pdf) = environment.sample(sampler.uniform_f64(dims), u)?;
        let cos_surface = ns.dot(wi);
        if cos_surface <= 0.0 || ng.dot(wi) <= 0.0 || self.bvh.occluded(self.bvh.offset_origin(p, ng, wi), wi, f32::INFINITY) {
            return None;
        }
        let weight = power_heuristic(pdf, bsdf.pdf(wi));
        Some((radiance * (cos_surface * weight / pdf), wi))
    }

    /// Next-event estimate from the emissive triangles at `p`, MIS-weighted against BSDF
    /// sampling: Le cos / pdf times the weight, still to be multiplied by f and the
    /// throughput; with its direction. None when the sample contributes nothing.
    #[allow(clippy::too_many_arguments)]
    fn sample_emitter(&self, hit: &Hit, bsdf: &Bsdf, p: Vec3, ns: Vec3, ng: Vec3, pick: f64, u: Vec2) -> Option<(Vec3, Vec3)> {
        let prim = self.emitters.pick(pick);
        if prim == hit.primitive {
            return None; // A flat emitter cannot light itself.
        }
        let [v0, v1, v2] = self.bvh.primitive_positions(prim);
        let bary = uniform_triangle(u);
        let q = v0 * bary.x + v1 * bary.y + v2 * bary.z;
        let light_normal = (v1 - v0).cross(v2 - v0).normalize_or_zero();
        let to = q - p;
        let distance2 = to.length_squared();
        if distance2 <= 0.0 {
            return None;
        }
        let wi = to / distance2.sqrt();
        let cos_light = -light_normal.dot(wi);
        let cos_surface = ns.dot(wi);
        if cos_light <= 0.0 || cos_surface <= 0.0 || ng.dot(wi) <= 0.0 {
            return None;
        }
        let light_pdf = self.emitters.pdf_area[prim as usize] * distance2 / cos_light;
        if light_pdf <= 0.0 {
            return None;
        }
        // The shadow segment runs between the two surfaces, each end moved off its surface.
        let from = self.bvh.offset_origin(p, ng, wi);
        let to_point = self.bvh.offset_origin(q, light_normal, -wi);
        let segment = to_point - from;
        let length = segment.length();
        if length <= 0.0 || (segment.dot(wi) <= 0.0) {
            return None;
        }
        if self.bvh.occluded(from, segment / length, length) {
            return None;
        }
        let material = &self.scene.materials[self.bvh.primitive_material(prim) as usize];
        let weight = power_heuristic(light_pdf, bsdf.pdf(wi));
        Some((material.emission * (cos_surface * weight / light_pdf), wi))
    }
}
