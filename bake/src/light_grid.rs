//! Which light a path vertex samples in a scene of many punctual lights: the box where lights
//! and surfaces meet cut into cells, each holding odds over the lights from the most light each
//! could shed on the cell's centre (its intensity over the squared distance, no less than the
//! cell's radius; a spot light's cone and a range window only lower it, so they are left out
//! and a point the cone lights never finds its light improbable), mixed with even odds so that
//! every light keeps a chance wherever it may reach. A vertex draws from its cell's table in
//! O(log lights) instead of weighing every light at every vertex.

use crate::environment::luminance;
use crate::scene::{bounds_of, LightKind, Scene};
use glam::{UVec3, Vec3};

/// The most cells; fewer for a box of few lights' worth of table (cells x lights entries).
const MAX_CELLS: usize = 4096;
const MAX_TABLE: usize = 1 << 22;
/// The share of every cell's odds spread evenly over the lights (the rest by irradiance).
const EVEN_SHARE: f64 = 0.1;

pub struct LightGrid {
    lo: Vec3,
    cell: Vec3,
    counts: UVec3,
    lights: usize,
    /// Per cell, its lights' cumulative odds; the last is 1.
    cdf: Vec<f64>,
}

impl LightGrid {
    /// The grid over the surfaces' box, clipped to the point and spot lights' box grown on every
    /// side by its longest side (so that a far ground plane does not make the cells coarse, and
    /// lights in one ceiling's plane still have the floor below them in the box), and holding
    /// the lights; points outside take the nearest cell.
    pub fn new(scene: &Scene) -> LightGrid {
        let lights = scene.lights.len().max(1);
        let placed: Vec<Vec3> = scene.lights.iter().filter(|l| l.kind != LightKind::Directional).map(|l| l.position).collect();
        let (mut lo, mut hi) = scene.bounds();
        if !placed.is_empty() {
            let (light_lo, light_hi) = bounds_of(&placed);
            let reach = Vec3::splat((light_hi - light_lo).max_element());
            lo = lo.max(light_lo - reach).min(light_lo);
            hi = hi.min(light_hi + reach).max(light_hi);
        }
        let size = (hi - lo).max(Vec3::splat(1e-3));
        let cells = (MAX_TABLE / lights).clamp(1, MAX_CELLS) as f32;
        let edge = (size.x * size.y * size.z / cells).cbrt();
        let counts = (size / edge).ceil().clamp(Vec3::ONE, Vec3::splat(cells)).as_uvec3();
        let cell = size / counts.as_vec3();
        let mut cdf = Vec::with_capacity((counts.x * counts.y * counts.z) as usize * lights);
        for z in 0..counts.z {
            for y in 0..counts.y {
                for x in 0..counts.x {
                    let centre = lo + (UVec3::new(x, y, z).as_vec3() + 0.5) * cell;
                    cdf.extend(cell_cdf(scene, centre, cell.length_squared() / 4.0));
                }
            }
        }
        LightGrid { lo, cell, counts, lights, cdf }
    }

    /// The light a uniform number `u` in [0, 1) picks at `point`, with its odds.
    pub fn pick(&self, point: Vec3, u: f64) -> (usize, f64) {
        let at = ((point - self.lo) / self.cell).floor().max(Vec3::ZERO).as_uvec3().min(self.counts - 1);
        let index = ((at.z * self.counts.y + at.y) * self.counts.x + at.x) as usize;
        let cdf = &self.cdf[index * self.lights..][..self.lights];
        let i = cdf.partition_point(|&c| c <= u).min(self.lights - 1);
        (i, cdf[i] - if i == 0 { 0.0 } else { cdf[i - 1] })
    }
}

/// The cumulative odds of the lights at a cell's `centre`, distances under `radius2`'s root
/// counted as that.
fn cell_cdf(scene: &Scene, centre: Vec3, radius2: f32) -> Vec<f64> {
    let shed: Vec<f64> = scene
        .lights
        .iter()
        .map(|light| {
            let falloff = match light.kind {
                LightKind::Directional => 1.0,
                _ => 1.0 / light.position.distance_squared(centre).max(radius2),
            };
            (luminance(light.intensity) * falloff).max(0.0) as f64
        })
        .collect();
    let total: f64 = shed.iter().sum();
    let even = if total > 0.0 { EVEN_SHARE } else { 1.0 };
    let n = shed.len().max(1) as f64;
    let mut running = 0.0;
    let mut cdf: Vec<f64> = shed
        .iter()
        .map(|s| {
            running += (1.0 - even) * s / total.max(f64::MIN_POSITIVE) + even / n;
            running
        })
        .collect();
    if let Some(last) = cdf.last_mut() {
        *last = 1.0;
    }
    cdf
}
