//! The light path maps of 000 (§3.2-3.4) on the GPU: the clustered transfer uploaded once, the
//! buffers the run-time passes write every frame, and the `indirect` image they fill.
//!
//! Uploaded at creation (device-local, never written again):
//! - `entry_points`: E x { vec4 position (w 1), vec4 normal (w 0) };
//! - `weights`: E x D f32, w^e_d at e * D + d - 1 (d from 1);
//! - `cluster_starts`: C + 1 u32, cluster c owning entry points `starts[c]..starts[c + 1]`;
//! - `textures`: packed f32 rgb, `[cluster][k][texel]` (k = 0 the mean M^c, k = d the
//!   eigen-texture B^c_d; texels in lightmap order), so texture k = c * (1 + D) + k' starts
//!   at float 3 * k * texel_count: the CPU layout of `ClusteredTransfer::textures`, unchanged;
//! - `coverage`: texel_count f32, the lightmap's alpha where > 0 (covered), 0 elsewhere.
//!
//! Written every frame (passes/entry_irradiance.rs, cluster_sums.rs, lpm_reconstruct.rs):
//! - `entry_irradiance`: E x vec4, rgb I_e;
//! - `cluster_sums`: C * (1 + D) x vec4, rgb s_c then t_c1 .. t_cD per cluster;
//! - `indirect`: an RGBA32F 2D-array image laid out as the lightmap (one layer per page),
//!   rgb the reconstructed indirect irradiance I (lux), alpha the coverage, then padded by
//!   this struct's own [`PaddingPass`] (empty texels: a covered neighbour's rgb, alpha < 0).

use crate::gpu_scene::submit_once;
use crate::lightmap::LightmapData;
use crate::passes::padding::{PaddingPass, LIGHTMAP_FORMAT};
use crate::vk::{vk, Access, Buffer, CommandRecorder, Context, Image, ImageDesc, Tracker, VkError, VkResult};
use glam::{Vec3, Vec4};
use gpu_allocator::MemoryLocation;
use relume_bake::clustered_transfer::ClusteredTransfer;

pub struct GpuLightPathMaps<'a> {
    pub entry_points: Buffer<'a>,
    pub weights: Buffer<'a>,
    pub cluster_starts: Buffer<'a>,
    pub textures: Buffer<'a>,
    pub coverage: Buffer<'a>,
    pub entry_irradiance: Buffer<'a>,
    pub cluster_sums: Buffer<'a>,
    pub indirect: Image<'a>,
    padding: PaddingPass<'a>,
    /// E, C, D.
    pub entry_count: u32,
    pub cluster_count: u32,
    pub basis_count: u32,
    /// Delta-l of §3.4 (square metres).
    pub light_area: f32,
}

impl<'a> GpuLightPathMaps<'a> {
    /// Checks `transfer` against `lightmap` (whose alpha is the coverage, and whose layout
    /// the indirect image takes) and uploads it in one submission that is waited for.
    /// Refused, by name: a transfer that fails `validate`, an empty one (no entry point, no
    /// cluster or no texel), one whose texel count is not the lightmap's, and one whose
    /// textures exceed the device's largest storage buffer.
    pub fn upload(ctx: &'a Context, transfer: &ClusteredTransfer, lightmap: &LightmapData) -> VkResult<Self> {
        check(ctx, transfer, lightmap)?;
        let entries: Vec<Vec4> = transfer.entry_points.iter().flat_map(|e| [e.position.extend(1.0), e.normal.extend(0.0)]).collect();
        let coverage: Vec<f32> = lightmap.texels.iter().map(|t| t.w.max(0.0)).collect();
        let textures: &[Vec3] = &transfer.textures;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let device_local = |name, bytes: usize| Buffer::new(ctx, name, bytes as u64, usage, MemoryLocation::GpuOnly);
        let sources: [(&str, &[u8]); 5] = [
            ("lpm entry points", bytemuck::cast_slice(&entries)),
            ("lpm weights", bytemuck::cast_slice(&transfer.weights)),
            ("lpm cluster starts", bytemuck::cast_slice(&transfer.cluster_starts)),
            ("lpm textures", bytemuck::cast_slice(textures)),
            ("lpm coverage", bytemuck::cast_slice(&coverage)),
        ];
        let mut uploaded = Vec::with_capacity(sources.len());
        for (name, bytes) in sources {
            uploaded.push((device_local(name, bytes.len())?, bytes));
        }
        upload_buffers(ctx, &uploaded)?;
        let mut uploaded = uploaded.into_iter().map(|(buffer, _)| buffer);
        let mut next = || uploaded.next().expect("five buffers");
        let (entry_points, weights, cluster_starts, textures, coverage) = (next(), next(), next(), next(), next());

        let per_frame = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        let terms = transfer.cluster_count() * transfer.terms_per_cluster();
        let entry_irradiance =
            Buffer::new(ctx, "lpm entry irradiance", transfer.entry_points.len() as u64 * 16, per_frame, MemoryLocation::GpuOnly)?;
        let cluster_sums = Buffer::new(ctx, "lpm cluster sums", terms as u64 * 16, per_frame, MemoryLocation::GpuOnly)?;
        let indirect = Image::new(
            ctx,
            "lpm indirect",
            ImageDesc {
                width: lightmap.width,
                height: lightmap.height,
                layers: lightmap.pages,
                format: LIGHTMAP_FORMAT,
                usage: vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC,
                view_type: vk::ImageViewType::TYPE_2D_ARRAY,
            },
        )?;
        let padding = PaddingPass::new(ctx, &indirect)?;
        Ok(GpuLightPathMaps {
            entry_points,
            weights,
            cluster_starts,
            textures,
            coverage,
            entry_irradiance,
            cluster_sums,
            indirect,
            padding,
            entry_count: transfer.entry_points.len() as u32,
            cluster_count: transfer.cluster_count() as u32,
            basis_count: transfer.basis_count,
            light_area: transfer.light_area,
        })
    }

    /// K = C * (1 + D): the textures, and the cluster sums weighing them.
    pub fn term_count(&self) -> u32 {
        self.cluster_count * (1 + self.basis_count)
    }

    /// Texels of the indirect image (and of every texture).
    pub fn texel_count(&self) -> usize {
        let d = self.indirect.desc;
        d.width as usize * d.height as usize * d.layers as usize
    }

    /// Records the padding of the indirect image after the reconstruction wrote it (see
    /// passes/padding.rs for what it reads, writes and costs).
    pub fn record_padding(&self, rec: &CommandRecorder, tracker: &mut Tracker) {
        self.padding.record(rec, tracker, &self.indirect);
    }
}

fn check(ctx: &Context, transfer: &ClusteredTransfer, lightmap: &LightmapData) -> VkResult<()> {
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
    if transfer.texel_count != lightmap.texels.len() {
        return refuse(format!(
            "the transfer's textures have {} texels but the lightmap ({}x{}x{}) has {}; were both baked on the same atlas?",
            transfer.texel_count,
            lightmap.width,
            lightmap.height,
            lightmap.pages,
            lightmap.texels.len()
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
    // lpm_reconstruct.comp indexes the textures with u32 floats.
    if transfer.textures.len() as u64 * 3 > u32::MAX as u64 {
        return refuse(format!("{} texture values are more than a u32 index reaches", transfer.textures.len()));
    }
    Ok(())
}

/// Fills device-local buffers from `data` through one staging buffer and one submission,
/// waited for; the buffers are then ready for compute-shader reads.
fn upload_buffers(ctx: &Context, buffers: &[(Buffer, &[u8])]) -> VkResult<()> {
    let total: usize = buffers.iter().map(|(_, bytes)| bytes.len()).sum();
    let staging = Buffer::new(ctx, "lpm upload staging", total as u64, vk::BufferUsageFlags::TRANSFER_SRC, MemoryLocation::CpuToGpu)?;
    let mut packed = Vec::with_capacity(total);
    for (_, bytes) in buffers {
        packed.extend_from_slice(bytes);
    }
    staging.write(&packed)?;
    submit_once(ctx, |rec, tracker| {
        let mut offset = 0u64;
        for (buffer, bytes) in buffers {
            if !bytes.is_empty() {
                tracker.use_buffer(rec, buffer, Access::TransferDestination);
                rec.copy_buffer(staging.raw, offset, buffer.raw, bytes.len() as u64);
                tracker.use_buffer(rec, buffer, Access::ComputeStorageRead);
            }
            offset += bytes.len() as u64;
        }
    })
}
