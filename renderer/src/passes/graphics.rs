//! The one shape of a graphics pass, as `compute.rs` is of a compute pass. A pass is one value:
//! its name, what its shaders bind with how they use it ([`Slot`]), the images it draws into
//! (colour attachments written, a depth attachment written), its push block (the type `P`)
//! and its shaders, whose SPIR-V is checked against all of them when the pipeline is made.
//! Each recording declares those uses to the tracker (which records the barriers), then
//! renders the draws it is given. Reads of the scene's vertex and index buffers need no
//! barrier: the host writes them while no frame is in flight.

use super::compute::{Sampling, Slot};
use crate::gpu_scene::{vertex_attributes, GpuScene, VERTEX_STRIDE};
use crate::vk::VkResult;
use crate::vk::{vk, Access, Binding, CommandRecorder, Context, DescriptorSet, GraphicsPipelineDesc, Image, Pipeline, Tracker, Use};
use bytemuck::NoUninit;
use std::marker::PhantomData;
use std::sync::Arc;

/// The shaders of a graphics pass and what its pipeline fixes.
pub struct Shaders<'s> {
    pub vertex: &'s [u8],
    pub fragment: &'s [u8],
    /// Specialization constants of both stages.
    pub specialization: &'s [u32],
    /// How many of the scene's vertex attributes (position, normal, uv0, uv1) it reads.
    pub attributes: usize,
}

/// A graphics pass drawing the scene's geometry into `N` colour attachments and a depth one,
/// every surface two-sided.
pub struct GraphicsPass<P, const N: usize> {
    pipeline: Pipeline,
    descriptors: DescriptorSet,
    uses: Vec<Use>,
    /// The scene's vertex and index buffers (they live as long as the renderer; moved meshes
    /// are rewritten in place).
    geometry: (vk::Buffer, vk::Buffer),
    push: PhantomData<(P, [(); N])>,
}

/// Where a recording draws: its extent, a view of each colour attachment (the whole image, or
/// one layer of it), their clear value, and the depth attachment's view (cleared to 1).
pub struct Target<const N: usize> {
    pub extent: vk::Extent2D,
    pub colors: [vk::ImageView; N],
    pub clear: [f32; 4],
    pub depth: vk::ImageView,
}

impl<P: NoUninit, const N: usize> GraphicsPass<P, N> {
    /// Pass `name`, drawing `scene`'s geometry into `colors` and `depth` (whole images; a
    /// recording may draw into one layer of them). Refused, naming the pass and the binding,
    /// like a compute pass.
    pub fn new(
        ctx: &Arc<Context>,
        name: &str,
        scene: &GpuScene,
        shaders: &Shaders,
        slots: &[Slot],
        (colors, depth): ([&Image; N], &Image),
    ) -> VkResult<Self> {
        let bindings: Vec<Binding> = slots.iter().map(Slot::binding).collect();
        let descriptors = DescriptorSet::new(ctx, vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT, &bindings)?;
        let color_formats = colors.map(|image| image.desc.format);
        let pipeline = Pipeline::graphics(
            ctx,
            &GraphicsPipelineDesc {
                name,
                vertex: shaders.vertex,
                fragment: shaders.fragment,
                specialization: shaders.specialization,
                vertex_stride: VERTEX_STRIDE,
                attributes: &vertex_attributes()[..shaders.attributes],
                color_formats: &color_formats,
                depth_format: depth.desc.format,
                // Surfaces are two-sided, as in the reference path tracer; a shadow map needs an
                // occluder's back faces, which are what a closed mesh shows the light.
                cull_mode: vk::CullModeFlags::NONE,
                set: &descriptors,
                push_bytes: std::mem::size_of::<P>() as u32,
            },
        )?;
        let mut uses: Vec<Use> = slots.iter().filter_map(|s| s.tracked(Sampling::Fragment)).collect();
        uses.extend(colors.iter().map(|image| Use::image(*image, Access::ColorAttachmentWrite)));
        uses.push(Use::image(depth, Access::DepthAttachmentWrite));
        Ok(GraphicsPass { pipeline, descriptors, uses, geometry: (scene.vertices.raw, scene.indices.raw), push: PhantomData })
    }

    /// Declares the pass's uses, then draws into `target` each of `draws` (a push block, the
    /// first index and the count of indices of the scene's index buffer). Allocates nothing.
    pub fn record(&self, rec: &CommandRecorder, tracker: &mut Tracker, target: Target<N>, draws: impl IntoIterator<Item = (P, u32, u32)>) {
        tracker.pass(rec, self.uses.iter().copied(), |rec| {
            rec.bind_graphics(self.pipeline.raw, self.pipeline.layout, self.descriptors.set);
            rec.begin_rendering(target.extent, target.colors, target.clear, target.depth);
            rec.bind_geometry(self.geometry.0, self.geometry.1);
            for (push, first_index, index_count) in draws {
                if std::mem::size_of::<P>() > 0 {
                    rec.push_constants(self.pipeline.layout, &push);
                }
                rec.draw_indexed(first_index, index_count);
            }
            rec.end_rendering();
        });
    }
}
