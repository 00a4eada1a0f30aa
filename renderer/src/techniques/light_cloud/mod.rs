//! Local radiance transfer with light clouds (Kristensen et al., 004 §6) at run time: each
//! user point light stands on its nearest visible cloud lights (weights on the CPU, when the
//! lights move: `Renderer::set_lights`), and one pass turns the weights into every vertex's
//! indirect irradiance, handed to the lighting pass as a vertex term (interpolated across
//! triangles: 004 §5's blending, Gouraud-style).
//!
//! Uploaded at creation (device-local, never written again):
//! - `transfer`: packed f32 rgb, `[vertex][cloud light]`, the bake's layout.
//!
//! Written every frame:
//! - `weights` (in the command stream, before the pass): up to one vec4 per cloud light, rgb
//!   the weight (candela), w the light's index as bits;
//! - `irradiance` by `reconstruct` (reconstruct.rs): one vec4 per vertex, rgb lux.
//!
//! Visibility between a user light and the cloud is asked of the caller (`Visibility`): an
//! engine has its own ray queries, relume's tools pass the path tracer's BVH.

mod reconstruct;

use crate::technique::{MakeTechnique, Resource, Shared, Source, Technique, Term};
use crate::upload::upload_buffers_blocking;
use crate::vk::{vk, Buffer, CommandRecorder, Context, Tracker, VkError, VkResult};
use glam::Vec3;
use gpu_allocator::MemoryLocation;
use reconstruct::ReconstructPass;
use relume_bake::light_cloud::{refuse_lights, CloudWeight, LightCloud, Weigher};
use relume_bake::scene::Light;
use std::sync::Arc;

/// Whether the segment between two points is unoccluded: asked between a user light and the
/// cloud lights when the lights move.
pub type Visibility = Arc<dyn Fn(Vec3, Vec3) -> bool + Send + Sync>;

/// What the technique is made from: a bake's cloud, m (each light's nearest visible cloud
/// lights) and the caller's visibility query.
pub struct LightCloudData<'d> {
    pub cloud: &'d LightCloud,
    pub nearest: usize,
    pub visibility: Visibility,
}

struct Buffers {
    transfer: Buffer,
    weights: Buffer,
    irradiance: Buffer,
}

pub struct LightCloudTechnique {
    buffers: Buffers,
    reconstruct: ReconstructPass,
    cloud: Vec<Vec3>,
    weigher: Weigher,
    visibility: Visibility,
    weights: Vec<CloudWeight>,
    /// `weights` as the shader reads them (same capacity: filling it never allocates).
    gpu_weights: Vec<[f32; 4]>,
    unseen: usize,
}

impl LightCloudTechnique {
    /// This frame's non-zero weights, in cloud order.
    pub fn weights(&self) -> &[CloudWeight] {
        &self.weights
    }

    /// How many of the lights see no cloud light (they add no indirect light).
    pub fn lights_without_cloud(&self) -> usize {
        self.unseen
    }

    fn weigh(&mut self, lights: &[Light]) {
        let visibility = &self.visibility;
        self.unseen = self.weigher.weigh(&self.cloud, lights, |a, b| visibility(a, b), &mut self.weights);
        self.gpu_weights.clear();
        self.gpu_weights.extend(self.weights.iter().map(|w| [w.weight.x, w.weight.y, w.weight.z, f32::from_bits(w.light)]));
    }
}

const PASSES: [&str; 1] = ["light_cloud.reconstruct"];

impl Technique for LightCloudTechnique {
    fn name(&self) -> &'static str {
        "light_cloud"
    }

    fn passes(&self) -> &'static [&'static str] {
        &PASSES
    }

    fn record(&self, _pass: usize, rec: &CommandRecorder, tracker: &mut Tracker) {
        if !self.gpu_weights.is_empty() {
            rec.update_buffers([(self.buffers.weights.raw, bytemuck::cast_slice(&self.gpu_weights))]);
        }
        self.reconstruct.record(rec, tracker, self.gpu_weights.len() as u32);
    }

    fn term(&self) -> Option<Term<'_>> {
        Some(Term::Irradiance { source: Source::Vertex(&self.buffers.irradiance), times_occlusion: false, occluded_direct: false })
    }

    /// The lights moved: their weights now, for the frames recorded from now on (004 §6.1).
    fn lights_set(&mut self, lights: &[Light]) {
        self.weigh(lights);
    }

    /// `irradiance` (one vec4 per vertex, rgb lux), as the last frame left it.
    fn resources(&self) -> Vec<(&'static str, Resource<'_>)> {
        vec![("irradiance", Resource::Buffer(&self.buffers.irradiance))]
    }
}

impl MakeTechnique for LightCloudData<'_> {
    /// Uploads the transfer in one submission that is waited for and weighs the scene's
    /// lights. Refused, by name: a cloud that fails `validate` or is for another vertex count,
    /// spot or directional lights, an m out of range, a transfer larger than one storage
    /// buffer, and a cloud too large for one in-stream weight update (64 KiB).
    fn make_blocking(&self, shared: &Shared) -> VkResult<Box<dyn Technique>> {
        let ctx = shared.ctx;
        let cloud = self.cloud;
        check(ctx, cloud, shared.gpu_scene.vertex_count())?;
        refuse_lights(&shared.scene.lights).map_err(|e| VkError::Invalid(format!("light cloud: {e}")))?;
        let weigher = Weigher::new(cloud.lights.len(), self.nearest).map_err(|e| VkError::Invalid(format!("light cloud: {e}")))?;
        let [transfer] = upload_buffers_blocking(ctx, [("light cloud transfer", bytemuck::cast_slice(&cloud.transfer))])?;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        let buffers = Buffers {
            transfer,
            weights: Buffer::new(
                ctx,
                "light cloud weights",
                cloud.lights.len() as u64 * 16,
                vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuOnly,
            )?,
            irradiance: Buffer::new(ctx, "light cloud irradiance", cloud.vertex_count as u64 * 16, usage, MemoryLocation::GpuOnly)?,
        };
        let mut technique = LightCloudTechnique {
            reconstruct: ReconstructPass::new(shared, &buffers, cloud.vertex_count as u32, cloud.lights.len() as u32)?,
            buffers,
            cloud: cloud.lights.clone(),
            weigher,
            visibility: Arc::clone(&self.visibility),
            weights: Vec::with_capacity(cloud.lights.len()),
            gpu_weights: Vec::with_capacity(cloud.lights.len()),
            unseen: 0,
        };
        technique.weigh(&shared.scene.lights);
        Ok(Box::new(technique))
    }
}

fn check(ctx: &Context, cloud: &LightCloud, vertex_count: usize) -> VkResult<()> {
    let refuse = |why: String| Err(VkError::Invalid(format!("light cloud: {why}")));
    if let Err(why) = cloud.validate() {
        return refuse(why);
    }
    if cloud.vertex_count != vertex_count {
        return refuse(format!(
            "the cloud was baked for {} vertices; the scene has {vertex_count}: rebake it for this scene",
            cloud.vertex_count
        ));
    }
    let bytes = cloud.transfer.len() as u64 * 4;
    let limit = ctx.info.max_storage_buffer_range;
    if bytes > limit || cloud.transfer.len() as u64 > u32::MAX as u64 {
        return refuse(format!(
            "the transfer takes {bytes} bytes, more than the {limit} bytes one storage buffer may span on {}; use fewer cloud lights",
            ctx.info.name
        ));
    }
    if cloud.lights.len() * 16 > 65536 {
        return refuse(format!("{} cloud lights: at most 4096 weights fit one in-stream update", cloud.lights.len()));
    }
    Ok(())
}
