//! Fullsphere irradiance vectors of Michael & Chrysanthou (003) at run time: the environment's
//! DifMap and the occluder types' tables uploaded once, and two passes a frame that turn the
//! occluders' current positions into each pixel's irradiance from the environment, handed to
//! the lighting pass as a pixel term (added as albedo / pi * I).
//!
//! Uploaded at creation (device-local, never written again):
//! - `difmap`: W x W/2 vec4, rgb I(N) (relume_bake::fiv::EnvironmentTerms), then FIV(Env)'s
//!   r, g and b vectors;
//! - `tables`: per type its samples, 3 vec4 each (the r, g, b vectors of FIV(EnvOcc); the
//!   first w 1 for a valid sample, 0 for one inside the type), then its surface points'
//!   masks alike; types one after another;
//! - `types`: per type { uvec4 grid (azimuths, polar, distances, first sample), vec4 (R,
//!   distance_min, distance_max, ln(max / min)), uvec4 (first surface sample, its shells) }.
//!
//! Written every frame, in order:
//! - `occluders` (per occluder { vec4 centre, uvec4 type }), from the technique's array,
//!   which follows `Renderer::set_mesh_translation` of the occluders' meshes without
//!   allocating;
//! 1. `surfaces` (surfaces.rs): `positions`, `normals` and the occluder per pixel;
//! 2. `occluder_sums` (occluder_sums.rs): `irradiance`, rgb lux per pixel.
//!
//! Occluders translate only: a table holds its type in the orientation it was baked in (the
//! paper's §6 limit), so there is no rotation here.

mod occluder_sums;
mod surfaces;

use crate::technique::{MakeTechnique, Resource, Shared, Source, Surfaces, Technique, Term};
use crate::upload::upload_buffers_blocking;
use crate::vk::{vk, Buffer, CommandRecorder, Image, ImageDesc, Tracker, VkError, VkResult};
use glam::{Vec3, Vec4};
use occluder_sums::{OccluderSumsPass, OccluderSumsPush};
use relume_bake::fiv::{FivBake, Occluder, SumOptions};
use surfaces::SurfacesPass;

/// What the technique is made from: a bake, the occluders (type and centre) where the
/// frame starts, and the run-time choices.
pub struct FivData<'d> {
    pub bake: &'d FivBake,
    pub occluders: &'d [Occluder],
    pub options: SumOptions,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuType {
    grid: [u32; 4],
    facts: [f32; 4],
    surface: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuOccluder {
    centre: Vec4,
    table: [u32; 4],
}

/// The most occluders one in-stream update carries (vkCmdUpdateBuffer's 65536 bytes).
pub const MAX_OCCLUDERS: usize = 65536 / std::mem::size_of::<GpuOccluder>();

struct Buffers {
    difmap: Buffer,
    tables: Buffer,
    types: Buffer,
    occluders: Buffer,
}

pub struct Fiv {
    buffers: Buffers,
    surfaces: SurfacesBy,
    occluder_sums: OccluderSumsPass,
    irradiance: Image,
    occluders: Vec<GpuOccluder>,
    /// Each occluder's mesh and centre as the scene had it, which mesh translations move.
    placed: Vec<Occluder>,
    options: SumOptions,
    difmap_width: u32,
}

impl Fiv {
    /// Changes the run-time choices for the frames recorded from now on.
    pub fn set_options(&mut self, options: SumOptions) {
        self.options = options;
    }
}

const PASSES: [&str; 2] = ["fiv.surfaces", "fiv.occluder_sums"];

/// Who draws the surfaces the occluder sums read.
enum SurfacesBy {
    /// Its own surfaces pass.
    Fiv(SurfacesPass),
    /// The engine (`Shared::surfaces`), writing each mesh's id: its occluder + 1 (0 for none).
    Engine(Vec<u32>),
}

/// Its passes when the engine draws the surfaces.
const ENGINE_SURFACES_PASSES: [&str; 1] = ["fiv.occluder_sums"];

impl Technique for Fiv {
    fn name(&self) -> &'static str {
        "fiv"
    }

    fn passes(&self) -> &'static [&'static str] {
        match self.surfaces {
            SurfacesBy::Fiv(_) => &PASSES,
            SurfacesBy::Engine(_) => &ENGINE_SURFACES_PASSES,
        }
    }

    fn record(&self, pass: usize, rec: &CommandRecorder, tracker: &mut Tracker) {
        match (&self.surfaces, pass) {
            (SurfacesBy::Fiv(surfaces), 0) => surfaces.record(rec, tracker),
            _ => {
                if !self.occluders.is_empty() {
                    rec.update_buffers([(self.buffers.occluders.raw, bytemuck::cast_slice(&self.occluders))]);
                }
                let push = OccluderSumsPush::new(self.occluders.len() as u32, self.difmap_width, self.options);
                self.occluder_sums.record(rec, tracker, &push);
            }
        }
    }

    fn term(&self) -> Option<Term<'_>> {
        Some(Term::Irradiance { source: Source::Pixel(&self.irradiance), times_occlusion: false, occluded_direct: false })
    }

    /// The occluders that are this mesh move with it (they translate only: 003 §6).
    fn mesh_translated(&mut self, mesh: usize, translation: Vec3) {
        for (gpu, placed) in self.occluders.iter_mut().zip(&self.placed) {
            if placed.mesh == mesh {
                gpu.centre = (placed.centre + translation).extend(1.0);
            }
        }
    }

    /// The mesh ids the engine writes into its surfaces' normals, when it draws them.
    fn surface_ids(&self) -> Option<&[u32]> {
        match &self.surfaces {
            SurfacesBy::Engine(ids) => Some(ids),
            SurfacesBy::Fiv(_) => None,
        }
    }

    /// `irradiance` (rgb lux) and, when it draws its own surfaces, `positions` (xyz world,
    /// alpha 1 on a surface) and `normals` (unnormalised), as the last frame left them.
    fn resources(&self) -> Vec<(&'static str, Resource<'_>)> {
        let mut resources = vec![("irradiance", Resource::Image(&self.irradiance))];
        if let SurfacesBy::Fiv(surfaces) = &self.surfaces {
            resources.extend([("positions", Resource::Image(&surfaces.positions)), ("normals", Resource::Image(&surfaces.normals))]);
        }
        resources
    }
}

/// Samples as the pass reads them: 3 vec4 each, the first's w 1 where valid.
fn rows<'a>(fiv: &'a [[Vec3; 3]], valid: &'a [bool]) -> impl Iterator<Item = Vec4> + 'a {
    fiv.iter().zip(valid).flat_map(|(f, valid)| [f[0].extend(*valid as u32 as f32), f[1].extend(0.0), f[2].extend(0.0)])
}

impl MakeTechnique for FivData<'_> {
    /// Uploads the bake in one submission that is waited for. Refused, by name: occluders of
    /// a type the bake lacks, more than [`MAX_OCCLUDERS`], and tables larger than one storage
    /// buffer may span.
    fn make_blocking(&self, shared: &Shared) -> VkResult<Box<dyn Technique>> {
        let ctx = shared.ctx;
        let refuse = |why: String| Err(VkError::Invalid(format!("fiv: {why}")));
        let tables = &self.bake.tables;
        if let Some((k, o)) = self.occluders.iter().enumerate().find(|(_, o)| o.table >= tables.len()) {
            return refuse(format!("occluder {k} is of type {}, but the bake has {} tables", o.table, tables.len()));
        }
        if self.occluders.len() > MAX_OCCLUDERS {
            return refuse(format!("{} occluders; at most {MAX_OCCLUDERS} are moved per frame", self.occluders.len()));
        }
        let samples: Vec<Vec4> = tables.iter().flat_map(|t| rows(&t.fiv, &t.valid).chain(rows(&t.surface, &t.surface_valid))).collect();
        let limit = ctx.info.max_storage_buffer_range;
        if std::mem::size_of_val(samples.as_slice()) as u64 > limit {
            return refuse(format!(
                "the tables take {} bytes, more than one storage buffer spans on {} ({limit})",
                samples.len() * 16,
                ctx.info.name
            ));
        }
        let mut first = 0u32;
        let types: Vec<GpuType> = tables
            .iter()
            .map(|t| {
                let grid = [t.grid.azimuths, t.grid.polar, t.grid.distances, first];
                let surface = [first + t.grid.samples() as u32, t.surface_shells(), 0, 0];
                first += (t.fiv.len() + t.surface.len()) as u32;
                GpuType { grid, facts: [t.radius, t.distance_min, t.distance_max, (t.distance_max / t.distance_min).ln()], surface }
            })
            .collect();
        let occluders: Vec<GpuOccluder> =
            self.occluders.iter().map(|o| GpuOccluder { centre: o.centre.extend(1.0), table: [o.table as u32, 0, 0, 0] }).collect();
        let environment = &self.bake.environment;
        let difmap: Vec<Vec4> = environment.difmap.iter().chain(&environment.fiv).map(|i| i.extend(0.0)).collect();
        // Never empty: a buffer of no bytes cannot be bound.
        let padded = |bytes: &[u8]| if bytes.is_empty() { vec![0u8; 32] } else { bytes.to_vec() };
        let [difmap, tables, types, occluders_buffer] = upload_buffers_blocking(
            ctx,
            [
                ("fiv difmap", bytemuck::cast_slice(&difmap)),
                ("fiv tables", &padded(bytemuck::cast_slice(&samples))),
                ("fiv types", &padded(bytemuck::cast_slice(&types))),
                ("fiv occluders", &padded(bytemuck::cast_slice(&occluders))),
            ],
        )?;
        let buffers = Buffers { difmap, tables, types, occluders: occluders_buffer };
        let irradiance = Image::new(
            ctx,
            "fiv irradiance",
            ImageDesc {
                width: shared.settings.width,
                height: shared.settings.height,
                layers: 1,
                format: vk::Format::R32G32B32A32_SFLOAT,
                usage: vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC,
                view_type: vk::ImageViewType::TYPE_2D_ARRAY,
            },
        )?;
        let mut occluder_of_mesh = vec![0u32; shared.scene.meshes.len()];
        for (k, o) in self.occluders.iter().enumerate() {
            match occluder_of_mesh.get_mut(o.mesh) {
                Some(slot) => *slot = k as u32 + 1,
                None => return refuse(format!("occluder {k} is mesh {}, but the scene has {} meshes", o.mesh, shared.scene.meshes.len())),
            }
        }
        let (surfaces, occluder_sums) = match shared.surfaces {
            Some(engine) => {
                check_surfaces(engine, &irradiance.desc)?;
                (SurfacesBy::Engine(occluder_of_mesh), OccluderSumsPass::new(shared, engine, &buffers, &irradiance)?)
            }
            None => {
                let own = SurfacesPass::new(shared, &occluder_of_mesh)?;
                let read = Surfaces { positions: &own.positions, normals: &own.normals };
                let occluder_sums = OccluderSumsPass::new(shared, read, &buffers, &irradiance)?;
                (SurfacesBy::Fiv(own), occluder_sums)
            }
        };
        Ok(Box::new(Fiv {
            buffers,
            surfaces,
            occluder_sums,
            irradiance,
            occluders,
            placed: self.occluders.to_vec(),
            options: self.options,
            difmap_width: self.bake.environment.difmap_width,
        }))
    }
}

/// Refuses, naming the image, engine surfaces the occluder sums cannot read at the frame's size.
fn check_surfaces(surfaces: Surfaces, frame: &ImageDesc) -> VkResult<()> {
    for (name, image) in [("positions", surfaces.positions), ("normals", surfaces.normals)] {
        let d = &image.desc;
        let fits = d.format == vk::Format::R32G32B32A32_SFLOAT && d.usage.contains(vk::ImageUsageFlags::STORAGE) && d.layers == 1;
        if !fits || (d.width, d.height) != (frame.width, frame.height) {
            return Err(VkError::Invalid(format!(
                "fiv: the engine's surface {name} is {}x{}x{} {:?} with usage {:?}; the occluder sums read an RGBA32F storage image of one layer at the effect's {}x{}",
                d.width, d.height, d.layers, d.format, d.usage, frame.width, frame.height
            )));
        }
    }
    Ok(())
}
