//! The FIV bake as plain data and its artifact sections (docs/FORMATS.md "fiv"):
//! - `fiv_environment` (keyed to the environment): DifMap, the unoccluded irradiance per
//!   normal of eq. (5) on a lat-long grid, and FIV(Env) of eq. (9);
//! - `fiv_occluder_<k>` (keyed to type k's first mesh): the type's table of FIV(EnvOcc) over
//!   the (azimuth, polar angle, distance) grid of §4.

use crate::artifact::{fail, Artifact, ArtifactError, Key, Section, REBAKE};
use crate::binary::{Reader, Writer};
use crate::scene::Scene;
use glam::Vec3;
use serde_json::json;
use std::f32::consts::{PI, TAU};

/// A table's sample grid (003 Table 1 writes it azimuths x polar angles x distances):
/// azimuth theta_i = 2 pi i / N (periodic, from +X towards -Z), polar angle phi_j =
/// pi j / (M - 1) from +Y (both poles sampled), distances geometric from `distance_min` to
/// `distance_max` (spec fiv.md B2, B4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grid {
    pub azimuths: u32,
    pub polar: u32,
    pub distances: u32,
}

/// The largest grid relume bakes: the paper's largest (256 x 129 x 30) with room to spare.
const MAX_SAMPLES: u64 = 4 << 20;

impl Grid {
    /// Reads `AxBxC` (azimuths x polar angles x distances), refusing grids that cannot
    /// interpolate (fewer than 3 azimuths, 2 polar angles or 2 distances) or are too large.
    pub fn parse(text: &str) -> Result<Grid, String> {
        let parts: Vec<Option<u32>> = text.split('x').map(|p| p.trim().parse().ok()).collect();
        let [Some(azimuths), Some(polar), Some(distances)] = parts[..] else {
            return Err(format!("\"{text}\" is not a grid; write azimuths x polar angles x distances, e.g. 64x33x30"));
        };
        let grid = Grid { azimuths, polar, distances };
        if azimuths < 3 || polar < 2 || distances < 2 {
            return Err(format!("grid {text} is too small: at least 3 azimuths, 2 polar angles and 2 distances"));
        }
        if grid.samples() as u64 > MAX_SAMPLES {
            return Err(format!("grid {text} has {} samples, more than {MAX_SAMPLES}; use a coarser grid", grid.samples()));
        }
        Ok(grid)
    }

    pub fn samples(&self) -> usize {
        self.azimuths as usize * self.polar as usize * self.distances as usize
    }

    /// The index of sample (i, j, k): azimuth fastest, then polar angle, then distance.
    pub fn index(&self, i: u32, j: u32, k: u32) -> usize {
        ((k * self.polar + j) * self.azimuths + i) as usize
    }

    /// The unit direction of azimuth sample i and polar sample j.
    pub fn direction(&self, i: u32, j: u32) -> Vec3 {
        let (theta, phi) = (TAU * i as f32 / self.azimuths as f32, PI * j as f32 / (self.polar - 1) as f32);
        Vec3::new(phi.sin() * theta.cos(), phi.cos(), -phi.sin() * theta.sin())
    }

    pub fn name(&self) -> String {
        format!("{}x{}x{}", self.azimuths, self.polar, self.distances)
    }
}

/// One occluder type's table.
#[derive(Clone, Debug, PartialEq)]
pub struct OccluderTable {
    pub grid: Grid,
    /// The bounding radius R of the type.
    pub radius: f32,
    pub distance_min: f32,
    pub distance_max: f32,
    /// FIV(EnvOcc) per sample, one vector per colour channel (r, g, b), in `Grid::index` order.
    pub fiv: Vec<[Vec3; 3]>,
    /// Per sample, whether a receiver there lies outside the type (spec fiv.md B10): inside
    /// it every direction is hidden, no receiver can be there, and a lookup leaves the
    /// sample out (its FIV is stored as zero).
    pub valid: Vec<bool>,
    /// For the first shells (those up to the first beyond R: where a receiver on the type's
    /// surface looks up), FIV(EnvOcc) seen from the surface point nearest each sample along
    /// its radial line, of the directions above that point's tangent plane only (what the
    /// type hides beyond its own surface), for self-shadowing (`SelfShadow::Surface`);
    /// `surface_valid` false where that line meets no surface.
    pub surface: Vec<[Vec3; 3]>,
    pub surface_valid: Vec<bool>,
}

impl OccluderTable {
    /// The number of shells `surface` covers: those no farther than R, and one more.
    pub fn surface_shells(&self) -> u32 {
        let within = (0..self.grid.distances).filter(|&k| self.distance(k) <= self.radius).count() as u32;
        (within + 1).min(self.grid.distances)
    }

    /// Distance k of the geometric sequence.
    pub fn distance(&self, k: u32) -> f32 {
        self.distance_min * (self.distance_max / self.distance_min).powf(k as f32 / (self.grid.distances - 1) as f32)
    }
}

/// DifMap and FIV(Env).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentTerms {
    /// DifMap's width; its height is half of it. Texel (x, y) holds I(N) for N through the
    /// texel's centre in the environment's lat-long mapping (`environment::lat_long_direction`).
    pub difmap_width: u32,
    pub difmap: Vec<Vec3>,
    /// FIV(Env) of eq. (9), one vector per colour channel.
    pub fiv: [Vec3; 3],
}

/// Everything a FIV bake holds.
#[derive(Clone, Debug, PartialEq)]
pub struct FivBake {
    pub environment: EnvironmentTerms,
    /// One table per occluder type, in `occluder_types` order.
    pub tables: Vec<OccluderTable>,
}

pub const ENVIRONMENT_SECTION: &str = "fiv_environment";
pub const OCCLUDER_SECTION: &str = "fiv_occluder";
/// 2: tables carry the samples' validity and the surface points' masks (self-shadowing).
pub const SECTION_VERSION: u32 = 2;
const ENVIRONMENT_MAGIC: &[u8; 8] = b"RLFIVENV";
const TABLE_MAGIC: &[u8; 8] = b"RLFIVOCC";

fn vectors(values: &[Vec3]) -> impl Iterator<Item = f32> + '_ {
    values.iter().flat_map(|v| v.to_array())
}

/// The sections of a bake; `representatives` names each table's first mesh (its key).
pub fn sections(bake: &FivBake, representatives: &[&str], summary: serde_json::Value) -> Vec<Section> {
    let e = &bake.environment;
    let mut writer = Writer::new(ENVIRONMENT_MAGIC);
    writer.u32s(&[e.difmap_width]);
    writer.f32s(&vectors(&e.difmap).chain(vectors(&e.fiv)).collect::<Vec<_>>());
    let mut sections = vec![Section {
        name: ENVIRONMENT_SECTION.into(),
        version: SECTION_VERSION,
        key: Key::Environment,
        summary,
        files: vec![(format!("{ENVIRONMENT_SECTION}.bin"), writer.bytes)],
    }];
    for (k, (table, mesh)) in bake.tables.iter().zip(representatives).enumerate() {
        let mut writer = Writer::new(TABLE_MAGIC);
        writer.u32s(&[table.grid.azimuths, table.grid.polar, table.grid.distances]);
        writer.f32s(&[table.radius, table.distance_min, table.distance_max]);
        writer.f32s(&table.fiv.iter().flat_map(|f| vectors(f).collect::<Vec<_>>()).collect::<Vec<_>>());
        writer.u32s(&validity_words(&table.valid));
        writer.f32s(&table.surface.iter().flat_map(|f| vectors(f).collect::<Vec<_>>()).collect::<Vec<_>>());
        writer.u32s(&validity_words(&table.surface_valid));
        sections.push(Section {
            name: format!("{OCCLUDER_SECTION}_{k}"),
            version: SECTION_VERSION,
            key: Key::Mesh(mesh.to_string()),
            summary: json!({ "grid": table.grid.name(), "radius": table.radius, "bytes": table.fiv.len() * 36 }),
            files: vec![(format!("{OCCLUDER_SECTION}_{k}.bin"), writer.bytes)],
        });
    }
    sections
}

/// The bake of `artifact` for `scene` with `types` occluder types (each table keyed to its
/// first mesh, `representatives`); refused when a section is missing, of another version or
/// scene, truncated, or holds a value that is not finite.
pub fn read(artifact: &Artifact, scene: &Scene, representatives: &[&str]) -> Result<FivBake, ArtifactError> {
    let data = artifact.section(ENVIRONMENT_SECTION, SECTION_VERSION, Some(scene))?;
    let (bytes, path) = data.file(&format!("{ENVIRONMENT_SECTION}.bin"))?;
    let mut reader = Reader::new(&bytes, &path, ENVIRONMENT_MAGIC, "FIV environment")?;
    let width = reader.u32("DifMap's width")?;
    if width < 4 || width % 2 != 0 {
        return Err(fail(&path, format!("DifMap width {width} is not an even number >= 4"), REBAKE));
    }
    let texels = width as usize * (width / 2) as usize;
    let difmap = finite_vectors(&mut reader, texels, "DifMap")?;
    // DifMap is an irradiance: radiance summed times a clamped cosine (003 eq. 5).
    if let Some(t) = difmap.iter().position(|e| e.min_element() < 0.0) {
        return Err(fail(&path, format!("DifMap texel {t} holds {}, not an irradiance >= 0", difmap[t]), REBAKE));
    }
    let fiv = finite_vectors(&mut reader, 3, "FIV(Env)")?;
    reader.finish("FIV(Env)")?;
    let environment = EnvironmentTerms { difmap_width: width, difmap, fiv: [fiv[0], fiv[1], fiv[2]] };
    let tables = representatives.iter().enumerate().map(|(k, mesh)| read_table(artifact, scene, k, mesh)).collect::<Result<_, _>>()?;
    Ok(FivBake { environment, tables })
}

fn read_table(artifact: &Artifact, scene: &Scene, k: usize, mesh: &str) -> Result<OccluderTable, ArtifactError> {
    let name = format!("{OCCLUDER_SECTION}_{k}");
    let data = artifact.section(&name, SECTION_VERSION, Some(scene))?;
    let (bytes, path) = data.file(&format!("{name}.bin"))?;
    let mut reader = Reader::new(&bytes, &path, TABLE_MAGIC, "FIV occluder table")?;
    let [azimuths, polar, distances] = [0; 3].map(|_| reader.u32("the grid"));
    let grid = Grid::parse(&format!("{}x{}x{}", azimuths?, polar?, distances?)).map_err(|e| fail(&path, e, REBAKE))?;
    let facts = reader.f32s(3, "radius and distances")?;
    let (radius, distance_min, distance_max) = (facts[0], facts[1], facts[2]);
    if !(radius > 0.0 && distance_min > 0.0 && distance_max > distance_min && distance_max.is_finite()) {
        return Err(fail(
            &path,
            format!("radius {radius} and distances {distance_min}..{distance_max} of mesh \"{mesh}\" are impossible"),
            REBAKE,
        ));
    }
    let (fiv, valid) = read_samples(&mut reader, grid.samples(), "the table")?;
    let mut table = OccluderTable { grid, radius, distance_min, distance_max, fiv, valid, surface: Vec::new(), surface_valid: Vec::new() };
    let surface_samples = table.surface_shells() as usize * (grid.azimuths * grid.polar) as usize;
    (table.surface, table.surface_valid) = read_samples(&mut reader, surface_samples, "the surface points' masks")?;
    reader.finish("the table")?;
    Ok(table)
}

/// `count` samples of 3 vectors, then their validity bits.
fn read_samples(reader: &mut Reader, count: usize, what: &str) -> Result<(Vec<[Vec3; 3]>, Vec<bool>), ArtifactError> {
    let values = finite_vectors(reader, 3 * count, what)?;
    let words = (0..count.div_ceil(32)).map(|_| reader.u32(what)).collect::<Result<Vec<_>, _>>()?;
    let valid = (0..count).map(|s| words[s / 32] >> (s % 32) & 1 == 1).collect();
    Ok((values.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(), valid))
}

/// The samples' validity as bits, sample s at bit s % 32 of word s / 32.
fn validity_words(valid: &[bool]) -> Vec<u32> {
    valid.chunks(32).map(|c| c.iter().enumerate().fold(0u32, |w, (b, v)| w | ((*v as u32) << b))).collect()
}

fn finite_vectors(reader: &mut Reader, count: usize, what: &str) -> Result<Vec<Vec3>, ArtifactError> {
    let values = reader.f32s(count.saturating_mul(3), what)?;
    if let Some(i) = values.iter().position(|v| !crate::artifact::stored(*v)) {
        return Err(fail(reader.path(), format!("{what} holds {} at value {i}, not a finite number within 1e9", values[i]), REBAKE));
    }
    Ok(values.chunks_exact(3).map(Vec3::from_slice).collect())
}
