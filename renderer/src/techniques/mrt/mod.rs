//! Modular radiance transfer (Loos et al. 2011, 002) at run time, §7.3: the dictionary's
//! operators and the level's tables uploaded once, and every frame, lights moving:
//! 1. `direct` (direct.rs): the shadowed direct light at every level sample, l = rho E_d;
//! 2. per bounce (the feedback of §7.3, iterated within the frame so that a frame depends on
//!    its lights alone): `coefficients` (b = T_d->b l per block), `transfer` (r = T_b->r b per
//!    receiver), `response` (U_b b + U_r r per sample, summed; times rho the next bounce's l);
//! 3. `light_map` (light_map.rs): the samples' indirect irradiance into their texels;
//! 4. `padding` (padding.rs): the tiles' borders by the copy records (the padded atlas).
//!
//! It hands the lighting pass the light map as a texel irradiance term (the scene's uv1 are
//! the level's light-map coordinates). `LevelData::indirect` (relume_bake) is the same on the
//! CPU.
//!
//! Uploaded at creation (device-local, never written again): `samples` (S x 3 vec4: position,
//! normal, albedo), `shapes` (6 x uvec4: n, k, where T_d->b and U_b start), `operators` (f32:
//! each shape's T_d->b and U_b, then U_r), `blocks` (B x uvec2: shape, first row), `rows`
//! (u32), `receivers` (R x uvec2: first source, count), `sources` (uvec2: block, first matrix
//! value), `matrices` (f32), `sample_rows` (S x 3 uvec4), `texel_samples` (u32 per texel),
//! `copies` (uvec2). Written every frame: `light`, `indirect`, `direct` (S x vec4), `b` (B k_max x vec4),
//! `r` (R k_r x vec4), the `light_map` image.

mod coefficients;
mod direct;
mod light_map;
mod padding;
mod response;
mod tables;
mod transfer;

use crate::passes::compute::ComputePass;
use crate::passes::padding::ATLAS_FORMAT;
use crate::technique::{MakeTechnique, Resource, Shared, Source, Technique, Term};
use crate::upload::upload_buffers_blocking;
use crate::vk::{vk, Buffer, CommandRecorder, Image, ImageDesc, Sampler, Tracker, VkError, VkResult};
use gpu_allocator::MemoryLocation;
use relume_bake::mrt::dictionary::Dictionary;
use relume_bake::mrt::level_data::LevelData;
use tables::Tables;

/// The most bounces a frame iterates.
pub const MAX_BOUNCES: u32 = 4;

/// What the technique is made from: a dictionary, a level made with it, and the bounces each
/// frame iterates (1..=MAX_BOUNCES; 1 is the paper's per-frame work).
pub struct MrtData<'d> {
    pub dictionary: &'d Dictionary,
    pub level: &'d LevelData,
    pub bounces: u32,
}

/// The counts every pass reads (shaders/mrt/push.glsl's MrtPush).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct MrtPush {
    sample_count: u32,
    block_count: u32,
    k_max: u32,
    receiver_count: u32,
    k_r: u32,
    n_r: u32,
    texel_count: u32,
    copy_count: u32,
    width: u32,
    first_bounce: u32,
    u_r: u32,
}

/// One compute pass and its workgroup count: the shape every MRT pass has.
struct Dispatch {
    pass: ComputePass,
    groups: u32,
}

impl Dispatch {
    fn new(shared: &Shared, spirv: &[u8], invocations: u32, slots: &[crate::passes::compute::Slot]) -> VkResult<Dispatch> {
        let pass = ComputePass::new(shared.ctx, spirv, std::mem::size_of::<MrtPush>() as u32, slots)?;
        Ok(Dispatch { pass, groups: invocations.div_ceil(64).max(1) })
    }

    fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, push: &MrtPush) {
        self.pass.dispatch(rec, tracker, 0, push, [self.groups, 1, 1]);
    }
}

/// The uploaded tables and the buffers the passes write.
struct Buffers {
    samples: Buffer,
    shapes: Buffer,
    operators: Buffer,
    blocks: Buffer,
    rows: Buffer,
    receivers: Buffer,
    sources: Buffer,
    matrices: Buffer,
    sample_rows: Buffer,
    texel_samples: Buffer,
    copies: Buffer,
    light: Buffer,
    indirect: Buffer,
    direct: Buffer,
    b: Buffer,
    r: Buffer,
}

pub struct Mrt {
    buffers: Buffers,
    light_map: Image,
    direct: Dispatch,
    coefficients: Dispatch,
    transfer: Dispatch,
    response: Dispatch,
    light_map_pass: Dispatch,
    padding: Dispatch,
    push: MrtPush,
    bounces: u32,
    // Held so the sampler lives as long as the descriptor set that names it.
    _shadow_sampler: Sampler,
}

const PASSES: [&[&str]; MAX_BOUNCES as usize] = [
    &["mrt.direct", "mrt.coefficients", "mrt.transfer", "mrt.response", "mrt.light_map", "mrt.padding"],
    &[
        "mrt.direct",
        "mrt.coefficients",
        "mrt.transfer",
        "mrt.response",
        "mrt.coefficients.2",
        "mrt.transfer.2",
        "mrt.response.2",
        "mrt.light_map",
        "mrt.padding",
    ],
    &[
        "mrt.direct",
        "mrt.coefficients",
        "mrt.transfer",
        "mrt.response",
        "mrt.coefficients.2",
        "mrt.transfer.2",
        "mrt.response.2",
        "mrt.coefficients.3",
        "mrt.transfer.3",
        "mrt.response.3",
        "mrt.light_map",
        "mrt.padding",
    ],
    &[
        "mrt.direct",
        "mrt.coefficients",
        "mrt.transfer",
        "mrt.response",
        "mrt.coefficients.2",
        "mrt.transfer.2",
        "mrt.response.2",
        "mrt.coefficients.3",
        "mrt.transfer.3",
        "mrt.response.3",
        "mrt.coefficients.4",
        "mrt.transfer.4",
        "mrt.response.4",
        "mrt.light_map",
        "mrt.padding",
    ],
];

impl Technique for Mrt {
    fn name(&self) -> &'static str {
        "mrt"
    }

    fn passes(&self) -> &'static [&'static str] {
        PASSES[self.bounces as usize - 1]
    }

    fn record(&self, pass: usize, rec: &CommandRecorder, tracker: &mut Tracker) {
        let last = self.passes().len() - 1;
        match pass {
            0 => self.direct.record(rec, tracker, &self.push),
            p if p == last => self.padding.record(rec, tracker, &self.push),
            p if p == last - 1 => self.light_map_pass.record(rec, tracker, &self.push),
            p => match (p - 1) % 3 {
                0 => self.coefficients.record(rec, tracker, &self.push),
                1 => self.transfer.record(rec, tracker, &self.push),
                _ => {
                    let push = MrtPush { first_bounce: (p == 3) as u32, ..self.push };
                    self.response.record(rec, tracker, &push)
                }
            },
        }
    }

    fn term(&self) -> Option<Term<'_>> {
        Some(Term::Irradiance { source: Source::Texel(&self.light_map), times_occlusion: false, occluded_direct: false })
    }

    /// `b` (blocks x k_max vec4), `r` (receivers x k_r vec4) of the last bounce, `indirect`
    /// and `direct` (samples x vec4, rgb the indirect and direct irradiance) and `light_map` (alpha 1 at sample texels,
    /// -1 at padded ones, 0 elsewhere), as the last frame left them.
    fn resources(&self) -> Vec<(&'static str, Resource<'_>)> {
        vec![
            ("b", Resource::Buffer(&self.buffers.b)),
            ("r", Resource::Buffer(&self.buffers.r)),
            ("indirect", Resource::Buffer(&self.buffers.indirect)),
            ("direct", Resource::Buffer(&self.buffers.direct)),
            ("light_map", Resource::Image(&self.light_map)),
        ]
    }
}

impl MakeTechnique for MrtData<'_> {
    /// Checks the level against the dictionary and uploads both in one submission that is
    /// waited for. Refused, by name: bounces outside 1..=MAX_BOUNCES, a level whose tables do
    /// not fit the dictionary or a sample reached through more than four openings, and tables
    /// larger than one storage buffer may span.
    fn make_blocking(&self, shared: &Shared) -> VkResult<Box<dyn Technique>> {
        let ctx = shared.ctx;
        if !(1..=MAX_BOUNCES).contains(&self.bounces) {
            return Err(VkError::Invalid(format!("mrt: {} bounces; give 1..={MAX_BOUNCES}", self.bounces)));
        }
        let t = Tables::new(self.dictionary, self.level).map_err(|e| VkError::Invalid(format!("mrt: {e}")))?;
        t.check(ctx.info.max_storage_buffer_range).map_err(|e| VkError::Invalid(format!("mrt: {e} on {}", ctx.info.name)))?;
        let [samples, shapes, operators, blocks, rows, receivers, sources, matrices, sample_rows, texel_samples, copies] =
            upload_buffers_blocking(
                ctx,
                [
                    ("mrt samples", bytemuck::cast_slice(&t.samples)),
                    ("mrt shapes", bytemuck::cast_slice(&t.shapes)),
                    ("mrt operators", bytemuck::cast_slice(&t.operators)),
                    ("mrt blocks", bytemuck::cast_slice(&t.blocks)),
                    ("mrt rows", bytemuck::cast_slice(&t.rows)),
                    ("mrt receivers", bytemuck::cast_slice(&t.receivers)),
                    ("mrt sources", bytemuck::cast_slice(&t.sources)),
                    ("mrt matrices", bytemuck::cast_slice(&t.matrices)),
                    ("mrt sample rows", bytemuck::cast_slice(&t.sample_rows)),
                    ("mrt texel samples", bytemuck::cast_slice(&t.texel_samples)),
                    ("mrt copies", bytemuck::cast_slice(&t.copies)),
                ],
            )?;
        let per_frame = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        let vec4s = |name: &str, count: u32| Buffer::new(ctx, name, count.max(1) as u64 * 16, per_frame, MemoryLocation::GpuOnly);
        let push = t.push;
        let buffers = Buffers {
            samples,
            shapes,
            operators,
            blocks,
            rows,
            receivers,
            sources,
            matrices,
            sample_rows,
            texel_samples,
            copies,
            light: vec4s("mrt light", push.sample_count)?,
            indirect: vec4s("mrt indirect", push.sample_count)?,
            direct: vec4s("mrt direct", push.sample_count)?,
            b: vec4s("mrt b", push.block_count * push.k_max)?,
            r: vec4s("mrt r", push.receiver_count * push.k_r)?,
        };
        let layout = self.level.layout;
        let light_map = Image::new(
            ctx,
            "mrt light map",
            ImageDesc {
                width: layout.width,
                height: layout.height,
                layers: 1,
                format: ATLAS_FORMAT,
                usage: vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC,
                view_type: vk::ImageViewType::TYPE_2D_ARRAY,
            },
        )?;
        // The lighting pass's shadow sampler: the same filtering, so the same visibility.
        let shadow_sampler = Sampler::new(ctx, ctx.info.linear_moments, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;
        Ok(Box::new(Mrt {
            direct: direct::new(shared, &buffers, &shadow_sampler, push.sample_count)?,
            coefficients: coefficients::new(shared, &buffers, push.block_count * push.k_max)?,
            transfer: transfer::new(shared, &buffers, push.receiver_count * push.k_r)?,
            response: response::new(shared, &buffers, push.sample_count)?,
            light_map_pass: light_map::new(shared, &buffers, &light_map, push.texel_count)?,
            padding: padding::new(shared, &buffers, &light_map, push.copy_count)?,
            buffers,
            light_map,
            push,
            bounces: self.bounces,
            _shadow_sampler: shadow_sampler,
        }))
    }
}
