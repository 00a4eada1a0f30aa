//! Modular radiance transfer (Loos et al. 2011, 002) at run time, §7.3: the dictionary's
//! operators and the level's tables uploaded once, and every frame, lights moving, seven
//! passes (nine when the scene declares dynamic meshes), each in a file of its own:
//! 1. `direct`: the shadowed direct light at every level sample, l_d = rho E_d;
//! 2. `coefficients`: b0 = T_d->b l_d per block;
//! 3. `feedback`: b = (I - K)^-1 b0, every bounce at once (the fixed point of §7.3's
//!    frame-to-frame feedback, solved at bake time), or b = b0 with feedback off;
//! 4. `transfer`: r = T_b->r b per receiver;
//! 5. `response`: U_b b + U_r r per sample, the indirect irradiance;
//! 6. `light_map`: the samples' indirect irradiance into their texels;
//! 7. `padding`: the tiles' borders by the copy records (the padded atlas);
//! 8. `volume`: the light volume's probes, U_bvol b + U_rvol r per block (§6.5);
//! 9. `dynamic`: each dynamic mesh's vertices lit by the volume where they stand now.
//!
//! It hands the lighting pass the light map as a texel irradiance term (the scene's uv1 are
//! the level's light-map coordinates), and with dynamic meshes the vertex light too, which
//! their vertices read instead. `LevelData::indirect` and `LevelData::volume` (relume_bake)
//! are the same on the CPU. A frame depends on its lights and where the meshes stand alone:
//! no state is carried from frame to frame.
//!
//! Uploaded at creation (device-local, never written again): `samples` (S x 3 vec4: position,
//! normal, albedo), `shapes` (6 x uvec4: n, k, where T_d->b and U_b start), `operators` (f32:
//! each shape's T_d->b and U_b, then U_r, each shape's U_bvol and U_rvol per side face), `blocks` (B x uvec2: shape, first row), `rows`
//! (u32), `receivers` (R x uvec2: first source, count), `sources` (uvec2: block, first matrix
//! value), `matrices` (f32), `feedback` (3 x D x D f32, D = B k_max), `sample_rows` (S x 3
//! uvec4), `texel_samples` (u32 per texel), `copies` (uvec2), `volume_blocks` (B x
//! shaders/mrt/volume.glsl's VolumeBlock), `dynamic_vertices` (u32: the scene's vertex indices
//! of the dynamic meshes). Written every frame: `light`, `direct`, `indirect` (S x vec4), `b0`,
//! `b` (D x vec4), `r` (R k_r x vec4), the `light_map` image, `volume` (B x 64 x 9 vec4) and
//! `vertex_light` (a vec4 per scene vertex, alpha 1 at dynamic ones, zero elsewhere).

mod coefficients;
mod direct;
mod dynamic;
mod feedback;
mod light_map;
mod padding;
mod response;
mod tables;
mod transfer;
mod volume;

use crate::passes::compute::ComputePass;
use crate::passes::padding::ATLAS_FORMAT;
use crate::technique::{MakeTechnique, Resource, Shared, Source, Technique, Term};
use crate::upload::upload_buffers_blocking;
use crate::vk::{vk, Buffer, CommandRecorder, Image, ImageDesc, Sampler, Tracker, VkError, VkResult};
use glam::Vec4;
use gpu_allocator::MemoryLocation;
use relume_bake::mrt::dictionary::Dictionary;
use relume_bake::mrt::level_data::LevelData;
use relume_bake::mrt::volume::ROWS;
use tables::Tables;

/// The scene's vertex indices of the level's dynamic meshes; refused when the level names a
/// mesh the scene lacks.
fn dynamic_vertices(shared: &Shared, level: &LevelData) -> VkResult<Vec<u32>> {
    let mut out = Vec::new();
    for &mesh in &level.dynamic {
        out.extend(shared.gpu_scene.range_of(mesh as usize)?.map(|v| v as u32));
    }
    Ok(out)
}

/// What the technique is made from: a dictionary, a level made with it, and whether every
/// bounce is fed back (the solved feedback) or the first only.
pub struct MrtData<'d> {
    pub dictionary: &'d Dictionary,
    pub level: &'d LevelData,
    pub feedback: bool,
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
    feedback: u32,
    u_r: u32,
    u_rvol: u32,
    dynamic_count: u32,
}

/// One compute pass and its invocations: the shape every MRT pass has.
struct Dispatch {
    pass: ComputePass<MrtPush>,
    invocations: u32,
}

impl Dispatch {
    fn new(shared: &Shared, name: &str, spirv: &[u8], invocations: u32, slots: &[crate::passes::compute::Slot]) -> VkResult<Dispatch> {
        let pass = ComputePass::new(shared.ctx, name, spirv, slots)?;
        Ok(Dispatch { pass, invocations: invocations.max(1) })
    }

    fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, push: &MrtPush) {
        self.pass.dispatch(rec, tracker, 0, push, [self.invocations, 1, 1]);
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
    feedback: Buffer,
    sample_rows: Buffer,
    texel_samples: Buffer,
    copies: Buffer,
    volume_blocks: Buffer,
    dynamic_vertices: Buffer,
    light: Buffer,
    indirect: Buffer,
    direct: Buffer,
    b0: Buffer,
    b: Buffer,
    r: Buffer,
    volume: Buffer,
    vertex_light: Buffer,
}

pub struct Mrt {
    buffers: Buffers,
    light_map: Image,
    /// The passes in `PASSES` order: the first seven, and the volume's two only for a level
    /// with dynamic vertices (the dynamic pass binds the scene's whole vertex buffer as storage).
    dispatches: Vec<Dispatch>,
    push: MrtPush,
    // Held so the sampler lives as long as the descriptor set that names it.
    _shadow_sampler: Sampler,
}

const PASSES: [&str; 9] = [
    "mrt.direct",
    "mrt.coefficients",
    "mrt.feedback",
    "mrt.transfer",
    "mrt.response",
    "mrt.light_map",
    "mrt.padding",
    "mrt.volume",
    "mrt.dynamic",
];

impl Technique for Mrt {
    fn name(&self) -> &'static str {
        "mrt"
    }

    fn passes(&self) -> &'static [&'static str] {
        &PASSES[..self.dispatches.len()]
    }

    fn record(&self, pass: usize, rec: &CommandRecorder, tracker: &mut Tracker) {
        self.dispatches[pass].record(rec, tracker, &self.push);
    }

    /// Its samples' direct light is shadowed by the variance shadow maps.
    fn reads_shadows(&self) -> bool {
        true
    }

    fn term(&self) -> Option<Term<'_>> {
        let source = match self.push.dynamic_count {
            0 => Source::Texel(&self.light_map),
            _ => Source::TexelOrVertex(&self.light_map, &self.buffers.vertex_light),
        };
        Some(Term::Irradiance { source, times_occlusion: false, occluded_direct: false })
    }

    /// `b0` and `b` (blocks x k_max vec4: before and after the feedback), `r` (receivers x
    /// k_r vec4), `indirect` and `direct` (samples x vec4, rgb the indirect and direct irradiance) and `light_map` (alpha 1 at sample texels,
    /// -1 at padded ones, 0 elsewhere), `volume` (blocks x 64 probes x 9 vec4: rgb radiance
    /// coefficients) and `vertex_light` (a vec4 per scene vertex), as the last frame left them.
    fn resources(&self) -> Vec<(&'static str, Resource<'_>)> {
        vec![
            ("b0", Resource::Buffer(&self.buffers.b0)),
            ("b", Resource::Buffer(&self.buffers.b)),
            ("r", Resource::Buffer(&self.buffers.r)),
            ("indirect", Resource::Buffer(&self.buffers.indirect)),
            ("direct", Resource::Buffer(&self.buffers.direct)),
            ("light_map", Resource::Image(&self.light_map)),
            ("volume", Resource::Buffer(&self.buffers.volume)),
            ("vertex_light", Resource::Buffer(&self.buffers.vertex_light)),
        ]
    }
}

impl MakeTechnique for MrtData<'_> {
    /// Checks the level against the dictionary and uploads both in one submission that is
    /// waited for. Refused, by name: a level whose tables do not fit the dictionary (shapes,
    /// rows, transfer sizes, an unsolved feedback, texels past the light map), a sample
    /// reached through more than four openings, and tables larger than one storage buffer may
    /// span.
    fn make_blocking(&self, shared: &Shared) -> VkResult<Box<dyn Technique>> {
        let ctx = shared.ctx;
        let t = Tables::new(self.dictionary, self.level).map_err(|e| VkError::Invalid(format!("mrt: {e}")))?;
        t.check(ctx.info.max_storage_buffer_range).map_err(|e| VkError::Invalid(format!("mrt: {e} on {}", ctx.info.name)))?;
        let dynamic = dynamic_vertices(shared, self.level)?;
        let vertex_count = shared.gpu_scene.vertex_count();
        let [samples, shapes, operators, blocks, rows, receivers, sources, matrices, feedback, sample_rows, texel_samples, copies, volume_blocks, dynamic_vertices, vertex_light] =
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
                    ("mrt feedback", bytemuck::cast_slice(&self.level.feedback)),
                    ("mrt sample rows", bytemuck::cast_slice(&t.sample_rows)),
                    ("mrt texel samples", bytemuck::cast_slice(&t.texel_samples)),
                    ("mrt copies", bytemuck::cast_slice(&t.copies)),
                    ("mrt volume blocks", bytemuck::cast_slice(&t.volume_blocks)),
                    ("mrt dynamic vertices", bytemuck::cast_slice(if dynamic.is_empty() { &[0u32] } else { &dynamic })),
                    // Zero (alpha 0: read the light map) but where the dynamic pass writes; one
                    // value, unread, without dynamic meshes.
                    ("mrt vertex light", bytemuck::cast_slice(&vec![Vec4::ZERO; if dynamic.is_empty() { 1 } else { vertex_count }])),
                ],
            )?;
        let per_frame = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        let vec4s = |name: &str, count: u32| Buffer::new(ctx, name, count.max(1) as u64 * 16, per_frame, MemoryLocation::GpuOnly);
        let dynamic_count = dynamic.len() as u32;
        let push = MrtPush { feedback: self.feedback as u32, dynamic_count, ..t.push };
        let buffers = Buffers {
            samples,
            shapes,
            operators,
            blocks,
            rows,
            receivers,
            sources,
            matrices,
            feedback,
            sample_rows,
            texel_samples,
            copies,
            volume_blocks,
            dynamic_vertices,
            vertex_light,
            light: vec4s("mrt light", push.sample_count)?,
            indirect: vec4s("mrt indirect", push.sample_count)?,
            direct: vec4s("mrt direct", push.sample_count)?,
            b0: vec4s("mrt b0", push.block_count * push.k_max)?,
            b: vec4s("mrt b", push.block_count * push.k_max)?,
            r: vec4s("mrt r", push.receiver_count * push.k_r)?,
            volume: vec4s("mrt volume", if dynamic_count > 0 { push.block_count * ROWS as u32 } else { 1 })?,
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
        let mut dispatches = vec![
            direct::new(shared, &buffers, &shadow_sampler, push.sample_count)?,
            coefficients::new(shared, &buffers, push.block_count * push.k_max)?,
            feedback::new(shared, &buffers, push.block_count * push.k_max)?,
            transfer::new(shared, &buffers, push.receiver_count * push.k_r)?,
            response::new(shared, &buffers, push.sample_count)?,
            light_map::new(shared, &buffers, &light_map, push.texel_count)?,
            padding::new(shared, &buffers, &light_map, push.copy_count)?,
        ];
        if dynamic_count > 0 {
            dispatches.push(volume::new(shared, &buffers, push.block_count * ROWS as u32)?);
            dispatches.push(dynamic::new(shared, &buffers, dynamic_count)?);
        }
        Ok(Box::new(Mrt { dispatches, buffers, light_map, push, _shadow_sampler: shadow_sampler }))
    }
}
