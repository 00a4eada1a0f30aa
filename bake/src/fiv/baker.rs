//! The FIV bake (003 §4): DifMap and FIV(Env) from the environment's working cube, and per
//! occluder type its table: at every grid sample the type is placed with its centre there,
//! relative to a receiver at the origin, and the environment's texels it hides (its mask,
//! traced against the type alone) are summed as L_s dw_s w_s.

use super::{bounding_sphere, occluder_types, EnvironmentTerms, FivBake, FivSceneSettings, Grid, OccluderTable, OccluderType};
use crate::bvh::SceneBvh;
use crate::environment::{face_point, lat_long_direction, Environment};
use crate::scene::{Camera, Mesh, Scene};
use crate::settings::{SceneSettings, ValueRange};
use crate::shards::Items;
use crate::work::{with_threads, Progress, WorkOptions};
use glam::{Mat4, Vec3};
use rayon::prelude::*;
use std::ops::Range;

/// The bake's parameters (spec fiv.md C6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FivBakeSettings {
    pub grid: Grid,
    /// The nearest and farthest table distance, in bounding radii (spec fiv.md B4: 0.1 and 16).
    pub distance_min: f32,
    pub distance_max: f32,
    /// Rays per texel side for the mask: k x k rays, the texel counting by the share that hits
    /// (the paper: 1).
    pub mask_supersample: u32,
    /// DifMap's width (height half of it).
    pub difmap_width: u32,
}

impl Default for FivBakeSettings {
    /// The paper's middle grid (64 x 33 x 30), distances 0.1 R to 16 R (spec fiv.md B4), one
    /// ray per texel, DifMap 128 x 64.
    fn default() -> Self {
        FivBakeSettings {
            grid: Grid { azimuths: 64, polar: 33, distances: 30 },
            distance_min: 0.1,
            distance_max: 16.0,
            mask_supersample: 1,
            difmap_width: 128,
        }
    }
}

impl FivBakeSettings {
    /// In bounding radii; the farthest distance also lies beyond the nearest.
    pub const DISTANCE_MIN: ValueRange = ValueRange::number(0.0, 1e3, true);
    pub const DISTANCE_MAX: ValueRange = ValueRange::number(0.0, 1e4, true);
    pub const MASK_SUPERSAMPLE: ValueRange = ValueRange::count(1, 16);
    /// Even: the DifMap is a lat-long grid half as high as it is wide.
    pub const DIFMAP_WIDTH: ValueRange = ValueRange::even(8, 1024);

    pub fn validate(&self) -> Result<(), String> {
        crate::settings::first_failed_check(&[
            (Self::DISTANCE_MIN.admits(self.distance_min.into()), "distance_min must be in >0..=1000 (bounding radii)"),
            (
                Self::DISTANCE_MAX.admits(self.distance_max.into()) && self.distance_max > self.distance_min,
                "distance_max must be in >0..=10000 and > distance_min",
            ),
            (Self::MASK_SUPERSAMPLE.admits_count(self.mask_supersample.into()), "mask_supersample must be 1..=16"),
            (Self::DIFMAP_WIDTH.admits_count(self.difmap_width.into()), "difmap_width must be even, 8..=1024"),
        ])
    }
}

/// Bakes `scene`'s environment and occluder tables; refused when the scene declares no
/// environment or its occluders cannot be typed (named in [`occluder_types`]).
pub fn bake(scene: &Scene, settings: &FivBakeSettings, work: &WorkOptions) -> Result<(FivBake, Vec<OccluderType>), String> {
    checked(scene, settings)?;
    let types = occluder_types(scene, &FivSceneSettings::of(scene)?)?;
    Ok((bake_types(scene, &types, settings, work)?, types))
}

/// The scene's environment, once the settings are checked.
fn checked<'s>(scene: &'s Scene, settings: &FivBakeSettings) -> Result<&'s Environment, String> {
    settings.validate()?;
    scene.environment.as_ref().ok_or_else(|| "the scene declares no environment (extras.relume.environment), and FIV is lit by one".into())
}

/// As [`bake`], for the scene's occluder `types` already found.
pub fn bake_types(scene: &Scene, types: &[OccluderType], settings: &FivBakeSettings, work: &WorkOptions) -> Result<FivBake, String> {
    let environment = checked(scene, settings)?;
    with_threads(work.threads, || {
        let terms = environment_terms(environment, settings.difmap_width);
        let shapes = types.iter().map(|t| Shape::new(&scene.meshes[t.meshes[0]], settings, work)).collect::<Result<Vec<_>, _>>()?;
        Ok(FivBake { environment: terms, tables: tables(shapes, environment, settings, work)? })
    })
}

/// DifMap (eq. 5, the hemispherical sum over the cube's texels per normal) and FIV(Env)
/// (eq. 9); each source is a texel of radiance L_s and solid angle dw_s (spec fiv.md B5).
pub fn environment_terms(environment: &Environment, difmap_width: u32) -> EnvironmentTerms {
    let height = difmap_width / 2;
    let sources: Vec<(Vec3, Vec3)> =
        environment.radiance.iter().zip(&environment.solid_angle).zip(&environment.direction).map(|((l, w), d)| (*l * *w, *d)).collect();
    let difmap = (0..difmap_width * height)
        .into_par_iter()
        .map(|t| {
            let n = lat_long_direction(
                ((t % difmap_width) as f32 + 0.5) / difmap_width as f32,
                ((t / difmap_width) as f32 + 0.5) / height as f32,
            );
            sources.iter().map(|(power, w)| *power * n.dot(*w).max(0.0)).sum()
        })
        .collect();
    let fiv = [0, 1, 2].map(|c| sources.iter().map(|(power, w)| *w * power[c]).sum());
    EnvironmentTerms { difmap_width, difmap, fiv }
}

/// An occluder type's shape alone, its bounding-sphere centre at the origin, and its table
/// before its samples.
struct Shape {
    bvh: SceneBvh,
    table: OccluderTable,
}

impl Shape {
    fn new(mesh: &Mesh, settings: &FivBakeSettings, work: &WorkOptions) -> Result<Shape, String> {
        let (centre, radius) = bounding_sphere(&mesh.positions);
        let bvh = SceneBvh::build(&alone(mesh, centre), work.ray_backend)?;
        let table = OccluderTable {
            grid: settings.grid,
            radius,
            distance_min: settings.distance_min * radius,
            distance_max: settings.distance_max * radius,
            fiv: Vec::new(),
            valid: Vec::new(),
            surface: Vec::new(),
            surface_valid: Vec::new(),
        };
        Ok(Shape { bvh, table })
    }

    /// Samples of its free table and of its surface table.
    fn samples(&self) -> [u64; 2] {
        let g = self.table.grid;
        [g.samples() as u64, (self.table.surface_shells() * g.azimuths * g.polar) as u64]
    }

    /// Sample `s` of its free table (`surface` false) or its surface table: the masked sum and
    /// whether the sample is valid.
    fn sample(&self, environment: &Environment, settings: &FivBakeSettings, surface: bool, s: u32) -> ([Vec3; 3], bool) {
        let (g, table, radius) = (self.table.grid, &self.table, self.table.radius);
        let (i, j, k) = (s % g.azimuths, (s / g.azimuths) % g.polar, s / (g.azimuths * g.polar));
        let v = table.distance(k) * g.direction(i, j);
        match surface {
            false if inside(&self.bvh, -v) => ([Vec3::ZERO; 3], false),
            false => (masked_sum(&self.bvh, environment, v, radius, settings.mask_supersample, Vec3::ZERO), true),
            true => match surface_point(&self.bvh, -v) {
                Some((point, normal)) => (masked_sum(&self.bvh, environment, -point, radius, settings.mask_supersample, normal), true),
                None => ([Vec3::ZERO; 3], false),
            },
        }
    }
}

/// Values of a table sample as the gather keeps it: its three sums, then 1 where it is valid.
const SAMPLE_VALUES: usize = 10;

/// Every type's free and surface tables: their samples are the bake's work items, a table
/// a chunk.
fn tables(
    shapes: Vec<Shape>,
    environment: &Environment,
    settings: &FivBakeSettings,
    work: &WorkOptions,
) -> Result<Vec<OccluderTable>, String> {
    let items = Items::sized::<f32>(SAMPLE_VALUES, shapes.iter().flat_map(Shape::samples));
    let starts: Vec<u64> = std::iter::once(0).chain(items.chunks.iter().copied()).collect();
    let mut progress = Progress::new(items.count, "fiv tables", work.progress);
    let mut tables: Vec<OccluderTable> = shapes.iter().map(|s| s.table.clone()).collect();
    let per_pass = samples_per_pass(environment, settings);
    let make = |chunk: usize, range: Range<u64>| {
        let start = starts[chunk];
        let shape = &shapes[chunk / 2];
        let samples = (range.start - start) as u32..(range.end - start) as u32;
        let sums = every_sample(work, samples, per_pass, &progress, |s| shape.sample(environment, settings, chunk % 2 == 1, s))?;
        Ok(sums.iter().flat_map(|(sum, valid)| sum.iter().flat_map(|v| v.to_array()).chain([*valid as u32 as f32])).collect())
    };
    let mut next = 0;
    let take = |rows: Vec<f32>| {
        let (sums, valid) =
            rows.chunks_exact(SAMPLE_VALUES).map(|r| ([0, 3, 6].map(|c| Vec3::from_slice(&r[c..c + 3])), r[9] != 0.0)).unzip();
        let table = &mut tables[next / 2];
        match next % 2 {
            0 => (table.fiv, table.valid) = (sums, valid),
            _ => (table.surface, table.surface_valid) = (sums, valid),
        }
        next += 1;
        Ok(())
    };
    work.gather(&items, make, take)?;
    progress.finish();
    Ok(tables)
}

/// Mask rays a pass casts before the time limit is looked at: 1,024 samples of a 32-texel
/// cube face unsupersampled.
const RAYS_PER_PASS: u64 = 1024 * 6 * 32 * 32;

/// Table samples a pass takes: each casts a ray per environment texel and supersample, so a
/// fixed count of samples (1,024) let `--mask-supersample 16` run 24 s past a 3 s limit.
fn samples_per_pass(environment: &Environment, settings: &FivBakeSettings) -> u32 {
    let rays = 6 * (environment.face as u64).pow(2) * (settings.mask_supersample as u64).pow(2);
    (RAYS_PER_PASS / rays.max(1)).clamp(1, 1 << 16) as u32
}

/// `sample(s)` for every s of `samples`, in passes that the time limit stops: a table needs
/// every sample, so a cut one is refused.
fn every_sample(
    work: &WorkOptions,
    samples: Range<u32>,
    per_pass: u32,
    progress: &Progress,
    sample: impl Fn(u32) -> ([Vec3; 3], bool) + Sync,
) -> Result<Vec<([Vec3; 3], bool)>, String> {
    let total = samples.len() as u32;
    let mut values = Vec::with_capacity(total as usize);
    let taken = work.in_passes(total, per_pass, |range| {
        values.par_extend(range.into_par_iter().map(|s| {
            progress.inc(1);
            sample(samples.start + s)
        }));
    });
    if taken < total {
        return Err(format!(
            "--time-limit ran out after {taken} of {total} samples of an occluder table, which needs every one: give a coarser --grid or a longer --time-limit"
        ));
    }
    Ok(values)
}

/// The surface point nearest `point` along its radial line (towards the centre or away
/// from it), moved off the surface by the ray epsilon to the side its face faces, and that
/// face's normal: where a receiver on the surface near `point` sits. The line is tilted by a thousandth of a radian:
/// the grid's poles and seam meet a generated mesh's vertices exactly, where a ray may pass
/// between triangles and report the far side.
fn surface_point(bvh: &SceneBvh, point: Vec3) -> Option<(Vec3, Vec3)> {
    let radial = (point.normalize_or(Vec3::Y) + Vec3::new(0.6e-3, 0.3e-3, 0.74e-3)).normalize();
    let hits = [-radial, radial].map(|d| bvh.closest_hit(point, d, f32::INFINITY));
    let nearest = hits.into_iter().flatten().min_by(|a, b| a.t.total_cmp(&b.t))?;
    Some((nearest.position + nearest.geometric_normal * bvh.epsilon(), nearest.geometric_normal))
}

/// Whether `point` lies inside the closed mesh of `bvh` (spec fiv.md B10): from inside, the
/// first face a ray meets shows its back. Three rays vote, so a ray grazing an edge cannot
/// decide alone.
fn inside(bvh: &SceneBvh, point: Vec3) -> bool {
    const VOTES: [Vec3; 3] = [Vec3::new(0.267, 0.535, 0.802), Vec3::new(-0.802, 0.267, -0.535), Vec3::new(0.535, -0.802, 0.267)];
    let back = |d: &Vec3| bvh.closest_hit(point, d.normalize(), f32::INFINITY).is_some_and(|h| h.geometric_normal.dot(*d) > 0.0);
    VOTES.iter().filter(|d| back(d)).count() >= 2
}

/// FIV(EnvOcc) for the occluder centred at `v` from the receiver: sum over texels of the
/// share of its k x k rays that hit, times L_s dw_s w_s. Only rays inside the bounding
/// sphere's cone can hit, so only they are traced; with a nonzero `above`, only rays with
/// w . above > 0.
fn masked_sum(bvh: &SceneBvh, environment: &Environment, v: Vec3, radius: f32, k: u32, above: Vec3) -> [Vec3; 3] {
    let distance = v.length();
    let axis = v / distance.max(1e-20);
    // Inside the bounding sphere every direction may hit.
    let cos_cone = if distance > radius { (1.0 - (radius / distance).powi(2)).sqrt() } else { -1.0 };
    let n = environment.face;
    let mut sum = [Vec3::ZERO; 3];
    for (texel, radiance) in environment.radiance.iter().enumerate() {
        let (face, t, s) = (texel / (n * n) as usize, (texel as u32 / n) % n, texel as u32 % n);
        let mut hits = 0;
        for (a, b) in (0..k).flat_map(|y| (0..k).map(move |x| (x, y))) {
            let sub = |texel: u32, i: u32| 2.0 * (texel as f32 + (i as f32 + 0.5) / k as f32) / n as f32 - 1.0;
            let w = face_point(face, sub(s, a), sub(t, b)).normalize();
            if w.dot(axis) >= cos_cone && (above == Vec3::ZERO || w.dot(above) > 0.0) && bvh.occluded(-v, w, f32::INFINITY) {
                hits += 1;
            }
        }
        if hits > 0 {
            let weight = environment.solid_angle[texel] * hits as f32 / (k * k) as f32;
            (0..3).for_each(|c| sum[c] += environment.direction[texel] * (radiance[c] * weight));
        }
    }
    sum
}

/// A scene of `mesh` alone, moved so that its bounding-sphere centre is the origin.
fn alone(mesh: &Mesh, centre: Vec3) -> Scene {
    let positions = mesh.positions.iter().map(|p| *p - centre).collect();
    let camera = Camera { world_from_camera: Mat4::IDENTITY, yfov: 1.0, znear: 0.1, zfar: 10.0 };
    Scene {
        source: format!("<occluder {}>", mesh.name).into(),
        meshes: vec![Mesh { positions, material: 0, ..mesh.clone() }],
        materials: vec![crate::scene::Material {
            name: "occluder".into(),
            base_color: glam::Vec4::ZERO,
            base_color_texture: None,
            emission: Vec3::ZERO,
            phong: None,
        }],
        textures: Vec::new(),
        lights: Vec::new(),
        environment: None,
        camera,
        settings: SceneSettings::defaults_for((Vec3::ZERO, Vec3::ONE)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pass casts about the same rays whatever the supersampling, so the time limit is looked
    /// at as often at `--mask-supersample 16` as at 1 (a fixed 1,024 samples ran 24 s past a
    /// 3 s limit).
    #[test]
    fn a_pass_casts_the_same_rays_at_any_supersampling() {
        let environment = crate::testing::environment(|_| Vec3::ONE, 32);
        let rays = |k: u32| {
            let settings = FivBakeSettings { mask_supersample: k, ..FivBakeSettings::default() };
            samples_per_pass(&environment, &settings) as u64 * 6 * 32 * 32 * (k as u64).pow(2)
        };
        assert_eq!(rays(1), RAYS_PER_PASS);
        assert!((1..=16).all(|k| rays(k) <= RAYS_PER_PASS && rays(k) * 2 > RAYS_PER_PASS), "{:?}", (1..=16).map(rays).collect::<Vec<_>>());
    }
}
