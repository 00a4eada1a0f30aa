//! Local radiance transfer with light clouds (Kristensen et al., 004 §6) at run time: each
//! user point or spot light stands on its nearest visible cloud lights (weights on the CPU, when
//! the lights move: `Renderer::set_lights`; a spot's shared out over the cloud lights' emission
//! functions by its cone), a directional light on the cloud's directions nearest it, and two
//! passes turn the weights into every vertex's
//! indirect irradiance (diffuse scenes) or exitant radiance in spherical harmonics (glossy
//! ones), handed to the lighting pass as a vertex term (interpolated across triangles: 004
//! §5's blending, Gouraud-style).
//!
//! Uploaded at creation (device-local, never written again), the bake's layout:
//! - `terms`: packed f32 rgb, cluster after cluster `[term][zone's column][coefficient]`
//!   (term 0 the mean, d the basis vector B_d; a column is one emission function of one cloud
//!   light; n_b coefficients);
//! - `clusters`: per cluster 4 u32, where its terms start, its zone's first column and column
//!   count, its D_c;
//! - `vertices`: per vertex 2 u32, its cluster and where its coordinates start;
//! - `coords`: D_c f32 per vertex, vertex after vertex.
//!
//! Written every frame:
//! - `weights` (in the command stream, before the passes): up to one per column (of every
//!   zone), the weight (candela, rgb f32) and the column's index (u32);
//! - `cluster_sums` by `cluster_sums` (cluster_sums.rs): C (1 + D) n_b vec4, rgb x^m then b_d
//!   (D the most vectors of any cluster; zero past a cluster's D_c);
//! - `vertex_values` by `reconstruct` (reconstruct.rs): n_b vec4 per vertex, rgb lux (n_b = 1)
//!   or the exitant radiance's coefficients (n_b = 16).
//!
//! Visibility between a user light and the cloud is asked of the caller (`Visibility`): an
//! engine has its own ray queries, relume's tools pass the path tracer's BVH.

mod cluster_sums;
mod reconstruct;

use crate::shaders;
use crate::technique::{MakeTechnique, Resource, Shared, Source, Technique, Term};
use crate::upload::upload_buffers_blocking;
use crate::vk::{vk, workgroup_size, Buffer, CommandRecorder, Context, Tracker, VkError, VkResult};
use cluster_sums::ClusterSumsPass;
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
/// lights), the directions each directional light stands on, the seconds a cloud light takes to fade in or out as it comes into or goes out of
/// a light's sight (`Renderer::move_lights`; 0: at once) and the caller's visibility query.
pub struct LightCloudData<'d> {
    pub cloud: &'d LightCloud,
    pub nearest: usize,
    pub nearest_directions: usize,
    pub fade_seconds: f32,
    pub visibility: Visibility,
}

/// A column's weight as `cluster_sums.comp` reads it (std430: 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuWeight {
    weight: [f32; 3],
    column: u32,
}

/// A cluster's layout as `cluster_sums.comp` reads it (std430: 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuCluster {
    offset: u32,
    first_column: u32,
    columns: u32,
    vectors: u32,
}

struct Buffers {
    terms: Buffer,
    clusters: Buffer,
    vertices: Buffer,
    coords: Buffer,
    weights: Buffer,
    cluster_sums: Buffer,
    vertex_values: Buffer,
}

pub struct LightCloudTechnique {
    buffers: Buffers,
    cluster_sums: ClusterSumsPass,
    reconstruct: ReconstructPass,
    cloud: Vec<Vec3>,
    weigher: Weigher,
    visibility: Visibility,
    /// n_b: 1 (irradiance) or 16 (spherical harmonics).
    coefficients: usize,
    weights: Vec<CloudWeight>,
    /// `weights` as the shader reads them (same capacity: filling it never allocates).
    gpu_weights: Vec<GpuWeight>,
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

    fn weigh(&mut self, lights: &[Light], elapsed: Option<f32>) {
        let visibility = &self.visibility;
        self.unseen = self.weigher.weigh_after(&self.cloud, lights, |a, b| visibility(a, b), elapsed, &mut self.weights);
        self.gpu_weights.clear();
        self.gpu_weights.extend(self.weights.iter().map(|w| GpuWeight { weight: w.weight.to_array(), column: w.column }));
    }
}

const PASSES: [&str; 2] = ["light_cloud.cluster_sums", "light_cloud.reconstruct"];

impl Technique for LightCloudTechnique {
    fn name(&self) -> &'static str {
        "light_cloud"
    }

    fn passes(&self) -> &'static [&'static str] {
        &PASSES
    }

    fn record(&self, pass: usize, rec: &CommandRecorder, tracker: &mut Tracker) {
        match pass {
            0 => {
                if !self.gpu_weights.is_empty() {
                    rec.update_buffers([(self.buffers.weights.raw, bytemuck::cast_slice(&self.gpu_weights))]);
                }
                self.cluster_sums.record(rec, tracker, self.gpu_weights.len() as u32);
            }
            _ => self.reconstruct.record(rec, tracker),
        }
    }

    fn term(&self) -> Option<Term<'_>> {
        let values = &self.buffers.vertex_values;
        Some(match self.coefficients {
            1 => Term::Irradiance { source: Source::Vertex(values), times_occlusion: false, occluded_direct: false },
            _ => Term::Radiance(values),
        })
    }

    /// The lights moved: their weights now, for the frames recorded from now on (004 §6.1),
    /// fading as visibility changes when they moved continuously.
    fn lights_set(&mut self, lights: &[Light], elapsed: Option<f32>) {
        self.weigh(lights, elapsed);
    }

    /// `cluster_sums` (C (1 + D) n_b vec4, rgb) and `vertex_values` (n_b vec4 per vertex, rgb),
    /// as the last frame left them.
    fn resources(&self) -> Vec<(&'static str, Resource<'_>)> {
        vec![
            ("cluster_sums", Resource::Buffer(&self.buffers.cluster_sums)),
            ("vertex_values", Resource::Buffer(&self.buffers.vertex_values)),
        ]
    }
}

impl MakeTechnique for LightCloudData<'_> {
    /// Uploads the transfer in one submission that is waited for and weighs the scene's
    /// lights. Refused, by name: a cloud that fails `validate` or is for another vertex count,
    /// directional lights when the cloud has no directions, an m out of range, and a transfer
    /// (or its weights) larger than one storage buffer.
    fn make_blocking(&self, shared: &Shared) -> VkResult<Box<dyn Technique>> {
        let ctx = shared.ctx;
        let cloud = self.cloud;
        check(ctx, cloud, shared.gpu_scene.vertex_count())?;
        refuse_lights(&shared.scene.lights, cloud.directions).map_err(|e| VkError::Invalid(format!("light cloud: {e}")))?;
        let weigher = Weigher::zoned(cloud.zone_lights.clone(), self.nearest)
            .and_then(|w| w.with_emission(cloud.emission))
            .and_then(|w| w.with_directions(cloud.directions, self.nearest_directions))
            .and_then(|w| w.with_fade(self.fade_seconds))
            .map_err(|e| VkError::Invalid(format!("light cloud: {e}")))?;
        let clusters: Vec<GpuCluster> = cloud
            .layout()
            .iter()
            .map(|c| GpuCluster { offset: c.offset as u32, first_column: c.first_column, columns: c.columns, vectors: c.vectors })
            .collect();
        let vertices: Vec<[u32; 2]> = cloud.assignment.iter().zip(cloud.coord_starts()).map(|(&c, start)| [c, start as u32]).collect();
        // A storage buffer may not be empty: no vectors bind one unread coordinate.
        let coords: &[f32] = if cloud.coords.is_empty() { &[0.0] } else { &cloud.coords };
        let [terms, clusters, vertices, coords] = upload_buffers_blocking(
            ctx,
            [
                ("light cloud terms", bytemuck::cast_slice(&cloud.terms)),
                ("light cloud clusters", bytemuck::cast_slice(&clusters)),
                ("light cloud vertices", bytemuck::cast_slice(&vertices)),
                ("light cloud coordinates", bytemuck::cast_slice(coords)),
            ],
        )?;
        let term_count = (cloud.cluster_count() * (1 + cloud.basis()) * cloud.coefficients) as u32;
        let per_frame = |name, bytes: u64| {
            let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
            Buffer::new(ctx, name, bytes, usage, MemoryLocation::GpuOnly)
        };
        let buffers = Buffers {
            terms,
            clusters,
            vertices,
            coords,
            weights: Buffer::new(
                ctx,
                "light cloud weights",
                weight_capacity(cloud) as u64 * 16,
                vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuOnly,
            )?,
            cluster_sums: per_frame("light cloud cluster sums", term_count as u64 * 16)?,
            vertex_values: per_frame("light cloud vertex values", (cloud.vertex_count() * cloud.coefficients) as u64 * 16)?,
        };
        let mut technique = LightCloudTechnique {
            cluster_sums: ClusterSumsPass::new(shared, &buffers, (term_count, 1 + cloud.basis() as u32, cloud.coefficients as u32))?,
            reconstruct: ReconstructPass::new(
                shared,
                &buffers,
                cloud.vertex_count() as u32,
                (cloud.basis() as u32, cloud.coefficients as u32),
            )?,
            coefficients: cloud.coefficients,
            buffers,
            cloud: cloud.lights.clone(),
            weigher,
            visibility: Arc::clone(&self.visibility),
            weights: Vec::with_capacity(weight_capacity(cloud)),
            gpu_weights: Vec::with_capacity(weight_capacity(cloud)),
            unseen: 0,
        };
        technique.weigh(&shared.scene.lights, None);
        Ok(Box::new(technique))
    }
}

/// What the GPU cannot hold or run, refused by name (`make_blocking` lists it).
fn check(ctx: &Context, cloud: &LightCloud, vertex_count: usize) -> VkResult<()> {
    let refuse = |why: String| Err(VkError::Invalid(format!("light cloud: {why}")));
    if let Err(why) = cloud.validate() {
        return refuse(why);
    }
    if cloud.vertex_count() != vertex_count {
        return refuse(format!(
            "the cloud was baked for {} vertices; the scene has {vertex_count}: rebake it for this scene",
            cloud.vertex_count()
        ));
    }
    // Every buffer the passes bind, in bytes, and the workgroups of each dispatch.
    let terms = (cloud.cluster_count() * (1 + cloud.basis()) * cloud.coefficients) as u64;
    let bytes = [
        cloud.terms.len() as u64 * 4,
        cloud.coords.len() as u64 * 4,
        (cloud.vertex_count() * cloud.coefficients) as u64 * 16,
        terms * 16,
        cloud.cluster_count() as u64 * 16,
        weight_capacity(cloud) as u64 * 16,
    ];
    let limit = ctx.info.max_storage_buffer_range;
    if bytes.iter().any(|&b| b > limit) || cloud.terms.len() as u64 > u32::MAX as u64 {
        return refuse(format!(
            "the transfer takes up to {} bytes in one buffer, more than the {limit} bytes one storage buffer may span on {}; use fewer cloud lights, clusters or vectors",
            bytes.iter().max().unwrap_or(&0),
            ctx.info.name
        ));
    }
    // 65,535 workgroups: the least maxComputeWorkGroupCount Vulkan allows.
    let groups = |pass, spirv, invocations: u64| Ok::<u64, VkError>(invocations.div_ceil(workgroup_size(pass, spirv)?[0] as u64));
    let sums = groups("light_cloud.cluster_sums", shaders::LIGHT_CLOUD_CLUSTER_SUMS_COMP, terms)?;
    let vertices = groups("light_cloud.reconstruct", shaders::LIGHT_CLOUD_RECONSTRUCT_COMP, cloud.vertex_count() as u64)?;
    if sums.max(vertices) > 65_535 {
        return refuse(format!(
            "{terms} cluster terms and {} vertices take {sums} and {vertices} workgroups; at most 65,535 fit one dispatch: use fewer clusters or vectors, or split the scene",
            cloud.vertex_count()
        ));
    }
    Ok(())
}

/// Every column of the cloud: its lights times their emission functions.
fn columns(cloud: &LightCloud) -> usize {
    cloud.lights.len() * cloud.emission
}

/// Room for every weight a frame can have: one per column (a scale hall's cloud has tens of
/// thousands; the frame uploads the non-zero ones).
fn weight_capacity(cloud: &LightCloud) -> usize {
    columns(cloud)
}
