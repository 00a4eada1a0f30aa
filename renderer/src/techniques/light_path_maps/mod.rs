//! The light path maps of Umenhoffer et al., "Partial, Multi-scale Precomputed Radiance
//! Transfer" (000 §3.2-3.4), at run time: the clustered transfer uploaded once, and four
//! passes that turn each frame's lights into the large-scale indirect irradiance I of every
//! atlas texel, handed to the lighting pass as a texel term composed as [`Composition`] says.
//!
//! Uploaded at creation (device-local, never written again):
//! - `entry_points`: E x { vec4 position (w 1), vec4 normal (w 0) };
//! - `weights`: E x D f32, w^e_d at e * D + d - 1 (d from 1);
//! - `cluster_starts`: C + 1 u32, cluster c owning entry points `starts[c]..starts[c + 1]`;
//! - `textures`: packed f32 rgb, `[cluster][k][texel]` (k = 0 the mean M^c, k = d the
//!   eigen-texture B^c_d; texels in atlas order), so texture k = c * (1 + D) + k' starts at
//!   float 3 * k * texel_count: the CPU layout of `ClusteredTransfer::textures`, unchanged;
//! - `coverage`: texel_count f32, the atlas's coverage where > 0 (covered), 0 elsewhere.
//!
//! Written every frame, by the passes in order:
//! 1. `entry_irradiance` (entry_irradiance.rs): E x vec4, rgb I_e;
//! 2. `cluster_sums` (cluster_sums.rs): C * (1 + D) x vec4, rgb s_c then t_c1 .. t_cD per cluster;
//! 3. `reconstruct` (reconstruct.rs): the `indirect` image, an RGBA32F 2D array laid out as
//!    the atlas (one layer per page), rgb I (lux), alpha the coverage;
//! 4. `padding` (passes/padding.rs): empty texels of `indirect` take a covered neighbour's rgb.

mod cluster_sums;
mod entry_irradiance;
mod reconstruct;

use crate::atlas_image::AtlasImage;
use crate::passes::padding::{PaddingPass, ATLAS_FORMAT};
use crate::technique::{MakeTechnique, Resource, Shared, Source, Technique, Term};
use crate::upload::upload_buffers_blocking;
use crate::vk::{vk, Buffer, CommandRecorder, Context, Image, ImageDesc, Tracker, VkError, VkResult};
use cluster_sums::ClusterSumsPass;
use entry_irradiance::EntryIrradiancePass;
use glam::{Vec3, Vec4};
use gpu_allocator::MemoryLocation;
use reconstruct::ReconstructPass;
use relume_bake::light_path_maps::ClusteredTransfer;

/// How the light path maps' indirect irradiance I is added to a surface of albedo a, with W
/// the frame's occlusion term (the spectral obscurance, 000 §3.3) and E_d the shadowed direct
/// irradiance. 000 §3.4 can be read three ways; relume renders each, to measure them. Plain is
/// the default: with no connection cut (`--threshold 0`) I holds the short range as well, and W
/// would darken it twice (docs/BENCHMARKS.md, "The papers' claims").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Composition {
    /// L += a / pi * I: the large scale alone, no small-scale term.
    #[default]
    Plain,
    /// L += a / pi * W * I: "the two texture values are multiplied".
    TimesObscurance,
    /// L += a / pi * W * (I + E_d): the literal reading, which also multiplies "the
    /// obscuration value by the direct illumination" (paths of length 2 whose last ray is
    /// small-scale).
    TimesObscuranceWithDirect,
}

impl Composition {
    pub const ALL: [Composition; 3] = [Composition::Plain, Composition::TimesObscurance, Composition::TimesObscuranceWithDirect];

    /// The name the command line and sweeps give.
    pub fn name(self) -> &'static str {
        match self {
            Composition::Plain => "plain",
            Composition::TimesObscurance => "times-obscurance",
            Composition::TimesObscuranceWithDirect => "times-obscurance-with-direct",
        }
    }

    pub fn parse(name: &str) -> Option<Composition> {
        Composition::ALL.into_iter().find(|c| c.name() == name)
    }
}

/// What the technique is made from: the clustered transfer of a bake, the atlas it was baked
/// on (its layout and coverage in alpha; rgb unused), and the composition to start with.
pub struct LightPathMapsData<'d> {
    pub transfer: &'d ClusteredTransfer,
    pub atlas: AtlasImage<'d>,
    pub composition: Composition,
}

/// The uploaded transfer and the buffers the passes write.
struct Buffers {
    entry_points: Buffer,
    weights: Buffer,
    cluster_starts: Buffer,
    textures: Buffer,
    coverage: Buffer,
    entry_irradiance: Buffer,
    cluster_sums: Buffer,
    /// E, C, D.
    entry_count: u32,
    cluster_count: u32,
    basis_count: u32,
}

impl Buffers {
    /// K = C * (1 + D): the textures, and the cluster sums weighing them.
    fn term_count(&self) -> u32 {
        self.cluster_count * (1 + self.basis_count)
    }
}

pub struct LightPathMaps {
    buffers: Buffers,
    indirect: Image,
    entry_irradiance: EntryIrradiancePass,
    cluster_sums: ClusterSumsPass,
    reconstruct: ReconstructPass,
    padding: PaddingPass,
    composition: Composition,
}

impl LightPathMaps {
    /// Changes how I is added (see [`Composition`]) for the frames recorded from now on,
    /// without allocating.
    pub fn set_composition(&mut self, composition: Composition) {
        self.composition = composition;
    }
}

const PASSES: [&str; 4] =
    ["light_path_maps.entry_irradiance", "light_path_maps.cluster_sums", "light_path_maps.reconstruct", "light_path_maps.padding"];

impl Technique for LightPathMaps {
    fn name(&self) -> &'static str {
        "light_path_maps"
    }

    fn passes(&self) -> &'static [&'static str] {
        &PASSES
    }

    fn record(&self, pass: usize, rec: &CommandRecorder, tracker: &mut Tracker) {
        match pass {
            0 => self.entry_irradiance.record(rec, tracker),
            1 => self.cluster_sums.record(rec, tracker),
            2 => self.reconstruct.record(rec, tracker),
            _ => self.padding.record(rec, tracker),
        }
    }

    /// Its entry points' direct light is shadowed by the variance shadow maps.
    fn reads_shadows(&self) -> bool {
        true
    }

    fn term(&self) -> Option<Term<'_>> {
        Some(Term::Irradiance {
            source: Source::Texel(&self.indirect),
            times_occlusion: self.composition != Composition::Plain,
            occluded_direct: self.composition == Composition::TimesObscuranceWithDirect,
        })
    }

    /// `entry_irradiance` (E x vec4, rgb I_e) and `indirect` (rgb I in lux, alpha the
    /// coverage: > 0 covered, < 0 padded from the nearest covered texel), as the last frame
    /// left them.
    fn resources(&self) -> Vec<(&'static str, Resource<'_>)> {
        vec![("entry_irradiance", Resource::Buffer(&self.buffers.entry_irradiance)), ("indirect", Resource::Image(&self.indirect))]
    }
}

impl MakeTechnique for LightPathMapsData<'_> {
    /// Checks the transfer against the atlas and uploads it in one submission that is waited
    /// for. Refused, by name: a transfer that fails `validate`, an empty one (no entry point,
    /// no cluster or no texel), one whose texel count is not the atlas's, and one whose
    /// textures exceed the device's largest storage buffer.
    fn make_blocking(&self, shared: &Shared) -> VkResult<Box<dyn Technique>> {
        let (ctx, transfer) = (shared.ctx, self.transfer);
        check(ctx, transfer, &self.atlas)?;
        let entries: Vec<Vec4> = transfer.entry_points.iter().flat_map(|e| [e.position.extend(1.0), e.normal.extend(0.0)]).collect();
        let coverage: Vec<f32> = self.atlas.texels.iter().map(|t| t.w.max(0.0)).collect();
        let textures: &[Vec3] = &transfer.textures;
        let [entry_points, weights, cluster_starts, textures, coverage] = upload_buffers_blocking(
            ctx,
            [
                ("light path maps entry points", bytemuck::cast_slice(&entries)),
                ("light path maps weights", bytemuck::cast_slice(&transfer.weights)),
                ("light path maps cluster starts", bytemuck::cast_slice(&transfer.cluster_starts)),
                ("light path maps textures", bytemuck::cast_slice(textures)),
                ("light path maps coverage", bytemuck::cast_slice(&coverage)),
            ],
        )?;
        let per_frame = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        let terms = transfer.cluster_count() * transfer.terms_per_cluster();
        let buffers = Buffers {
            entry_points,
            weights,
            cluster_starts,
            textures,
            coverage,
            entry_irradiance: Buffer::new(
                ctx,
                "light path maps entry irradiance",
                transfer.entry_points.len() as u64 * 16,
                per_frame,
                MemoryLocation::GpuOnly,
            )?,
            cluster_sums: Buffer::new(ctx, "light path maps cluster sums", terms as u64 * 16, per_frame, MemoryLocation::GpuOnly)?,
            entry_count: transfer.entry_points.len() as u32,
            cluster_count: transfer.cluster_count() as u32,
            basis_count: transfer.basis_count,
        };
        let indirect = Image::new(
            ctx,
            "light path maps indirect",
            ImageDesc {
                width: self.atlas.width,
                height: self.atlas.height,
                layers: self.atlas.pages,
                format: ATLAS_FORMAT,
                usage: vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC,
                view_type: vk::ImageViewType::TYPE_2D_ARRAY,
            },
        )?;
        Ok(Box::new(LightPathMaps {
            entry_irradiance: EntryIrradiancePass::new(shared, &buffers, transfer.light_area)?,
            cluster_sums: ClusterSumsPass::new(shared, &buffers)?,
            reconstruct: ReconstructPass::new(shared, &buffers, &indirect)?,
            padding: PaddingPass::new(ctx, &indirect)?,
            buffers,
            indirect,
            composition: self.composition,
        }))
    }
}

fn check(ctx: &Context, transfer: &ClusteredTransfer, coverage: &AtlasImage) -> VkResult<()> {
    let refuse = |why: String| Err(VkError::Invalid(format!("light path maps: {why}")));
    if let Err(why) = transfer.validate() {
        return refuse(why);
    }
    if transfer.entry_points.is_empty() || transfer.cluster_count() == 0 || transfer.texel_count == 0 {
        return refuse(format!(
            "the transfer is empty ({} entry points, {} clusters, {} texels); bake the light path maps with at least one entry point",
            transfer.entry_points.len(),
            transfer.cluster_count(),
            transfer.texel_count
        ));
    }
    if transfer.texel_count != coverage.texels.len() {
        return refuse(format!(
            "the transfer's textures have {} texels but the atlas ({}x{}x{}) has {}; were both baked on the same atlas?",
            transfer.texel_count,
            coverage.width,
            coverage.height,
            coverage.pages,
            coverage.texels.len()
        ));
    }
    let texture_bytes = transfer.textures.len() as u64 * 12;
    let limit = ctx.info.max_storage_buffer_range;
    if texture_bytes > limit {
        return refuse(format!(
            "the textures take {texture_bytes} bytes, more than the {limit} bytes one storage buffer may span on {}; use fewer clusters, basis textures or texels",
            ctx.info.name
        ));
    }
    // reconstruct.comp indexes the textures with u32 floats.
    if transfer.textures.len() as u64 * 3 > u32::MAX as u64 {
        return refuse(format!("{} texture values are more than a u32 index reaches", transfer.textures.len()));
    }
    Ok(())
}
